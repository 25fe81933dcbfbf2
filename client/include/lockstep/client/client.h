#pragma once
// The C++ client of a running Lockstep simulation: the world (settings, ticks, weather,
// reset, maps), actors (spawn, destroy, state), batches of commands with per-command
// replies, sensors (listen / stop with the no-lost-frames guarantee) and drones
// (lockstep/client/multirotor.h). Everything goes over the DDS topics of idl/; Fast DDS
// stays behind the runtime's Bus. Poses are world ENU, metres, radians (the wire's
// convention); the Python layers convert to CARLA's and AirSim's.
#include <cstdint>
#include <functional>
#include <memory>
#include <optional>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "lockstep/client/blueprint_library.h"
#include "lockstep/client/sensor_data.h"
#include "lockstep/runtime/command_builders.h"
#include "lockstep/runtime/messages.h"

namespace lockstep::map {
class Map;
}

namespace lockstep::client {

// No simulation, a timeout, or a broken call. The message says what and why.
class ClientError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// The coordinator (or the owning service) rejected a command; reason() is its reply.
class CommandRejected : public ClientError {
 public:
  CommandRejected(const std::string& what, std::string reason) : ClientError(what), reason_(std::move(reason)) {}
  const std::string& reason() const { return reason_; }

 private:
  std::string reason_;
};

// tick() finished frame k but some listened sensors had not delivered their data of k
// within ClientOptions::sensor_timeout_s. Their data is still delivered once, in order,
// when it arrives.
class SensorLate : public ClientError {
 public:
  SensorLate(const std::string& what, std::vector<uint32_t> sensors, uint64_t frame)
      : ClientError(what), sensors_(std::move(sensors)), frame_(frame) {}
  const std::vector<uint32_t>& sensors() const { return sensors_; }
  uint64_t frame() const { return frame_; }

 private:
  std::vector<uint32_t> sensors_;
  uint64_t frame_;
};

// A wait was stopped by ClientOptions::interrupted (the Python module: a signal such as
// Ctrl-C arrived, and its handler raised).
class Interrupted : public ClientError {
 public:
  using ClientError::ClientError;
};

struct ClientOptions {
  int domain = -1;               // DDS domain; -1 = $LOCKSTEP_DOMAIN, else 0
  double timeout_s = 10;         // s, to find the simulation and for each command reply
  double tick_timeout_s = 60;    // s, for one tick to complete
  double sensor_timeout_s = 10;  // s, how long tick() waits for a listened sensor's frame
  double state_timeout_s = 2;    // s, how long tick() waits for the frame's ground / air state
  std::string name;              // unique client name; empty = "client-<host>-<pid>-<n>"
  Bus* bus = nullptr;            // an existing bus (tests: the in-process bus); null = a new DDS participant
  // Polled about every 100 ms while a call waits, without the client's lock held: true ends
  // the wait with Interrupted. The Python module checks for signals here, so Ctrl-C reaches a
  // script blocked in tick(), wait_for_tick() or a drone command's join(). Empty: never.
  std::function<bool()> interrupted;
};

// An actor of the current run: what its spawn said (from the ticks and our replies).
struct ActorInfo {
  uint32_t id = 0;
  std::string blueprint;
  msg::ActorKind kind = msg::ActorKind::ACTOR_OTHER;
  uint32_t parent = 0;
  std::string owner;                       // the service that simulates it
  AttributeList attributes;                // as spawned
  msg::Pose spawn_pose;                    // world ENU (parent frame if parent != 0)
  uint64_t spawn_frame = 0;                // the frame whose tick carried the spawn
  std::string Attribute(const std::string& key, const std::string& fallback = "") const;
};

// Kinematic state of one actor in a frame, whatever service simulates it.
struct ActorState {
  uint32_t id = 0;
  std::string blueprint;
  msg::ActorKind kind = msg::ActorKind::ACTOR_OTHER;
  msg::Pose transform;          // world ENU
  msg::Vector3 velocity;        // m/s, world
  msg::Vector3 angular_velocity;  // rad/s (world for ground actors, body for drones)
  msg::Vector3 acceleration;    // m/s^2, world
  msg::Vector3 half_extents;    // m
};

// The world at one frame: the latest ground and air state of that frame.
struct Snapshot {
  uint32_t run = 0;
  uint64_t frame = 0;
  double sim_time = 0;                        // s
  std::optional<msg::GroundState> ground;     // absent: no ground service
  std::optional<msg::AirState> air;           // absent: no air service
  std::vector<ActorState> Actors() const;
  std::optional<ActorState> Find(uint32_t id) const;
  const msg::VehicleState* Vehicle(uint32_t id) const;
  const msg::WalkerState* Walker(uint32_t id) const;
  const msg::DroneState* Drone(uint32_t id) const;
  const msg::TrafficLightState* TrafficLight(uint32_t id) const;
};

using SensorCallback = std::function<void(const SensorSample&)>;

class Client {
 public:
  // Connects: waits up to options.timeout_s for the coordinator's WorldInfo and for
  // the command topics to match. Throws ClientError naming the domain otherwise.
  explicit Client(ClientOptions options = {});
  ~Client();
  Client(const Client&) = delete;
  Client& operator=(const Client&) = delete;

  // Stops the client for good: no more callbacks (the dispatch thread is joined); every
  // call waiting now, and every later call that would wait, throws
  // ClientError("... closed"). Idempotent. The Python module closes its clients before the
  // interpreter finalizes, so no client thread outlives it.
  void close();
  bool closed() const;

  int domain() const;
  const std::string& name() const;
  const ClientOptions& options() const;

  // --- world ---
  msg::WorldInfo world_info() const;
  // Waits until every required service has joined (run ready or running); false on timeout.
  bool wait_ready(double timeout_s);
  std::optional<msg::RunStatus> run_status() const;
  uint32_t run() const;
  uint64_t frame() const;  // last completed frame of the current run (0 = none yet)
  msg::WorldSettings settings() const;
  // Applies new settings; returns the frame whose tick first uses them.
  uint64_t apply_settings(const msg::WorldSettings& settings);
  void set_weather(const msg::WeatherParameters& weather);
  // Synchronous mode: runs one tick and returns its frame once it is complete, its
  // ground / air state has arrived and every listened sensor delivered its data for it
  // (or throws SensorLate naming the late ones). timeout_s bounds the wait for the frame to
  // complete (CARLA's world.tick(seconds)); negative: ClientOptions::tick_timeout_s.
  uint64_t tick(double timeout_s = -1);
  // Any mode: waits for the next completed frame after the current one; returns it.
  uint64_t wait_for_tick(double timeout_s = -1);
  // A new run with no actors (seed 0 = keep); returns the new run id.
  uint32_t reset(uint64_t seed = 0);
  // Loads a map by .xodr path (or the current map's name to reload), or inline
  // OpenDRIVE text; returns the new run id.
  uint32_t load_map(const std::string& name, const std::string& opendrive = "", const std::string& scene = "");

  // --- commands ---
  // Sends one command and waits for its reply; throws CommandRejected (with the
  // reason) when rejected and `throw_if_rejected`.
  msg::CommandReply Submit(msg::CommandBody body, bool throw_if_rejected = true);
  // Sends every command, then collects every reply, in order (CARLA apply_batch_sync).
  std::vector<msg::CommandReply> SubmitBatch(const std::vector<msg::CommandBody>& bodies);
  // Sends without waiting; the reply can be collected with WaitReply.
  uint64_t Send(msg::CommandBody body);
  msg::CommandReply WaitReply(uint64_t sequence);

  uint32_t spawn(const std::string& blueprint, const msg::Pose& pose, const AttributeList& attributes = {},
                 uint32_t parent = 0);
  // nullopt when rejected; `reason` (if given) receives why.
  std::optional<uint32_t> try_spawn(const std::string& blueprint, const msg::Pose& pose,
                                    const AttributeList& attributes = {}, uint32_t parent = 0,
                                    std::string* reason = nullptr);
  void destroy(uint32_t actor);

  // --- commands the owning service may still refuse ---
  // A command the coordinator accepted can still fail where it is applied (ground_sim
  // refuses a physics control whose wheel radius is too small, an impulse on a car whose
  // physics is off): the service reports it as an EVENT_COMMAND_FAILED for the actor in
  // the frame whose tick carried the command. A watched command's failure is thrown as
  // CommandRejected (named by `call`, with the service's reason) by the next tick(),
  // wait_for_tick() or check_failures() that sees it: in synchronous mode the tick that
  // applies it, or the one after if the event arrives late.
  msg::CommandReply SubmitWatched(msg::CommandBody body, const std::string& call);
  void watch(uint32_t actor, uint32_t run, uint64_t frame, const std::string& call);
  // Throws CommandRejected for the first watched command whose failure has arrived.
  void check_failures();

  // --- ground actors (ground_sim; each is SubmitWatched) ---
  void apply_ackermann_control(const msg::VehicleAckermannControl& control);
  // set_target_velocity, set_target_angular_velocity, add_impulse, set_simulate_physics,
  // set_light_state (ActorPhysicsCommand.kind).
  void apply_actor_physics(const msg::ActorPhysicsCommand& command);
  void apply_physics_control(uint32_t actor, const msg::VehiclePhysicsControl& physics);
  // The vehicle's physics as ground_sim reports it in the latest GroundState (a change
  // shows from the frame that applied it); nullopt if no state lists the vehicle.
  std::optional<msg::VehiclePhysicsControl> physics_control(uint32_t actor) const;
  // controller.ai.walker: start, stop, go_to_location, set_max_speed (WalkerAICommand.kind).
  void walker_ai(const msg::WalkerAICommand& command);

  // --- the recorder (CARLA's Client.start_recorder family; docs/compatibility.md) ---
  // Records from the tick that carries the command into `name` (a name without '/', '\\'
  // or ':' goes into the recordings folder, as CARLA's Saved folder); returns the file's
  // path, as CARLA's start_recorder does. additional_data: CARLA's flag.
  std::string start_recorder(const std::string& name, bool additional_data = false);
  void stop_recorder();
  // CARLA's replay_file: the coordinator plays the log back (actors follow their recorded
  // states) from `start` s (< 0: from the end) for `duration` s (<= 0: to the end).
  // Returns CARLA's text, also for a file it cannot replay; throws CommandRejected for a
  // bad value.
  std::string replay_file(const std::string& name, double start = 0, double duration = 0, uint32_t follow_id = 0,
                          bool replay_sensors = false);
  void stop_replayer(bool keep_actors);
  void set_replayer_time_factor(double time_factor);
  void set_replayer_ignore_hero(bool ignore_hero);
  void set_replayer_ignore_spectator(bool ignore_spectator);

  // --- what exists ---
  // The union of the services' blueprint declarations (lockstep/blueprints); waits up
  // to `wait_s` for the first declarations.
  BlueprintLibrary blueprints(double wait_s = 2) const;
  std::vector<ActorInfo> actors() const;
  std::optional<ActorInfo> actor(uint32_t id) const;
  Snapshot snapshot() const;  // the latest frame's state
  // The map of the current run, built from lockstep/map (waits up to timeout_s).
  std::shared_ptr<const map::Map> map();
  // The coordinator's MapData of the current map (OpenDRIVE and scene text), waiting up to
  // timeout_s; nullopt if none arrived.
  std::optional<msg::MapData> map_data();

  // --- sensors ---
  // Delivers every sample of `sensor` to `callback` once, in frame order, on the
  // client's dispatch thread. In synchronous mode tick() returns only after the sample
  // of its frame was delivered (strict perception; pipelined: the frame before).
  void listen(uint32_t sensor, SensorCallback callback);
  void stop(uint32_t sensor);
  bool is_listening(uint32_t sensor) const;
  // Frames delivered to listen callbacks, per sensor (diagnostics and tests).
  uint64_t delivered(uint32_t sensor) const;

  // --- drones ---
  // Latest DroneState of a drone (nullopt if no air state lists it).
  std::optional<msg::DroneState> drone_state(uint32_t actor) const;
  // Sends a DroneCommand with a fresh command_id (returned); throws CommandRejected.
  uint64_t send_drone(msg::DroneCommand command);
  // Waits until the drone reports `command_id` finished (completed, timed out,
  // cancelled, rejected) or replaced by a newer command; in synchronous mode it ticks
  // the world while it waits. Throws ClientError after timeout_s (< 0: none).
  msg::DroneCommandStatus wait_drone(uint32_t actor, uint64_t command_id, double timeout_s = -1);
  // Why air_sim rejected a drone command (its EVENT_COMMAND_FAILED message), waiting up
  // to wait_s for it; empty if none arrived.
  std::string drone_failure(uint32_t actor, uint64_t command_id, double wait_s = 0) const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

// The domain a client uses when none is given: $LOCKSTEP_DOMAIN, else 0.
int DefaultDomain();
const char* CommandKindName(msg::CommandKind kind);
const char* DroneStatusName(msg::DroneCommandStatus status);
// The actor a command is about (0 for world commands).
uint32_t CommandActor(const msg::CommandBody& body);

}  // namespace lockstep::client
