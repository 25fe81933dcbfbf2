#pragma once
// The actor types ground_sim simulates, with CARLA's ids and attributes (0.9.15 library).
#include <map>
#include <string>
#include <vector>

#include "lockstep/ground/types.h"

namespace lockstep::ground {

struct VehicleSpec {
  std::string id;                   // e.g. "vehicle.tesla.model3"
  BaseType base_type = BaseType::kCar;
  int wheels = 4;                   // number_of_wheels
  int generation = 2;
  Vec3 half_extents = Vec3(2.3, 1.0, 0.75);  // m, CARLA's bounding box
  std::vector<std::string> colors;  // recommended "r,g,b" values; first = default
  std::string special_type;         // "", "electric", "emergency", "taxi"
  bool has_lights = true;
  VehiclePhysics physics;
};

struct WalkerSpec {
  std::string id;                   // e.g. "walker.pedestrian.0001"
  double height = 1.8;              // m
  double radius = 0.3;              // m, capsule (CARLA's bounding box half width)
  double walk_speed = 1.4;          // m/s, recommended "speed" values: walking, running
  double run_speed = 2.8;
  std::string gender = "male";      // male | female
  std::string age = "adult";        // adult | child
  int generation = 2;
};

const std::vector<VehicleSpec>& VehicleCatalog();
const std::vector<WalkerSpec>& WalkerCatalog();
const VehicleSpec* FindVehicle(const std::string& id);
const WalkerSpec* FindWalker(const std::string& id);

inline constexpr const char* kWalkerControllerBlueprint = "controller.ai.walker";

// Spawn attributes applied to a spec: role_name, color, speed, is_invincible, ...
// Throws InvalidAttribute (std::invalid_argument) naming the attribute.
struct SpawnAttributes {
  std::string role_name;
  std::string color;
  double walker_speed = 0;          // m/s, 0 = the blueprint's walking speed
  bool invincible = true;
  bool sticky_control = true;
};
SpawnAttributes ParseSpawnAttributes(const std::map<std::string, std::string>& attributes);

}  // namespace lockstep::ground
