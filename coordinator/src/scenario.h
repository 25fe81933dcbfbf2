#pragma once
// The launch config's scenario (`scenario:` steps, ScheduledCommand): the commands the
// coordinator puts in the tick of their frame, validated like a client's, with actor
// aliases (a spawn's `alias`, a later step's `actor`) resolved to the ids the spawns got.
// No bus and no lock: the coordinator submits through the callback it gives.
#include <cstdint>
#include <functional>
#include <map>
#include <string>
#include <vector>

#include "lockstep/runtime/launch_config.h"
#include "lockstep/runtime/messages.h"

namespace lockstep {

class Scenario {
 public:
  explicit Scenario(const std::vector<ScheduledCommand>& steps) : steps_(steps) {}

  // Steps for `for_frame` or earlier are still to submit: the tick of that frame starts on
  // the coordinator's main loop (a spawn may wait for its owner's check).
  bool Due(uint64_t for_frame) const { return next_ < steps_.size() && steps_[next_].frame <= for_frame; }
  // A new run (reset, new map): from the first step again, no aliases.
  void Restart();
  // Submits the steps of `for_frame`, in order, through `submit` (skipping those of earlier
  // frames, after a reset); a rejected step or one naming an unknown alias is logged and
  // left out. A spawn's alias then names the actor it got.
  void Submit(uint64_t for_frame, const std::function<msg::CommandReply(const msg::Command&)>& submit);

 private:
  const std::vector<ScheduledCommand>& steps_;
  size_t next_ = 0;                           // the first step not yet submitted
  std::map<std::string, uint32_t> aliases_;   // scenario actor names -> actor ids
};

}  // namespace lockstep
