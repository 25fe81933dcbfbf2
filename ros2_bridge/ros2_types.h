#pragma once
// Bus type operations for the ROS 2 message types of idl/ros2/ (their DDS type names are
// ROS 2's: "sensor_msgs::msg::dds_::Image_", ...), and the bridge's ROS 2 topics.
#include "lockstep/runtime/bus.h"
#include "ros2/msg/carla_msgs.h"
#include "ros2/msg/rosgraph_msgs.h"
#include "ros2/msg/sensor_msgs.h"
#include "ros2/msg/std_msgs.h"

#define LOCKSTEP_ROS2_TYPES(X)                                                                    \
  X(rosgraph_msgs, Clock_) X(std_msgs, String_) X(sensor_msgs, Image_) X(sensor_msgs, CameraInfo_) \
  X(sensor_msgs, PointCloud2_) X(sensor_msgs, Imu_) X(sensor_msgs, NavSatFix_)                    \
  X(carla_msgs, CarlaCollisionEvent_) X(carla_msgs, CarlaEgoVehicleControl_)

namespace lockstep {

#define LOCKSTEP_ROS2_DECLARE_TYPE_OPS(PKG, T) \
  template <>                                   \
  const TypeOps& TypeOpsOf<PKG::msg::dds_::T>();
LOCKSTEP_ROS2_TYPES(LOCKSTEP_ROS2_DECLARE_TYPE_OPS)
#undef LOCKSTEP_ROS2_DECLARE_TYPE_OPS

namespace ros2 {
// ROS 2 topic "/clock" is DDS topic "rt/clock" (rmw's "rt" prefix for topics).
inline constexpr Topic<rosgraph_msgs::msg::dds_::Clock_> kClock{"rt/clock", QosKind::kClock};
// The OpenDRIVE text of the run's map, kept for late readers (TRANSIENT_LOCAL).
inline constexpr Topic<std_msgs::msg::dds_::String_> kMap{"rt/carla/map", QosKind::kClock};
}  // namespace ros2

}  // namespace lockstep
