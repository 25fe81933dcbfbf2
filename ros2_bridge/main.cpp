// lockstep_ros2_bridge: the ROS 2 view of a run, on the run's DDS domain with ROS 2's
// topic and type names (docs/deployment.md#ros-2). `lockstep up --ros2` or `ros2: true`
// in the launch config adds it to the run as a required service named ros2_bridge.
#include "bridge.h"
#include "lockstep/runtime/service_main.h"

int main(int argc, char** argv) {
  return lockstep::RunServiceMain(argc, argv, "ros2_bridge", true, [](lockstep::ServiceContext& ctx) {
    return std::make_unique<lockstep::ros2::Bridge>(*ctx.bus, ctx.name);
  });
}
