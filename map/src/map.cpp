#include "lockstep/map/map.h"

#include <algorithm>
#include <cmath>
#include <numbers>

#include "lockstep/map/opendrive_reader.h"
#include "map_internal.h"

namespace lockstep::map {

Eigen::Vector3d Transform::Forward() const {
  return {std::cos(pitch) * std::cos(yaw), std::cos(pitch) * std::sin(yaw), std::sin(pitch)};
}

Map::Map(OpenDrive data, std::string name) : data_(std::move(data)), name_(std::move(name)) {
  BuildGraph();
  index_ = BuildSegmentIndex(*this, &bounds_min_, &bounds_max_);
  BuildJunctions();
}
Map::~Map() = default;
Map::Map(Map&&) noexcept = default;
Map& Map::operator=(Map&&) noexcept = default;

Map Map::Load(const std::string& path) {
  const std::size_t slash = path.find_last_of('/');
  std::string name = slash == std::string::npos ? path : path.substr(slash + 1);
  if (name.size() > 5 && name.substr(name.size() - 5) == ".xodr") name.resize(name.size() - 5);
  return Map(LoadOpenDriveFile(path), name);
}

Map Map::FromString(const std::string& text, const std::string& name) { return Map(ParseOpenDrive(text, name), name); }

int Map::NodeOf(int road, int section, int lane) const {
  if (road < 0 || road >= static_cast<int>(node_lookup_.size())) return -1;
  const auto r = static_cast<std::size_t>(road);
  const int col = lookup_offset_[r] - lane;
  if (section < 0 || col < 0 || col >= lookup_stride_[r]) return -1;
  const std::size_t idx = static_cast<std::size_t>(section * lookup_stride_[r] + col);
  return idx < node_lookup_[r].size() ? node_lookup_[r][idx] : -1;
}

void Map::BuildGraph() {
  nodes_.clear();
  node_lookup_.assign(data_.roads.size(), {});
  lookup_offset_.assign(data_.roads.size(), 0);
  lookup_stride_.assign(data_.roads.size(), 1);
  for (std::size_t r = 0; r < data_.roads.size(); ++r) {
    const Road& road = data_.roads[r];
    int max_left = 0, max_right = 0;
    for (const LaneSection& sec : road.sections) {
      max_left = std::max(max_left, sec.left_count);
      max_right = std::max(max_right, static_cast<int>(sec.lanes.size()) - sec.left_count - 1);
    }
    lookup_offset_[r] = max_left;
    lookup_stride_[r] = max_left + max_right + 1;
    node_lookup_[r].assign(road.sections.size() * static_cast<std::size_t>(lookup_stride_[r]), -1);
    for (std::size_t si = 0; si < road.sections.size(); ++si) {
      const LaneSection& sec = road.sections[si];
      for (const Lane& lane : sec.lanes) {
        if (lane.id == 0) continue;
        LaneNode n;
        n.road = static_cast<int>(r);
        n.section = static_cast<int>(si);
        n.lane = lane.id;
        n.s_begin = sec.s;
        n.s_end = sec.s + sec.length;
        n.type = lane.type;
        node_lookup_[r][si * static_cast<std::size_t>(lookup_stride_[r]) +
                        static_cast<std::size_t>(max_left - lane.id)] = static_cast<int>(nodes_.size());
        nodes_.push_back(std::move(n));
      }
    }
  }
  for (std::size_t i = 0; i < nodes_.size(); ++i) {
    const LaneNode n = nodes_[i];
    const Road& road = data_.roads[static_cast<std::size_t>(n.road)];
    const LaneSection& sec = road.sections[static_cast<std::size_t>(n.section)];
    const Lane& lane = *sec.Find(n.lane);
    const bool forward = n.lane < 0;
    const int next_section = n.section + (forward ? 1 : -1);
    if (next_section >= 0 && next_section < static_cast<int>(road.sections.size())) {
      // Only explicit lane links, from either side: this lane's successors (in s) or
      // the next section's lanes that name this one as their predecessor.
      std::vector<int> ids = forward ? lane.successors : lane.predecessors;
      for (const Lane& other : road.sections[static_cast<std::size_t>(next_section)].lanes) {
        const std::vector<int>& back = forward ? other.predecessors : other.successors;
        if (other.id != 0 && std::find(back.begin(), back.end(), n.lane) != back.end()) ids.push_back(other.id);
      }
      for (int id : ids) {
        if ((id < 0) != forward) continue;  // a lane link may not reverse direction inside a road
        const int target = NodeOf(n.road, next_section, id);
        if (target >= 0) nodes_[i].successors.push_back(target);
      }
    } else {
      LinkRoadEnd(static_cast<int>(i), forward);
    }
  }
  for (std::size_t i = 0; i < nodes_.size(); ++i) {
    auto& succ = nodes_[i].successors;
    std::sort(succ.begin(), succ.end());
    succ.erase(std::unique(succ.begin(), succ.end()), succ.end());
    for (int t : succ) nodes_[static_cast<std::size_t>(t)].predecessors.push_back(static_cast<int>(i));
  }
}

// Adds the successors of a node that leaves its road at the end (at_end) or the start.
void Map::LinkRoadEnd(int node_id, bool at_end) {
  LaneNode& n = nodes_[static_cast<std::size_t>(node_id)];
  const Road& road = data_.roads[static_cast<std::size_t>(n.road)];
  const Lane& lane = *road.sections[static_cast<std::size_t>(n.section)].Find(n.lane);
  const RoadLink& link = at_end ? road.successor : road.predecessor;
  auto add = [&](int target_road, ContactPoint cp, int target_lane) {
    const Road& tr = data_.roads[static_cast<std::size_t>(target_road)];
    if (tr.sections.empty()) return;
    const bool enters_at_start = cp != ContactPoint::End;
    if ((target_lane < 0) != enters_at_start) return;  // would travel back into this road
    const int section = enters_at_start ? 0 : static_cast<int>(tr.sections.size()) - 1;
    const int t = NodeOf(target_road, section, target_lane);
    if (t >= 0) n.successors.push_back(t);
  };
  if (link.kind == RoadLink::Kind::Road) {
    auto it = data_.road_index.find(link.element_id);
    if (it == data_.road_index.end()) return;
    // Only explicit lane links (OpenDRIVE has no implicit ones): this lane's own
    // successors/predecessors, and the lanes of the linked road that name this lane
    // in their list for this end, when that road's link there names this road.
    for (int id : at_end ? lane.successors : lane.predecessors) add(it->second, link.contact, id);
    const Road& tr = data_.roads[static_cast<std::size_t>(it->second)];
    const bool enters_at_start = link.contact != ContactPoint::End;
    const RoadLink& back_link = enters_at_start ? tr.predecessor : tr.successor;
    const ContactPoint this_end = at_end ? ContactPoint::End : ContactPoint::Start;
    if (!tr.sections.empty() && back_link.kind == RoadLink::Kind::Road && back_link.element_id == road.id &&
        (back_link.contact == this_end || back_link.contact == ContactPoint::None)) {
      const LaneSection& entry = enters_at_start ? tr.sections.front() : tr.sections.back();
      for (const Lane& other : entry.lanes) {
        const std::vector<int>& back = enters_at_start ? other.predecessors : other.successors;
        if (other.id != 0 && std::find(back.begin(), back.end(), n.lane) != back.end()) add(it->second, link.contact, other.id);
      }
    }
  } else if (link.kind == RoadLink::Kind::Junction) {
    auto jt = data_.junction_index.find(link.element_id);
    if (jt == data_.junction_index.end()) return;
    const RoadLink& other = at_end ? road.predecessor : road.successor;
    const bool both_ends_here = other.kind == RoadLink::Kind::Junction && other.element_id == link.element_id;
    const double exit_s = at_end ? road.length : 0.0;
    const Eigen::Vector3d exit_p = RoadToWorld(road, exit_s, 0.0);
    const Eigen::Vector3d other_p = RoadToWorld(road, road.length - exit_s, 0.0);
    for (const Connection& c : data_.junctions[static_cast<std::size_t>(jt->second)].connections) {
      if (c.incoming_road != road.id) continue;
      auto ct = data_.road_index.find(c.connecting_road);
      if (ct == data_.road_index.end()) continue;
      const Road& cr = data_.roads[static_cast<std::size_t>(ct->second)];
      if (both_ends_here) {  // pick the connections that touch this end
        const Eigen::Vector3d cp = RoadToWorld(cr, c.contact == ContactPoint::End ? cr.length : 0.0, 0.0);
        if ((cp - exit_p).squaredNorm() > (cp - other_p).squaredNorm()) continue;
      }
      for (const auto& [from, to] : c.lane_links)
        if (from == n.lane) add(ct->second, c.contact, to);
    }
  }
}

Waypoint Map::MakeWaypoint(int road, int section, int lane, double s) const {
  Waypoint wp;
  if (road < 0 || road >= static_cast<int>(data_.roads.size())) return wp;
  const Road& r = data_.roads[static_cast<std::size_t>(road)];
  if (r.sections.empty()) return wp;
  if (section < 0 || section >= static_cast<int>(r.sections.size()))
    section = static_cast<int>(FindSection(r, s));
  const LaneSection& sec = r.sections[static_cast<std::size_t>(section)];
  s = std::clamp(s, sec.s, sec.s + sec.length);
  wp.road = road;
  wp.section = section;
  wp.lane = lane;
  wp.s = s;
  const LaneCentre centre = LaneCentreOf(r, static_cast<std::size_t>(section), lane, s);
  const Pose2 ref = EvaluateReferenceLine(r.plan_view, s);
  const double t = centre.t;
  double z, slope;
  EvalPoly3SequenceWithSlope(r.elevation, s, &z, &slope);
  wp.transform.location = Eigen::Vector3d(ref.x - t * std::sin(ref.hdg), ref.y + t * std::cos(ref.hdg), z);
  // Direction of the lane centre p(s) + t(s) n(s): d/ds = (1 - k t) T + t' N. CARLA
  // adds t' to the heading; this is the exact angle (equal to first order).
  const double hdg = centre.dt == 0 ? ref.hdg : ref.hdg + std::atan2(centre.dt, std::max(1.0 - ref.curvature * t, 1e-3));
  const bool forward = lane <= 0;
  wp.transform.yaw = forward ? hdg : hdg + std::numbers::pi;
  // Wrap to [-pi, pi]. Within 3 pi one exact subtraction gives what std::remainder
  // gives, at a fraction of its cost (this is the hottest path of waypoint queries).
  double& yaw = wp.transform.yaw;
  if (!(std::fabs(yaw) < 3 * std::numbers::pi)) yaw = std::remainder(yaw, 2 * std::numbers::pi);
  else if (yaw > std::numbers::pi) yaw -= 2 * std::numbers::pi;
  else if (yaw < -std::numbers::pi) yaw += 2 * std::numbers::pi;
  wp.transform.pitch = std::atan(forward ? slope : -slope);
  wp.lane_width = centre.width;
  if (const Lane* l = sec.Find(lane)) wp.lane_type = l->type;
  wp.junction = r.junction_index;
  wp.road_id = r.id;
  if (r.junction_index >= 0) wp.junction_id = data_.junctions[static_cast<std::size_t>(r.junction_index)].id;
  const auto mm = static_cast<std::uint64_t>(static_cast<std::int64_t>(std::llround(s * 1000.0)));
  wp.id = (static_cast<std::uint64_t>(road) * 0x9E3779B97F4A7C15ull) ^
          (static_cast<std::uint64_t>(section) << 48) ^ (static_cast<std::uint64_t>(lane + 512) << 36) ^ mm;
  return wp;
}

std::vector<Waypoint> Map::Walk(const Waypoint& wp, double distance, bool forward, int* budget) const {
  // Depth first over the branches, in successor order, with a stack of our own: a chain of
  // thousands of tiny lanes (a hostile map) must not overflow the call stack. The budget
  // bounds the branching walk on pathological graphs (zero-length loops).
  struct Pending {
    Waypoint at;
    double distance;
  };
  std::vector<Waypoint> out;
  std::vector<Pending> stack{{wp, distance}};
  while (!stack.empty()) {
    const Pending p = std::move(stack.back());
    stack.pop_back();
    const int id = NodeOf(p.at);
    if (id < 0 || --*budget < 0 || !(p.distance >= 0)) continue;
    const LaneNode& n = nodes_[static_cast<std::size_t>(id)];
    const double sign = ((n.lane < 0) == forward) ? 1.0 : -1.0;
    const double room = sign > 0 ? n.s_end - p.at.s : p.at.s - n.s_begin;
    if (p.distance <= room + 1e-9) {
      out.push_back(MakeWaypoint(n.road, n.section, n.lane, p.at.s + sign * p.distance));
      continue;
    }
    const std::vector<int>& next = forward ? n.successors : n.predecessors;
    for (auto it = next.rbegin(); it != next.rend(); ++it) {  // reversed: the first successor is walked first
      const LaneNode& m = nodes_[static_cast<std::size_t>(*it)];
      stack.push_back({MakeWaypoint(m.road, m.section, m.lane, forward ? m.EntryS() : m.ExitS()), p.distance - std::max(0.0, room)});
    }
  }
  return out;
}

std::vector<Waypoint> Map::Next(const Waypoint& wp, double distance) const {
  int budget = kWalkBudget;
  return Walk(wp, distance, true, &budget);
}
std::vector<Waypoint> Map::Previous(const Waypoint& wp, double distance) const {
  int budget = kWalkBudget;
  return Walk(wp, distance, false, &budget);
}

// CARLA's next_until_lane_end / previous_until_lane_start: steps of `distance` while
// the walk stays on one branch of the same road, then the point where the lane leaves
// the road (the lane end; across lane sections, as CARLA's lane end is the road's).
std::vector<Waypoint> Map::UntilRoadEnd(const Waypoint& wp, double distance, bool forward) const {
  std::vector<Waypoint> out;
  if (NodeOf(wp) < 0 || !(distance > 0)) return out;
  const Road& road = data_.roads[static_cast<std::size_t>(wp.road)];
  // Bounded so a tiny step on a long road cannot allocate without limit.
  const std::size_t max_points = 100000;
  Waypoint cur = wp;
  while (out.size() < max_points) {
    int budget = kWalkBudget;
    std::vector<Waypoint> step = Walk(cur, distance, forward, &budget);
    if (step.size() != 1 || step.front().road != wp.road) break;
    // s moves monotonically along a lane within a road; stop if it does not (loops).
    const bool advances = ((wp.lane < 0) == forward) ? step.front().s > cur.s : step.front().s < cur.s;
    if (!advances) break;
    cur = step.front();
    out.push_back(cur);
  }
  // The rest of the way to the road end in this walk's direction.
  const bool towards_end = (wp.lane < 0) == forward;
  const double remaining = towards_end ? road.length - cur.s : cur.s;
  int budget = kWalkBudget;
  for (const Waypoint& w : Walk(cur, std::max(0.0, remaining), forward, &budget)) {
    if (w.road != wp.road) continue;
    if (out.empty() || std::fabs(out.back().s - w.s) > 1e-9 || out.back().lane != w.lane) out.push_back(w);
    break;
  }
  return out;
}

std::vector<Waypoint> Map::NextUntilLaneEnd(const Waypoint& wp, double distance) const {
  return UntilRoadEnd(wp, distance, true);
}
std::vector<Waypoint> Map::PreviousUntilLaneStart(const Waypoint& wp, double distance) const {
  return UntilRoadEnd(wp, distance, false);
}

int Map::RoadIndex(const std::string& road_id) const {
  auto it = data_.road_index.find(road_id);
  return it == data_.road_index.end() ? -1 : it->second;
}

std::optional<Waypoint> Map::WaypointXodr(const std::string& road_id, int lane_id, double s) const {
  const int road = RoadIndex(road_id);
  if (road < 0 || lane_id == 0) return std::nullopt;
  const Road& r = data_.roads[static_cast<std::size_t>(road)];
  if (!(s >= 0) || !(s < r.length) || r.sections.empty()) return std::nullopt;
  // Where two sections meet, s belongs to both: take the one that has the lane.
  const int section = static_cast<int>(FindSection(r, s));
  for (int sec : {section, section - 1}) {
    if (sec < 0 || NodeOf(road, sec, lane_id) < 0) continue;
    const LaneSection& ls = r.sections[static_cast<std::size_t>(sec)];
    if (s < ls.s - 1e-9 || s > ls.s + ls.length + 1e-9) continue;
    return MakeWaypoint(road, sec, lane_id, s);
  }
  return std::nullopt;
}

std::optional<Waypoint> Map::WaypointXodr(int road_id, int lane_id, double s) const {
  return WaypointXodr(std::to_string(road_id), lane_id, s);
}

std::optional<Waypoint> Map::Neighbour(const Waypoint& wp, int lane) const {
  if (lane == 0 || NodeOf(wp.road, wp.section, lane) < 0) return std::nullopt;
  return MakeWaypoint(wp.road, wp.section, lane, wp.s);
}

namespace {
int LeftOf(int lane) { return lane < 0 ? (lane + 1 == 0 ? 1 : lane + 1) : (lane - 1 == 0 ? -1 : lane - 1); }
int RightOf(int lane) { return lane < 0 ? lane - 1 : lane + 1; }
bool Allows(MarkLaneChange m, int from, int to) {
  switch (m) {
    case MarkLaneChange::Both: return true;
    case MarkLaneChange::None: return false;
    case MarkLaneChange::Increase: return to > from;
    case MarkLaneChange::Decrease: return to < from;
  }
  return false;
}
}  // namespace

std::optional<Waypoint> Map::LeftLane(const Waypoint& wp) const { return Neighbour(wp, LeftOf(wp.lane)); }
std::optional<Waypoint> Map::RightLane(const Waypoint& wp) const { return Neighbour(wp, RightOf(wp.lane)); }

// The marking on the border between lane_a and its neighbour lane_b (|b| = |a| +- 1 or across 0).
std::optional<LaneMarking> Map::MarkingBetween(const Waypoint& wp, int lane_a, int lane_b) const {
  if (wp.road < 0) return std::nullopt;
  const Road& r = data_.roads[static_cast<std::size_t>(wp.road)];
  const LaneSection& sec = r.sections[static_cast<std::size_t>(wp.section)];
  // A lane's <roadMark> is its outer border, so a border belongs to the lane nearer the
  // centre; the centre line belongs to lane 0.
  int owner;
  if ((lane_a < 0) != (lane_b < 0)) owner = 0;
  else owner = std::abs(lane_a) < std::abs(lane_b) ? lane_a : lane_b;
  const Lane* l = sec.Find(owner);
  if (!l) return std::nullopt;  // no such border (e.g. outside the outermost lane)
  const RoadMark* m = MarkAt(*l, wp.s - sec.s);
  LaneMarking out;
  if (!m) return out;
  out.type = m->type;
  out.color = m->color;
  out.width = m->width;
  const bool to_left = lane_b == LeftOf(lane_a);
  if (m->lane_change == MarkLaneChange::Both) out.lane_change = LaneChange::Both;
  else if (Allows(m->lane_change, lane_a, lane_b)) out.lane_change = to_left ? LaneChange::Left : LaneChange::Right;
  else out.lane_change = LaneChange::None;
  return out;
}

// Left in the travel direction is always the inner border (towards the centre line).
std::optional<LaneMarking> Map::LeftMarking(const Waypoint& wp) const {
  if (wp.road < 0) return std::nullopt;
  return MarkingBetween(wp, wp.lane, LeftOf(wp.lane));
}

std::optional<LaneMarking> Map::RightMarking(const Waypoint& wp) const {
  if (wp.road < 0) return std::nullopt;
  return MarkingBetween(wp, wp.lane, RightOf(wp.lane));
}

LaneChange Map::AllowedLaneChange(const Waypoint& wp) const {
  int bits = 0;
  const auto left = LeftMarking(wp), right = RightMarking(wp);
  if (left && (left->lane_change == LaneChange::Both || left->lane_change == LaneChange::Left) && LeftLane(wp))
    bits |= static_cast<int>(LaneChange::Left);
  if (right && (right->lane_change == LaneChange::Both || right->lane_change == LaneChange::Right) && RightLane(wp))
    bits |= static_cast<int>(LaneChange::Right);
  return static_cast<LaneChange>(bits);
}

double Map::SpeedLimitAt(const Eigen::Vector3d& p, double fallback) const {
  const auto wp = NearestWaypoint(p, true, LaneType::Driving);
  return wp ? SpeedLimit(*wp, fallback) : fallback;
}

double Map::SpeedLimit(const Waypoint& wp, double fallback) const {
  if (wp.road < 0) return fallback;
  const Road& r = data_.roads[static_cast<std::size_t>(wp.road)];
  const bool forward = wp.lane < 0;
  double best_s = -1, best = std::numeric_limits<double>::quiet_NaN();
  auto consider = [&](double s, double t, const std::string& orientation, double mps) {
    bool serves;
    if (orientation == "+") serves = forward;
    else if (orientation == "-") serves = !forward;
    else serves = (t <= 0) == forward;
    if (!serves || !std::isfinite(mps) || mps <= 0) return;
    const double behind = forward ? wp.s - s : s - wp.s;
    if (behind < -1e-6) return;
    if (best_s < 0 || behind < best_s) {
      best_s = behind;
      best = mps;
    }
  };
  for (const Signal& sig : r.signals) {
    if (sig.type != "274") continue;  // German catalogue id for "maximum speed", used by OpenDRIVE
    const double v = sig.unit == "mph" ? sig.value * 0.44704 : sig.unit == "m/s" ? sig.value : sig.value / 3.6;
    consider(sig.s, sig.t, sig.orientation, v);
  }
  for (const RoadObject& o : r.objects) {
    // RoadRunner exports (CARLA towns) place speed signs as objects named "Speed_<km/h>".
    if (o.name.rfind("Speed_", 0) != 0) continue;
    const double kmh = std::atof(o.name.c_str() + 6);
    consider(o.s, o.t, "", kmh / 3.6);
  }
  if (std::isfinite(best)) return best;
  const LaneSection& sec = r.sections[static_cast<std::size_t>(wp.section)];
  if (const Lane* l = sec.Find(wp.lane); l && std::isfinite(l->speed_max_mps)) return l->speed_max_mps;
  for (auto it = r.types.rbegin(); it != r.types.rend(); ++it)
    if (it->s <= wp.s + 1e-9 && std::isfinite(it->speed_max_mps)) return it->speed_max_mps;
  return fallback;
}

}  // namespace lockstep::map
