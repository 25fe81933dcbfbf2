#pragma once
// The wire's geometry (Vector3, Quaternion, Pose of idl/lockstep/common.idl) to Eigen and
// back, once for every service: air_sim, ground_sim and sensors convert with these. A core's
// pose is any struct with `position` (Eigen::Vector3d) and `orientation`
// (Eigen::Quaterniond), as air::Pose, ground::Pose and sensors::Pose are.
// Header only, over Eigen: the services' cores bring it (lockstep_*_core link Eigen3::Eigen).
#include <Eigen/Core>
#include <Eigen/Geometry>

#include "lockstep/runtime/messages.h"

namespace lockstep::wire {

inline Eigen::Vector3d ToVec(const msg::Vector3& v) { return {v.x(), v.y(), v.z()}; }

inline msg::Vector3 FromVec(const Eigen::Vector3d& v) {
  msg::Vector3 m;
  m.x(v.x());
  m.y(v.y());
  m.z(v.z());
  return m;
}

// Normalized; an unset (zero) quaternion is no rotation.
inline Eigen::Quaterniond ToQuat(const msg::Quaternion& q) {
  const Eigen::Quaterniond out(q.w(), q.x(), q.y(), q.z());
  if (out.norm() < 1e-9) return Eigen::Quaterniond::Identity();
  return out.normalized();
}

inline msg::Quaternion FromQuat(const Eigen::Quaterniond& q) {
  msg::Quaternion m;
  m.w(q.w());
  m.x(q.x());
  m.y(q.y());
  m.z(q.z());
  return m;
}

template <class Pose>
Pose ToPose(const msg::Pose& p) {
  Pose out;
  out.position = ToVec(p.position());
  out.orientation = ToQuat(p.orientation());
  return out;
}

template <class Pose>
msg::Pose FromPose(const Pose& p) {
  msg::Pose m;
  m.position(FromVec(p.position));
  m.orientation(FromQuat(p.orientation));
  return m;
}

// A core's object kind on the wire, by the names of its enumerators (kNone, kGround,
// kStatic, kVehicle, kDrone, and kWalker where the core has walkers).
template <class Kind>
msg::ObjectKind ObjectKindToWire(Kind k) {
  if (k == Kind::kGround) return msg::ObjectKind::OBJECT_GROUND;
  if (k == Kind::kStatic) return msg::ObjectKind::OBJECT_STATIC;
  if (k == Kind::kVehicle) return msg::ObjectKind::OBJECT_VEHICLE;
  if (k == Kind::kDrone) return msg::ObjectKind::OBJECT_DRONE;
  if constexpr (requires { Kind::kWalker; }) {
    if (k == Kind::kWalker) return msg::ObjectKind::OBJECT_WALKER;
  }
  return msg::ObjectKind::OBJECT_NONE;
}

// The drone's box, half sizes along body x, y, z (m): AirSim's generic quad spans about
// 0.55 m across its rotors. AirState carries no box; ground_sim (drones as obstacles) and
// the sensors (ray hits) build the drones' boxes from this one value.
inline Eigen::Vector3d DroneHalfExtents() { return {0.3, 0.3, 0.1}; }

}  // namespace lockstep::wire
