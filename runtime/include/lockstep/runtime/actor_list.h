#pragma once
// lockstep/actors: the coordinator's list of live actors with their spawns (ActorList,
// idl/lockstep/actors.idl), kept for clients that join later. Apart from messages.h so
// that the sources that do not use it do not depend on its type.
#include "lockstep/msg/actors.h"
#include "lockstep/runtime/messages.h"

namespace lockstep {

template <>
const TypeOps& TypeOpsOf<msg::ActorList>();

namespace topics {
inline constexpr Topic<msg::ActorList> kActors{"lockstep/actors", QosKind::kClock};
}  // namespace topics

}  // namespace lockstep
