#pragma once
// The moving actors of a frame as ray queries see them, from the physics services' state
// messages: the sensors service's scene and the client's World.cast_ray / project_point
// build their actor boxes with these same functions, so both see the same world.
#include <vector>

#include "lockstep/runtime/messages.h"
#include "lockstep/sensors/types.h"

namespace lockstep::sensors {

Vec3 FromWire(const msg::Vector3& v);
Quat FromWire(const msg::Quaternion& q);  // an unset (zero) quaternion is no rotation
Pose FromWire(const msg::Pose& p);

// Vehicles (with their light state) and walkers of a GroundState; drones of an AirState
// (a box of kDroneHalfExtents, angular velocity turned to world). Appended in message order.
void AppendActors(const msg::GroundState& g, std::vector<Actor>* out);
void AppendActors(const msg::AirState& a, std::vector<Actor>* out);

}  // namespace lockstep::sensors
