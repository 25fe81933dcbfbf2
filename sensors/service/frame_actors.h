#pragma once
// The moving actors of a frame as ray queries see them, from the physics services' state
// messages: the sensors service's scene and the client's World.cast_ray / project_point
// build their actor boxes with these same functions, so both see the same world.
#include <vector>

#include "lockstep/runtime/messages.h"
#include "lockstep/runtime/wire_geometry.h"
#include "lockstep/sensors/types.h"

namespace lockstep::sensors {

// The runtime's converters (lockstep/runtime/wire_geometry.h) under the sensors' names.
inline Vec3 FromWire(const msg::Vector3& v) { return wire::ToVec(v); }
inline Quat FromWire(const msg::Quaternion& q) { return wire::ToQuat(q); }  // an unset (zero) quaternion is no rotation
inline Pose FromWire(const msg::Pose& p) { return wire::ToPose<Pose>(p); }

// Vehicles (with their light state) and walkers of a GroundState; drones of an AirState
// (a box of wire::DroneHalfExtents(), angular velocity turned to world). Appended in message order.
void AppendActors(const msg::GroundState& g, std::vector<Actor>* out);
void AppendActors(const msg::AirState& a, std::vector<Actor>* out);

// A spawned custom.<name> prop (an asset another service imported and declared): the box its
// declaration gives, with the semantic class its tags name ("custom,<name>,<Class>"; Static
// when none), at its spawn transform relative to its parent's mount (world if no parent).
struct CustomProp {
  uint32_t id = 0;
  uint32_t parent = 0;
  Pose transform;
  Vec3 half_extents = Vec3::Zero();
  uint8_t tag = 20;
};
CustomProp MakeCustomProp(const msg::BlueprintDeclaration& declaration, uint32_t id, uint32_t parent, const msg::Pose& transform);
// Appends the props, in order, whose parent (if any) is among `actors` (the frame's actors and
// the props appended before), placed on it.
void AppendProps(const std::vector<CustomProp>& props, std::vector<Actor>* actors);

}  // namespace lockstep::sensors
