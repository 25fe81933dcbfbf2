#pragma once
// The blueprint library: what a client may spawn and which attributes each blueprint
// takes, with their types and ranges. Spawn requests are checked against it.
#include <limits>
#include <string>
#include <vector>

#include "lockstep/msg/common.h"

namespace lockstep {

enum class ActorKind { kVehicle, kWalker, kDrone, kSensor, kTrafficLight };
const char* ActorKindName(ActorKind kind);

enum class AttributeType { kBool, kInt, kFloat, kString, kRgb };

struct AttributeDef {
  std::string name;
  AttributeType type = AttributeType::kString;
  std::string default_value;
  double min = -std::numeric_limits<double>::infinity();  // for int and float
  double max = std::numeric_limits<double>::infinity();
  std::vector<std::string> options;  // allowed values for strings; empty = any
};

struct Blueprint {
  std::string id;  // e.g. "vehicle.lockstep.sedan"
  ActorKind kind = ActorKind::kVehicle;
  std::vector<AttributeDef> attributes;
};

class BlueprintLibrary {
 public:
  static BlueprintLibrary Default();
  void Add(Blueprint bp);
  const Blueprint* Find(const std::string& id) const;
  const std::vector<Blueprint>& all() const { return blueprints_; }
  // Empty if every attribute is known and its value parses as its type within range;
  // otherwise the reason, naming the attribute.
  std::string Check(const Blueprint& bp, const std::vector<msg::BlueprintAttribute>& attributes) const;

 private:
  std::vector<Blueprint> blueprints_;
};

}  // namespace lockstep
