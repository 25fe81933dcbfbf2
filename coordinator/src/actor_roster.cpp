#include "actor_roster.h"

#include <utility>

namespace lockstep {

std::optional<msg::ActorList> ActorRoster::Apply(const msg::Tick& t) {
  bool changed = list_.run() != t.run() || list_.frame() == 0;
  if (list_.run() != t.run()) list_.actors().clear();
  auto& list = list_.actors();
  for (const auto& c : t.commands()) {
    const auto& b = c.body();
    if (b._d() == msg::CommandKind::CMD_SPAWN_ACTOR) {
      msg::ActorSpawned a;
      a.spawn(b.spawn_actor());
      a.frame(t.frame());
      list.push_back(std::move(a));
      changed = true;
    } else if (b._d() == msg::CommandKind::CMD_DESTROY_ACTOR) {
      // Only the actor (CARLA): what was attached to it stays listed, detached where it was
      // (its spawn still names the parent, which is gone: clients read that as detached).
      const uint32_t gone = b.destroy_actor().actor();
      std::erase_if(list, [&](const msg::ActorSpawned& a) { return a.spawn().actor() == gone; });
      changed = true;
    }
  }
  if (!changed) return std::nullopt;
  list_.run(t.run());
  list_.frame(t.frame());
  return list_;
}

}  // namespace lockstep
