#pragma once
// lockstep/actors: the coordinator's roster of the live actors of a run with their spawns
// (ActorList), kept from the ticks that go out: a spawn adds its actor, a destroy removes
// only that actor (CARLA: what was attached to it stays listed, detached where it was).
// A client joining late reads the world from it. No bus and no lock: the coordinator
// publishes what Apply returns.
#include <optional>

#include "lockstep/runtime/actor_list.h"
#include "lockstep/runtime/messages.h"

namespace lockstep {

class ActorRoster {
 public:
  // The roster after tick `t` when the tick changed it (or began a run, or is the first):
  // the list to publish; nullopt when it is as before.
  std::optional<msg::ActorList> Apply(const msg::Tick& t);

 private:
  msg::ActorList list_;
};

}  // namespace lockstep
