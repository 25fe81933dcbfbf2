#pragma once
// The sensor models, each a small state machine: configured from its blueprint's
// attributes, sampled with the sensor's world pose and the time since its last sample.
// Random draws come from the sensor's own seeded stream, in CARLA's order.
#include <cstdint>
#include <vector>

#include "lockstep/sensors/blueprints.h"
#include "lockstep/sensors/geo.h"
#include "lockstep/sensors/ray_scene.h"
#include "lockstep/sensors/types.h"

namespace lockstep::sensors {

// ---- outputs (the service turns them into sensor.idl messages) ----

struct PointCloudSample {
  bool semantic = false;       // false: XYZI (4 x float32); true: x, y, z, cos_inc (float32), object, tag (uint32)
  uint32_t point_count = 0;
  uint32_t point_step = 16;    // bytes per point
  std::vector<uint32_t> points_per_channel;
  std::vector<uint8_t> data;   // point_count * point_step bytes, sensor frame (FLU), m

  // Point i read back (tests, writers).
  Vec3 Point(size_t i) const;
  float Intensity(size_t i) const;     // XYZI only
  float CosIncidence(size_t i) const;  // semantic only
  uint32_t Object(size_t i) const;     // semantic only
  uint32_t Tag(size_t i) const;        // semantic only
};

struct RadarDetection {
  float velocity = 0;   // m/s, radial, towards the sensor negative
  float azimuth = 0;    // rad, positive to the left (FLU; the carla module gives CARLA's, right positive)
  float altitude = 0;   // rad, positive up
  float depth = 0;      // m
};

struct ImuSample {
  Vec3 accelerometer = Vec3::Zero();  // m/s^2, sensor frame, specific force (gravity included)
  Vec3 gyroscope = Vec3::Zero();      // rad/s, sensor frame (FLU; CARLA's is (-x, y, -z) of it)
  double compass = 0;                 // rad, from north, clockwise
  Quat orientation = Quat::Identity();
};

struct GnssSample {
  double latitude = 0, longitude = 0, altitude = 0;  // deg, deg, m
  double eph = 0, epv = 0;                           // m
  bool fix = false;
};

struct BarometerSample {
  double altitude = 0;  // m
  double pressure = 0;  // Pa
  double qnh = 0;       // hPa
};

struct DistanceSample {
  double distance = 0, min_distance = 0, max_distance = 0;  // m
};

struct ObstacleSample {
  uint32_t other_actor = 0;
  HitKind other_kind = HitKind::kNone;
  uint8_t other_tag = 0;  // CARLA semantic tag of what was hit (carla: "static.<tag>" for the scene)
  double distance = 0;  // m
};

// ---- models ----

class Lidar {
 public:
  Lidar(const Attributes& a, bool semantic, uint64_t seed);
  // The slice swept during `dt` seconds (CARLA: points_per_second * dt / channels per
  // channel, rounded half away from zero), from `pose` (world), then the angle advances.
  PointCloudSample Scan(const RayScene& scene, const Pose& pose, double dt, const Weather& weather);
  double horizontal_angle() const { return angle_; }  // deg
  uint64_t Fingerprint() const;
  // What changes from step to step (a snapshot for a replacement process).
  void Save(StateOut& out) const;
  void Load(StateIn& in);

 private:
  int channels_;
  double range_, pps_, frequency_, hfov_;
  double attenuation_, drop_general_, drop_limit_, drop_zero_, noise_;
  bool semantic_;
  std::vector<double> vertical_;   // deg per channel, upper first
  double angle_ = 0;               // deg, current horizontal angle in [0, hfov)
  Rng rng_;
  std::vector<Ray> rays_;
  std::vector<Hit> hits_;
  std::vector<uint32_t> ray_channel_;
  std::vector<Vec3> ray_local_;
  std::vector<double> column_cos_, column_sin_;
};

class Radar {
 public:
  Radar(const Attributes& a, uint64_t seed);
  std::vector<RadarDetection> Scan(const RayScene& scene, const WorldFrame& world, const Pose& pose, double dt);
  uint64_t Fingerprint() const { return rng_.Fingerprint(); }
  void Save(StateOut& out) const;
  void Load(StateIn& in);

 private:
  double hfov_, vfov_, range_, pps_;
  Rng rng_;
  bool has_prev_ = false;
  Vec3 prev_position_ = Vec3::Zero();
};

class Imu {
 public:
  Imu(const Attributes& a, uint64_t seed);
  // velocity: the sensor's world velocity (for the first sample's history only).
  ImuSample Sample(const Pose& pose, const Vec3& velocity, const Vec3& angular_velocity_world, double dt);
  uint64_t Fingerprint() const { return rng_.Fingerprint(); }
  void Save(StateOut& out) const;
  void Load(StateIn& in);

 private:
  Vec3 accel_stddev_, gyro_stddev_, gyro_bias_;
  double gyro_drift_, accel_drift_;
  Vec3 gyro_walk_ = Vec3::Zero(), accel_walk_ = Vec3::Zero();
  bool started_ = false;
  Vec3 prev_[2];            // [0]: two samples ago, [1]: last sample (CARLA's PrevLocation)
  double prev_dt_ = 0;
  Rng rng_;
};

class Gnss {
 public:
  Gnss(const Attributes& a, uint64_t seed);
  GnssSample Sample(const GeoReference& ref, const Pose& pose, double dt);
  uint64_t Fingerprint() const { return rng_.Fingerprint(); }
  void Save(StateOut& out) const;
  void Load(StateIn& in);

 private:
  double lat_bias_, lat_sd_, lon_bias_, lon_sd_, alt_bias_, alt_sd_;
  double age_ = 0;  // s since the first sample (AirSim's eph / epv convergence)
  bool started_ = false;
  Rng rng_;
};

class Barometer {
 public:
  Barometer(const Attributes& a, uint64_t seed);
  BarometerSample Sample(const GeoReference& ref, const Pose& pose, double dt);
  uint64_t Fingerprint() const { return rng_.Fingerprint(); }
  void Save(StateOut& out) const;
  void Load(StateIn& in);

 private:
  double qnh_, noise_, factor_sigma_, factor_tau_;
  double factor_ = 0;  // Gauss-Markov pressure drift factor
  Rng rng_;
};

class Magnetometer {
 public:
  Magnetometer(const Attributes& a, uint64_t seed);
  Vec3 Sample(const GeoReference& ref, const Pose& pose);  // gauss, sensor frame
  uint64_t Fingerprint() const { return rng_.Fingerprint(); }
  void Save(StateOut& out) const;
  void Load(StateIn& in);

 private:
  double noise_, bias_, scale_;
  Rng rng_;
};

class DistanceSensor {
 public:
  DistanceSensor(const Attributes& a, uint64_t seed);
  DistanceSample Sample(const RayScene& scene, const Pose& pose, uint32_t parent);
  uint64_t Fingerprint() const { return rng_.Fingerprint(); }
  void Save(StateOut& out) const;
  void Load(StateIn& in);

 private:
  double min_, max_, noise_;
  Rng rng_;
};

class ObstacleDetector {
 public:
  explicit ObstacleDetector(const Attributes& a);
  // nullopt-like: other_kind kNone when nothing is within `distance`.
  ObstacleSample Sample(const RayScene& scene, const Pose& pose, uint32_t parent) const;

 private:
  double distance_, radius_;
  bool only_dynamics_;
};

}  // namespace lockstep::sensors
