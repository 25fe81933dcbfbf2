#pragma once
// Traffic lights and Traffic Manager parameters (CARLA's names and defaults).
#include <cmath>
#include <cstdint>
#include <limits>
#include <string>
#include <vector>

#include "lockstep/ground/types.h"

namespace lockstep::ground {

enum class LightColor { kRed, kYellow, kGreen, kOff, kUnknown };

struct LightState {
  LightColor color = LightColor::kRed;
  double elapsed = 0;         // s in the current colour
  double green_time = 10;     // s, CARLA's defaults
  double yellow_time = 3;
  double red_time = 2;        // s of all-red before the group's next light turns green
  bool frozen = false;
  int group = 0;
};

// Global parameters: carla.TrafficManager setters with CARLA's defaults
// (../shared/reference/carla_constants.json traffic_manager_defaults).
struct TmGlobal {
  double distance_to_leading_vehicle = 2.0;   // m
  double percentage_speed_difference = 0.0;   // % below the speed limit
  double ignore_lights_percentage = 0;
  double ignore_signs_percentage = 0;
  double ignore_vehicles_percentage = 0;
  double ignore_walkers_percentage = 0;
  bool auto_lane_change = true;
  double keep_right_percentage = 0;
  double random_left_lanechange_percentage = 0;
  double random_right_lanechange_percentage = 0;
  bool hybrid_physics_mode = false;
  double hybrid_physics_radius = 70.0;        // m, CARLA's Parameters.h (the docs' 50 is the setter's example)
  uint64_t random_seed = 0;                   // deterministic seed (0 = the run seed)
  bool synchronous_mode = true;               // always lock-step here
  double blocked_time_threshold = 90.0;       // s, then respawned
  double red_light_blocked_time_threshold = 180.0;
  bool respawn_dormant_vehicles = false;
  double lane_offset = 0;                     // m from the lane centre, > 0 right (CARLA's global_lane_offset)
  // set_boundaries_respawn_dormant_vehicles: a dormant vehicle respawns this far from the
  // hero (CARLA's Parameters.h defaults; set values are clamped to kRespawnMinLowerBound and
  // actor_active_distance, as CARLA's SetMaxBoundaries).
  double respawn_lower_bound = 100.0;         // m
  double respawn_upper_bound = 1000.0;        // m
  // CARLA's world setting actor_active_distance (not on the wire: its default): a vehicle
  // farther than this from every hero is dormant (CARLA: large maps only).
  double actor_active_distance = 2000.0;      // m
};

inline constexpr double kRespawnMinLowerBound = 20.0;  // m, CARLA: SetMaxBoundaries(20, actor_active_distance)

inline constexpr double kUnset = std::numeric_limits<double>::quiet_NaN();

// Per-vehicle overrides; NaN = use the global value.
struct TmVehicleParams {
  double distance_to_leading_vehicle = kUnset;
  double percentage_speed_difference = kUnset;
  double desired_speed = kUnset;              // m/s (set_desired_speed), overrides the limit
  double ignore_lights_percentage = kUnset;
  double ignore_signs_percentage = kUnset;
  double ignore_vehicles_percentage = kUnset;
  double ignore_walkers_percentage = kUnset;
  double auto_lane_change = kUnset;           // 1 / 0
  double keep_right_percentage = kUnset;
  double random_left_lanechange_percentage = kUnset;
  double random_right_lanechange_percentage = kUnset;
  double lane_offset = kUnset;                // m, > 0 right (vehicle_lane_offset)
  bool update_lights = false;                 // update_vehicle_lights: the TM drives its lights (CARLA: off)
};

// The TM parameter names accepted by World::SetTrafficManager (CARLA's setter names).
enum class TmParam {
  kDistanceToLeadingVehicle,
  kPercentageSpeedDifference,
  kDesiredSpeed,
  kIgnoreLightsPercentage,
  kIgnoreSignsPercentage,
  kIgnoreVehiclesPercentage,
  kIgnoreWalkersPercentage,
  kAutoLaneChange,
  kKeepRightPercentage,
  kRandomLeftLaneChangePercentage,
  kRandomRightLaneChangePercentage,
  kHybridPhysicsMode,
  kHybridPhysicsRadius,
  kRandomSeed,
  kRespawnDormantVehicles,
  kSynchronousMode,
  kLaneOffset,                                // m from the lane centre, > 0 right; vehicle 0 = global
};

}  // namespace lockstep::ground
