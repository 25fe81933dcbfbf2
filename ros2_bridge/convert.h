#pragma once
// Lockstep samples as the ROS 2 messages of CARLA's native ROS 2 interface (no DDS here:
// pure functions, tested in tests/ros2_bridge/convert_test.cpp). Lockstep's sensor frame
// (FLU) and world frame (ENU) are ROS's (REP 103), so no axis flips: CARLA's publishers
// flip Unreal's left-handed y to reach the same result.
#include <cstdint>
#include <map>
#include <optional>
#include <string>

#include "lockstep/msg/command.h"
#include "lockstep/msg/sensor.h"
#include "ros2/msg/carla_msgs.h"
#include "ros2/msg/rosgraph_msgs.h"
#include "ros2/msg/sensor_msgs.h"
#include "ros2/msg/std_msgs.h"

namespace lockstep::ros2 {

// CARLA's ROS2::SetTimestamp: whole seconds and the truncated fraction in ns.
builtin_interfaces::msg::dds_::Time_ RosTime(double sim_time);
std::string TimeString(const builtin_interfaces::msg::dds_::Time_& t);

// What the bridge publishes for a sensor blueprint.
enum class SensorKind { kNone, kCamera, kLidar, kSemanticLidar, kImu, kGnss, kCollision };
SensorKind SensorKindOf(const std::string& blueprint);
// Published every frame (the bridge waits for it before it acks): cameras, LiDARs, IMU
// and GNSS whose sensor_tick is not longer than the step, as a CARLA client expects them.
bool PerFrame(SensorKind kind, double sensor_tick, double dt);

// An actor of the run as its spawn described it.
struct ActorInfo {
  uint32_t id = 0;
  uint32_t parent = 0;
  uint64_t spawn_frame = 0;
  std::string blueprint;
  std::map<std::string, std::string> attributes;
  std::string Attribute(const std::string& key, const std::string& fallback = "") const;
};
ActorInfo ActorFromSpawn(const msg::SpawnActor& spawn, uint64_t frame);

// The actor's ROS name (CARLA's ros_name): its role_name when the spawn gave one (a
// vehicle's default 'autopilot' excepted), else CARLA's defaults: "vehicle<id>" for a
// vehicle, the blueprint's last token and the id for anything else ("rgb7", "ray_cast8").
std::string RosName(const ActorInfo& actor);
// "rt/carla/<ancestors' ROS names>/<ROS name>": a sensor's topic (cameras add /image and
// /camera_info), a vehicle's base for vehicle_control_cmd. `actors` resolves parents.
std::string BaseTopic(const ActorInfo& actor, const std::map<uint32_t, ActorInfo>& actors);
// CARLA's rule: only a vehicle whose role_name is hero or ego takes vehicle_control_cmd.
bool TakesControl(const ActorInfo& actor);

// sensor_msgs/Image of a camera image; nullopt for an encoding ROS has no name for
// (optical flow, DVS events). `why` then says which.
std::optional<sensor_msgs::msg::dds_::Image_> ToRosImage(const msg::Image& image, const std::string& frame_id, std::string* why);
const char* RosEncoding(uint32_t lockstep_encoding);  // nullptr if none
// CARLA's CameraInfo(height, width, fov): pinhole, no distortion ("plumb_bob", d = 0),
// fx = fy = width / (2 tan(fov / 2)), principal point at the centre.
sensor_msgs::msg::dds_::CameraInfo_ ToCameraInfo(uint32_t width, uint32_t height, double fov_rad,
                                                 const builtin_interfaces::msg::dds_::Time_& stamp, const std::string& frame_id);
// PointCloud2 as CARLA's LiDAR publishers: x, y, z, intensity float32 (semantic: x, y, z,
// cos_inc_angle float32, object_idx, object_tag uint32), height 1, little-endian, not dense.
sensor_msgs::msg::dds_::PointCloud2_ ToPointCloud2(const msg::PointCloud& cloud, const std::string& frame_id);
sensor_msgs::msg::dds_::Imu_ ToRosImu(const msg::Imu& imu, const std::string& frame_id);
sensor_msgs::msg::dds_::NavSatFix_ ToNavSatFix(const msg::Gnss& gnss, const std::string& frame_id);
carla_msgs::msg::dds_::CarlaCollisionEvent_ ToCollision(const msg::CollisionEvent& event, const std::string& frame_id);
// carla_msgs/CarlaEgoVehicleControl -> Lockstep's VehicleControl for `actor`.
msg::VehicleControl FromEgoControl(const carla_msgs::msg::dds_::CarlaEgoVehicleControl_& control, uint32_t actor);

}  // namespace lockstep::ros2
