#include "lockstep/air/frames.h"

#include <cmath>
#include <numbers>

namespace lockstep::air {
namespace {
// M_ne maps ENU coordinates to NED coordinates; M_fb maps FRD coordinates to FLU.
const Mat3& Mne() {
  static const Mat3 m = (Mat3() << 0, 1, 0, 1, 0, 0, 0, 0, -1).finished();
  return m;
}
const Mat3& Mfb() {
  static const Mat3 m = Eigen::Vector3d(1, -1, -1).asDiagonal().toDenseMatrix();
  return m;
}
}  // namespace

double WrapAngle(double a) {
  constexpr double kPi = std::numbers::pi;
  a = std::remainder(a, 2.0 * kPi);
  if (a <= -kPi) a += 2.0 * kPi;
  return a;
}

Euler ToEuler(const Quat& q) {
  const Mat3 r = q.toRotationMatrix();
  Euler e;
  e.pitch = std::asin(std::clamp(-r(2, 0), -1.0, 1.0));
  e.roll = std::atan2(r(2, 1), r(2, 2));
  e.yaw = std::atan2(r(1, 0), r(0, 0));
  return e;
}

Quat FromEuler(double roll, double pitch, double yaw) {
  return Quat(Eigen::AngleAxisd(yaw, Vec3::UnitZ()) * Eigen::AngleAxisd(pitch, Vec3::UnitY()) *
              Eigen::AngleAxisd(roll, Vec3::UnitX()));
}

double YawOf(const Quat& q) {
  const Mat3 r = q.toRotationMatrix();
  return std::atan2(r(1, 0), r(0, 0));
}

Vec3 EnuToNed(const Vec3& v) { return Vec3(v.y(), v.x(), -v.z()); }
Vec3 NedToEnu(const Vec3& v) { return Vec3(v.y(), v.x(), -v.z()); }
Vec3 FluToFrd(const Vec3& v) { return Vec3(v.x(), -v.y(), -v.z()); }
Vec3 FrdToFlu(const Vec3& v) { return Vec3(v.x(), -v.y(), -v.z()); }

Vec3 WorldToAirSimPosition(const Vec3& p_world, const Vec3& spawn_world) {
  return EnuToNed(p_world - spawn_world);
}
Vec3 AirSimToWorldPosition(const Vec3& p_ned, const Vec3& spawn_world) {
  return NedToEnu(p_ned) + spawn_world;
}

Quat EnuFluToNedFrd(const Quat& q_enu_flu) {
  Quat q(Mat3(Mne() * q_enu_flu.toRotationMatrix() * Mfb()));
  return q.normalized();
}
Quat NedFrdToEnuFlu(const Quat& q_ned_frd) {
  // Mne and Mfb are symmetric involutions.
  Quat q(Mat3(Mne() * q_ned_frd.toRotationMatrix() * Mfb()));
  return q.normalized();
}

double EnuYawToNedYaw(double yaw_enu) { return WrapAngle(std::numbers::pi / 2 - yaw_enu); }
double NedYawToEnuYaw(double yaw_ned) { return WrapAngle(std::numbers::pi / 2 - yaw_ned); }

Euler EnuEulerToNedEuler(const Euler& e) {
  return Euler{e.roll, -e.pitch, EnuYawToNedYaw(e.yaw)};
}
Euler NedEulerToEnuEuler(const Euler& e) {
  return Euler{e.roll, -e.pitch, NedYawToEnuYaw(e.yaw)};
}

}  // namespace lockstep::air
