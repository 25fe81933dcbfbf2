// Landmarks along a lane and crosswalk polygons: what a Traffic Manager looks up.
#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <unordered_map>

#include "lockstep/map/map.h"

namespace lockstep::map {

bool BoundingBox::Contains(const Eigen::Vector3d& p) const {
  const Eigen::Vector3d d = p - location;
  const double c = std::cos(yaw), s = std::sin(yaw);
  const double x = c * d.x() + s * d.y(), y = -s * d.x() + c * d.y();
  return std::fabs(x) <= extent.x() && std::fabs(y) <= extent.y() && std::fabs(d.z()) <= extent.z();
}

namespace {

// Whether a signal with this orientation and validity applies to `lane`. RoadRunner's
// <validity fromLane="0" toLane="0"/> names no lane and is ignored.
bool AppliesTo(int lane, const std::string& orientation, const std::vector<std::pair<int, int>>& validity) {
  bool named = false;
  for (const auto& [from, to] : validity) {
    if (from == 0 && to == 0) continue;
    named = true;
    if (lane >= std::min(from, to) && lane <= std::max(from, to)) return true;
  }
  if (named) return false;
  if (orientation == "+") return lane < 0;
  if (orientation == "-") return lane > 0;
  return true;
}

}  // namespace

std::vector<Landmark> Map::LandmarksAhead(const Waypoint& wp, double distance, bool stop_at_junction) const {
  std::vector<Landmark> out;
  const int start = NodeOf(wp);
  if (start < 0 || !(distance >= 0)) return out;
  // Signals by id, for references.
  std::unordered_map<std::string, const Signal*> by_id;
  for (const Road& r : data_.roads)
    for (const Signal& sig : r.signals) by_id.emplace(sig.id, &sig);
  struct Visit {
    int node;
    double s_from, before;  // entry s on this node, distance walked before it
  };
  std::vector<Visit> stack{{start, wp.s, 0.0}};
  int budget = kWalkBudget;
  while (!stack.empty() && --budget >= 0) {
    const Visit v = stack.back();
    stack.pop_back();
    const LaneNode& n = nodes_[static_cast<std::size_t>(v.node)];
    const Road& road = data_.roads[static_cast<std::size_t>(n.road)];
    if (stop_at_junction && road.junction_index >= 0 && v.before > 0) continue;
    const double sign = n.Forward() ? 1.0 : -1.0;
    const double length = std::max(0.0, sign * (n.ExitS() - v.s_from));
    auto consider = [&](const Signal& sig, double s, double t, const std::string& orientation,
                        const std::vector<std::pair<int, int>>& validity) {
      const double along = sign * (s - v.s_from);
      if (along < -1e-9 || along > length + 1e-9 || v.before + along > distance) return;
      if (!AppliesTo(n.lane, orientation, validity)) return;
      const double d = v.before + std::max(0.0, along);
      auto it = std::find_if(out.begin(), out.end(), [&](const Landmark& l) { return l.id == sig.id; });
      if (it != out.end() && it->distance <= d) return;
      Landmark l;
      l.id = sig.id;
      l.name = sig.name;
      l.type = sig.type;
      l.subtype = sig.subtype;
      l.unit = sig.unit;
      l.text = sig.text;
      l.value = sig.value;
      l.dynamic = sig.dynamic;
      l.road = n.road;
      l.s = s;
      l.t = t;
      l.pose.location = Eigen::Vector3d(sig.x, sig.y, sig.z - sig.z_offset);
      l.pose.yaw = std::remainder(sig.yaw, 2 * std::numbers::pi);
      l.distance = d;
      l.waypoint = MakeWaypoint(n.road, n.section, n.lane, std::clamp(s, n.s_begin, n.s_end));
      if (it != out.end()) *it = std::move(l);
      else out.push_back(std::move(l));
    };
    for (const Signal& sig : road.signals) consider(sig, sig.s, sig.t, sig.orientation, sig.validity);
    for (const SignalReference& ref : road.signal_refs) {
      auto it = by_id.find(ref.id);
      if (it != by_id.end()) consider(*it->second, ref.s, ref.t, ref.orientation, ref.validity);
    }
    if (v.before + length < distance)
      for (int next : n.successors)
        stack.push_back({next, nodes_[static_cast<std::size_t>(next)].EntryS(), v.before + length});
  }
  std::stable_sort(out.begin(), out.end(), [](const Landmark& a, const Landmark& b) { return a.distance < b.distance; });
  return out;
}

std::vector<std::vector<Eigen::Vector3d>> Map::Crosswalks() const {
  std::vector<std::vector<Eigen::Vector3d>> out;
  for (const Road& road : data_.roads) {
    for (const RoadObject& o : road.objects) {
      std::string type = o.type;
      std::transform(type.begin(), type.end(), type.begin(), [](unsigned char c) { return std::tolower(c); });
      if (type != "crosswalk") continue;
      std::vector<Eigen::Vector3d> poly;
      const double c = std::cos(o.yaw), sn = std::sin(o.yaw);
      auto local = [&](double u, double v) { return Eigen::Vector3d(o.x + u * c - v * sn, o.y + u * sn + v * c, o.z); };
      if (!o.outline_local.empty()) {
        for (const auto& [u, v] : o.outline_local) poly.push_back(local(u, v));
      } else if (!o.outline_road.empty()) {
        for (const auto& [s, t] : o.outline_road) poly.push_back(RoadToWorld(road, std::clamp(s, 0.0, road.length), t));
      } else if (o.length > 0 && o.width > 0) {
        const double hl = 0.5 * o.length, hw = 0.5 * o.width;
        poly = {local(-hl, -hw), local(hl, -hw), local(hl, hw), local(-hl, hw)};
      }
      if (poly.size() < 3) continue;
      poly.push_back(poly.front());
      out.push_back(std::move(poly));
    }
  }
  return out;
}

}  // namespace lockstep::map
