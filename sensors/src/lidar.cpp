// CARLA's ray-cast LiDAR (ARayCastLidar / ARayCastSemanticLidar), slice by slice.
#include <cmath>
#include <cstring>

#include "lockstep/sensors/models.h"

namespace lockstep::sensors {

namespace {
constexpr double kDeg = M_PI / 180.0;
// Extra extinction (1/m) at full fog / full rain: CARLA's ray-cast LiDAR ignores weather;
// Lockstep adds it to the atmosphere attenuation rate (docs/sensors.md).
constexpr double kFogAttenuation = 0.03;
constexpr double kRainAttenuation = 0.01;

template <class T>
T Read(const std::vector<uint8_t>& d, size_t offset) {
  T v;
  std::memcpy(&v, d.data() + offset, sizeof v);
  return v;
}
}  // namespace

Vec3 PointCloudSample::Point(size_t i) const {
  const size_t o = i * point_step;
  return Vec3(Read<float>(data, o), Read<float>(data, o + 4), Read<float>(data, o + 8));
}
float PointCloudSample::Intensity(size_t i) const { return Read<float>(data, i * point_step + 12); }
float PointCloudSample::CosIncidence(size_t i) const { return Read<float>(data, i * point_step + 12); }
uint32_t PointCloudSample::Object(size_t i) const { return Read<uint32_t>(data, i * point_step + 16); }
uint32_t PointCloudSample::Tag(size_t i) const { return Read<uint32_t>(data, i * point_step + 20); }

Lidar::Lidar(const Attributes& a, bool semantic, uint64_t seed)
    : channels_(static_cast<int>(a.Int("channels"))),
      range_(a.Float("range")),
      pps_(static_cast<double>(a.Int("points_per_second"))),
      frequency_(a.Float("rotation_frequency")),
      hfov_(a.Float("horizontal_fov")),
      attenuation_(semantic ? 0 : a.Float("atmosphere_attenuation_rate")),
      drop_general_(semantic ? 0 : a.Float("dropoff_general_rate")),
      drop_limit_(semantic ? 1 : a.Float("dropoff_intensity_limit")),
      drop_zero_(semantic ? 0 : a.Float("dropoff_zero_intensity")),
      noise_(semantic ? 0 : a.Float("noise_stddev")),
      semantic_(semantic),
      rng_(seed) {
  // CARLA's CreateLasers: evenly spaced from upper_fov down to lower_fov.
  const double upper = a.Float("upper_fov"), lower = a.Float("lower_fov");
  const double step = channels_ == 1 ? 0.0 : (upper - lower) / (channels_ - 1);
  for (int i = 0; i < channels_; ++i) vertical_.push_back(upper - i * step);
}

uint64_t Lidar::Fingerprint() const {
  uint64_t bits;
  std::memcpy(&bits, &angle_, sizeof bits);
  return rng_.Fingerprint() ^ bits;
}

PointCloudSample Lidar::Scan(const RayScene& scene, const Pose& pose, double dt, const Weather& weather) {
  PointCloudSample out;
  out.semantic = semantic_;
  out.point_step = semantic_ ? 24 : 16;
  out.points_per_channel.assign(channels_, 0);
  const long per_channel = std::lround(pps_ * dt / channels_);  // RoundHalfFromZero
  if (per_channel <= 0) return out;  // CARLA logs and emits nothing
  const double tick_angle = frequency_ * hfov_ * dt;
  const double step = tick_angle / per_channel;

  // The slice's columns: CARLA's yaw is clockwise seen from above (Unreal's y points
  // right), so a column at yaw h has FLU direction (cos h, -sin h) before the elevation.
  column_cos_.resize(per_channel);
  column_sin_.resize(per_channel);
  for (long i = 0; i < per_channel; ++i) {
    const double h = (std::fmod(angle_ + step * static_cast<double>(i), hfov_) - hfov_ / 2) * kDeg;
    column_cos_[i] = std::cos(h);
    column_sin_[i] = -std::sin(h);
  }
  // RayPreprocessCondition: each ray is kept unless dropoff_general_rate > U[0,1).
  rays_.clear();
  ray_channel_.clear();
  ray_local_.clear();
  const Eigen::Matrix3d r = pose.orientation.toRotationMatrix();
  const float ox = static_cast<float>(pose.position.x()), oy = static_cast<float>(pose.position.y()),
              oz = static_cast<float>(pose.position.z());
  for (int ch = 0; ch < channels_; ++ch) {
    const double v = vertical_[ch] * kDeg;
    const double cv = std::cos(v), sv = std::sin(v);
    for (long i = 0; i < per_channel; ++i) {
      const bool keep = semantic_ || drop_general_ <= 0 || !(drop_general_ > rng_.Uniform());
      if (!keep) continue;
      const Vec3 local(cv * column_cos_[i], cv * column_sin_[i], sv);
      const Vec3 world = r * local;
      rays_.push_back(Ray{{ox, oy, oz},
                          {static_cast<float>(world.x()), static_cast<float>(world.y()), static_cast<float>(world.z())},
                          static_cast<float>(range_)});
      ray_channel_.push_back(static_cast<uint32_t>(ch));
      ray_local_.push_back(local);
    }
  }
  hits_.resize(rays_.size());
  scene.Intersect(rays_.data(), hits_.data(), rays_.size());

  // ComputeAndSaveDetections: channel by channel, in ray order; noise along the ray,
  // then the intensity-based drop-off (only at or below dropoff_intensity_limit): CARLA's
  // PostprocessDetection keeps a point with probability alpha * I + beta, alpha =
  // dropoff_zero_intensity / dropoff_intensity_limit, beta = 1 - dropoff_zero_intensity (so
  // an intensity of 0 is dropped with probability dropoff_zero_intensity, one at the limit
  // always kept).
  const double attenuation = attenuation_ + kFogAttenuation * weather.fog_density / 100.0 +
                             kRainAttenuation * weather.precipitation / 100.0;
  const double alpha = drop_limit_ > 0 ? drop_zero_ / drop_limit_ : 0.0;
  const double beta = 1.0 - drop_zero_;
  out.data.reserve(rays_.size() * out.point_step);
  for (size_t i = 0; i < rays_.size(); ++i) {
    const Hit& h = hits_[i];
    if (!h.hit()) continue;
    Vec3 p = ray_local_[i] * h.distance;
    if (semantic_) {
      const Eigen::Vector3f n(h.normal[0], h.normal[1], h.normal[2]);
      const float cos_inc = std::abs(n.dot(Eigen::Vector3f(-rays_[i].dir[0], -rays_[i].dir[1], -rays_[i].dir[2])));
      const float xyzc[4] = {static_cast<float>(p.x()), static_cast<float>(p.y()), static_cast<float>(p.z()), cos_inc};
      const uint32_t ids[2] = {h.actor, h.tag};
      const size_t o = out.data.size();
      out.data.resize(o + 24);
      std::memcpy(out.data.data() + o, xyzc, 16);
      std::memcpy(out.data.data() + o + 16, ids, 8);
    } else {
      if (noise_ > 1e-7) p += ray_local_[i] * rng_.Normal(0.0, noise_);
      const double intensity = std::exp(-attenuation * h.distance);
      if (intensity <= drop_limit_ && !(rng_.Uniform() < alpha * intensity + beta)) continue;
      const float xyzi[4] = {static_cast<float>(p.x()), static_cast<float>(p.y()), static_cast<float>(p.z()),
                             static_cast<float>(intensity)};
      const size_t o = out.data.size();
      out.data.resize(o + 16);
      std::memcpy(out.data.data() + o, xyzi, 16);
    }
    ++out.points_per_channel[ray_channel_[i]];
    ++out.point_count;
  }
  angle_ = std::fmod(angle_ + tick_angle, hfov_);
  return out;
}

}  // namespace lockstep::sensors
