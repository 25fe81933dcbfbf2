#pragma once
// Conversions between the wire types (idl/) and the ground core's types, and the
// blueprint declarations ground_sim publishes.
#include <optional>
#include <vector>

#include "lockstep/ground/world.h"
#include "lockstep/runtime/messages.h"
#include "lockstep/runtime/wire_geometry.h"

namespace lockstep::ground_wire {

// Vectors and poses: the runtime's converters (lockstep/runtime/wire_geometry.h).
using wire::FromPose;
using wire::FromVec;
using wire::ToVec;
inline ground::Pose ToPose(const msg::Pose& p) { return wire::ToPose<ground::Pose>(p); }
msg::VehiclePhysicsControl ToWire(const ground::VehiclePhysics& p);
ground::VehiclePhysics FromWire(const msg::VehiclePhysicsControl& p);
msg::LaneMarking ToWire(const map::LaneMarking& m);
msg::ObjectKind ToWire(ground::ObjectKind k);
msg::TrafficLightColor ToWire(ground::LightColor c);
std::optional<ground::LightColor> FromWire(msg::TrafficLightColor c);
std::optional<ground::TmParam> FromWire(msg::TrafficManagerParameter p);
// A vehicle's state on the wire (all but its physics control).
msg::VehicleState ToWire(const ground::VehicleView& v);

// CARLA-compatible vehicles and walkers, and controller.ai.walker.
std::vector<msg::BlueprintDeclaration> Blueprints();

}  // namespace lockstep::ground_wire
