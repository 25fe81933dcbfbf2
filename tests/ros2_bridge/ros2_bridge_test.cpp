// The ROS 2 view end to end: `lockstep up --ros2` runs ground_sim, sensors, render and the
// ROS 2 bridge with a hero car carrying a camera, a LiDAR and a GNSS; a Cyclone DDS (C)
// participant that knows only the ROS 2 type names (lockstep_ros2_reader) reads the image,
// camera info and point cloud, checks their fields and stamps, and drives the car with
// vehicle_control_cmd until its GNSS has moved.
#include <gtest/gtest.h>

#include <csignal>
#include <cstdio>
#include <string>

#include "process.h"

namespace lockstep::testing {
namespace {

using namespace std::chrono_literals;

TEST(Ros2Bridge, ACycloneReaderWithRos2TypesSeesTheFramesAndDrivesTheCar) {
  const int domain = TestDomain();
  const std::string config = WriteTempFile("ros2.yaml", R"(name: ros2_view
seed: 5
map: ${LOCKSTEP_BUILD_DIR}/maps/generated/LockstepTown1.xodr
participant_profile: lockstep.participant.loopback
recorder: false
ros2: true
world:
  synchronous_mode: false
  fixed_delta_seconds: 0.05
  real_time_factor: 1
  service_timeout: 30
services:
  - {name: ground_sim, kind: ground_sim}
  - {name: sensors, kind: sensors, perception: true}
  - {name: render, kind: render, perception: true}
scenario:
  - {frame: 1, spawn: vehicle.tesla.model3, as: hero, at: [122.75, 1.75, 0.8], yaw: 3.1416, attributes: {role_name: hero}}
  - {frame: 2, spawn: sensor.camera.rgb, as: cam, parent: hero, at: [1.5, 0, 2.4],
     attributes: {role_name: front, image_size_x: "64", image_size_y: "48", fov: "90"}}
  - {frame: 2, spawn: sensor.lidar.ray_cast, as: lidar, parent: hero, at: [0, 0, 2.4],
     attributes: {role_name: lidar, channels: "8", range: "30", points_per_second: "4000", rotation_frequency: "20"}}
  - {frame: 2, spawn: sensor.other.gnss, as: gnss, parent: hero, attributes: {role_name: gnss}}
)");
  const std::map<std::string, std::string> env{
      {"CYCLONEDDS_URI", "file://" + SourceDir() + "/client/cyclone_c/cyclone_loopback.xml"}};
  Process up({Bin("lockstep"), "up", config, "--domain", std::to_string(domain)}, {{"LOCKSTEP_ROS2", "1"}});
  Process reader({Bin("lockstep_ros2_reader"), "--domain", std::to_string(domain), "--role", "hero", "--camera", "front", "--lidar",
                  "lidar", "--gnss", "gnss", "--width", "64", "--height", "48", "--fov", "90", "--dt", "0.05", "--timeout", "90",
                  "--move-m", "2"},
                 env);
  const auto rc = reader.Wait(120s);
  up.Signal(SIGINT);
  up.Wait(30s);
  EXPECT_EQ(rc, std::optional<int>(0)) << "reader:\n" << reader.Output() << "\nlockstep up:\n" << up.Output();
  EXPECT_NE(reader.Output().find("ROS2 READER PASS"), std::string::npos) << reader.Output();
  EXPECT_NE(up.Output().find("rt/carla/hero/vehicle_control_cmd"), std::string::npos) << up.Output();
  std::printf("%s", reader.Output().c_str());
}

}  // namespace
}  // namespace lockstep::testing
