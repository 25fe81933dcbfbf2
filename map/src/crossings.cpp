// Crossings at junction mouths (crossings.h).
#include "lockstep/map/crossings.h"

#include <algorithm>

namespace lockstep::map {

bool OnDrivingLane(const Map& m, const Eigen::Vector3d& p) {
  for (const LanePoint& lp : m.LanesAt(p.x(), p.y())) {
    if (m.Nodes()[static_cast<size_t>(lp.node)].type == LaneType::Driving) return true;
  }
  return false;
}

std::vector<MouthCrossing> JunctionMouthCrossings(const Map& m, double setback) {
  using Vec3 = Eigen::Vector3d;
  // A mouth that already has a crosswalk object of the map (the generated towns put one
  // about 5 m before the stop line) gets no second crossing.
  constexpr double kObjectNearby = 10.0;  // m, object centre to the derived crossing's centre
  std::vector<Vec3> objects;
  for (const auto& poly : m.Crosswalks()) {
    if (poly.empty()) continue;
    Vec3 c = Vec3::Zero();
    for (const Vec3& p : poly) c += p;
    objects.push_back(c / static_cast<double>(poly.size()));
  }
  std::vector<MouthCrossing> out;
  const auto& roads = m.Data().roads;
  for (size_t r = 0; r < roads.size(); ++r) {
    const Road& road = roads[r];
    if (road.junction_index >= 0 || road.sections.empty()) continue;
    for (const bool at_end : {false, true}) {
      const RoadLink& link = at_end ? road.successor : road.predecessor;
      if (link.kind != RoadLink::Kind::Junction) continue;
      MouthCrossing c;
      c.road = static_cast<int>(r);
      c.at_end = at_end;
      c.section = at_end ? static_cast<int>(road.sections.size()) - 1 : 0;
      const LaneSection& ls = road.sections[static_cast<size_t>(c.section)];
      int left = 0, right = 0;  // innermost sidewalk lane on each side
      for (const Lane& l : ls.lanes) {
        if (l.type == LaneType::Sidewalk && l.id > 0 && (left == 0 || l.id < left)) left = l.id;
        if (l.type == LaneType::Sidewalk && l.id < 0 && (right == 0 || l.id > right)) right = l.id;
        if (l.type == LaneType::Driving) c.driving_lanes.push_back(l.id);
      }
      if (left == 0 || right == 0 || c.driving_lanes.empty()) continue;
      const double s_end = at_end ? road.length - 1e-3 : 1e-3;
      const double s_in = at_end ? std::max(0.0, road.length - 1.0) : std::min(road.length, 1.0);
      const Vec3 pl = m.MakeWaypoint(c.road, c.section, left, s_end).transform.location;
      const Vec3 pr = m.MakeWaypoint(c.road, c.section, right, s_end).transform.location;
      Vec3 out_dir = pl - m.MakeWaypoint(c.road, c.section, left, s_in).transform.location;
      out_dir.z() = 0;
      if (out_dir.norm() < 1e-6) continue;
      c.into_junction = out_dir.normalized();
      bool ok = false;
      for (const double back : {setback, 1.0, 0.0}) {
        c.ends[0] = pl + c.into_junction * back;
        c.ends[1] = pr + c.into_junction * back;
        if (!OnDrivingLane(m, c.ends[0]) && !OnDrivingLane(m, c.ends[1])) {
          ok = true;
          break;
        }
      }
      if (!ok) continue;
      const Vec3 centre = (c.ends[0] + c.ends[1]) / 2;
      const bool has_object = std::any_of(objects.begin(), objects.end(), [&](const Vec3& o) { return (o - centre).head<2>().norm() < kObjectNearby; });
      if (!has_object) out.push_back(std::move(c));
    }
  }
  return out;
}

}  // namespace lockstep::map
