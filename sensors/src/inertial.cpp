// Inertial and navigation sensors: CARLA's IMU and GNSS, AirSim's barometer and
// magnetometer (with AirSim's noise models where CARLA has none).
#include <cmath>

#include "lockstep/sensors/models.h"

namespace lockstep::sensors {

namespace {
constexpr double kGravity = 9.81;  // m/s^2, CARLA's IMU constant
Vec3 Axes(const Attributes& a, const std::string& prefix) {
  return Vec3(a.Float(prefix + "_x"), a.Float(prefix + "_y"), a.Float(prefix + "_z"));
}
// CARLA's noise_gyro_bias_{x,y,z} add to CARLA's gyroscope, whose frame is Unreal's (y right):
// an angular velocity there is the FLU one as (-x, y, -z), so the bias in FLU is the same.
Vec3 CarlaRatesToFlu(const Vec3& w) { return Vec3(-w.x(), w.y(), -w.z()); }
}  // namespace

Imu::Imu(const Attributes& a, uint64_t seed)
    : accel_stddev_(Axes(a, "noise_accel_stddev")),
      gyro_stddev_(Axes(a, "noise_gyro_stddev")),
      gyro_bias_(CarlaRatesToFlu(Axes(a, "noise_gyro_bias"))),
      gyro_drift_(a.Float("noise_gyro_bias_stability")),
      accel_drift_(a.Float("noise_accel_bias_stability")),
      rng_(seed) {}

ImuSample Imu::Sample(const Pose& pose, const Vec3& velocity, const Vec3& angular_velocity_world, double dt) {
  const Vec3 y0 = pose.position;
  if (!started_) {
    // History as if the sensor had moved at its current velocity (CARLA starts from the
    // spawn location, which reads a spike on a moving parent).
    prev_[0] = y0 - 2 * dt * velocity;
    prev_[1] = y0 - dt * velocity;
    prev_dt_ = dt;
    started_ = true;
  }
  // CARLA: second derivative of the quadratic through the last three positions.
  const double h1 = dt, h2 = prev_dt_;
  Vec3 accel = Vec3::Zero();
  if (h1 > 0 && h2 > 0) {
    const Vec3 a = prev_[1] / (h1 * h2), b = prev_[0] / (h2 * (h1 + h2)), c = y0 / (h1 * (h1 + h2));
    accel = -2.0 * (a - b - c);
  }
  prev_[0] = prev_[1];
  prev_[1] = y0;
  prev_dt_ = dt;
  accel.z() += kGravity;
  const Quat q = pose.orientation;
  ImuSample s;
  s.orientation = q;
  s.accelerometer = q.conjugate() * accel;
  s.gyroscope = q.conjugate() * angular_velocity_world;
  // Compass: the forward vector's heading from north (+y), clockwise, in [0, 2 pi).
  const Vec3 f = q * Vec3::UnitX();
  double c = std::atan2(f.x(), f.y());
  if (c < 0) c += 2 * M_PI;
  s.compass = c;
  // CARLA's noise: accelerometer N(0, sd) per axis, then gyroscope N(bias, sd) per axis.
  for (int k = 0; k < 3; ++k) s.accelerometer[k] += rng_.Normal(0.0, accel_stddev_[k]);
  for (int k = 0; k < 3; ++k) s.gyroscope[k] += rng_.Normal(gyro_bias_[k], gyro_stddev_[k]);
  // AirSim's bias instability: a random walk of sigma = stability * sqrt(dt).
  s.accelerometer += accel_walk_;
  s.gyroscope += gyro_walk_;
  // Off by default (CARLA has none): no draws then, CARLA's noise stream alone.
  const double sq = std::sqrt(std::max(dt, 0.0));
  if (gyro_drift_ > 0) {
    for (int k = 0; k < 3; ++k) gyro_walk_[k] += rng_.Normal(0.0, gyro_drift_ * sq);
  }
  if (accel_drift_ > 0) {
    for (int k = 0; k < 3; ++k) accel_walk_[k] += rng_.Normal(0.0, accel_drift_ * sq);
  }
  return s;
}

Gnss::Gnss(const Attributes& a, uint64_t seed)
    : lat_bias_(a.Float("noise_lat_bias")),
      lat_sd_(a.Float("noise_lat_stddev")),
      lon_bias_(a.Float("noise_lon_bias")),
      lon_sd_(a.Float("noise_lon_stddev")),
      alt_bias_(a.Float("noise_alt_bias")),
      alt_sd_(a.Float("noise_alt_stddev")),
      rng_(seed) {}

GnssSample Gnss::Sample(const GeoReference& ref, const Pose& pose, double dt) {
  if (started_) age_ += dt;
  started_ = true;
  const GeoPoint g = ToGeo(ref, pose.position);
  GnssSample s;
  const double lat_err = rng_.Normal(0.0, lat_sd_);
  const double lon_err = rng_.Normal(0.0, lon_sd_);
  const double alt_err = rng_.Normal(0.0, alt_sd_);
  s.latitude = g.latitude + lat_bias_ + lat_err;
  s.longitude = g.longitude + lon_bias_ + lon_err;
  s.altitude = g.altitude + alt_bias_ + alt_err;
  // AirSim's GPS: eph / epv converge from 100 m to 0.1 m with tau 0.9 s; 3D fix at eph <= 3 m.
  s.eph = 0.1 + (100.0 - 0.1) * std::exp(-age_ / 0.9);
  s.epv = s.eph;
  s.fix = s.eph <= 3.0;
  return s;
}

Barometer::Barometer(const Attributes& a, uint64_t seed)
    : qnh_(a.Float("qnh")),
      noise_(a.Float("noise_pressure_stddev")),
      factor_sigma_(a.Float("drift_pressure_factor_sigma")),
      factor_tau_(a.Float("drift_pressure_factor_tau")),
      rng_(seed) {}

BarometerSample Barometer::Sample(const GeoReference& ref, const Pose& pose, double dt) {
  const double altitude = ref.altitude + pose.position.z();
  double pressure = StandardPressure(altitude);
  // AirSim's GaussianMarkov: x = alpha x + (1 - alpha) N(0, sigma), alpha = exp(-dt / tau).
  const double alpha = std::exp(-dt / factor_tau_);
  factor_ = alpha * factor_ + (1 - alpha) * rng_.Normal(0.0, factor_sigma_);
  pressure += pressure * factor_;
  pressure += rng_.Normal(0.0, noise_);
  BarometerSample s;
  s.pressure = pressure - 101325.0 + qnh_ * 100.0;
  s.altitude = PressureAltitude(pressure);
  s.qnh = qnh_;
  return s;
}

Magnetometer::Magnetometer(const Attributes& a, uint64_t seed)
    : noise_(a.Float("noise_stddev")), bias_(a.Float("noise_bias")), scale_(a.Float("scale_factor")), rng_(seed) {}

Vec3 Magnetometer::Sample(const GeoReference& ref, const Pose& pose) {
  const Vec3 field = MagneticFieldEnu(ToGeo(ref, pose.position));
  Vec3 body = (pose.orientation.conjugate() * field) * scale_;
  for (int k = 0; k < 3; ++k) body[k] += rng_.Normal(0.0, noise_) + bias_;
  return body;
}

}  // namespace lockstep::sensors
