#pragma once
// The service loop every Lockstep service runs: receive Tick k, apply its commands,
// step, publish outputs stamped k, then Ack k. The step itself lives in a ServiceCore,
// which never sees DDS.
#include <algorithm>
#include <atomic>
#include <chrono>
#include <cstdint>
#include <functional>
#include <memory>
#include <optional>
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
                                     // the latest, then replays the tick log from there); at
                                     // most kMaxSnapshotPeriod: the inputs of a replay are kept
                                     // that long (state topics' history, QosHistoryDepth(kState))
};

// The longest snapshot period whose replay the kept inputs cover: the state topics keep
// QosHistoryDepth(QosKind::kState) frames, less a margin for the open tick and the frame
// before it (pipelined perception reads k-1).
uint64_t MaxSnapshotPeriod();

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

 protected:
  // Waits for one input of a step: `wait(slice)` returns the input, or nullopt when it did
  // not come within `slice`. Gives up (nullopt) after `timeout` of waiting while the run
  // goes on, never while the run is faulted by another service: a producer being replaced
  // (its replacement publishes the input once it has rebuilt its state) is no reason to
  // fail, and failing would make the consumer a second casualty (issue 21, "no cascade").
  // The timeout starts again when the fault clears. Throws ServiceFailed when the service
  // is asked to stop meanwhile.
  template <class Wait>
  auto AwaitInput(Wait&& wait, std::chrono::milliseconds timeout) -> decltype(wait(timeout)) {
    using Steady = std::chrono::steady_clock;
    const auto slice = std::min<std::chrono::milliseconds>(timeout, std::chrono::milliseconds(100));
    const auto deadline = Steady::now() + timeout;
    std::optional<Steady::time_point> fault_seen;  // last time the run was seen faulted by another service
    for (;;) {
      if (auto got = wait(slice)) return got;
      const auto now = Steady::now();
      if (run_faulted_by_ && !run_faulted_by_().empty()) {
        if (now >= deadline) held_by_fault_ = true;  // past its timeout: held by the fault, not failed
        fault_seen = now;
      } else if (now >= deadline && (!fault_seen || now >= *fault_seen + timeout)) {
        return decltype(wait(timeout))();
      }
      if (stopping_ && stopping_()) throw ServiceFailed("asked to stop while waiting for an input");
    }
  }

 public:
  // True once AwaitInput waited beyond its timeout because the run was faulted by another
  // service (tests, diagnostics).
  bool held_by_fault() const { return held_by_fault_; }

 private:
  friend class ServiceRunner;
  bool replaying_ = false;
  std::atomic<bool> held_by_fault_{false};
  std::function<std::string()> run_faulted_by_;  // set by the runner: who faulted the run, if not us
  std::function<bool()> stopping_;               // set by the runner
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
