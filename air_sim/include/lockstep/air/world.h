// The air simulation core (MuJoCo style): an immutable model (World), a mutable state
// (WorldState), per-tick inputs (Commands, Environment) and one step function.
//
//   World model;                       AddDrone(&model, 1, params, spawn)
//   WorldState state = MakeState(model);
//   Step(model, &state, commands, env, 0.05);   // sub-steps at model.physics_dt
//
// No DDS, no YAML, no wall clock and no global state inside Step.
#pragma once

#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include "lockstep/air/collision.h"
#include "lockstep/air/commands.h"
#include "lockstep/air/controller.h"
#include "lockstep/air/params.h"

namespace lockstep::air {

// ---------------------------------------------------------------- model (immutable in Step)
struct DroneModel {
  DroneId id = 0;
  MultirotorParams params;
  DerivedParams derived;  // from DeriveParams(params)
  Pose spawn;             // world ENU; AirSim NED coordinates are relative to spawn.position
};

struct World {
  std::vector<DroneModel> drones;   // sorted by id; stepped in this order
  StaticGeometry statics;           // ground plane + town mesh
  double physics_dt = 0.001;        // s, sub-step (1 kHz); a tick dt is split into
                                    // round(dt / physics_dt) equal sub-steps
  double gravity = 9.80665;         // m/s^2, along -z
  std::uint64_t seed = 0;           // run seed; per-drone generators derive from (seed, id)
  double restitution_threshold = 0.3;  // m/s: slower impacts do not bounce (resting contact)
  bool drone_collisions = true;     // drones collide with each other (Jacobi: each sees the
                                    // others' tick-start pose, extrapolated by velocity)

  const DroneModel* Find(DroneId id) const;
};

// ------------------------------------------------------------------- inputs of one tick
struct Environment {
  Vec3 wind = Vec3::Zero();         // m/s, world ENU, mean wind (drag acts on v - wind)
  double air_density = 1.225;       // kg/m^3 (thrust, torque and drag scale with it)
  double turbulence_sigma = 0;      // m/s, std-dev of a Gauss-Markov gust per drone (seeded)
  double turbulence_tau = 2.0;      // s, gust correlation time
  std::vector<VehicleBox> vehicles; // vehicles at frame k (extrapolated across the tick)
};

// ------------------------------------------------------------------------ mutable state
enum class LandedState : std::uint8_t { kLanded = 0, kFlying = 1 };  // AirSim values

struct CollisionInfo {                  // AirSim CollisionInfo, last collision of the drone
  bool has_collided = false;
  ObjectKind kind = ObjectKind::kNone;  // what was hit
  std::uint32_t object_id = 0;          // vehicle id / mesh id / 0 ground
  Vec3 normal = Vec3::UnitZ();          // unit, world ENU, from the object to the drone
  Vec3 impact_point = Vec3::Zero();     // m, world ENU
  Vec3 position = Vec3::Zero();         // m, world ENU, drone position at impact
  double penetration_depth = 0;         // m
  double impact_speed = 0;              // m/s, approach speed along the normal
  double time = 0;                      // s, sim time
  std::uint64_t frame = 0;              // tick index
  std::uint64_t collision_count = 0;    // number of contact onsets so far
};

struct RotorState {
  double command = 0;   // 1, control signal asked by the controller [0, 1]
  double signal = 0;    // 1, after the first-order motor lag
  double speed = 0;     // rad/s
  double thrust = 0;    // N, along body +z
  double torque = 0;    // N m, reaction torque magnitude
};

struct RandomState {    // xoshiro256** state; seeded from (seed, drone id)
  std::array<std::uint64_t, 4> s{};
};

enum class CommandMode : std::uint8_t {
  kIdle,            // motors off (disarmed, just armed, or landed after Land)
  kHold,            // hold hold_position / yaw_ref
  kTakeoff, kLand, kPath, kTrack, kVelocity, kVelocityZ, kRpyThrottle, kRpyZ,
  kRpyRateThrottle, kRatesThrottle, kRatesZ, kPwm, kRotateToYaw, kRotateByYawRate, kRpyRateZ
};

struct ActiveCommand {
  CommandId id = 0;
  CommandMode mode = CommandMode::kIdle;
  bool running = false;          // a RUNNING command is attached
  double start_time = 0;         // s
  double end_time = 0;           // s, duration end or timeout
  CommandBody body;              // copy of the command
  // Reference generator of path-like commands (takeoff, land, path, go home).
  std::vector<Vec3> path;        // m, world ENU, first point = position at command start
  std::vector<double> path_s;    // m, cumulative length
  std::vector<double> path_vmax; // m/s, speed allowed at each vertex (corners, end)
  double s = 0;                  // m, reference progress
  double s_dot = 0;              // m/s
  std::size_t segment = 1;       // index of the first vertex ahead of s
  double speed = 0;              // m/s, cruise
  double lookahead = 0;          // m
  double adaptive_lookahead = 0; // s
  Vec3 velocity = Vec3::Zero();  // m/s world (velocity commands, converted at start)
  Vec3 target = Vec3::Zero();    // m world (track / hold)
  double landed_since = -1;      // s, Land / RotateToYaw: time the completion condition began
};

struct DroneState {
  DroneId id = 0;
  // Rigid body.
  Vec3 position = Vec3::Zero();          // m, world ENU, centre of mass
  Quat orientation = Quat::Identity();   // body FLU -> world ENU
  Vec3 velocity = Vec3::Zero();          // m/s, world ENU
  Vec3 angular_velocity = Vec3::Zero();  // rad/s, body FLU
  Vec3 acceleration = Vec3::Zero();      // m/s^2, world ENU, last sub-step (incl. contact)
  Vec3 angular_acceleration = Vec3::Zero();  // rad/s^2, body FLU
  std::array<RotorState, kMaxRotors> rotors{};  // first RotorCount(frame) used
  double total_thrust = 0;               // N, sum over rotors
  bool armed = false;
  bool api_control = true;               // AirSim API control (cmd::SetApiControl); Lockstep's own
                                         // commands find it on, the airsim clients spawn without it
  // A motion command accepted without API control: it steers nothing and ends as AirSim's
  // call does, after its duration (COMPLETED) or its timeout (TIMED_OUT); Land completes once
  // the drone does not descend (<= 0.05 m/s) for 0.22 s, Hover and a goal already reached at once.
  struct Unsteered {
    CommandId id = 0;
    bool running = false;
    enum class Ends : std::uint8_t { kDuration, kTimeout, kLand } ends = Ends::kDuration;
    double end_time = 0;                 // s
    double still_since = -1;             // s, kLand: when the drone stopped descending
    // On API control taken back before it ends, the command steers again, as AirSim's loop
    // (still running) then gets its goals accepted: a command released mid-run goes on from
    // where it was (`resume`, its mode; the ActiveCommand kept its state); one issued without
    // API control (resume kIdle; the ActiveCommand holds its id and body) starts then, its
    // deadline still counted from `start_time`.
    CommandMode resume = CommandMode::kIdle;
    double start_time = 0;               // s
  } unsteered;
  LandedState landed = LandedState::kLanded;
  bool grounded = false;                 // AirSim ground lock: levelled, moving with the surface
                                         // under it, until thrust exceeds weight
  std::uint32_t carrier = 0;             // grounded on this vehicle (0: none) ...
  Vec3 carrier_offset = Vec3::Zero();    // m, ... at this position in its box frame,
  double carrier_yaw = 0;                // rad, ... and this yaw relative to its heading
  double last_support_time = -1;         // s, last contact with a supporting surface
  Vec3 support_velocity = Vec3::Zero();  // m/s, velocity of that surface
  CollisionInfo collision;
  struct Touch {
    ObjectKind kind = ObjectKind::kNone;
    std::uint32_t id = 0;
    double time = -1;
  };
  std::array<Touch, 8> touching{};       // recent contacts (onset detection)
  ControllerState controller;
  ActiveCommand command;
  Vec3 gust = Vec3::Zero();              // m/s, world ENU, turbulence state
  RandomState rng;
  std::uint64_t reset_count = 0;         // non-finite resets so far
};

enum class EventKind : std::uint8_t {
  kCollision,   // contact onset with an object
  kReset,       // non-finite or runaway state: drone reset to its spawn pose
  kLanded,      // FLYING -> LANDED
  kTookOff      // LANDED -> FLYING
};
const char* ToString(EventKind k);

struct AirEvent {
  EventKind kind = EventKind::kCollision;
  DroneId drone = 0;
  double time = 0;                      // s
  std::uint64_t frame = 0;              // tick index
  ObjectKind object_kind = ObjectKind::kNone;
  std::uint32_t object_id = 0;
  Vec3 position = Vec3::Zero();         // m, world ENU (drone, or impact point for collisions)
  Vec3 normal = Vec3::Zero();           // collisions
  double impact_speed = 0;              // m/s
  std::string message;                  // kReset: what was non-finite
};

struct WorldState {
  std::uint64_t frame = 0;               // ticks stepped
  double time = 0;                       // s, sim time
  std::vector<DroneState> drones;        // parallel to World::drones
  std::vector<CommandReport> reports;    // command status changes of the last Step
  std::vector<AirEvent> events;          // events of the last Step

  // Scratch rebuilt by every Step (kept here so that stepping does not allocate): each drone's
  // state at the tick start, and for each drone the other drones it may touch in this tick.
  struct Proximity {
    std::vector<Pose> pose;                // tick-start pose per drone index
    std::vector<Vec3> velocity;            // tick-start velocity per drone index
    std::vector<double> reach;             // bounding radius + travel in the tick
    std::vector<std::uint32_t> order;      // drone indices sorted by x
    std::vector<std::uint32_t> start;      // CSR offsets into others (size drones + 1)
    std::vector<std::uint32_t> others;     // neighbour drone indices
    std::vector<std::uint32_t> count;      // per-drone fill counter
  } proximity;

  DroneState* Find(DroneId id);
  const DroneState* Find(DroneId id) const;
};

// ------------------------------------------------------------------------------- API
// Adds a drone (sorted by id) to the model and, if state != nullptr, its initial state resting
// at `spawn`, disarmed. Throws std::invalid_argument (duplicate id, bad params, bad pose).
void AddDrone(World* model, WorldState* state, DroneId id, const MultirotorParams& params,
              const Pose& spawn);
// Removes a drone; returns false if unknown.
bool RemoveDrone(World* model, WorldState* state, DroneId id);
// Initial state for every drone of the model.
WorldState MakeState(const World& model);
DroneState MakeDroneState(const World& model, const DroneModel& drone);

// Empty when the command can be applied; otherwise why not ("drone 7: unknown drone id").
std::string ValidateCommand(const World& model, const WorldState& state, const Command& c);

// Advances the state by one tick of dt seconds: applies `commands` in order (invalid ones are
// reported kRejected and skipped), then sub-steps every drone in id order at model.physics_dt:
// controller -> rotors -> forces -> integration -> contacts. Fills state->reports and
// state->events (cleared first); frame += 1; time += dt. Throws std::invalid_argument only for a
// bad dt (<= 0 or non-finite).
void Step(const World& model, WorldState* state, const Commands& commands,
          const Environment& env, double dt);

// AirSim-shaped views (NED relative to spawn, FRD body).
struct AirSimKinematics {
  Vec3 position;            // m, NED from spawn
  Quat orientation;         // FRD -> NED
  Vec3 linear_velocity;     // m/s, NED
  Vec3 angular_velocity;    // rad/s, FRD body
  Vec3 linear_acceleration; // m/s^2, NED
};
AirSimKinematics ToAirSim(const DroneModel& model, const DroneState& s);
struct AirSimCollisionInfo {     // AirSim's CollisionInfo fields
  bool has_collided = false;
  Vec3 normal = Vec3::Zero();        // NED
  Vec3 impact_point = Vec3::Zero();  // m, NED from spawn
  Vec3 position = Vec3::Zero();      // m, NED from spawn
  double penetration_depth = 0;      // m
  std::uint64_t time_stamp_ns = 0;   // sim time, ns
  std::string object_name;           // "ground", "static_<mesh id>", "vehicle_<actor id>"
  std::int64_t object_id = -1;
  std::uint64_t collision_count = 0;
};
AirSimCollisionInfo ToAirSim(const DroneModel& model, const CollisionInfo& c);

// Order-sensitive FNV-1a hash (bitwise) of everything a later step depends on: frame and time;
// per drone the rigid body, rotors, contact memory, controller memory and gains, the active
// command and its reference, the gust and the random generator state.
std::uint64_t StateHash(const WorldState& state);

}  // namespace lockstep::air
