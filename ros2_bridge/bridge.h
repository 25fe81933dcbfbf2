#pragma once
// lockstep_ros2_bridge: the ROS 2 view of a run (docs/deployment.md#ros-2). A barrier
// member (perception): in tick k it publishes rt/clock, then waits until every sensor
// that publishes each frame has had its sample of the perception frame forwarded as the
// ROS 2 message of CARLA's native interface, and only then acks. So a ROS 2 node sees
// every frame, stamped with its simulation time, before the run moves on: the ROS view
// stays in lock-step with the world. vehicle_control_cmd from ROS 2 becomes a
// CMD_VEHICLE_CONTROL command, sequenced by the coordinator into the next tick as a
// client's would be (so a recorded run replays it).
#include <condition_variable>
#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <variant>
#include <vector>

#include "convert.h"
#include "lockstep/runtime/service.h"
#include "ros2_types.h"

namespace lockstep::ros2 {

struct BridgeOptions {
  double input_timeout_s = 0;  // how long a step waits for a sensor's frame; 0 = 0.9 x world.service_timeout
};

class Bridge : public ServiceCore {
 public:
  Bridge(Bus& bus, std::string name, BridgeOptions options = {});
  ~Bridge() override;
  void BeginRun(const msg::WorldInfo& world) override;
  void Step(const msg::Tick& tick) override;

  // Counters for tests and the log.
  uint64_t published() const;

 private:
  using Pending = std::variant<msg::PointCloud, msg::Imu, msg::Gnss, msg::CollisionEvent>;
  struct Output {
    ActorInfo actor;
    SensorKind kind = SensorKind::kNone;
    std::string base;      // rt/carla/<parent>/<name>
    std::string frame_id;  // the sensor's ROS name, as CARLA's publishers set it
    bool per_frame = false;
    uint64_t last_frame = 0;  // last frame forwarded (this run)
    std::unique_ptr<RawWriter> writer;       // image / point cloud / imu / gnss / collision
    std::unique_ptr<RawWriter> info_writer;  // camera_info
    bool warned = false;
  };

  void Register(const ActorInfo& a);                          // runner thread
  void Unregister(uint32_t id);                               // runner thread
  void ResetActors();                                         // runner thread
  void PublishMap();                                          // runner thread
  double InputTimeout() const;
  template <class Sample>
  void OnSensor(const Sample& s);                             // DDS threads
  void Forward(Output& out, const Pending& s);                // under mu_
  void ForwardImage(uint32_t sensor, const msg::FrameStamp& stamp, uint32_t width, uint32_t height, uint32_t step,
                    uint32_t encoding, double fov, const std::vector<uint8_t>& data);  // DDS threads
  void OnControl(uint32_t actor, const carla_msgs::msg::dds_::CarlaEgoVehicleControl_& c);  // DDS threads

  Bus& bus_;
  std::string name_;
  BridgeOptions options_;
  msg::WorldInfo world_;
  bool map_published_ = false;

  Writer<rosgraph_msgs::msg::dds_::Clock_> clock_;
  Writer<std_msgs::msg::dds_::String_> map_;
  Writer<msg::Command> commands_;

  mutable std::mutex mu_;
  std::condition_variable cv_;
  uint32_t run_ = 0;
  std::map<uint32_t, ActorInfo> actors_;
  std::map<uint32_t, Output> outputs_;                  // by sensor id
  std::map<uint32_t, std::vector<Pending>> pending_;    // samples of sensors whose spawn this step has not applied yet
  std::optional<msg::MapData> map_data_;
  uint64_t published_ = 0;
  uint64_t sequence_ = 0;

  // Readers: created and destroyed by the runner thread only, never under mu_ (a reader's
  // destruction waits for its callback, which takes mu_).
  std::map<uint32_t, std::unique_ptr<Reader<msg::Image>>> image_readers_;
  std::map<uint32_t, std::unique_ptr<Reader<msg::LargeImage>>> large_image_readers_;
  std::map<uint32_t, std::unique_ptr<Reader<carla_msgs::msg::dds_::CarlaEgoVehicleControl_>>> control_readers_;
  Reader<msg::MapData> map_reader_;
  Reader<msg::CommandReply> replies_;
  Reader<msg::PointCloud> clouds_;
  Reader<msg::Imu> imus_;
  Reader<msg::Gnss> gnss_;
  Reader<msg::CollisionEvent> collisions_;
};

}  // namespace lockstep::ros2
