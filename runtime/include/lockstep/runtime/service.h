#pragma once
// The service loop every Lockstep service runs: receive Tick k, apply its commands,
// step, publish outputs stamped k, then Ack k. The step itself lives in a ServiceCore,
// which never sees DDS.
#include <atomic>
#include <cstdint>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

#include "lockstep/runtime/bus.h"
#include "lockstep/runtime/error.h"
#include "lockstep/runtime/messages.h"

namespace lockstep {

// No world info from a coordinator within ServiceOptions::world_info_timeout_s.
class JoinTimeout : public InputError {
 public:
  using InputError::InputError;
};

// A step threw (on whichever thread it ran): the service stops, announcing the reason,
// and Run throws this. A core whose input for a frame is missing throws MissingInput: the
// run then faults with the reason instead of the state changing without it.
class ServiceFailed : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};
class MissingInput : public InputError {
 public:
  using InputError::InputError;
};

struct ServiceOptions {
  std::string name;                  // unique in a run, e.g. "air_sim"
  std::string kind;                  // implementation, e.g. "air_sim"
  bool perception = false;           // render / sensors: read-only phase
  double heartbeat_period_s = 0.1;   // s, how often the service re-announces itself (liveliness)
  double world_info_timeout_s = 30;  // s, how long to wait for the coordinator at start
  uint64_t snapshot_period = 200;    // frames between state snapshots (a replacement restores
                                     // the latest, then replays the tick log from there)
};

// Implemented by each service; called on the runner's thread only.
class ServiceCore {
 public:
  virtual ~ServiceCore() = default;
  // A run begins (first join, reset or new map). Seed and settings are in `world`.
  virtual void BeginRun(const msg::WorldInfo& world) = 0;
  // Apply tick.commands() in order, advance the state to tick.frame(), publish outputs
  // stamped with it.
  virtual void Step(const msg::Tick& tick) = 0;
  // The blueprints this service simulates (blueprint.idl), published on
  // lockstep/blueprints when it joins. Spawns of these arrive in ticks with
  // SpawnActor.owner naming the service that must simulate the actor.
  virtual std::vector<msg::BlueprintDeclaration> Blueprints() const { return {}; }
  // Checks what a declaration cannot express (a parameter combination) for a spawn of one
  // of this service's blueprints: empty = it can be simulated, else the reason. The
  // coordinator asks the owner before it replies to the client (docs/topics.md).
  virtual std::string CheckSpawn(const msg::SpawnActor& /*spawn*/) const { return {}; }
  // FNV-1a of the state after the last step (0: the service keeps no state).
  virtual uint64_t StateHash() const { return 0; }
  // Full state for a replacement process, every ServiceOptions::snapshot_period frames.
  // Empty: no snapshots; a replacement rebuilds the state by replaying the tick log.
  virtual std::vector<uint8_t> SaveState() const { return {}; }
  virtual void RestoreState(const std::vector<uint8_t>& /*state*/) {}
  // True if Step never waits for other topics: the runner may then step on the DDS
  // receive thread, saving a thread hand-off per tick. A core that waits for inputs
  // (perception in strict mode) must return false, or it would block their delivery.
  virtual bool StepNeverWaits() const { return false; }

  // True while a replacement replays past ticks to rebuild its state: Step must not
  // publish (those frames were published by the service it replaces).
  bool replaying() const { return replaying_; }

 private:
  friend class ServiceRunner;
  bool replaying_ = false;
};

class ServiceRunner {
 public:
  ServiceRunner(Bus& bus, ServiceOptions options, ServiceCore& core);
  ~ServiceRunner();
  ServiceRunner(const ServiceRunner&) = delete;
  ServiceRunner& operator=(const ServiceRunner&) = delete;

  // Runs until `stop` becomes true. Throws JoinTimeout if the coordinator never shows up,
  // ServiceFailed if a step throws (the reason reaches the coordinator in the announcement).
  void Run(const std::atomic<bool>& stop);
  uint64_t last_frame() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace lockstep
