// The walker AI controller (CARLA's controller.ai.walker) on the town's pedestrian graph
// (walker_graph.h): go_to_location plans with A* and walks the route, wandering picks a
// random edge at each split and a crossing with the world's cross factor; at a crossing
// the walker waits at the kerb for the walk light and a free road, then crosses.
#include <algorithm>
#include <cmath>
#include <limits>

#include "internal.h"
#include "walker_crowd.h"

namespace lockstep::ground {
namespace {

using Vec2 = Eigen::Vector2d;

constexpr double kPass = 0.6;         // m: a node on the way counts as passed
constexpr double kExact = 0.1;        // m: a kerb, a crossing's far end or the goal counts as reached
constexpr double kOffGraph = 3.0;     // m: farther from its last node, a walker rejoins the nearest one
constexpr double kClear = 1.0;        // m: room a vehicle must leave to a crossing
constexpr double kLookAhead = 5.0;    // s: vehicles that would reach the crossing this soon hold it
constexpr double kClearance = 1.0;    // s: red left for the cars after a walker's crossing time

double SegmentDistance(const Vec2& p, const Vec2& a, const Vec2& b) {
  const Vec2 ab = b - a;
  const double len2 = ab.squaredNorm();
  const double t = len2 > 1e-12 ? std::clamp((p - a).dot(ab) / len2, 0.0, 1.0) : 0.0;
  return (a + ab * t - p).norm();
}

double Cross(const Vec2& a, const Vec2& b) { return a.x() * b.y() - a.y() * b.x(); }

double SegmentsDistance(const Vec2& a, const Vec2& b, const Vec2& c, const Vec2& d) {
  const double d1 = Cross(b - a, c - a), d2 = Cross(b - a, d - a), d3 = Cross(d - c, a - c), d4 = Cross(d - c, b - c);
  if (((d1 > 0 && d2 < 0) || (d1 < 0 && d2 > 0)) && ((d3 > 0 && d4 < 0) || (d3 < 0 && d4 > 0))) return 0;
  return std::min({SegmentDistance(a, c, d), SegmentDistance(b, c, d), SegmentDistance(c, a, b), SegmentDistance(d, a, b)});
}

double Flat(const Vec3& a, const Vec3& b) { return (a - b).head<2>().norm(); }

}  // namespace

// Walk light and a free road: every light of the lanes crossed is red for the vehicles
// (CARLA's walkers wait for the light at a crossing) and stays red for need_s more seconds
// (the walker's time to cross plus kClearance: a pedestrian signal's clearance phase, so
// walkers do not start late in the red and hold the cars when their light turns green; a
// frozen red stays red), and no vehicle is on the crossing or would reach it within
// kLookAhead along its Traffic Manager path (else straight on): cars turning in on green,
// or any car where the crossing has no lights.
bool World::Impl::MayCross(const TownCrosswalk& cw, double need_s) const {
  for (int l : cw.lights) {
    if (lights[static_cast<size_t>(l)].color != LightColor::kRed) return false;
    if (RedTimeLeft(l) < need_s + kClearance) return false;
  }
  const Vec2 a = cw.ends[0].head<2>(), b = cw.ends[1].head<2>();
  for (const auto& [id, v] : vehicles) {
    const Pose pose = BodyPose(v->body);
    const Vec2 c = pose.position.head<2>();
    const double hx = v->spec->half_extents.x(), hy = v->spec->half_extents.y();
    const double d = SegmentDistance(c, a, b);
    if (d < hx + kClear) return false;  // on it or at its edge
    const Vec3 vel = v->kinematic ? Vec3(pose.orientation * Vec3(v->tm.speed, 0, 0)) : ToVec(dBodyGetLinearVel(v->body));
    const double speed = vel.head<2>().norm();
    if (speed < 0.5) continue;
    const double reach = speed * kLookAhead + hx;
    if (d > reach + hy + kClear) continue;
    const Vec2 fwd = vel.head<2>() / speed;
    Vec2 from = c;
    double run = 0;
    auto blocks = [&](const Vec2& to) {
      const bool hit = SegmentsDistance(from, to, a, b) < hy + kClear;
      run += (to - from).norm();
      from = to;
      return hit;
    };
    if (v->autopilot && v->tm.path.size() >= 2) {
      for (const auto& wp : v->tm.path) {
        const Vec2 q = wp.transform.location.head<2>();
        if ((q - c).dot(fwd) <= 0) continue;  // behind the car
        if (blocks(q)) return false;
        if (run > reach) break;
      }
    } else if (blocks(c + fwd * reach)) {
      return false;
    }
  }
  return true;
}

// go_to_location: A* from the walker's node to the node nearest the goal, then straight to
// the goal (or, off the graph, to the nearest graph point).
void World::Impl::PlanRoute(ControllerActor& c, const Vec3& pos) {
  const WalkerGraph& g = town->WalkerNav();
  c.planned = true;
  c.route.clear();
  c.goal_point = c.goal;
  const int start = c.at_node >= 0 && Flat(pos, g.Position(c.at_node)) < kPass ? c.at_node : g.Nearest(pos);
  if (start < 0) return;  // no graph: straight to the goal
  int goal_node = -1;
  const bool on_sidewalk = !WalkerGraph::OnDrivingLane(town->Map(), c.goal) &&
                           town->Map().NearestWaypoint(c.goal, false, map::LaneType::Sidewalk).has_value();
  if (on_sidewalk) {
    goal_node = g.Nearest(c.goal);
  } else {
    c.goal_point = g.NearestPoint(c.goal, &goal_node);
  }
  if (Flat(pos, g.Position(start)) >= kPass) c.route.emplace_back(start, -1);
  for (const auto& step : g.Route(start, goal_node)) c.route.emplace_back(step.first, step.second);
  const int last = c.route.empty() ? start : c.route.back().first;
  if (last != goal_node) c.goal_point = g.Position(last);  // unreachable: as near as the graph goes
  // The goal lies on the last sidewalk edge: walk straight to it from the node before.
  if (c.route.size() >= 2 && c.route.back().second < 0) {
    const Vec3& p = g.Position(c.route[c.route.size() - 2].first);
    const Vec3& q = g.Position(c.route.back().first);
    if ((c.goal_point - p).head<2>().dot((q - p).head<2>()) < (q - p).head<2>().squaredNorm()) c.route.pop_back();
  }
}

// Wander: the next node from the last one reached, a random sidewalk edge (not straight
// back unless at a dead end), or a crossing with the cross factor, drawn once per arrival.
bool World::Impl::ExtendWander(ControllerActor& c, const Vec3& pos) {
  const WalkerGraph& g = town->WalkerNav();
  if (c.at_node < 0 || Flat(pos, g.Position(c.at_node)) > kOffGraph) {
    const int n = g.Nearest(pos);
    if (n < 0) return false;
    c.at_node = -1;
    c.came_from = -1;
    c.route.emplace_back(n, -1);
    return true;
  }
  const auto& edges = g.Edges(c.at_node);
  std::vector<const WalkerEdge*> crossings, sidewalk, back;
  for (const auto& e : edges) {
    if (e.crossing >= 0) crossings.push_back(&e);
    else if (e.to == c.came_from) back.push_back(&e);
    else sidewalk.push_back(&e);
  }
  if (!crossings.empty() && c.drawn_node != c.at_node) {
    c.drawn_node = c.at_node;
    if (c.rng.Percent(cross_factor * 100.0)) {
      const WalkerEdge* e = crossings.size() == 1 ? crossings[0] : crossings[c.rng.Next() % crossings.size()];
      c.route.emplace_back(e->to, e->crossing);
      return true;
    }
  }
  if (sidewalk.empty()) sidewalk = back;  // dead end: turn back
  if (sidewalk.empty()) return false;     // a lone kerb: stand
  const WalkerEdge* e = sidewalk.size() == 1 ? sidewalk[0] : sidewalk[c.rng.Next() % sidewalk.size()];
  c.route.emplace_back(e->to, -1);
  return true;
}

// Controllers in id order; each walker then steers round the walkers ahead of it.
void World::Impl::StepControllers(double dt) {
  crowd.Build(walkers);
  for (auto& [id, c] : controllers) {
    WalkerActor* w = FindWalker(c.walker);
    if (!w || !c.running) continue;
    const size_t self = crowd.Find(c.walker);
    StepController(c, *w, self, dt);
    if (w->control.speed > 0) {
      w->control.direction = AvoidWalkers(self, w->control.direction, w->control.speed, c.crossing >= 0 && !c.cross_wait);
    }
  }
}

void World::Impl::StepController(ControllerActor& c, WalkerActor& walker, size_t self, double dt) {
  const WalkerGraph& g = town->WalkerNav();
  WalkerActor* w = &walker;
  const Vec3 pos = BodyPose(w->body).position;
  w->control.jump = false;
  auto walk_to = [&](const Vec3& target, bool exact) {
    Vec3 d = target - pos;
    d.z() = 0;
    const double n = d.norm();
    if (n > 1e-9) w->control.direction = d / n;
    w->control.speed = exact ? std::min(c.max_speed, n / dt) : c.max_speed;
  };
  // Within tol of the target, or, for a crossing's far end, the goal or a node on the way
  // (queue true), within kQueue of it, off the road, while another walker stands on it. A
  // kerb where the walker will wait is reached only exactly: a walker behind one waiting
  // there waits behind it (walkers queueing round a kerb and crossing from there slowed
  // Town01's traffic from 16.7 to 14.8 km/h).
  auto reached = [&](const Vec3& target, double tol, bool queue) {
    const double d = Flat(pos, target);
    if (d < tol) return true;
    return queue && d < kQueue && crowd.Occupied(self, target) && !WalkerGraph::OnDrivingLane(town->Map(), pos);
  };
  // On a crossing: wait at the kerb for the walk light and a free road, then cross.
  if (c.crossing >= 0) {
    const TownCrosswalk& cw = g.Crossings()[static_cast<size_t>(c.crossing)];
    const Vec3& far = cw.ends[c.cross_end];
    if (c.cross_wait) {
      walk_to(far, true);
      w->control.speed = 0;
      // Time to cross at the controller's speed (a walker that cannot walk never starts).
      const double need = c.max_speed > 0.05 ? Flat(pos, far) / c.max_speed : std::numeric_limits<double>::infinity();
      if (!MayCross(cw, need)) return;
      c.cross_wait = false;
    }
    if (!reached(far, kExact, true)) {
      walk_to(far, true);
      return;
    }
    c.came_from = c.at_node;
    c.at_node = cw.nodes[c.cross_end];
    c.drawn_node = c.at_node;  // just crossed: no draw to cross straight back
    c.crossing = -1;
    if (!c.route.empty() && c.route.front().first == c.at_node) c.route.pop_front();
  }
  if (c.has_goal && !c.planned) PlanRoute(c, pos);
  bool moving = false;
  for (int guard = 0; guard < 4 && !moving; ++guard) {
    if (c.route.empty()) {
      if (c.has_goal) {
        if (!reached(c.goal_point, kExact, true)) {
          walk_to(c.goal_point, true);
        } else {
          // Arrived: CARLA's walker then sets off to a new random place; here it wanders.
          c.has_goal = false;
          c.planned = false;
          w->control.speed = 0;
        }
        moving = true;
        break;
      }
      if (!ExtendWander(c, pos)) break;
    }
    const auto [node, crossing] = c.route.front();
    if (crossing >= 0) {  // at the kerb: the crossing starts
      c.crossing = crossing;
      c.cross_end = g.Crossings()[static_cast<size_t>(crossing)].nodes[0] == node ? 0 : 1;
      c.cross_wait = true;
      walk_to(g.Position(node), true);
      w->control.speed = 0;
      moving = true;
      break;
    }
    // A kerb before a crossing is reached exactly, other nodes are passed.
    bool exact = c.route.size() >= 2 && c.route[1].second >= 0;
    if (c.route.size() == 1 && !c.has_goal) {
      for (const auto& e : g.Edges(node)) exact |= e.crossing >= 0;
    }
    if (reached(g.Position(node), exact ? kExact : kPass, !exact)) {
      c.came_from = c.at_node;
      c.at_node = node;
      c.route.pop_front();
      continue;
    }
    walk_to(g.Position(node), exact);
    moving = true;
  }
  if (!moving) w->control.speed = 0;
}

}  // namespace lockstep::ground
