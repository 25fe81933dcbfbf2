#pragma once
// Small builders for the wire types clients send most: poses, spawn requests and the
// bodies of one-actor commands; and the services' command-failed event.
#include <string>
#include <utility>
#include <vector>

#include "lockstep/runtime/messages.h"

namespace lockstep {

using AttributeList = std::vector<std::pair<std::string, std::string>>;

// World ENU position (m) and heading (rad, 0 = east, counter-clockwise).
msg::Pose MakePose(double x, double y, double z, double yaw = 0);
std::vector<msg::BlueprintAttribute> MakeAttributes(const AttributeList& attributes);
msg::CommandBody SpawnBody(const std::string& blueprint, const msg::Pose& pose, const AttributeList& attributes = {},
                           uint32_t parent = 0);

// Bodies of the one-actor commands that playback, scenarios, benchmarks and tests send.
msg::CommandBody TransformBody(uint32_t actor, const msg::Pose& pose);     // set_transform (world ENU)
msg::CommandBody SimulatePhysicsBody(uint32_t actor, bool on);            // set_simulate_physics
msg::CommandBody AutopilotBody(uint32_t actor, bool on);                  // Traffic Manager autopilot
msg::CommandBody VehicleLightsBody(uint32_t actor, uint32_t light_state); // carla.VehicleLightState bits
// A traffic light's state (its green/yellow/red times kept), frozen there or running again.
msg::CommandBody TrafficLightBody(uint32_t actor, msg::TrafficLightColor state, bool freeze);
// The recorder's and replayer's commands: name = log file (start_recorder, replay_file),
// flag by action (additional_data, keep_actors, ...).
msg::CommandBody RecorderBody(msg::RecorderAction action, const std::string& name = "", bool flag = false);

// A service's SimEvent EVENT_COMMAND_FAILED: an accepted command it could not apply to
// `actor`, the reason cut to the wire's 511 characters; stamped with the frame's stamp.
msg::SimEvent CommandFailedEvent(const std::string& service, uint32_t actor, const std::string& why,
                                 const msg::FrameStamp& stamp = {});

// Human-readable run state ("running", "faulted", ...).
const char* RunStateName(msg::RunState state);

}  // namespace lockstep
