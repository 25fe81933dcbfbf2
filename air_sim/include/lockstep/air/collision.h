// What a drone collides with: a ground plane, a static triangle mesh (the town) and moving
// oriented boxes (vehicles from ground_sim). Queries are sphere-based: a drone is a set of
// contact spheres (MultirotorParams::contact_spheres).
#pragma once

#include <cstddef>
#include <cstdint>
#include <memory>
#include <span>
#include <vector>

#include "lockstep/air/types.h"

namespace lockstep::air {

enum class ObjectKind : std::uint8_t { kNone = 0, kGround = 1, kStatic = 2, kVehicle = 3, kDrone = 4 };
const char* ToString(ObjectKind k);

// One contact between a drone sphere and an object.
struct ContactPoint {
  Vec3 point = Vec3::Zero();            // m, world ENU, on the object's surface
  Vec3 normal = Vec3::UnitZ();          // unit, world ENU, from the object towards the drone
  double depth = 0;                     // m, penetration (> 0)
  Vec3 object_velocity = Vec3::Zero();  // m/s, world ENU, velocity of the object's surface at point
  ObjectKind kind = ObjectKind::kNone;
  std::uint32_t object_id = 0;          // vehicle id, mesh id, drone id, 0 for the ground
};

// A vehicle (or any moving obstacle) as an oriented box, as seen at frame k. The air sim
// extrapolates it across the tick: p(t) = p + v t, R(t) = exp([w] t) R (Jacobi coupling).
struct VehicleBox {
  std::uint32_t id = 0;                  // actor id
  Pose pose;                             // box centre and orientation (box axes -> world ENU)
  Vec3 velocity = Vec3::Zero();          // m/s, world ENU, of the box centre
  Vec3 angular_velocity = Vec3::Zero();  // rad/s, world ENU
  Vec3 half_extents{2.4, 1.0, 0.75};     // m, along the box axes
};

// Pose of a vehicle box `t` seconds after its snapshot.
Pose ExtrapolateVehicle(const VehicleBox& v, double t);

// Immutable triangle mesh with a uniform XY grid for sphere queries. Thread-safe to query.
class StaticMesh {
 public:
  // xyz: 3 floats per vertex (world ENU, m); indices: 3 per triangle. cell_size in m.
  // Throws std::invalid_argument on an index out of range, a non-finite vertex or bad sizes.
  static std::shared_ptr<const StaticMesh> Build(std::span<const float> xyz,
                                                 std::span<const std::uint32_t> indices,
                                                 double cell_size = 4.0, std::uint32_t id = 1);

  std::size_t triangle_count() const { return tris_.size(); }
  std::uint32_t id() const { return id_; }
  // Contacts of a sphere with the mesh, at most one per triangle, merged when normals agree.
  // Writes up to max_out contacts to out; returns how many. Allocation-free.
  int QuerySphere(const Vec3& center, double radius, ContactPoint* out, int max_out) const;
  // Distance from p down to the highest triangle below it within max_drop (m); < 0 if none.
  double HeightBelow(const Vec3& p, double max_drop) const;

 private:
  struct Tri {
    Vec3 a, b, c;
    Vec3 lo, hi;  // bounding box
  };
  std::vector<Tri> tris_;
  std::vector<std::uint32_t> cell_start_;  // (nx * ny + 1) offsets into cell_tris_
  std::vector<std::uint32_t> cell_tris_;
  Vec3 lo_ = Vec3::Zero(), hi_ = Vec3::Zero();
  double cell_ = 4.0;
  int nx_ = 0, ny_ = 0;
  std::uint32_t id_ = 1;
};

// Static world the drones collide with (part of the immutable model).
struct StaticGeometry {
  bool has_ground = true;
  double ground_height = 0;                // m, world z of the ground plane
  std::shared_ptr<const StaticMesh> mesh;  // optional town mesh
};

// Closest point on triangle abc to p (Ericson, Real-Time Collision Detection 5.1.5).
Vec3 ClosestPointOnTriangle(const Vec3& p, const Vec3& a, const Vec3& b, const Vec3& c);
// Sphere vs oriented box; true and fills *out (kind/id/velocity left to the caller) on overlap.
bool SphereBoxContact(const Vec3& center, double radius, const Pose& box, const Vec3& half,
                      ContactPoint* out);

}  // namespace lockstep::air
