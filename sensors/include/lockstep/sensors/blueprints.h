#pragma once
// The sensor blueprints this service simulates: CARLA's ids, attribute names and
// defaults; AirSim's models and defaults where CARLA has none (docs/sensors.md). Plain
// data, so the service declares exactly what the core accepts.
#include <cstdint>
#include <limits>
#include <map>
#include <string>
#include <vector>

namespace lockstep::sensors {

enum class AttrType { kBool, kInt, kFloat, kString };

struct AttributeSpec {
  std::string id;
  AttrType type = AttrType::kFloat;
  std::string default_value;
  double min = -std::numeric_limits<double>::infinity();  // inclusive, int and float
  double max = std::numeric_limits<double>::infinity();
  std::vector<std::string> choices = {};  // strings: the only values accepted (CARLA's restricted recommended values); empty = any
};

enum class SensorType { kLidar, kSemanticLidar, kRadar, kImu, kGnss, kBarometer, kMagnetometer, kDistance, kObstacle,
                        kCollision, kLaneInvasion, kV2X, kCustomV2X };

struct SensorBlueprint {
  std::string id;                 // e.g. "sensor.lidar.ray_cast"
  SensorType type;
  std::vector<AttributeSpec> attributes;
};

const std::vector<SensorBlueprint>& SensorBlueprints();
const SensorBlueprint* FindSensorBlueprint(const std::string& id);  // nullptr if not ours

// A blueprint's attributes with the client's values over the defaults, each checked.
class Attributes {
 public:
  double Float(const std::string& id) const;
  int64_t Int(const std::string& id) const;
  bool Bool(const std::string& id) const;
  const std::string& String(const std::string& id) const;
  bool Given(const std::string& id) const { return given_.count(id) > 0; }

 private:
  friend std::string ResolveAttributes(const SensorBlueprint&, const std::map<std::string, std::string>&, Attributes*);
  std::map<std::string, std::string> values_;
  std::map<std::string, bool> given_;
};

// Empty on success, else why the attributes are rejected (naming the attribute).
std::string ResolveAttributes(const SensorBlueprint& bp, const std::map<std::string, std::string>& given, Attributes* out);

}  // namespace lockstep::sensors
