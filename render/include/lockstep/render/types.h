#pragma once
// Basic types of the render core: poses in the world frame (ENU, metres; body x forward,
// y left, z up) and which outputs a camera pass writes.
#include <cstdint>

#include <Eigen/Core>
#include <Eigen/Geometry>

namespace lockstep::render {

using Vec3 = Eigen::Vector3d;
using Quat = Eigen::Quaterniond;

struct Pose {
  Vec3 position = Vec3::Zero();
  Quat orientation = Quat::Identity();  // body to parent (world)

  // This pose applied to `child` expressed in this pose's body frame.
  Pose operator*(const Pose& child) const {
    return Pose{position + orientation * child.position, (orientation * child.orientation).normalized()};
  }
  Vec3 Apply(const Vec3& p) const { return position + orientation * p; }
};

// Outputs one camera pass can write (bit mask): all come from the same draw.
enum Output : std::uint32_t {
  kOutColor = 1u << 0,    // lit scene, BGRA8
  kOutDepth = 1u << 1,    // planar depth, float metres
  kOutLabels = 1u << 2,   // semantic tag (R) and instance id (G low byte, B high byte)
  kOutNormals = 1u << 3,  // camera-frame normals mapped to (n + 1) / 2 * 255, BGRA8
  kOutFlow = 1u << 4,     // optical flow, two floats per pixel (CARLA's [-2, 2] screen units)
};

}  // namespace lockstep::render
