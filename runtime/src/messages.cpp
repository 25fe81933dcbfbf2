// Type operations for every message: the only place that sees the generated
// PubSubTypes (and through them Fast DDS headers).
#include "lockstep/runtime/messages.h"

#include <algorithm>
#include <iterator>

#include "lockstep/runtime/actor_list.h"

#include "lockstep/msg/actorsPubSubTypes.h"
#include "lockstep/msg/blueprintPubSubTypes.h"
#include "lockstep/msg/clockPubSubTypes.h"
#include "lockstep/msg/commandPubSubTypes.h"
#include "lockstep/msg/mapPubSubTypes.h"
#include "lockstep/msg/sensorPubSubTypes.h"
#include "lockstep/msg/statePubSubTypes.h"
#include "lockstep/msg/worldPubSubTypes.h"

namespace lockstep {

#define LOCKSTEP_DEFINE_TYPE_OPS(T)                                                           \
  template <>                                                                                 \
  const TypeOps& TypeOpsOf<msg::T>() {                                                        \
    static const TypeOps ops{                                                                 \
        "lockstep::msg::" #T,                                                                 \
        []() -> void* {                                                                       \
          return static_cast<eprosima::fastdds::dds::TopicDataType*>(new msg::T##PubSubType()); \
        },                                                                                    \
        []() -> void* { return new msg::T(); },                                               \
        [](void* p) { delete static_cast<msg::T*>(p); },                                      \
        [](void* dst, const void* src) {                                                      \
          *static_cast<msg::T*>(dst) = *static_cast<const msg::T*>(src);                      \
        },                                                                                    \
        [](const void* sample, std::array<uint8_t, 16>* out) -> bool {                        \
          thread_local msg::T##PubSubType type;                                               \
          eprosima::fastrtps::rtps::InstanceHandle_t h;                                       \
          if (!type.getKey(const_cast<void*>(sample), &h, false)) return false;               \
          for (size_t i = 0; i < out->size(); ++i) (*out)[i] = h.value[i];                   \
          return true;                                                                        \
        }};                                                                                   \
    return ops;                                                                               \
  }
LOCKSTEP_MESSAGE_TYPES(LOCKSTEP_DEFINE_TYPE_OPS)
LOCKSTEP_DEFINE_TYPE_OPS(ActorList)
#undef LOCKSTEP_DEFINE_TYPE_OPS

}  // namespace lockstep
