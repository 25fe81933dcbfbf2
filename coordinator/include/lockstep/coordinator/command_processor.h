#pragma once
// Validates client commands and sequences the accepted ones into ticks. Owns actor ids.
// Plain logic: the coordinator process feeds it commands and takes the batches.
#include <cstdint>
#include <functional>
#include <map>
#include <string>
#include <vector>

#include "lockstep/coordinator/blueprints.h"
#include "lockstep/msg/command.h"

namespace lockstep {

struct ActorRecord {
  uint32_t id = 0;
  std::string blueprint;
  msg::ActorKind kind = msg::ACTOR_VEHICLE;
  uint32_t parent = 0;
  std::string owner;  // the service that simulates it ("" for the map's actors)
};

// The owner's own check of a spawn (the coordinator asks it over DDS): empty = accepted.
using OwnerCheck = std::function<std::string(const msg::SpawnActor& spawn)>;

class CommandProcessor {
 public:
  CommandProcessor() = default;
  explicit CommandProcessor(BlueprintLibrary library);

  // Checks `cmd`. Accepted commands join the pending batch (spawns with their new
  // actor id and their owner filled in). `synchronous` tells whether tick requests are
  // allowed. A spawn that passes the declaration checks goes to `owner_check`, if
  // given, with its owner set. The reply carries the reason of a rejection.
  msg::CommandReply Submit(const msg::Command& cmd, uint32_t run, uint64_t next_frame, bool synchronous,
                           const OwnerCheck& owner_check = {});

  // The accepted commands for the next tick, in acceptance order.
  std::vector<msg::Command> TakePending();
  bool HasPending() const { return !pending_.empty(); }

  // A new run: actors are gone, ids start again at 1.
  void ResetActors();
  // The live recorder services (kind "recorder"): CMD_RECORDER is accepted only while one runs.
  void SetRecorders(std::vector<std::string> services) { recorders_ = std::move(services); }
  // The log a RECORDER_START named (absolute path) until RECORDER_STOP; "" when none.
  const std::string& recording() const { return recording_; }

  // Actors the map brings (traffic lights), so commands can address them.
  uint32_t AddMapActor(const std::string& blueprint, msg::ActorKind kind);

  const std::map<uint32_t, ActorRecord>& actors() const { return actors_; }
  const BlueprintLibrary& library() const { return library_; }
  BlueprintLibrary& library() { return library_; }

  // Empty if valid, else the reason. Exposed for tests and the client libraries.
  std::string Check(const msg::Command& cmd, bool synchronous) const;
  // The owner of a valid spawn: the one it names, else the live declarer owning the
  // fewest actors (ties: first in name order).
  std::string ChooseOwner(const msg::SpawnActor& spawn) const;

 private:
  std::string CheckActor(uint32_t id, msg::ActorKind kind) const;
  std::string CheckDrone(const msg::DroneCommand& d) const;

  BlueprintLibrary library_;
  std::map<uint32_t, ActorRecord> actors_;
  uint32_t next_actor_ = 1;
  std::vector<msg::Command> pending_;
  std::vector<std::string> recorders_;
  std::string recording_;
};

}  // namespace lockstep
