// CARLA's radar (ARadar::SendLineTraces): points_per_second * dt random rays in an
// elliptic cone; a hit reports depth, the ray's azimuth and altitude, and the radial
// velocity of the hit object relative to the sensor.
#include <cmath>

#include "lockstep/sensors/models.h"

namespace lockstep::sensors {

Radar::Radar(const Attributes& a, uint64_t seed)
    : hfov_(a.Float("horizontal_fov")),
      vfov_(a.Float("vertical_fov")),
      range_(a.Float("range")),
      pps_(static_cast<double>(a.Int("points_per_second"))),
      rng_(seed) {}

std::vector<RadarDetection> Radar::Scan(const RayScene& scene, const WorldFrame& world, const Pose& pose, double dt) {
  // The sensor's own velocity from its displacement since the last sample (as CARLA).
  const Vec3 own_velocity = has_prev_ && dt > 0 ? Vec3((pose.position - prev_position_) / dt) : Vec3::Zero();
  prev_position_ = pose.position;
  has_prev_ = true;

  const double max_rx = std::tan(hfov_ * M_PI / 360.0) * range_;
  const double max_ry = std::tan(vfov_ * M_PI / 360.0) * range_;
  const int n = static_cast<int>(pps_ * dt);
  const Eigen::Matrix3d r = pose.orientation.toRotationMatrix();
  std::vector<Ray> rays(n > 0 ? n : 0);
  std::vector<Vec3> local(rays.size());
  for (int i = 0; i < n; ++i) {
    const double radius = rng_.Uniform();
    const double angle = rng_.Uniform(0.0, 2 * M_PI);
    // Unreal (x forward, y right, z up) end point; y flipped into FLU.
    local[i] = Vec3(range_, -max_rx * radius * std::cos(angle), max_ry * radius * std::sin(angle)).normalized();
    const Vec3 d = r * local[i];
    for (int k = 0; k < 3; ++k) {
      rays[i].origin[k] = static_cast<float>(pose.position[k]);
      rays[i].dir[k] = static_cast<float>(d[k]);
    }
    rays[i].tfar = static_cast<float>(range_);
  }
  std::vector<Hit> hits(rays.size());
  scene.Intersect(rays.data(), hits.data(), rays.size());
  std::vector<RadarDetection> out;
  for (size_t i = 0; i < rays.size(); ++i) {
    if (!hits[i].hit()) continue;
    const Vec3 dir(rays[i].dir[0], rays[i].dir[1], rays[i].dir[2]);
    Vec3 target_velocity = Vec3::Zero();
    if (hits[i].actor) {
      if (const Actor* a = world.Find(hits[i].actor)) target_velocity = a->velocity;
    }
    RadarDetection d;
    d.velocity = static_cast<float>((target_velocity - own_velocity).dot(dir));
    d.azimuth = static_cast<float>(std::atan2(local[i].y(), local[i].x()));
    d.altitude = static_cast<float>(std::atan2(local[i].z(), std::hypot(local[i].x(), local[i].y())));
    d.depth = hits[i].distance;
    out.push_back(d);
  }
  return out;
}

}  // namespace lockstep::sensors
