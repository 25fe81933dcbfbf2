// AirSim's distance sensor and CARLA's obstacle detector: rays along the sensor's +x
// that pass through the actor the sensor is attached to.
#include <cmath>

#include "lockstep/sensors/models.h"

namespace lockstep::sensors {

namespace {
Ray MakeRay(const Vec3& origin, const Vec3& dir, double length) {
  Ray r;
  for (int k = 0; k < 3; ++k) {
    r.origin[k] = static_cast<float>(origin[k]);
    r.dir[k] = static_cast<float>(dir[k]);
  }
  r.tfar = static_cast<float>(length);
  return r;
}
}  // namespace

DistanceSensor::DistanceSensor(const Attributes& a, uint64_t seed)
    : min_(a.Float("min_distance")), max_(a.Float("max_distance")), noise_(a.Float("noise_stddev")), rng_(seed) {}

DistanceSample DistanceSensor::Sample(const RayScene& scene, const Pose& pose, uint32_t parent) {
  const Vec3 forward = pose.orientation * Vec3::UnitX();
  const Hit h = scene.IntersectSkipping(MakeRay(pose.position, forward, max_), [&](const Hit& x) { return parent && x.actor == parent; });
  DistanceSample s;
  s.min_distance = min_;
  s.max_distance = max_;
  s.distance = (h.hit() ? h.distance : max_) + rng_.Normal(0.0, noise_);
  return s;
}

ObstacleDetector::ObstacleDetector(const Attributes& a)
    : distance_(a.Float("distance")), radius_(a.Float("hit_radius")), only_dynamics_(a.Bool("only_dynamics")) {}

ObstacleSample ObstacleDetector::Sample(const RayScene& scene, const Pose& pose, uint32_t parent) const {
  // CARLA sweeps a sphere of hit_radius; here a centre ray and 8 rays on its rim.
  const Vec3 forward = pose.orientation * Vec3::UnitX();
  const Vec3 left = pose.orientation * Vec3::UnitY(), up = pose.orientation * Vec3::UnitZ();
  ObstacleSample best;
  best.distance = distance_;
  auto skip = [&](const Hit& x) {
    if (parent && x.actor == parent) return true;
    return only_dynamics_ && x.actor == 0;
  };
  for (int i = 0; i <= 8; ++i) {
    Vec3 origin = pose.position;
    if (i > 0) {
      const double a = (i - 1) * M_PI / 4;
      origin += radius_ * (std::cos(a) * left + std::sin(a) * up);
    }
    const Hit h = scene.IntersectSkipping(MakeRay(origin, forward, distance_), skip);
    if (h.hit() && h.distance <= best.distance) {
      best.distance = h.distance;
      best.other_actor = h.actor;
      best.other_kind = h.kind;
      best.other_tag = h.tag;
    }
  }
  if (best.other_kind == HitKind::kNone) best.distance = 0;
  return best;
}

}  // namespace lockstep::sensors
