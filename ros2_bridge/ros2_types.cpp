// The only source of the bridge that sees the generated PubSubTypes (and through them
// Fast DDS headers).
#include "ros2_types.h"

#include "ros2/msg/carla_msgsPubSubTypes.h"
#include "ros2/msg/rosgraph_msgsPubSubTypes.h"
#include "ros2/msg/sensor_msgsPubSubTypes.h"
#include "ros2/msg/std_msgsPubSubTypes.h"

namespace lockstep {

#define LOCKSTEP_ROS2_DEFINE_TYPE_OPS(PKG, T)                                                           \
  template <>                                                                                           \
  const TypeOps& TypeOpsOf<PKG::msg::dds_::T>() {                                                       \
    using Msg = PKG::msg::dds_::T;                                                                      \
    using PubSub = PKG::msg::dds_::T##PubSubType;                                                       \
    static const TypeOps ops{                                                                           \
        #PKG "::msg::dds_::" #T,                                                                        \
        []() -> void* { return static_cast<eprosima::fastdds::dds::TopicDataType*>(new PubSub()); },   \
        []() -> void* { return new Msg(); },                                                            \
        [](void* p) { delete static_cast<Msg*>(p); },                                                   \
        [](void* dst, const void* src) { *static_cast<Msg*>(dst) = *static_cast<const Msg*>(src); },    \
        [](const void*, std::array<uint8_t, 16>*) -> bool { return false; }}; /* ROS 2 types: no key */ \
    return ops;                                                                                         \
  }
LOCKSTEP_ROS2_TYPES(LOCKSTEP_ROS2_DEFINE_TYPE_OPS)
#undef LOCKSTEP_ROS2_DEFINE_TYPE_OPS

}  // namespace lockstep
