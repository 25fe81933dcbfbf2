// Basic math types of the air simulation core.
// World frame: right-handed ENU (x east, y north, z up), metres. Body frame: FLU
// (x forward, y left, z up). Angles in radians. SI units everywhere.
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <cstdint>

namespace lockstep::air {

using Vec3 = Eigen::Vector3d;
using Mat3 = Eigen::Matrix3d;
using Quat = Eigen::Quaterniond;

using DroneId = std::uint32_t;
using CommandId = std::uint64_t;

struct Pose {
  Vec3 position = Vec3::Zero();          // m, world ENU
  Quat orientation = Quat::Identity();   // body FLU -> world ENU rotation
};

// Roll, pitch, yaw (intrinsic Z-Y-X: R = Rz(yaw) Ry(pitch) Rx(roll)), FLU body in ENU world.
// Positive roll is right wing down; positive pitch is nose DOWN (rotation about the left axis,
// so the thrust tilts forward). AirSim (FRD/NED): same roll, pitch negated, yaw = pi/2 - yaw.
struct Euler {
  double roll = 0;   // rad, about body x (forward)
  double pitch = 0;  // rad, about body y (left)
  double yaw = 0;    // rad, about world z (up), 0 = facing east, counter-clockwise positive
};

}  // namespace lockstep::air
