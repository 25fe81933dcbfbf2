#pragma once
// Helpers for a service's blueprint declarations (blueprint.idl), so each service writes
// its actor types as data: Blueprint("vehicle.tesla.model3", ACTOR_VEHICLE, {...}).
#include <cstdint>
#include <limits>
#include <string>
#include <vector>

#include "lockstep/msg/blueprint.h"

namespace lockstep::blueprint {

inline constexpr double kInf = std::numeric_limits<double>::infinity();

msg::AttributeDeclaration Bool(const std::string& id, bool def, bool modifiable = true);
msg::AttributeDeclaration Int(const std::string& id, int64_t def, double min = -kInf, double max = kInf,
                              bool modifiable = true);
msg::AttributeDeclaration Float(const std::string& id, double def, double min = -kInf, double max = kInf,
                                bool modifiable = true);
// recommended: CARLA's recommended values; restricted: the value must be one of them.
msg::AttributeDeclaration String(const std::string& id, const std::string& def,
                                 const std::vector<std::string>& recommended = {}, bool restricted = false,
                                 bool modifiable = true);
msg::AttributeDeclaration Rgb(const std::string& id, const std::string& def,
                              const std::vector<std::string>& recommended = {}, bool modifiable = true);

// tags: comma-separated; empty = the id's dot-separated parts.
msg::BlueprintDeclaration Make(const std::string& id, msg::ActorKind kind,
                               std::vector<msg::AttributeDeclaration> attributes, const std::string& tags = {},
                               double half_x = 0, double half_y = 0, double half_z = 0);

// Empty if `value` is valid for `decl`, else why not, naming the attribute.
std::string CheckValue(const msg::AttributeDeclaration& decl, const std::string& value);

}  // namespace lockstep::blueprint
