#pragma once
// Small builders for the wire types clients send most: poses and spawn requests.
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

// Human-readable run state ("running", "faulted", ...).
const char* RunStateName(msg::RunState state);

}  // namespace lockstep
