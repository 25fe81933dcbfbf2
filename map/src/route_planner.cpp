#include "lockstep/map/route_planner.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <queue>

namespace lockstep::map {

const char* ToString(RoadOption o) {
  switch (o) {
    case RoadOption::Void: return "VOID";
    case RoadOption::Left: return "LEFT";
    case RoadOption::Right: return "RIGHT";
    case RoadOption::Straight: return "STRAIGHT";
    case RoadOption::LaneFollow: return "LANEFOLLOW";
    case RoadOption::ChangeLaneLeft: return "CHANGELANELEFT";
    case RoadOption::ChangeLaneRight: return "CHANGELANERIGHT";
  }
  return "VOID";
}

namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();
constexpr std::size_t kMaxSteps = 2000000;  // ~4000 km at 2 m: far beyond any real route

struct Parent {
  int prev = -1;                 // node whose exit we came from (-1: the start)
  int via = -1;                  // lane change: node driven first, then changed out of
  RoadOption kind = RoadOption::LaneFollow;
};

struct Leg {
  int node;
  RoadOption into;  // LaneFollow, or the lane change that led into this node
  double from, to;  // road s range, in travel order
};

class Planner {
 public:
  Planner(const Map& m, const RoutePlannerOptions& o) : m_(m), o_(o), dist_(m.Nodes().size(), kInf), parent_(m.Nodes().size()) {}

  std::optional<Route> Run(const Waypoint& from, const Waypoint& to) {
    const int start = m_.NodeOf(from), goal = m_.NodeOf(to);
    if (start < 0 || goal < 0) return std::nullopt;
    const LaneNode& sn = Node(start);
    const LaneNode& gn = Node(goal);
    goal_pos_ = to.transform.location;
    const double rem = sn.Forward() ? sn.s_end - from.s : from.s - sn.s_begin;
    const double partial = gn.Forward() ? to.s - gn.s_begin : gn.s_end - to.s;
    const double ahead = sn.Forward() ? to.s - from.s : from.s - to.s;
    double best = kInf;
    Parent best_parent;
    bool direct = false;
    if (start == goal && ahead >= 0) {
      best = ahead;
      direct = true;
    }
    for (auto [nb, kind] : Changes(start)) {
      if (nb == goal && ahead >= 0 && ahead + o_.lane_change_cost_m < best) {
        best = ahead + o_.lane_change_cost_m;
        best_parent = Parent{-1, start, kind};
        direct = false;
      }
      Relax(nb, rem + o_.lane_change_cost_m, Parent{-1, start, kind});
    }
    Relax(start, rem, Parent{});
    while (!open_.empty()) {
      const auto [f, v] = open_.top();
      open_.pop();
      if (f >= best) break;
      if (f > dist_[static_cast<std::size_t>(v)] + Heuristic(v) + 1e-9) continue;  // stale entry
      const double dv = dist_[static_cast<std::size_t>(v)];
      for (int u : Node(v).successors) {
        if (Node(u).type != LaneType::Driving) continue;
        if (u == goal && dv + partial < best) {
          best = dv + partial;
          best_parent = Parent{v, -1, RoadOption::LaneFollow};
          direct = false;
        }
        Relax(u, dv + Node(u).Length(), Parent{v, -1, RoadOption::LaneFollow});
        for (auto [nb, kind] : Changes(u)) {
          if (nb == goal && dv + partial + o_.lane_change_cost_m < best) {
            best = dv + partial + o_.lane_change_cost_m;
            best_parent = Parent{v, u, kind};
            direct = false;
          }
          Relax(nb, dv + Node(u).Length() + o_.lane_change_cost_m, Parent{v, u, kind});
        }
      }
    }
    if (!std::isfinite(best)) return std::nullopt;
    std::vector<Leg> legs;
    if (direct) {
      legs.push_back(Leg{start, RoadOption::LaneFollow, 0, 0});
    } else {
      int cur = goal;
      Parent pi = best_parent;
      while (true) {
        if (pi.via >= 0) {
          legs.push_back(Leg{cur, pi.kind, 0, 0});
          legs.push_back(Leg{pi.via, RoadOption::LaneFollow, 0, 0});
        } else {
          legs.push_back(Leg{cur, RoadOption::LaneFollow, 0, 0});
        }
        if (pi.prev < 0 || legs.size() > m_.Nodes().size() * 2 + 4) break;
        cur = pi.prev;
        pi = parent_[static_cast<std::size_t>(cur)];
      }
      std::reverse(legs.begin(), legs.end());
    }
    for (Leg& l : legs) {
      l.from = Node(l.node).EntryS();
      l.to = Node(l.node).ExitS();
    }
    legs.front().from = from.s;
    legs.back().to = to.s;
    for (std::size_t i = 1; i < legs.size(); ++i) {
      if (legs[i].into == RoadOption::LaneFollow) continue;
      const double mid = 0.5 * (legs[i - 1].from + legs[i].to);  // change halfway along the shared stretch
      legs[i - 1].to = mid;
      legs[i].from = mid;
    }
    return Emit(legs);
  }

 private:
  const LaneNode& Node(int i) const { return m_.Nodes()[static_cast<std::size_t>(i)]; }

  double Heuristic(int v) {
    if (heuristic_.empty()) heuristic_.assign(m_.Nodes().size(), -1.0);
    double& h = heuristic_[static_cast<std::size_t>(v)];
    if (h < 0) {
      const LaneNode& n = Node(v);
      h = (m_.MakeWaypoint(n.road, n.section, n.lane, n.ExitS()).transform.location - goal_pos_).head<2>().norm();
      h = std::max(0.0, h - 0.5);  // admissible despite small geometric slack
    }
    return h;
  }

  void Relax(int v, double d, const Parent& p) {
    if (d < dist_[static_cast<std::size_t>(v)]) {
      dist_[static_cast<std::size_t>(v)] = d;
      parent_[static_cast<std::size_t>(v)] = p;
      open_.emplace(d + Heuristic(v), v);
    }
  }

  // Same-direction driving neighbours the road marks allow changing into.
  std::vector<std::pair<int, RoadOption>> Changes(int v) const {
    std::vector<std::pair<int, RoadOption>> out;
    if (!o_.allow_lane_changes) return out;
    const LaneNode& n = Node(v);
    if (n.Length() < 10.0) return out;  // no lane changes on short pieces (junction stubs)
    const Waypoint mid = m_.MakeWaypoint(n.road, n.section, n.lane, 0.5 * (n.s_begin + n.s_end));
    if (mid.IsJunction()) return out;
    const int allowed = static_cast<int>(m_.AllowedLaneChange(mid));
    auto add = [&](const std::optional<Waypoint>& w, RoadOption kind) {
      if (!w || w->lane_type != LaneType::Driving || (w->lane < 0) != (n.lane < 0)) return;
      out.emplace_back(m_.NodeOf(*w), kind);
    };
    if (allowed & static_cast<int>(LaneChange::Left)) add(m_.LeftLane(mid), RoadOption::ChangeLaneLeft);
    if (allowed & static_cast<int>(LaneChange::Right)) add(m_.RightLane(mid), RoadOption::ChangeLaneRight);
    return out;
  }

  Route Emit(const std::vector<Leg>& legs) const {
    Route route;
    std::vector<int> junction_of(legs.size(), -1);
    for (std::size_t i = 0; i < legs.size(); ++i)
      junction_of[i] = m_.Data().roads[static_cast<std::size_t>(Node(legs[i].node).road)].junction_index;
    // One command per junction passage, from the heading change across it.
    std::vector<RoadOption> command(legs.size(), RoadOption::LaneFollow);
    for (std::size_t i = 0; i < legs.size();) {
      if (junction_of[i] < 0) {
        ++i;
        continue;
      }
      std::size_t j = i;
      while (j + 1 < legs.size() && junction_of[j + 1] == junction_of[i]) ++j;
      const LaneNode& a = Node(legs[i].node);
      const LaneNode& b = Node(legs[j].node);
      const double yaw_in = m_.MakeWaypoint(a.road, a.section, a.lane, legs[i].from).transform.yaw;
      const double yaw_out = m_.MakeWaypoint(b.road, b.section, b.lane, legs[j].to).transform.yaw;
      const double turn = std::remainder(yaw_out - yaw_in, 2 * 3.14159265358979323846);
      const RoadOption c = std::fabs(turn) < o_.straight_threshold_rad ? RoadOption::Straight
                           : turn > 0                                  ? RoadOption::Left  // ENU: CCW is left
                                                                       : RoadOption::Right;
      for (std::size_t k = i; k <= j; ++k) command[k] = c;
      i = j + 1;
    }
    for (std::size_t i = 0; i < legs.size(); ++i) {
      const Leg& l = legs[i];
      const LaneNode& n = Node(l.node);
      const double span = std::fabs(l.to - l.from);
      const double sign = l.to >= l.from ? 1.0 : -1.0;
      route.length_m += span;
      const bool last = i + 1 == legs.size();
      bool first_of_leg = true;
      const Road& road = m_.Data().roads[static_cast<std::size_t>(n.road)];
      for (double d = 0; d < span - 1e-6;) {
        RouteStep step;
        const double s = l.from + sign * d;
        step.waypoint = m_.MakeWaypoint(n.road, n.section, n.lane, s);
        // Space the points by distance along the lane centre, not along the reference
        // line: in a bend a lane at offset t is (1 - curvature * t) times as long, and
        // widening lanes move sideways. Start from that estimate, then shrink to the chord.
        const double t = LaneCentreOf(road, static_cast<std::size_t>(n.section), n.lane, s).t;
        const double stretch = std::max(0.2, 1.0 - EvaluateReferenceLine(road.plan_view, s).curvature * t);
        double ds = o_.resolution_m / stretch;
        for (int it = 0; it < 4; ++it) {
          const double probe = std::min(ds, span - d);
          const double sq = s + sign * probe;  // the lane centre there (a whole waypoint is not needed)
          const Eigen::Vector3d q = RoadToWorld(road, sq, LaneCentreOf(road, static_cast<std::size_t>(n.section), n.lane, sq).t);
          const double chord = (q - step.waypoint.transform.location).norm();
          if (chord <= o_.resolution_m * 1.01) break;
          ds = probe * o_.resolution_m / chord;
        }
        // Floor: hostile geometry (lanes that jump sideways) must not stall the walk.
        d += std::max(ds, 0.05 * o_.resolution_m);
        if (route.steps.size() > kMaxSteps) return route;
        step.option = first_of_leg && l.into != RoadOption::LaneFollow ? l.into : command[i];
        first_of_leg = false;
        route.steps.push_back(std::move(step));
      }
      if (last) route.steps.push_back(RouteStep{m_.MakeWaypoint(n.road, n.section, n.lane, l.to), command[i]});
    }
    return route;
  }

  const Map& m_;
  const RoutePlannerOptions& o_;
  std::vector<double> dist_;
  std::vector<Parent> parent_;
  std::vector<double> heuristic_;
  Eigen::Vector3d goal_pos_ = Eigen::Vector3d::Zero();
  std::priority_queue<std::pair<double, int>, std::vector<std::pair<double, int>>, std::greater<>> open_;
};

}  // namespace

std::optional<Route> PlanRoute(const Map& map, const Waypoint& from, const Waypoint& to, const RoutePlannerOptions& o) {
  if (!(o.resolution_m > 0)) return std::nullopt;
  return Planner(map, o).Run(from, to);
}

std::optional<Route> PlanRoute(const Map& map, const Eigen::Vector3d& from, const Eigen::Vector3d& to,
                               const RoutePlannerOptions& o) {
  const auto a = map.NearestWaypoint(from, true, LaneType::Driving);
  const auto b = map.NearestWaypoint(to, true, LaneType::Driving);
  if (!a || !b) return std::nullopt;
  return PlanRoute(map, *a, *b, o);
}

}  // namespace lockstep::map
