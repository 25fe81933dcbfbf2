// The Traffic Manager: lane following on a buffer of lane-centre waypoints, car following,
// traffic lights, junction conflicts, hybrid (kinematic) mode far from the hero.
#include <algorithm>
#include <cmath>
#include <limits>

#include "internal.h"
#include "lockstep/map/route_planner.h"

namespace lockstep::ground {
namespace {

constexpr double kSpacing = 2.0;           // m between path points
constexpr double kComfortDecel = 3.0;      // m/s^2 for planned stops
constexpr double kYellowDecel = 4.0;       // m/s^2: stop on yellow if this suffices
constexpr double kHardDecel = 6.0;         // m/s^2: a car that can stop with this before the line does on red
constexpr double kMaxLateralAccel = 4.0;   // m/s^2 in curves (kinematic cars)
constexpr double kPhysicsLateralAccel = 1.5;  // m/s^2 in curves for cars on physics (they must hold their lane)
constexpr double kStopSignTime = 2.0;      // s of full stop at a stop sign (docs/ground.md)
constexpr double kLaneObstacleDistance = 50.0;  // m: a slower leader this close triggers a lane change (CARLA)
constexpr double kLaneChangeCooldown = 5.0;     // s between two lane changes of a vehicle
// Respawn of dormant vehicles (CARLA's MotionPlanStage, InMemoryMap::GetWaypointsInDelta,
// Constants.h): a square ring DELTA wide around the hero, ATTEMPTS_TO_TELEPORT candidates,
// each free when no vehicle is within a geodesic grid length, the car put 0.5 m above it.
constexpr double kRespawnDelta = 25.0;          // m, Map::DELTA
constexpr double kRespawnZDelta = 500.0;        // m, Map::Z_DELTA
constexpr int kRespawnAttempts = 5;             // MotionPlan::ATTEMPTS_TO_TELEPORT
constexpr double kRespawnFree = 20.0;           // m, Map::MAX_GEODESIC_GRID_LENGTH
constexpr double kRespawnLift = 0.5;            // m above the lane point
constexpr double kRespawnSpacing = 5.0;         // m between candidate lane points (Map::MAP_RESOLUTION)

constexpr double kInf = std::numeric_limits<double>::infinity();

double Get(double per_vehicle, double global) { return std::isnan(per_vehicle) ? global : per_vehicle; }

uint64_t LaneKey(const map::Waypoint& w) {
  return (static_cast<uint64_t>(static_cast<uint32_t>(w.road)) << 32) ^ (static_cast<uint64_t>(static_cast<uint32_t>(w.section)) << 12) ^
         static_cast<uint64_t>(static_cast<uint32_t>(w.lane + 2048));
}

Vec3 Loc(const map::Waypoint& w) { return w.transform.location; }

// Distance from p to segment ab (xy) and the parameter of the projection.
double SegmentDistance(const Eigen::Vector2d& p, const Eigen::Vector2d& a, const Eigen::Vector2d& b, double* t) {
  const Eigen::Vector2d ab = b - a;
  const double len2 = ab.squaredNorm();
  *t = len2 > 1e-12 ? std::clamp((p - a).dot(ab) / len2, 0.0, 1.0) : 0.0;
  return (a + *t * ab - p).norm();
}

// Turn of a branch: 1 left, 2 right, 3 straight (CARLA's RoadOption values).
int TurnOf(const map::Map& m, const map::Waypoint& from, const map::Waypoint& branch) {
  auto ahead = m.Next(branch, 20.0);
  const double yaw = ahead.empty() ? branch.transform.yaw : ahead.front().transform.yaw;
  const double d = Wrap(yaw - from.transform.yaw);
  if (std::abs(d) < 0.5236) return 3;
  return d > 0 ? 1 : 2;
}

}  // namespace

bool World::Impl::Dormant(const VehicleActor& v) const {
  if (v.hero()) return false;
  const Vec3 p = ToVec(dBodyGetPosition(v.body));
  bool hero = false;
  for (const auto& [id, o] : vehicles) {
    if (!o->hero()) continue;
    hero = true;
    if ((ToVec(dBodyGetPosition(o->body)) - p).norm() <= tm.actor_active_distance) return false;
  }
  return hero;
}

bool World::Impl::HybridKinematic(const VehicleActor& v) const {
  if (!v.autopilot || v.hero() || !v.simulate_physics) return false;
  // CARLA's dormant vehicles leave the physics world; the TM moves them by teleports.
  if (Dormant(v)) return true;
  if (!tm.hybrid_physics_mode) return false;
  const Vec3 p = ToVec(dBodyGetPosition(v.body));
  for (const auto& [id, o] : vehicles) {
    if (o->hero() && (ToVec(dBodyGetPosition(o->body)) - p).norm() < tm.hybrid_physics_radius) return false;
  }
  return true;
}

// Drops the points behind the vehicle and appends points until the buffer reaches the
// lookahead. path[0] stays at or behind the vehicle, path[1] ahead of it.
void World::Impl::FillPath(VehicleActor* v) {
  const map::Map& m = town->Map();
  auto& path = v->tm.path;
  const Vec3 pos = ToVec(dBodyGetPosition(v->body));
  if (path.empty()) {
    const Pose pose = BodyPose(v->body);
    auto wp = m.NearestWaypoint(pos);
    if (!wp) return;
    // The lane's travel direction must agree with the vehicle's heading.
    if (std::abs(Wrap(wp->transform.yaw - pose.Yaw())) > M_PI / 2) {
      if (auto other = m.LeftLane(*wp); other && std::abs(Wrap(other->transform.yaw - pose.Yaw())) < M_PI / 2) wp = other;
    }
    path.push_back(*wp);
    auto back = m.Previous(*wp, 0.5);
    if (!back.empty()) path.push_front(back.front());
  }
  while (path.size() >= 2) {
    const Vec3 a = Loc(path[0]), b = Loc(path[1]);
    if ((pos - b).head<2>().dot((b - a).head<2>()) < 0) break;  // not past path[1] yet
    path.pop_front();
  }
  const double speed = ToVec(dBodyGetLinearVel(v->body)).norm();
  const double lookahead = std::max(40.0, 4.0 * speed + 15.0);
  double length = 0;
  for (size_t i = 1; i < path.size(); ++i) length += (Loc(path[i]) - Loc(path[i - 1])).norm();
  int guard = 0;
  while (length < lookahead && ++guard < 200) {
    map::Waypoint next;
    if (!v->tm.planned.empty()) {
      next = v->tm.planned.front();
      v->tm.planned.pop_front();
    } else {
      auto branches = m.Next(path.back(), kSpacing);
      if (branches.empty()) break;  // dead end: the car stops at the end of its buffer
      size_t pick = 0;
      if (branches.size() > 1) {
        std::sort(branches.begin(), branches.end(), [](const map::Waypoint& x, const map::Waypoint& y) {
          return std::make_tuple(x.road, x.lane, x.s) < std::make_tuple(y.road, y.lane, y.s);
        });
        pick = static_cast<size_t>(v->tm.rng.Next() % branches.size());
        if (!v->tm.route.empty()) {
          for (size_t k = 0; k < branches.size(); ++k) {
            if (TurnOf(m, path.back(), branches[k]) == v->tm.route.front()) {
              pick = k;
              break;
            }
          }
          v->tm.route.erase(v->tm.route.begin());
        }
      }
      next = branches[pick];
    }
    length += (Loc(next) - Loc(path.back())).norm();
    path.push_back(next);
  }
}

// Puts a kinematic vehicle exactly on its target pose.
void World::Impl::AnchorPath(VehicleActor* v) {
  SetBodyPose(v->body, v->tm.kin_target);
}

void World::Impl::MoveKinematic(VehicleActor* v, double dt) {
  auto& tm_state = v->tm;
  const double target = tm_state.target_speed;
  // CARLA's hybrid mode teleports the car by its target velocity x dt each step: no
  // acceleration limit (MotionPlanStage); stops are in the target's braking profile.
  tm_state.speed = std::max(0.0, target);
  const auto& path = tm_state.path;
  const Pose pose = BodyPose(v->body);
  Pose out = pose;
  if (path.size() >= 2) {
    // Position along the buffer: projection on segment 0, then advance.
    const Vec3 a0 = Loc(path[0]), b0 = Loc(path[1]);
    double t = 0;
    SegmentDistance(pose.position.head<2>(), a0.head<2>(), b0.head<2>(), &t);
    double remaining = tm_state.speed * dt + t * (b0 - a0).norm();
    size_t i = 0;
    while (i + 1 < path.size()) {
      const double seg = (Loc(path[i + 1]) - Loc(path[i])).norm();
      if (remaining <= seg || i + 2 == path.size()) {
        const double f = seg > 1e-9 ? std::min(1.0, remaining / seg) : 1.0;
        const Vec3 p = Loc(path[i]) + f * (Loc(path[i + 1]) - Loc(path[i]));
        const Vec3 d = Loc(path[i + 1]) - Loc(path[i]);
        const double yaw = d.head<2>().norm() > 1e-6 ? std::atan2(d.y(), d.x()) : path[i].transform.yaw;
        out = Pose::FromYaw(p + Vec3(0, 0, v->spec->half_extents.z()), yaw);
        break;
      }
      remaining -= seg;
      ++i;
    }
  }
  tm_state.kin_target = out;
  const Vec3 lin = (out.position - pose.position) / dt;
  const double dyaw = Wrap(out.Yaw() - pose.Yaw());
  // Level the car (kinematic cars stay upright) and move it linearly over the step.
  SetBodyPose(v->body, Pose::FromYaw(pose.position, pose.Yaw()));
  dBodySetLinearVel(v->body, lin.x(), lin.y(), lin.z());
  dBodySetAngularVel(v->body, 0, 0, dyaw / dt);
}

void World::Impl::PlaceAt(VehicleActor* v, const Pose& pose) {
  SetBodyPose(v->body, pose);
  dBodySetLinearVel(v->body, 0, 0, 0);
  dBodySetAngularVel(v->body, 0, 0, 0);
  v->tm.path.clear();
  v->tm.planned.clear();
  v->tm.speed = 0;
  v->tm.blocked = 0;
  v->tm.committed_junction = -1;
  v->tm.kin_target = pose;
  v->has_footprint = false;
}

void World::Impl::Respawn(VehicleActor* v) {
  const auto& points = town->SpawnPoints();
  if (points.empty()) return;
  for (int attempt = 0; attempt < 20; ++attempt) {
    const auto& sp = points[static_cast<size_t>(tm_rng.Next() % points.size())];
    const Pose pose = Pose::FromYaw(sp.location + Vec3(0, 0, v->spec->half_extents.z() - 0.5 + 0.05), sp.yaw);
    bool free = true;
    for (const auto& [id, o] : vehicles) {
      if (id != v->id && (ToVec(dBodyGetPosition(o->body)) - pose.position).norm() < 10.0) free = false;
    }
    if (!free) continue;
    PlaceAt(v, pose);
    return;
  }
}

void World::Impl::RespawnNearHero(VehicleActor* v, const Vec3& hero) {
  if (!respawn_points_ready) {
    for (const auto& w : town->Map().GenerateWaypoints(kRespawnSpacing)) {
      if (!w.IsJunction()) respawn_points.push_back(w);
    }
    respawn_points_ready = true;
  }
  // CARLA: lower + next() x (upper - lower) / 100 with next() uniform in [0, 100); the lane
  // points inside the square of half-width r + DELTA around the hero but not inside the one
  // of half-width r (in the map's order; CARLA: its R-tree's), the first free of the first
  // five. None free: the vehicle stays where it is.
  const double lower = tm.respawn_lower_bound, upper = tm.respawn_upper_bound;
  const double r = lower + v->tm.rng.Uniform() * (upper - lower);
  int tried = 0;
  for (const auto& w : respawn_points) {
    const Vec3 d = Loc(w) - hero;
    const double ring = std::max(std::abs(d.x()), std::abs(d.y()));
    if (ring <= r || ring >= r + kRespawnDelta || std::abs(d.z()) >= kRespawnZDelta) continue;
    if (++tried > kRespawnAttempts) return;
    bool free = true;
    for (const auto& [id, o] : vehicles) {
      if (id != v->id && (ToVec(dBodyGetPosition(o->body)) - Loc(w)).head<2>().norm() < kRespawnFree) free = false;
    }
    if (!free) continue;
    PlaceAt(v, Pose::FromYaw(Loc(w) + Vec3(0, 0, kRespawnLift + v->spec->half_extents.z()), w.transform.yaw));
    return;
  }
}

// Moves the buffer over to the neighbouring lane of the same direction: the old lane up
// to ~6 m ahead, then the new lane 8 m further on. With `obstacles`, only if no vehicle
// or walker is on the new lane from 15 m behind to 20 m ahead (forced changes skip it).
bool World::Impl::ChangeLane(VehicleActor* v, bool left, const std::vector<Obstacle>* obstacles) {
  const map::Map& m = town->Map();
  auto& path = v->tm.path;
  size_t at = 0;
  double length = 0;
  for (at = 1; at < path.size() && length < 6.0; ++at) length += (Loc(path[at]) - Loc(path[at - 1])).norm();
  if (at >= path.size()) return false;
  for (size_t k = 0; k <= at; ++k) {
    if (path[k].IsJunction()) return false;
  }
  const auto side = left ? m.LeftLane(path[at]) : m.RightLane(path[at]);
  if (!side || side->lane_type != map::LaneType::Driving || (side->lane < 0) != (path[at].lane < 0) || side->IsJunction()) return false;
  const auto ahead = m.Next(*side, 8.0);
  if (ahead.empty() || ahead.front().IsJunction()) return false;
  if (obstacles) {
    std::vector<Vec3> lane{Loc(*side)};
    for (double d : {5.0, 10.0, 15.0}) {
      if (auto b = m.Previous(*side, d); !b.empty()) lane.push_back(Loc(b.front()));
    }
    for (double d : {5.0, 10.0, 15.0, 20.0}) {
      if (auto f = m.Next(*side, d); !f.empty()) lane.push_back(Loc(f.front()));
    }
    for (const Obstacle& o : *obstacles) {
      if (o.id == v->id) continue;
      for (const Vec3& p : lane) {
        if ((o.position - p).head<2>().norm() < 2.5 + std::max(o.half_x, o.half_y) && std::abs(o.position.z() - p.z()) < 4.0) return false;
      }
    }
  }
  path.erase(path.begin() + static_cast<std::ptrdiff_t>(at) + 1, path.end());
  path.push_back(ahead.front());
  v->tm.planned.clear();
  v->tm.lane_change_cooldown = kLaneChangeCooldown;
  return true;
}

void World::Impl::StepTrafficManager(double dt) {
  std::map<int, std::vector<const VehicleActor*>> junction_users;
  // CARLA's hero location for respawns (one hero: here the lowest id).
  const VehicleActor* hero = nullptr;
  for (const auto& [id, v] : vehicles) {
    if (v->hero()) {
      hero = v.get();
      break;
    }
  }
  for (auto& [id, v] : vehicles) {
    if (!v->autopilot) {
      v->kinematic = false;
      continue;
    }
    if (tm.respawn_dormant_vehicles && hero && Dormant(*v)) RespawnNearHero(v.get(), ToVec(dBodyGetPosition(hero->body)));
    const bool kin = HybridKinematic(*v);
    if (kin && !v->kinematic) {
      dBodySetKinematic(v->body);
      v->tm.speed = ToVec(dBodyGetLinearVel(v->body)).norm();
    } else if (!kin && v->kinematic && v->simulate_physics) {
      dBodySetDynamic(v->body);
      const Pose p = BodyPose(v->body);
      const Vec3 vel = p.orientation * Vec3(v->tm.speed, 0, 0);
      dBodySetLinearVel(v->body, vel.x(), vel.y(), vel.z());
      dBodySetAngularVel(v->body, 0, 0, 0);
    }
    v->kinematic = kin;
    FillPath(v.get());
    const auto& path = v->tm.path;
    int inside = -1;
    for (size_t i = 0; i < std::min<size_t>(2, path.size()); ++i) {
      if (path[i].IsJunction()) inside = path[i].junction;
    }
    if (v->tm.committed_junction >= 0 && inside != v->tm.committed_junction) {
      // Still committed while its junction is the next one ahead.
      bool ahead = false;
      for (size_t i = 0; i + 1 < path.size() && i < 12; ++i) {
        if (!path[i].IsJunction() && path[i + 1].IsJunction()) {
          ahead = path[i + 1].junction == v->tm.committed_junction;
          break;
        }
      }
      if (!ahead) v->tm.committed_junction = -1;
    }
    if (inside >= 0) junction_users[inside].push_back(v.get());
    if (v->tm.committed_junction >= 0 && v->tm.committed_junction != inside)
      junction_users[v->tm.committed_junction].push_back(v.get());
  }
  // Where everything is at the start of the step: what the TM sees (decisions do not
  // depend on the order vehicles are handled in, except junction commitments).
  std::vector<Obstacle> obstacles;
  obstacles.reserve(vehicles.size() + walkers.size());
  for (const auto& [oid, o] : vehicles) {
    const Pose op = BodyPose(o->body);
    const double yaw = op.Yaw();
    const Vec3 ov = o->kinematic ? Vec3(op.orientation * Vec3(o->tm.speed, 0, 0)) : ToVec(dBodyGetLinearVel(o->body));
    obstacles.push_back(Obstacle{oid, op.position, ov, Eigen::Vector2d(std::cos(yaw), std::sin(yaw)), o->spec->half_extents.x(),
                                 o->spec->half_extents.y(), false});
  }
  for (const auto& [wid, w] : walkers) {
    const Pose wp = BodyPose(w->body);
    Obstacle o{wid, wp.position, w->velocity, Eigen::Vector2d(1, 0), w->spec->radius, w->spec->radius, true};
    // A walker crossing the road (a crossing of the walker graph) holds the rest of the
    // crossing, up to its far kerb: cars stop before it, not only when it is in their lane.
    if (auto c = controllers.find(w->controller); w->controller && c != controllers.end() && c->second.crossing >= 0 &&
                                                  !c->second.cross_wait) {
      const Vec3& far = town->Crosswalks()[static_cast<size_t>(c->second.crossing)].ends[c->second.cross_end];
      const Eigen::Vector2d rest = (far - wp.position).head<2>();
      const double len = rest.norm();
      if (len > 0.1) {
        o.forward = rest / len;
        o.half_x += len / 2;
        o.position.head<2>() += rest / 2;
      }
    }
    obstacles.push_back(o);
  }
  for (auto& [id, v] : vehicles) {
    if (v->autopilot) TmVehicle(v.get(), dt, &junction_users, obstacles);
  }
}

void World::Impl::TmVehicle(VehicleActor* v, double dt, std::map<int, std::vector<const VehicleActor*>>* junction_users,
                            const std::vector<Obstacle>& obstacles) {
  const map::Map& m = town->Map();
  TmState& s = v->tm;
  const auto& path = s.path;
  const Pose pose = BodyPose(v->body);
  const Vec3 vel = ToVec(dBodyGetLinearVel(v->body));
  const double speed = v->kinematic ? s.speed : std::max(0.0, vel.dot(pose.orientation * Vec3::UnitX()));
  const double half_x = v->spec->half_extents.x(), half_y = v->spec->half_extents.y();
  s.light = -1;
  s.light_distance = -1;
  double stop_distance = kInf;  // m the front bumper may still travel (stop line, leader)
  if (path.size() < 2) {
    s.target_speed = 0;
  } else {
    // Arc length of every path point from the vehicle's projection on segment 0.
    std::vector<double> arc(path.size(), 0.0);
    double t0 = 0;
    SegmentDistance(pose.position.head<2>(), Loc(path[0]).head<2>(), Loc(path[1]).head<2>(), &t0);
    arc[0] = -t0 * (Loc(path[1]) - Loc(path[0])).norm();
    for (size_t i = 1; i < path.size(); ++i) arc[i] = arc[i - 1] + (Loc(path[i]) - Loc(path[i - 1])).norm();

    double limit = Get(s.params.desired_speed, kInf);
    if (!std::isfinite(limit)) {
      // CARLA: the limit of the last speed sign passed (sticky across roads).
      if (const double sign = town->SignSpeedLimit(path[0]); std::isfinite(sign)) v->speed_limit = sign;
      limit = v->speed_limit * (1.0 - Get(s.params.percentage_speed_difference, tm.percentage_speed_difference) / 100.0);
    }
    double target = std::max(0.0, limit);
    double stop_at = arc.back() - half_x;  // end of a dead-end buffer

    // Curves: slow down to keep the lateral acceleration comfortable.
    for (size_t i = 1; i + 1 < path.size() && arc[i] < 30; ++i) {
      const double ds = std::max(0.5, arc[i + 1] - arc[i - 1]);
      const Vec3 d1 = Loc(path[i]) - Loc(path[i - 1]), d2 = Loc(path[i + 1]) - Loc(path[i]);
      const double turn = std::abs(Wrap(std::atan2(d2.y(), d2.x()) - std::atan2(d1.y(), d1.x())));
      if (turn < 1e-3) continue;
      const double v_curve = std::sqrt((v->kinematic ? kMaxLateralAccel : kPhysicsLateralAccel) * ds / turn);
      target = std::min(target, std::sqrt(v_curve * v_curve + 2 * kComfortDecel * std::max(0.0, arc[i] - half_x)));
    }

    // The first junction entry ahead: its light, its conflicts.
    for (size_t i = 0; i + 1 < path.size(); ++i) {
      if (path[i].IsJunction() || !path[i + 1].IsJunction()) continue;
      const int node = m.NodeOf(path[i]);
      const double to_end = node >= 0 ? std::abs(m.Nodes()[static_cast<size_t>(node)].ExitS() - path[i].s) : 0.0;
      const double line = arc[i] + to_end;  // stop line along the buffer
      const double front = line - half_x;   // front bumper to the line
      const int junction = path[i + 1].junction;
      const uint64_t key = LaneKey(path[i]);
      const int light = town->LightOfLane(path[i].road, path[i].section, path[i].lane);
      bool must_stop = false;
      // CARLA's TrafficLightStage draws the ignore percentages every tick, not once per
      // junction: at a red or yellow light (a stop sign) the vehicle stops this tick unless
      // a draw in [0, 100) falls below ignore_lights_percentage (ignore_signs_percentage).
      s.ignore_light = false;
      s.ignore_sign = false;
      if (s.entry_key != key) s.sign_done_key = 0, s.sign_wait = 0;  // a new junction entry ahead
      const int sign = town->SignOfLane(path[i].road, path[i].section, path[i].lane);
      if (sign >= 0 && light < 0 && town->Signs()[static_cast<size_t>(sign)].type == "206") {
        // Stop sign: a full stop at the line for kStopSignTime, then the junction's
        // conflict check decides (yield signs: the conflict check alone).
        const bool done = s.sign_done_key == key;
        if (!done) s.ignore_sign = s.rng.Percent(Get(s.params.ignore_signs_percentage, tm.ignore_signs_percentage));
        if (!done && !s.ignore_sign) {
          must_stop = true;
          if (front < 2.0 && speed < 0.1) {
            s.sign_wait += dt;
            if (s.sign_wait >= kStopSignTime) {
              s.sign_done_key = key;
              s.sign_wait = 0;
              must_stop = false;
            }
          }
        }
        if (s.entry_key == key && s.front_to_line > 0 && front <= 0 && !done) ++v->infractions.stop_signs;
      }
      if (light >= 0) {
        s.light = light;
        s.light_distance = std::max(0.0, front);
        const LightColor c = lights[static_cast<size_t>(light)].color;
        if (c == LightColor::kRed || c == LightColor::kYellow)
          s.ignore_light = s.rng.Percent(Get(s.params.ignore_lights_percentage, tm.ignore_lights_percentage));
        if (!s.ignore_light) {
          if (c == LightColor::kRed) must_stop = front > -0.5;
          if (c == LightColor::kYellow) must_stop = front > speed * speed / (2 * kYellowDecel);
          // Committed on green but still able to stop before the line (held by a walker
          // on the crossing, slowed for the turn): it stops on yellow and red.
          if (must_stop && s.committed_junction == junction && front > 0 && front > speed * speed / (2 * kHardDecel))
            s.committed_junction = -1;
        }
        // Red-light infraction: the front crossed the line during this step on red.
        if (s.entry_key == key && s.front_to_line > 0 && front <= 0 && c == LightColor::kRed) ++v->infractions.red_lights;
      }
      s.entry_key = key;
      s.front_to_line = front;
      if (!must_stop && s.committed_junction != junction && front < std::max(6.0, speed * speed / (2 * kComfortDecel) + 4.0)) {
        // Cross only if no vehicle in (or committed to) the junction drives a path that
        // comes within 2.5 m of ours (vehicles from our own lane are followed instead).
        std::vector<Vec3> mine;
        for (size_t k = i + 1; k < path.size() && path[k].junction == junction; ++k) mine.push_back(Loc(path[k]));
        bool conflict = false;
        for (const VehicleActor* o : (*junction_users)[junction]) {
          if (o == v || s.ignore_collision.count(o->id)) continue;
          const auto& op = o->tm.path;
          bool same_entry = false;
          for (size_t k = 0; k + 1 < op.size(); ++k) {
            if (!op[k].IsJunction() && op[k + 1].junction == junction) {
              same_entry = LaneKey(op[k]) == key;
              break;
            }
          }
          if (same_entry) continue;
          for (size_t k = 0; k < op.size() && !conflict && k < 30; ++k) {
            if (op[k].junction != junction) continue;
            for (const Vec3& p : mine) {
              if ((Loc(op[k]) - p).head<2>().norm() < 2.5) {
                conflict = true;
                break;
              }
            }
          }
          if (conflict) break;
        }
        if (conflict) {
          must_stop = true;
          s.waiting += dt;
        } else {
          s.committed_junction = junction;
          s.waiting = 0;
          (*junction_users)[junction].push_back(v);
        }
      }
      if (must_stop && s.committed_junction != junction) stop_at = std::min(stop_at, front - 0.5);
      break;
    }

    // Leading vehicle or walker on the buffer ahead (obstacles snapshot of this step).
    const double min_gap = Get(s.params.distance_to_leading_vehicle, tm.distance_to_leading_vehicle);
    const double reach = arc.back() + 10.0;
    std::vector<Eigen::Vector2d> pts(path.size()), dirs(path.size() - 1);
    Eigen::Vector2d lo(kInf, kInf), hi(-kInf, -kInf);
    for (size_t i = 0; i < path.size(); ++i) {
      pts[i] = Loc(path[i]).head<2>();
      lo = lo.cwiseMin(pts[i]);
      hi = hi.cwiseMax(pts[i]);
    }
    for (size_t i = 0; i + 1 < path.size(); ++i) {
      const Eigen::Vector2d d = pts[i + 1] - pts[i];
      dirs[i] = d.norm() > 1e-9 ? Eigen::Vector2d(d.normalized()) : Eigen::Vector2d(1, 0);
    }
    lo -= Eigen::Vector2d(8, 8);
    hi += Eigen::Vector2d(8, 8);
    const double ignore_v = Get(s.params.ignore_vehicles_percentage, tm.ignore_vehicles_percentage);
    const double ignore_w = Get(s.params.ignore_walkers_percentage, tm.ignore_walkers_percentage);
    double lead_gap = kInf, lead_v = 0;  // nearest vehicle ahead on the buffer
    for (const Obstacle& o : obstacles) {
      if (o.id == v->id || s.ignore_collision.count(o.id)) continue;  // CARLA: collision_detection(v, o, False)
      const Vec3 rel = o.position - pose.position;
      if (std::abs(rel.x()) > reach || std::abs(rel.y()) > reach || std::abs(rel.z()) > 4.0) continue;
      if (o.position.x() < lo.x() || o.position.y() < lo.y() || o.position.x() > hi.x() || o.position.y() > hi.y()) continue;
      const double coarse = half_y + std::max(o.half_x, o.half_y) + 0.3;
      for (size_t i = 0; i + 1 < path.size(); ++i) {
        double t = 0;
        const double d = SegmentDistance(o.position.head<2>(), pts[i], pts[i + 1], &t);
        if (d > coarse) continue;
        const double c = std::abs(dirs[i].dot(o.forward)), sn = std::abs(dirs[i].x() * o.forward.y() - dirs[i].y() * o.forward.x());
        if (d > half_y + sn * o.half_x + c * o.half_y + 0.3) continue;
        const double along = arc[i] + t * (arc[i + 1] - arc[i]);
        if (along <= 0) break;  // beside or behind us
        const double pct = o.walker ? ignore_w : ignore_v;
        if (pct > 0 && s.rng.Percent(pct)) break;
        const double gap = along - half_x - (c * o.half_x + sn * o.half_y);
        const double lead_speed = std::max(0.0, o.velocity.head<2>().dot(dirs[i]));
        const double room = gap - min_gap - 0.5 * speed;
        if (!o.walker && gap < lead_gap) lead_gap = gap, lead_v = lead_speed;
        if (lead_speed < 0.5) stop_distance = std::min(stop_distance, gap - min_gap);
        target = std::min(target, room <= 0 ? 0.0 : std::sqrt(lead_speed * lead_speed + 2 * kComfortDecel * room));
        break;
      }
    }
    if (stop_at < kInf) target = std::min(target, stop_at <= 0.05 ? 0.0 : std::sqrt(2 * kComfortDecel * stop_at));
    stop_distance = std::min(stop_distance, stop_at);
    s.target_speed = target;

    // Lane changes (CARLA's auto_lane_change around a slower leader, the random left /
    // right percentages and keep-right, drawn once a second), one per kLaneChangeCooldown,
    // never on a given path or route.
    s.lane_change_cooldown = std::max(0.0, s.lane_change_cooldown - dt);
    s.random_draw_timer += dt;
    if (s.lane_change_cooldown <= 0 && s.planned.empty() && s.route.empty()) {
      bool changed = false;
      const bool auto_change = Get(s.params.auto_lane_change, tm.auto_lane_change ? 1.0 : 0.0) != 0;
      if (auto_change && lead_gap < kLaneObstacleDistance && lead_v < limit - 2.0 && stop_at > lead_gap + 10.0)
        changed = ChangeLane(v, true, &obstacles) || ChangeLane(v, false, &obstacles);
      if (!changed && s.random_draw_timer >= 1.0) {
        s.random_draw_timer = 0;
        if (s.rng.Percent(Get(s.params.random_left_lanechange_percentage, tm.random_left_lanechange_percentage)))
          changed = ChangeLane(v, true, &obstacles);
        if (!changed && s.rng.Percent(Get(s.params.random_right_lanechange_percentage, tm.random_right_lanechange_percentage)))
          changed = ChangeLane(v, false, &obstacles);
        if (!changed && s.rng.Percent(Get(s.params.keep_right_percentage, tm.keep_right_percentage)))
          changed = ChangeLane(v, false, &obstacles);
      }
    }
  }

  // Blocked vehicles are respawned (CARLA's thresholds; longer at a red light).
  if (speed < 0.1) {
    s.blocked += dt;
  } else {
    s.blocked = 0;
  }
  const bool at_red = s.light >= 0 && lights[static_cast<size_t>(s.light)].color == LightColor::kRed;
  if (s.blocked > (at_red ? tm.red_light_blocked_time_threshold : tm.blocked_time_threshold)) {
    Respawn(v);
    FillPath(v);
  }

  if (v->kinematic) {
    MoveKinematic(v, dt);
    v->control.throttle = s.target_speed > s.speed ? 0.5 : 0.0;
    v->control.brake = s.target_speed < s.speed - 0.1 || s.target_speed == 0 ? 0.5 : 0.0;
    v->control.steer = 0;
    return;
  }
  // Physics: pure pursuit on the buffer, PI speed control. CARLA's lane offset moves the
  // target point along the lane's right vector (> 0 right); kinematic (hybrid or dormant)
  // vehicles follow the lane centre, as CARLA's teleports do.
  double steer = 0;
  if (path.size() >= 2) {
    const double lookahead = std::clamp(2.0 + 0.6 * speed, 3.0, 12.0);
    const Vec3 rear = pose.position - pose.orientation * Vec3(v->physics.wheelbase / 2, 0, 0);
    const double offset = Get(s.params.lane_offset, tm.lane_offset);
    auto target = [&](size_t i) {
      const double yaw = path[i].transform.yaw;
      return Vec3(Loc(path[i]) + offset * Vec3(std::sin(yaw), -std::cos(yaw), 0));  // ENU right of the lane
    };
    Vec3 goal = target(path.size() - 1);
    for (size_t i = 1; i < path.size(); ++i) {
      const Vec3 p = target(i);
      if ((p - rear).head<2>().norm() >= lookahead && (p - rear).dot(pose.orientation * Vec3::UnitX()) > 0) {
        goal = p;
        break;
      }
    }
    const Vec3 local = pose.orientation.inverse() * (goal - rear);
    const double l2 = std::max(1.0, local.head<2>().squaredNorm());
    const double delta = std::atan2(2 * v->physics.wheelbase * local.y(), l2);
    steer = std::clamp(-delta / v->physics.max_steer_angle, -1.0, 1.0);
  }
  const double err = s.target_speed - speed;
  VehicleControl c;
  c.steer = steer;
  if (s.target_speed < 0.05) {
    c.brake = speed > 0.5 ? 0.6 : 1.0;
  } else if (err >= 0) {
    c.throttle = std::clamp(0.25 + 0.4 * err, 0.0, 1.0);
  } else if (err < -0.6) {
    c.brake = std::clamp(-0.25 * err, 0.0, 1.0);
  }
  // Feed-forward for a stop ahead: the deceleration that stops the car in the room left
  // (full brake is about 1 g); the PI loop alone lags and creeps over stop lines.
  if (stop_distance < kInf && speed > 0.05) {
    const double need = speed * speed / (2 * std::max(0.05, stop_distance));
    if (need > 1.0) {
      c.throttle = 0;
      c.brake = std::max(c.brake, std::clamp(need / 9.0, 0.0, 1.0));
    }
  }
  v->control = c;
  v->use_ackermann = false;
}

// ---- commands ----

std::string World::SetAutopilot(uint32_t id, bool on) {
  auto* v = impl_->FindVehicle(id);
  if (!v) return "actor " + std::to_string(id) + " is not a vehicle of ground_sim";
  if (v->autopilot == on) return {};
  v->autopilot = on;
  v->tm.path.clear();
  v->tm.committed_junction = -1;
  v->use_ackermann = false;
  if (!on) {
    if (v->kinematic && v->simulate_physics) dBodySetDynamic(v->body);
    v->kinematic = false;
    v->control = VehicleControl{};
  } else {
    v->tm.speed = ToVec(dBodyGetLinearVel(v->body)).norm();
  }
  return {};
}

std::string World::SetTrafficManager(TmParam p, uint32_t id, double value) {
  auto& I = *impl_;
  if (!std::isfinite(value)) return "traffic manager value is not finite";
  VehicleActor* v = nullptr;
  if (id != 0) {
    v = I.FindVehicle(id);
    if (!v) return "actor " + std::to_string(id) + " is not a vehicle of ground_sim";
  }
  auto percent = [&](double* global, double* local) -> std::string {
    if (value < 0 || value > 100) return "percentage must be in 0..100";
    (v ? *local : *global) = value;
    return {};
  };
  TmVehicleParams dummy;
  TmVehicleParams& vp = v ? v->tm.params : dummy;
  switch (p) {
    case TmParam::kDistanceToLeadingVehicle:
      if (value < 0 || value > 100) return "distance to leading vehicle must be in 0..100 m";
      (v ? vp.distance_to_leading_vehicle : I.tm.distance_to_leading_vehicle) = value;
      return {};
    case TmParam::kPercentageSpeedDifference:
      if (value < -500 || value > 100) return "percentage speed difference must be in -500..100";
      (v ? vp.percentage_speed_difference : I.tm.percentage_speed_difference) = value;
      return {};
    case TmParam::kDesiredSpeed:
      if (!v) return "desired speed is set per vehicle";
      if (value < 0 || value > 100) return "desired speed must be in 0..100 m/s";
      vp.desired_speed = value;
      return {};
    case TmParam::kIgnoreLightsPercentage: return percent(&I.tm.ignore_lights_percentage, &vp.ignore_lights_percentage);
    case TmParam::kIgnoreSignsPercentage: return percent(&I.tm.ignore_signs_percentage, &vp.ignore_signs_percentage);
    case TmParam::kIgnoreVehiclesPercentage: return percent(&I.tm.ignore_vehicles_percentage, &vp.ignore_vehicles_percentage);
    case TmParam::kIgnoreWalkersPercentage: return percent(&I.tm.ignore_walkers_percentage, &vp.ignore_walkers_percentage);
    case TmParam::kKeepRightPercentage: return percent(&I.tm.keep_right_percentage, &vp.keep_right_percentage);
    case TmParam::kRandomLeftLaneChangePercentage:
      return percent(&I.tm.random_left_lanechange_percentage, &vp.random_left_lanechange_percentage);
    case TmParam::kRandomRightLaneChangePercentage:
      return percent(&I.tm.random_right_lanechange_percentage, &vp.random_right_lanechange_percentage);
    case TmParam::kAutoLaneChange:
      if (v) vp.auto_lane_change = value != 0 ? 1 : 0;
      else I.tm.auto_lane_change = value != 0;
      return {};
    case TmParam::kHybridPhysicsMode:
      if (v) return "hybrid physics mode is global";
      I.tm.hybrid_physics_mode = value != 0;
      return {};
    case TmParam::kHybridPhysicsRadius:
      if (v) return "hybrid physics radius is global";
      if (value < 0) return "hybrid physics radius must be >= 0 m";
      I.tm.hybrid_physics_radius = value;
      return {};
    case TmParam::kRandomSeed:
      if (v) return "the random seed is global";
      if (value < 0) return "seed must be >= 0";
      I.tm.random_seed = static_cast<uint64_t>(value);
      // CARLA's set_random_device_seed: every vehicle's draws restart from the new seed.
      for (auto& [vid, o] : I.vehicles) o->tm.rng.s = MixSeed(I.tm.random_seed, vid);
      I.tm_rng.s = MixSeed(I.tm.random_seed, 0x7E4D);
      return {};
    case TmParam::kRespawnDormantVehicles:
      I.tm.respawn_dormant_vehicles = value != 0;
      return {};
    case TmParam::kSynchronousMode:
      if (value == 0) return "ground_sim's Traffic Manager always runs in lock-step (synchronous mode)";
      return {};
    case TmParam::kLaneOffset:
      // CARLA: no limit (an offset into other lanes "might break the controller").
      (v ? vp.lane_offset : I.tm.lane_offset) = value;
      return {};
  }
  return "unknown traffic manager parameter";
}

std::string World::SetPath(uint32_t id, const std::vector<Vec3>& locations) {
  auto* v = impl_->FindVehicle(id);
  if (!v) return "actor " + std::to_string(id) + " is not a vehicle of ground_sim";
  if (locations.empty()) return "set_path needs at least one location";
  const map::Map& m = impl_->town->Map();
  impl_->FillPath(v);
  if (v->tm.path.empty()) return "vehicle " + std::to_string(id) + " is not on a road";
  // Keep the next few metres, then the planned lanes through every location in turn.
  while (v->tm.path.size() > 3) v->tm.path.pop_back();
  std::deque<map::Waypoint> planned;
  map::Waypoint from = v->tm.path.back();
  for (const Vec3& loc : locations) {
    if (!loc.allFinite()) return "set_path: a location is not finite";
    auto to = m.NearestWaypoint(loc);
    if (!to) return "set_path: no road near a location";
    map::RoutePlannerOptions o;
    o.resolution_m = 2.0;
    o.allow_lane_changes = true;
    auto route = map::PlanRoute(m, from, *to, o);
    if (!route) return "set_path: no route to a location";
    for (size_t k = 1; k < route->steps.size(); ++k) planned.push_back(route->steps[k].waypoint);
    from = *to;
  }
  v->tm.planned = std::move(planned);
  v->tm.route.clear();
  return {};
}

std::string World::SetRoute(uint32_t id, const std::vector<std::string>& options) {
  auto* v = impl_->FindVehicle(id);
  if (!v) return "actor " + std::to_string(id) + " is not a vehicle of ground_sim";
  std::vector<int> route;
  for (const auto& o : options) {
    if (o == "Left") route.push_back(1);
    else if (o == "Right") route.push_back(2);
    else if (o == "Straight") route.push_back(3);
    else return "set_route: '" + o + "' is not Left, Right or Straight";
  }
  v->tm.route = std::move(route);
  v->tm.planned.clear();
  // Re-plan from a few metres ahead so the next junction follows the route.
  while (v->tm.path.size() > 3) v->tm.path.pop_back();
  return {};
}

std::string World::SetCollisionDetection(uint32_t id, uint32_t other, bool detect) {
  auto* v = impl_->FindVehicle(id);
  if (!v) return "actor " + std::to_string(id) + " is not a vehicle of ground_sim";
  if (other == 0) return "collision_detection needs another actor";
  if (detect) v->tm.ignore_collision.erase(other);
  else v->tm.ignore_collision.insert(other);
  return {};
}

std::string World::SetRespawnBoundaries(double lower, double upper) {
  if (!std::isfinite(lower) || !std::isfinite(upper)) return "respawn boundaries are not finite";
  auto& t = impl_->tm;
  // CARLA's Parameters::SetBoundariesRespawnDormantVehicles with SetMaxBoundaries(20, actor_active_distance).
  t.respawn_lower_bound = std::max(kRespawnMinLowerBound, lower);
  t.respawn_upper_bound = std::min(t.actor_active_distance, upper);
  return {};
}

std::string World::ForceLaneChange(uint32_t id, bool left) {
  auto* v = impl_->FindVehicle(id);
  if (!v) return "actor " + std::to_string(id) + " is not a vehicle of ground_sim";
  impl_->FillPath(v);
  if (v->tm.path.size() < 2) return "vehicle " + std::to_string(id) + " is not on a road";
  // CARLA's force_lane_change: no check for other vehicles on the new lane.
  if (!impl_->ChangeLane(v, left, nullptr))
    return "no lane to the " + std::string(left ? "left" : "right") + " in the same direction (or a junction is too near)";
  return {};
}

}  // namespace lockstep::ground
