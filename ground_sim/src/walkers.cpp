// Walkers: kinematic capsules that follow their WalkerControl, stand on the town's
// surfaces and stop at walls. The AI controller (controller.ai.walker) walks sidewalks.
#include <algorithm>
#include <cmath>

#include "internal.h"

namespace lockstep::ground {
namespace {

struct BlockQuery {
  bool blocked = false;
};

void BlockCallback(void* data, dGeomID o1, dGeomID o2) {
  auto* q = static_cast<BlockQuery*>(data);
  if (q->blocked) return;
  const auto* t = static_cast<const GeomTag*>(dGeomGetData(o2));
  if (!t || t->object == ObjectKind::kGround) return;  // surfaces carry walkers, they do not stop them
  dContactGeom c[1];
  if (dCollide(o1, o2, 1, c, sizeof(dContactGeom)) > 0) q->blocked = true;
}

constexpr double kArrive = 1.0;       // m: a sidewalk path point counts as reached
constexpr double kGoalReached = 0.2;  // m: go_to_location's destination counts as reached

}  // namespace

void World::Impl::StepWalkers(double dt) {
  for (auto& [id, wp] : walkers) {
    WalkerActor& w = *wp;
    const Pose pose = BodyPose(w.body);
    const double half_h = w.spec->height / 2;
    Vec3 dir = w.control.direction;
    dir.z() = 0;
    const double n = dir.norm();
    Vec3 step = Vec3::Zero();
    if (n > 1e-9 && w.control.speed > 0) step = dir / n * (w.control.speed * dt);
    Vec3 next = pose.position + step;
    if (!step.isZero()) {
      // Blocked by a wall, pole or building: slide along it (the step turned by 45 and
      // then 90 degrees, left first), else stay.
      bool moved = false;
      for (double turn : {0.0, 0.785398, -0.785398, 1.570796, -1.570796}) {
        const Eigen::Vector2d d = Eigen::Rotation2Dd(turn) * step.head<2>() * (turn == 0 ? 1.0 : std::cos(turn) + 0.3);
        const Vec3 candidate = pose.position + Vec3(d.x(), d.y(), 0);
        SetBodyPose(w.body, Pose::FromYaw(candidate, pose.Yaw()));
        BlockQuery q;
        dSpaceCollide2(w.geom, reinterpret_cast<dGeomID>(static_space), &q, &BlockCallback);
        if (!q.blocked) {
          next = candidate;
          moved = true;
          break;
        }
      }
      if (!moved) next = pose.position;
    }
    bool hit = false;
    const double feet = next.z() - half_h;
    const double ground = GroundHeight(Vec3(next.x(), next.y(), feet), 0.5, 3.0, &hit);
    double z = hit ? ground + half_h : next.z();
    if (w.control.jump && !w.airborne) {
      w.vertical_speed = 3.0;
      w.airborne = true;
    }
    if (w.airborne) {
      z = pose.position.z() + w.vertical_speed * dt;
      w.vertical_speed -= 9.81 * dt;
      if (z <= ground + half_h || !hit) {
        z = hit ? ground + half_h : z;
        w.airborne = !hit;
        w.vertical_speed = 0;
      }
    }
    next.z() = z;
    const double yaw = step.head<2>().norm() > 1e-6 ? std::atan2(step.y(), step.x()) : pose.Yaw();
    w.velocity = (next - pose.position) / dt;
    // Kinematic body: ODE carries it over the sub-steps with this velocity.
    SetBodyPose(w.body, Pose::FromYaw(pose.position, yaw));
    dBodySetLinearVel(w.body, w.velocity.x(), w.velocity.y(), w.velocity.z());
    dBodySetAngularVel(w.body, 0, 0, 0);
  }
}

void World::Impl::StepControllers(double dt) {
  const map::Map& m = town->Map();
  for (auto& [id, c] : controllers) {
    WalkerActor* w = FindWalker(c.walker);
    if (!w) continue;
    if (!c.running) continue;
    const Vec3 pos = BodyPose(w->body).position;
    if (c.has_goal) {
      // go_to_location: straight towards the goal (no navigation mesh; docs/ground.md).
      Vec3 d = c.goal - pos;
      d.z() = 0;
      if (d.norm() < kGoalReached) {
        // Arrived; like CARLA's walkers it walks on afterwards (here: the sidewalks).
        c.has_goal = false;
        c.path.clear();
        w->control.speed = 0;
      } else {
        w->control.direction = d.normalized();
        w->control.speed = std::min(c.max_speed, d.norm() / dt);
      }
      w->control.jump = false;
      continue;
    }
    // Crossing at a crosswalk: wait at the kerb for the walk light (or a gap), then walk
    // straight over to the other end.
    if (c.crossing >= 0) {
      const TownCrosswalk& cw = town->Crosswalks()[static_cast<size_t>(c.crossing)];
      w->control.jump = false;
      if (c.cross_wait && !MayCross(cw)) {
        w->control.speed = 0;
        continue;
      }
      c.cross_wait = false;
      Vec3 d = cw.ends[c.cross_end] - pos;
      d.z() = 0;
      if (d.norm() > 0.3) {
        w->control.direction = d.normalized();
        w->control.speed = std::min(c.max_speed, d.norm() / dt);
        continue;
      }
      c.crossing = -1;
      c.path.clear();
    }
    // At a crosswalk's end: cross with the world's cross factor, drawn once per arrival.
    bool at_kerb = false;
    for (size_t k = 0; k < town->Crosswalks().size() && c.crossing < 0; ++k) {
      for (int e = 0; e < 2; ++e) {
        if ((town->Crosswalks()[k].ends[e] - pos).head<2>().norm() > 1.5) continue;
        at_kerb = true;
        if (c.last_crosswalk != static_cast<int>(k)) {
          c.last_crosswalk = static_cast<int>(k);
          if (c.rng.Percent(cross_factor * 100.0)) {
            c.crossing = static_cast<int>(k);
            c.cross_end = 1 - e;
            c.cross_wait = true;
          }
        }
        break;
      }
    }
    if (!at_kerb) c.last_crosswalk = -1;
    if (c.crossing >= 0) {
      w->control.speed = 0;  // starts from the kerb next step, when it may
      continue;
    }
    // Wander along sidewalk lanes, random branch at each split, turning back at dead ends.
    auto& path = c.path;
    while (!path.empty() && (path.front().transform.location - pos).head<2>().norm() < kArrive) path.pop_front();
    if (path.empty()) {
      auto start = m.NearestWaypoint(pos, true, map::LaneType::Sidewalk);
      if (!start) {
        w->control.speed = 0;
        continue;
      }
      path.push_back(*start);
    }
    while (path.size() < 4) {
      // Keep walking the way we go: of the points 2 m on (either lane direction, walkers
      // walk both ways), those ahead of the last step; at a dead end, turn back.
      const map::Waypoint& last = path.back();
      std::vector<map::Waypoint> next = m.Next(last, 2.0);
      for (auto& p : m.Previous(last, 2.0)) next.push_back(p);
      if (next.empty()) break;
      std::sort(next.begin(), next.end(), [](const map::Waypoint& x, const map::Waypoint& y) {
        return std::make_tuple(x.road, x.lane, x.s) < std::make_tuple(y.road, y.lane, y.s);
      });
      const Vec3 heading = path.size() >= 2 ? Vec3(last.transform.location - path[path.size() - 2].transform.location)
                                            : Vec3(pos - last.transform.location) * -1.0;
      std::vector<map::Waypoint> ahead;
      for (const auto& p : next) {
        const Vec3 d = p.transform.location - last.transform.location;
        if (d.head<2>().norm() > 0.1 && (path.size() < 2 || d.head<2>().dot(heading.head<2>()) > 0)) ahead.push_back(p);
      }
      if (ahead.empty()) {
        for (const auto& p : next) {
          if ((p.transform.location - last.transform.location).head<2>().norm() > 0.1) ahead.push_back(p);
        }
      }
      if (ahead.empty()) break;
      path.push_back(ahead[static_cast<size_t>(c.rng.Next() % ahead.size())]);
    }
    Vec3 d = path.front().transform.location - pos;
    d.z() = 0;
    if (d.norm() > 1e-6) w->control.direction = d.normalized();
    w->control.speed = c.max_speed;
    w->control.jump = false;
  }
}

// Walk light: every light of the lanes crossed is red for the vehicles; without lights,
// no vehicle near the crosswalk and none approaching within 25 m.
bool World::Impl::MayCross(const TownCrosswalk& cw) const {
  if (!cw.lights.empty()) {
    for (int l : cw.lights) {
      if (lights[static_cast<size_t>(l)].color != LightColor::kRed) return false;
    }
    return true;
  }
  for (const auto& [id, v] : vehicles) {
    const Vec3 p = ToVec(dBodyGetPosition(v->body));
    const Vec3 vel = v->kinematic ? Vec3(BodyPose(v->body).orientation * Vec3(v->tm.speed, 0, 0)) : ToVec(dBodyGetLinearVel(v->body));
    const Vec3 to = cw.centre - p;
    const double d = to.head<2>().norm();
    if (d < 4.0) return false;
    if (d < 25.0 && vel.head<2>().norm() > 0.5 && vel.head<2>().dot(to.head<2>()) > 0) return false;
  }
  return true;
}

std::string World::SetPedestriansCrossFactor(double factor) {
  if (!(factor >= 0 && factor <= 1)) return "pedestrians cross factor must be in 0..1";
  impl_->cross_factor = factor;
  return {};
}

uint64_t World::Impl::ControllerSeed(uint32_t id) const {
  return has_pedestrians_seed ? MixSeed(MixSeed(seed, pedestrians_seed ^ 0x9ED5EEDull), id) : MixSeed(seed, id);
}

void World::SetPedestriansSeed(uint64_t s) {
  impl_->has_pedestrians_seed = true;
  impl_->pedestrians_seed = s;
  for (auto& [id, c] : impl_->controllers) c.rng.s = impl_->ControllerSeed(id);
}

std::string World::ControllerStart(uint32_t id) {
  auto it = impl_->controllers.find(id);
  if (it == impl_->controllers.end()) return "actor " + std::to_string(id) + " is not a controller.ai.walker";
  it->second.running = true;
  return {};
}
std::string World::ControllerStop(uint32_t id) {
  auto it = impl_->controllers.find(id);
  if (it == impl_->controllers.end()) return "actor " + std::to_string(id) + " is not a controller.ai.walker";
  it->second.running = false;
  it->second.has_goal = false;
  if (auto* w = impl_->FindWalker(it->second.walker)) w->control.speed = 0;
  return {};
}
std::string World::ControllerGoTo(uint32_t id, const Vec3& location) {
  auto it = impl_->controllers.find(id);
  if (it == impl_->controllers.end()) return "actor " + std::to_string(id) + " is not a controller.ai.walker";
  if (!location.allFinite()) return "go_to_location: location is not finite";
  it->second.goal = location;
  it->second.has_goal = true;
  return {};
}
std::string World::ControllerMaxSpeed(uint32_t id, double speed) {
  auto it = impl_->controllers.find(id);
  if (it == impl_->controllers.end()) return "actor " + std::to_string(id) + " is not a controller.ai.walker";
  if (!(speed >= 0 && speed <= 10)) return "set_max_speed: speed must be in 0..10 m/s";
  it->second.max_speed = speed;
  return {};
}

}  // namespace lockstep::ground
