#include "scenario.h"

#include "lockstep/runtime/log.h"

namespace lockstep {

void Scenario::Restart() {
  next_ = 0;
  aliases_.clear();
}

void Scenario::Submit(uint64_t for_frame, const std::function<msg::CommandReply(const msg::Command&)>& submit) {
  while (next_ < steps_.size() && steps_[next_].frame < for_frame) ++next_;  // after a reset
  while (next_ < steps_.size() && steps_[next_].frame == for_frame) {
    const ScheduledCommand& step = steps_[next_++];
    msg::Command c = step.command;
    if (!step.actor_alias.empty()) {
      auto it = aliases_.find(step.actor_alias);
      if (it == aliases_.end()) {
        spdlog::error("scenario step {} at frame {}: no actor named '{}'", c.sequence_number(), for_frame, step.actor_alias);
        continue;
      }
      if (c.body()._d() == msg::CommandKind::CMD_DRONE) c.body().drone().actor(it->second);
      if (c.body()._d() == msg::CommandKind::CMD_TRAFFIC_MANAGER) c.body().traffic_manager().actor(it->second);
      if (c.body()._d() == msg::CommandKind::CMD_WALKER_AI) c.body().walker_ai().actor(it->second);
      if (c.body()._d() == msg::CommandKind::CMD_SPAWN_ACTOR) c.body().spawn_actor().parent(it->second);
    }
    const msg::CommandReply r = submit(c);
    if (!r.accepted()) {
      spdlog::error("scenario step {} at frame {} rejected: {}", c.sequence_number(), for_frame, r.reason().to_string());
      continue;
    }
    if (!step.alias.empty()) aliases_[step.alias] = r.actor();
  }
}

}  // namespace lockstep
