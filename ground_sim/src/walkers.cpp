// Walkers: kinematic capsules that follow their WalkerControl, stand on the town's
// surfaces and stop at walls and at each other (walker_crowd.cpp); the AI controller's
// commands (its step: walker_ai.cpp).
#include <algorithm>
#include <cmath>

#include "internal.h"
#include "walker_crowd.h"

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


}  // namespace

// In id order, each walker against the walkers before it where they moved to and the ones
// after it where they stand: no step ends inside another capsule (Gauss-Seidel).
void World::Impl::StepWalkers(double dt) {
  crowd.Build(walkers);
  double max_step = 0;
  for (const auto& [id, wp] : walkers) max_step = std::max(max_step, std::max(0.0, wp->control.speed) * dt);
  // How far apart in x (at the start) two walkers may be and still meet: the radii and the
  // gap, and both moves (a slide is up to 1.007 times the step).
  const double reach = 2 * crowd.max_radius + kWalkerGap + 1.1 * (max_step + kPushSpeed * dt);
  for (auto& [id, wp] : walkers) {
    WalkerActor& w = *wp;
    const size_t self = crowd.Find(id);
    const Pose pose = BodyPose(w.body);
    const double half_h = w.spec->height / 2;
    Vec3 dir = w.control.direction;
    dir.z() = 0;
    const double n = dir.norm();
    Vec3 walk = Vec3::Zero();
    if (n > 1e-9 && w.control.speed > 0) walk = dir / n * (w.control.speed * dt);
    Vec3 step = walk;
    step.head<2>() += crowd.Push(self, kPushSpeed, dt);
    Vec3 next = pose.position + step;
    if (!step.isZero()) {
      // Blocked by a wall, pole, building or another walker: slide along it (the step
      // turned by 45 and then 90 degrees, left first), else stay.
      bool moved = false;
      for (double turn : {0.0, 0.785398, -0.785398, 1.570796, -1.570796}) {
        const Eigen::Vector2d d = Eigen::Rotation2Dd(turn) * step.head<2>() * (turn == 0 ? 1.0 : std::cos(turn) + 0.3);
        const Vec3 candidate = pose.position + Vec3(d.x(), d.y(), 0);
        if (crowd.Blocks(self, pose.position, candidate, reach)) continue;
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
    crowd.entries[self].position = next;
    const double yaw = walk.head<2>().norm() > 1e-6 ? std::atan2(walk.y(), walk.x()) : pose.Yaw();
    w.velocity = (next - pose.position) / dt;
    // Kinematic body: ODE carries it over the sub-steps with this velocity.
    SetBodyPose(w.body, Pose::FromYaw(pose.position, yaw));
    dBodySetLinearVel(w.body, w.velocity.x(), w.velocity.y(), w.velocity.z());
    dBodySetAngularVel(w.body, 0, 0, 0);
  }
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
  ControllerActor& c = it->second;
  c.running = false;
  c.has_goal = false;
  c.planned = false;
  c.route.clear();
  c.crossing = -1;
  c.cross_wait = false;
  if (auto* w = impl_->FindWalker(it->second.walker)) w->control.speed = 0;
  return {};
}
std::string World::ControllerGoTo(uint32_t id, const Vec3& location) {
  auto it = impl_->controllers.find(id);
  if (it == impl_->controllers.end()) return "actor " + std::to_string(id) + " is not a controller.ai.walker";
  if (!location.allFinite()) return "go_to_location: location is not finite";
  ControllerActor& c = it->second;
  c.goal = location;
  c.has_goal = true;
  c.planned = false;  // replanned at its next step (after a crossing it is on)
  c.route.clear();
  if (c.cross_wait) c.crossing = -1, c.cross_wait = false;
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
