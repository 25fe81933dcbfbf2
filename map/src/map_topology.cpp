// Whole-map enumerations: waypoints, topology, junction pairs, spawn points.
#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>

#include "lockstep/map/map.h"
#include "map_internal.h"

namespace lockstep::map {

std::vector<Waypoint> Map::GenerateWaypoints(double distance, LaneTypeMask types) const {
  std::vector<Waypoint> out;
  if (!(distance > 0)) return out;
  std::size_t count = 0;  // reserve: a Waypoint is large enough that regrowing costs
  for (const LaneNode& n : nodes_)
    if (types.Has(n.type)) count += 1 + static_cast<std::size_t>(std::min(n.Length() / distance, 1e7));
  out.reserve(count);
  for (const LaneNode& n : nodes_) {
    if (!types.Has(n.type)) continue;
    // Along the travel direction, starting at the entry, like CARLA's GenerateWaypoints.
    const double sign = n.Forward() ? 1.0 : -1.0;
    for (double d = 0; d < n.Length() - 1e-6 || d == 0; d += distance) {
      out.push_back(MakeWaypoint(n.road, n.section, n.lane, n.EntryS() + sign * d));
      if (n.Length() <= 1e-6) break;
    }
  }
  return out;
}

std::vector<std::pair<Waypoint, Waypoint>> Map::Topology() const {
  std::vector<std::pair<Waypoint, Waypoint>> out;
  for (const LaneNode& n : nodes_) {
    if (n.type != LaneType::Driving || n.Length() <= 1e-6) continue;
    out.emplace_back(MakeWaypoint(n.road, n.section, n.lane, n.EntryS()),
                     MakeWaypoint(n.road, n.section, n.lane, n.ExitS()));
  }
  return out;
}

std::vector<std::pair<Waypoint, Waypoint>> Map::JunctionWaypoints(int junction, LaneTypeMask types) const {
  std::vector<std::pair<Waypoint, Waypoint>> out;
  for (std::size_t r = 0; r < data_.roads.size(); ++r) {
    const Road& road = data_.roads[r];
    if (road.junction_index != junction || road.sections.empty()) continue;
    // A lane through a junction may span several sections: entry of the first, exit of the last.
    const LaneSection& first = road.sections.front();
    for (const Lane& lane : first.lanes) {
      if (lane.id == 0 || !types.Has(lane.type)) continue;
      const int last = static_cast<int>(road.sections.size()) - 1;
      const bool fwd = lane.id < 0;
      const int in_sec = fwd ? 0 : last, out_sec = fwd ? last : 0;
      if (NodeOf(static_cast<int>(r), out_sec, lane.id) < 0) continue;
      out.emplace_back(MakeWaypoint(static_cast<int>(r), in_sec, lane.id, fwd ? 0.0 : road.length),
                       MakeWaypoint(static_cast<int>(r), out_sec, lane.id, fwd ? road.length : 0.0));
    }
  }
  return out;
}

void Map::BuildJunctions() {
  junctions_.clear();
  for (std::size_t j = 0; j < data_.junctions.size(); ++j) {
    JunctionInfo info;
    info.index = static_cast<int>(j);
    info.id = data_.junctions[j].id;
    junctions_.push_back(std::move(info));
  }
  // CARLA bounds the junction by points on the lane centres of its connecting roads
  // (all lane types); here every lane node of those roads.
  const double inf = std::numeric_limits<double>::infinity();
  std::vector<Eigen::Vector3d> lo(junctions_.size(), Eigen::Vector3d::Constant(inf));
  std::vector<Eigen::Vector3d> hi(junctions_.size(), Eigen::Vector3d::Constant(-inf));
  for (const LaneNode& n : nodes_) {
    const Road& road = data_.roads[static_cast<std::size_t>(n.road)];
    if (road.junction_index < 0) continue;
    const auto j = static_cast<std::size_t>(road.junction_index);
    // Steps of 5 m on straights, 1.5 m in curves (CARLA: 10 steps per lane).
    for (double s : SampleStations(road, n.s_begin, n.s_end, 5.0, 1.5)) {
      const Eigen::Vector3d p = RoadToWorld(road, s, LaneCentreOf(road, static_cast<std::size_t>(n.section), n.lane, s).t);
      if (!p.allFinite()) continue;
      lo[j] = lo[j].cwiseMin(p);
      hi[j] = hi[j].cwiseMax(p);
    }
  }
  for (std::size_t j = 0; j < junctions_.size(); ++j) {
    if (!(lo[j].x() <= hi[j].x())) continue;  // no connecting road: an empty box at the origin
    junctions_[j].bounding_box.location = 0.5 * (lo[j] + hi[j]);
    junctions_[j].bounding_box.extent = 0.5 * (hi[j] - lo[j]);
  }
}

std::optional<JunctionInfo> Map::JunctionOf(const Waypoint& wp) const {
  if (wp.junction < 0 || wp.junction >= static_cast<int>(junctions_.size())) return std::nullopt;
  return junctions_[static_cast<std::size_t>(wp.junction)];
}

std::optional<JunctionInfo> Map::JunctionById(const std::string& junction_id) const {
  auto it = data_.junction_index.find(junction_id);
  if (it == data_.junction_index.end()) return std::nullopt;
  return junctions_[static_cast<std::size_t>(it->second)];
}

namespace {
// Lane ids of a road a signal (reference) applies to: its <validity> ranges, else every
// lane of the direction given by `orientation` ("+": with s, "-": against, else both).
// RoadRunner writes <validity fromLane="0" toLane="0"/>, which names no lane: ignored.
std::vector<int> LanesFor(const Road& road, const std::string& orientation,
                          const std::vector<std::pair<int, int>>& validity) {
  std::vector<int> out;
  for (const auto& [from, to] : validity) {
    if (from == 0 && to == 0) continue;
    for (int id = std::min(from, to); id <= std::max(from, to) && id - std::min(from, to) < 128; ++id)
      if (id != 0) out.push_back(id);
  }
  if (!out.empty()) return out;
  int max_left = 0, max_right = 0;
  for (const LaneSection& sec : road.sections) {
    max_left = std::max(max_left, sec.left_count);
    max_right = std::max(max_right, static_cast<int>(sec.lanes.size()) - sec.left_count - 1);
  }
  if (orientation != "-")
    for (int id = -1; id >= -max_right; --id) out.push_back(id);
  if (orientation != "+")
    for (int id = 1; id <= max_left; ++id) out.push_back(id);
  return out;
}
}  // namespace

namespace {
// The zone in front of the stop line where a vehicle must react to a signal, like the
// trigger volume of CARLA's traffic light and stop sign actors: 3 m of lane before the
// stop line, across every controlled lane, 2 m high, oriented along the first lane.
BoundingBox TriggerVolumeOf(const std::vector<Waypoint>& stops, const Transform& pole) {
  BoundingBox box;
  if (stops.empty()) {
    box.location = pole.location;
    box.yaw = pole.yaw;
    return box;
  }
  constexpr double kDepth = 3.0, kHeight = 2.0;
  const double yaw = stops.front().transform.yaw;
  const Eigen::Vector2d f(std::cos(yaw), std::sin(yaw)), l(-f.y(), f.x());
  const Eigen::Vector2d o = stops.front().transform.location.head<2>();
  double a0 = 1e300, a1 = -1e300, b0 = 1e300, b1 = -1e300, z = 0;
  for (const Waypoint& w : stops) {
    const Eigen::Vector2d p = w.transform.location.head<2>() - o;
    const Eigen::Vector2d wf(std::cos(w.transform.yaw), std::sin(w.transform.yaw)), wl(-wf.y(), wf.x());
    const Eigen::Vector2d half = 0.5 * w.lane_width * wl, back = p - kDepth * wf;
    const Eigen::Vector2d corners[] = {p + half, p - half, back + half, back - half};
    for (const Eigen::Vector2d& c : corners) {
      a0 = std::min(a0, c.dot(f)); a1 = std::max(a1, c.dot(f));
      b0 = std::min(b0, c.dot(l)); b1 = std::max(b1, c.dot(l));
    }
    z += w.transform.location.z() / static_cast<double>(stops.size());
  }
  const Eigen::Vector2d c = o + 0.5 * (a0 + a1) * f + 0.5 * (b0 + b1) * l;
  box.location = Eigen::Vector3d(c.x(), c.y(), z + 0.5 * kHeight);
  box.extent = Eigen::Vector3d(0.5 * (a1 - a0), 0.5 * (b1 - b0), 0.5 * kHeight);
  box.yaw = yaw;
  return box;
}
}  // namespace

std::vector<TrafficLightInfo> Map::ControlledSignals(bool (*selects)(const Signal&)) const {
  std::vector<TrafficLightInfo> out;
  for (std::size_t r = 0; r < data_.roads.size(); ++r) {
    const Road& road = data_.roads[r];
    if (road.sections.empty()) continue;
    for (const Signal& sig : road.signals) {
      if (!selects(sig)) continue;
      TrafficLightInfo tl;
      tl.signal_id = sig.id;
      tl.type = sig.type;
      tl.road = static_cast<int>(r);
      tl.s = sig.s;
      tl.t = sig.t;
      const bool forward = sig.t < 0 || (sig.t == 0 && sig.orientation != "-");
      tl.pose.location = Eigen::Vector3d(sig.x, sig.y, sig.z - sig.z_offset);
      const double hdg = EvaluateReferenceLine(road.plan_view, std::clamp(sig.s, 0.0, road.length)).hdg;
      tl.pose.yaw = std::remainder(forward ? hdg + std::numbers::pi : hdg, 2 * std::numbers::pi);
      for (const Controller& c : data_.controllers)
        if (std::find(c.signal_ids.begin(), c.signal_ids.end(), sig.id) != c.signal_ids.end()) tl.controller_id = c.id;
      // Preferred: <signalReference>s on junction roads name the controlled connecting
      // lanes (RoadRunner/CARLA towns); the stop point is where they begin.
      for (std::size_t rr = 0; rr < data_.roads.size(); ++rr) {
        const Road& jr = data_.roads[rr];
        if (jr.junction_index < 0 || jr.sections.empty()) continue;
        for (const SignalReference& ref : jr.signal_refs) {
          if (ref.id != sig.id) continue;
          for (int lane_id : LanesFor(jr, ref.orientation, ref.validity)) {
            const bool fwd = lane_id < 0;
            const int sec = fwd ? 0 : static_cast<int>(jr.sections.size()) - 1;
            const int node = NodeOf(static_cast<int>(rr), sec, lane_id);
            if (node < 0 || nodes_[static_cast<std::size_t>(node)].type != LaneType::Driving) continue;
            tl.junction = jr.junction_index;
            // Stop on the incoming lane's end when there is one (same place, CARLA's choice).
            const auto& preds = nodes_[static_cast<std::size_t>(node)].predecessors;
            const LaneNode& stop = nodes_[static_cast<std::size_t>(preds.empty() ? node : preds.front())];
            const Waypoint w = MakeWaypoint(stop.road, stop.section, stop.lane, preds.empty() ? stop.EntryS() : stop.ExitS());
            const bool dup = std::any_of(tl.stop_waypoints.begin(), tl.stop_waypoints.end(), [&](const Waypoint& o) {
              return o.road == w.road && o.section == w.section && o.lane == w.lane;
            });
            if (!dup) tl.stop_waypoints.push_back(w);
          }
        }
      }
      if (tl.stop_waypoints.empty()) {
        // Otherwise: the lanes on the signal's side of its own road, stopping where they
        // leave the road (its end for lanes driving with s).
        const RoadLink& link = forward ? road.successor : road.predecessor;
        if (link.kind == RoadLink::Kind::Junction) {
          auto it = data_.junction_index.find(link.element_id);
          if (it != data_.junction_index.end()) tl.junction = it->second;
        }
        const int section = forward ? static_cast<int>(road.sections.size()) - 1 : 0;
        for (int lane_id : LanesFor(road, forward ? "+" : "-", sig.validity)) {
          const Lane* lane = road.sections[static_cast<std::size_t>(section)].Find(lane_id);
          if (!lane || lane->type != LaneType::Driving) continue;
          tl.stop_waypoints.push_back(MakeWaypoint(static_cast<int>(r), section, lane_id, forward ? road.length : 0.0));
        }
      }
      tl.trigger_volume = TriggerVolumeOf(tl.stop_waypoints, tl.pose);
      out.push_back(std::move(tl));
    }
  }
  return out;
}

std::vector<TrafficLightInfo> Map::TrafficLights() const {
  return ControlledSignals([](const Signal& sig) { return sig.dynamic || sig.type == "1000001"; });
}

std::vector<TrafficLightInfo> Map::StopSigns() const {
  // OpenDRIVE's German catalogue (which CARLA's towns use): 206 stop, 205 yield.
  return ControlledSignals([](const Signal& sig) { return !sig.dynamic && (sig.type == "206" || sig.type == "205"); });
}

namespace {
std::vector<Transform> SpawnAlong(const Map& map, LaneType type, double spacing, double lift, bool skip_junctions) {
  std::vector<Transform> out;
  if (!(spacing > 0)) return out;
  const double margin = 0.25 * spacing;
  for (const LaneNode& n : map.Nodes()) {
    if (n.type != type) continue;
    const Road& road = map.Data().roads[static_cast<std::size_t>(n.road)];
    if (skip_junctions && road.junction_index >= 0) continue;
    if (n.Length() < 2 * margin) continue;
    const double sign = n.Forward() ? 1.0 : -1.0;
    for (double d = margin; d <= n.Length() - margin; d += spacing) {
      Transform t = map.MakeWaypoint(n.road, n.section, n.lane, n.EntryS() + sign * d).transform;
      t.location.z() += lift;
      t.pitch = 0;
      out.push_back(t);
    }
  }
  return out;
}
}  // namespace

std::vector<Transform> Map::SpawnPoints(double spacing) const { return SpawnAlong(*this, LaneType::Driving, spacing, 0.5, true); }

std::vector<Transform> Map::PedestrianSpawnPoints(double spacing) const {
  return SpawnAlong(*this, LaneType::Sidewalk, spacing, 1.0, false);
}

}  // namespace lockstep::map
