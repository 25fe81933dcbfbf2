#pragma once
// The ground world: vehicles (ODE rigid bodies on ray-cast suspension, or kinematic far
// from the hero), walkers (kinematic capsules), traffic lights and the Traffic Manager,
// stepped deterministically. No DDS: the service maps wire commands onto these calls.
#include <cstdint>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "lockstep/ground/blueprints.h"
#include "lockstep/ground/town.h"
#include "lockstep/ground/traffic.h"
#include "lockstep/ground/types.h"
#include "lockstep/map/lane_invasion.h"

namespace lockstep::ground {

// CARLA's world settings for physics sub-stepping.
struct PhysicsSettings {
  bool substepping = true;
  double max_substep_delta_time = 0.01;  // s
  int max_substeps = 10;
};

// A collision of one actor during the last step (one per actor and other object).
struct Collision {
  uint32_t actor = 0;
  uint32_t other_actor = 0;       // 0 for static geometry
  ObjectKind other_kind = ObjectKind::kNone;
  uint8_t other_semantic_tag = 0; // CARLA palette id of the other object
  Vec3 normal_impulse = Vec3::Zero();  // N s on `actor`, world
};

struct LaneInvasion {
  uint32_t actor = 0;
  std::vector<map::LaneMarking> crossed;
};

// Infractions the 2017 benchmark and the leaderboard count, per vehicle, cumulative.
struct Infractions {
  int red_lights = 0;             // entered a junction from a lane whose light was red
  int vehicle_collisions = 0;
  int walker_collisions = 0;
  int static_collisions = 0;
  int lane_invasions = 0;
  int stop_signs = 0;             // crossed a stop sign's line without a full stop first
  // The 2017 benchmark's intersections (CARLA 0.8 driving_benchmark thresholds): onsets of
  // more than 40 % of the footprint on the opposite lane, more than 30 % off the road
  // (sidewalk or no lane).
  int opposite_lane = 0;
  int offroad = 0;
  double distance = 0;            // m driven (horizontal), for distance between infractions
};

inline constexpr double kOppositeLaneThreshold = 0.4;  // CARLA 0.8 intersection_otherlane
inline constexpr double kOffroadThreshold = 0.3;       // CARLA 0.8 intersection_offroad

struct VehicleView {
  uint32_t id = 0;
  std::string blueprint;
  std::string role_name;
  Pose pose;                      // bounding-box centre
  Vec3 half_extents = Vec3::Zero();
  Vec3 velocity = Vec3::Zero();
  Vec3 angular_velocity = Vec3::Zero();
  Vec3 acceleration = Vec3::Zero();
  VehicleControl control;         // last applied (the TM's when on autopilot)
  bool autopilot = false;
  bool kinematic = false;         // hybrid mode or simulate_physics off
  double speed_limit = 0;         // m/s
  uint32_t traffic_light = 0;     // actor id of the light ahead governing it, 0 = none
  double stop_line_distance = -1; // m to that light's stop line, -1 = none
  double opposite_lane = 0;       // fraction of the footprint on the opposite lane
  double sidewalk = 0;            // fraction on the sidewalk
  double offroad = 0;             // fraction off the drivable road (sidewalk or no lane)
  uint32_t light_state = 0;       // carla.VehicleLightState bits
  int gear = 0;
  Infractions infractions;
};

struct WalkerView {
  uint32_t id = 0;
  std::string blueprint;
  Pose pose;                      // capsule centre
  Vec3 half_extents = Vec3::Zero();
  Vec3 velocity = Vec3::Zero();
  bool ai_controlled = false;
  WalkerControl control;
};

struct LightView {
  uint32_t id = 0;                // actor id (light index + 1)
  map::Transform pose;
  LightState state;
  std::string opendrive_id;
};

// What the Traffic Manager's vehicle lights follow (carla.WeatherParameters fields).
struct LightWeather {
  double sun_altitude_angle = 45;  // deg
  double precipitation = 0;        // 0..100
  double fog_density = 0;          // 0..100
};
// CARLA's light stage: the light bits a TM vehicle with update_vehicle_lights gets from
// `current` under `weather` with the TM's brake command `brake`.
uint32_t TmLightState(uint32_t current, const LightWeather& weather, double brake);

// The spawn check's overlap test: the box `half` at `pose` (with a 0.2 m margin) against the
// box `other_half` at `other` (yawed rectangles; heights within 2 m).
bool SpawnOverlaps(const Pose& pose, const Vec3& half, const Pose& other, const Vec3& other_half);

// Another simulator's body (a drone from air_sim, Jacobi: its pose of the previous frame).
struct ExternalBody {
  uint32_t id = 0;
  ObjectKind kind = ObjectKind::kDrone;
  Pose pose;
  Vec3 velocity = Vec3::Zero();
  Vec3 half_extents = Vec3::Zero();  // m, the box its simulator gives (a drone's: lockstep/runtime/wire_geometry.h)
  double mass = 1.0;              // kg: a dynamic body of that mass within the step
};

class World {
 public:
  World(std::shared_ptr<const Town> town, uint64_t seed, PhysicsSettings settings = {});
  ~World();
  World(const World&) = delete;
  World& operator=(const World&) = delete;

  const Town& town() const;
  uint64_t seed() const;
  uint64_t frame() const;         // steps taken
  void SetPhysicsSettings(const PhysicsSettings& s);

  // Actors. Each returns "" on success, else why not (nothing changes then).
  std::string AddVehicle(uint32_t id, const std::string& blueprint, const std::map<std::string, std::string>& attributes,
                         const Pose& pose);
  std::string AddWalker(uint32_t id, const std::string& blueprint, const std::map<std::string, std::string>& attributes,
                        const Pose& pose);
  std::string AddWalkerController(uint32_t id, uint32_t walker);
  // CARLA's try_spawn_actor: "" if the box at `pose` is free of vehicles and walkers.
  std::string CheckFree(const Pose& pose, const Vec3& half_extents) const;
  // A static box for another service's actor (a prop whose blueprint declares a bounding
  // box): vehicles collide with it (events name it, kind static, tag Static), walkers are
  // blocked by it. Removed by Remove(id).
  std::string AddProp(uint32_t id, const Pose& pose, const Vec3& half_extents);
  bool IsProp(uint32_t id) const;
  bool Remove(uint32_t id);
  bool Has(uint32_t id) const;
  bool IsVehicle(uint32_t id) const;
  bool IsWalker(uint32_t id) const;
  bool IsController(uint32_t id) const;

  std::string SetTransform(uint32_t id, const Pose& pose);
  std::string ApplyControl(uint32_t id, const VehicleControl& c);
  std::string ApplyAckermann(uint32_t id, const AckermannControl& c);
  std::string ApplyWalkerControl(uint32_t id, const WalkerControl& c);
  std::string SetTargetVelocity(uint32_t id, const Vec3& v);
  std::string SetTargetAngularVelocity(uint32_t id, const Vec3& w);
  std::string AddImpulse(uint32_t id, const Vec3& impulse);
  std::string SetSimulatePhysics(uint32_t id, bool on);
  std::string SetVehiclePhysics(uint32_t id, const VehiclePhysics& p);
  std::optional<VehiclePhysics> GetVehiclePhysics(uint32_t id) const;
  std::string SetLightState(uint32_t vehicle, uint32_t bits);
  // TrafficManager.update_vehicle_lights: the TM sets the vehicle's lights each step
  // (TmLightState) while it drives it.
  std::string SetUpdateVehicleLights(uint32_t vehicle, bool on);
  // The weather the TM's vehicle lights follow (part of the state).
  void SetWeather(const LightWeather& weather);

  // Traffic lights by actor id (1..n).
  std::string SetTrafficLight(uint32_t id, std::optional<LightColor> color, double green, double yellow, double red,
                              std::optional<bool> freeze);
  void FreezeAllLights(bool freeze);
  // CARLA's TrafficLight.reset_group: the light's group back to the start of its cycle
  // (every light red, then the group's first light green, elapsed 0; times and freeze kept).
  std::string ResetLightGroup(uint32_t id);
  // CARLA's world.reset_all_traffic_lights: ResetLightGroup for every group.
  void ResetAllLights();

  // Traffic Manager.
  std::string SetAutopilot(uint32_t vehicle, bool on);
  std::string SetTrafficManager(TmParam p, uint32_t vehicle, double value);  // vehicle 0 = global
  std::string SetPath(uint32_t vehicle, const std::vector<Vec3>& locations);
  std::string SetRoute(uint32_t vehicle, const std::vector<std::string>& options);  // Left/Right/Straight
  std::string ForceLaneChange(uint32_t vehicle, bool left);
  // CARLA's collision_detection(reference, other, detect): with detect false the TM vehicle
  // `vehicle` ignores `other` (any actor id) as a hazard (car following, walkers, junction
  // conflicts); true (the default) avoids it again. One way: `other` still avoids `vehicle`.
  std::string SetCollisionDetection(uint32_t vehicle, uint32_t other, bool detect);
  // CARLA's set_boundaries_respawn_dormant_vehicles: lower clamped up to 20 m, upper down to
  // actor_active_distance (CARLA's Parameters::SetBoundariesRespawnDormantVehicles).
  std::string SetRespawnBoundaries(double lower, double upper);
  const TmGlobal& TrafficManager() const;

  // Walker AI controllers (controller.ai.walker) by controller id.
  std::string ControllerStart(uint32_t controller);
  std::string ControllerStop(uint32_t controller);
  std::string ControllerGoTo(uint32_t controller, const Vec3& location);
  std::string ControllerMaxSpeed(uint32_t controller, double speed);
  // CARLA's world.set_pedestrians_cross_factor: the share (0..1) of AI walkers that cross
  // the road at a crosswalk they reach (when its lights, if any, are red for vehicles;
  // else when no vehicle approaches within 25 m). Default 0.5.
  std::string SetPedestriansCrossFactor(double factor);
  // CARLA's world.set_pedestrians_seed: every walker AI controller's generator (those that
  // exist and those spawned later) restarts from this seed mixed with the run seed and the
  // controller id. Without it they draw from the run seed and their id.
  void SetPedestriansSeed(uint64_t seed);

  // Bodies of other simulators for this step (replaces the previous set).
  void SetExternalBodies(std::vector<ExternalBody> bodies);

  // Advances by dt (s): TM and walker AI, lights, physics sub-steps, events.
  void Step(double dt);

  // After a step.
  const std::vector<Collision>& Collisions() const;
  const std::vector<LaneInvasion>& LaneInvasions() const;
  std::vector<VehicleView> Vehicles() const;
  std::vector<WalkerView> Walkers() const;
  std::vector<LightView> Lights() const;
  std::optional<VehicleView> Vehicle(uint32_t id) const;
  std::optional<WalkerView> Walker(uint32_t id) const;

  uint64_t StateHash() const;
  std::vector<uint8_t> Save() const;
  // Rebuilds a world saved by Save() on the same town; throws std::runtime_error if the
  // bytes are not a ground state of this town.
  static std::unique_ptr<World> Restore(std::shared_ptr<const Town> town, const std::vector<uint8_t>& bytes);

  struct Impl;

 private:
  std::unique_ptr<Impl> impl_;
};

// Seeded population (CARLA's generate_traffic.py): vehicles at shuffled spawn points on
// autopilot, walkers at pedestrian spawn points with AI controllers. Ids from first_id.
struct PopulationReport {
  std::vector<uint32_t> vehicles, walkers, controllers;
  int vehicle_failures = 0;      // spawn point occupied (try_spawn_actor returned None)
};
PopulationReport Populate(World* world, int vehicles, int walkers, uint64_t seed, uint32_t first_id,
                          const std::vector<std::string>& vehicle_blueprints = {});

}  // namespace lockstep::ground
