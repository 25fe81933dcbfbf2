#pragma once
// A stand-in sensors service for client tests: it declares an IMU and an RGB camera
// (blueprint declarations, like the real services) and, every tick, publishes one sample
// per sensor it owns stamped with the tick's frame, before its ack. A sensor spawned with
// role_name "late" skips frame `skip_frame`, so tests can see the API name a late sensor.
#include <condition_variable>
#include <map>
#include <mutex>
#include <string>

#include "lockstep/runtime/blueprint_builder.h"
#include "lockstep/runtime/service.h"

namespace lockstep::testing {

class FakeSensors final : public ServiceCore {
 public:
  FakeSensors(Bus& bus, std::string name, uint64_t skip_frame = 0)
      : bus_(bus), name_(std::move(name)), skip_frame_(skip_frame), imu_(bus, topics::kImu) {}

  std::vector<msg::BlueprintDeclaration> Blueprints() const override {
    namespace bp = lockstep::blueprint;
    return {bp::Make("sensor.other.imu", msg::ActorKind::ACTOR_SENSOR,
                     {bp::String("role_name", ""), bp::Float("sensor_tick", 0, 0, 1e6)}),
            bp::Make("sensor.camera.rgb", msg::ActorKind::ACTOR_SENSOR,
                     {bp::String("role_name", ""), bp::Int("image_size_x", 8, 1, 3840), bp::Int("image_size_y", 4, 1, 2160),
                      bp::Float("fov", 90, 1, 179), bp::Float("sensor_tick", 0, 0, 1e6)})};
  }

  void BeginRun(const msg::WorldInfo&) override { sensors_.clear(); }
  // Readers of the shared IMU topic (a client reads it from connect, before any listen()).
  int ImuReaders() const { return imu_.MatchedReaders(); }
  // While held, Step does not return: the frame stays incomplete (a stalled service).
  void Hold(bool hold) {
    {
      std::lock_guard<std::mutex> lock(hold_mu_);
      held_ = hold;
    }
    hold_cv_.notify_all();
  }

  void Step(const msg::Tick& tick) override {
    {
      std::unique_lock<std::mutex> lock(hold_mu_);
      hold_cv_.wait(lock, [&] { return !held_; });
    }
    for (const auto& c : tick.commands()) {
      const auto& b = c.body();
      if (b._d() == msg::CommandKind::CMD_SPAWN_ACTOR) {
        const auto& s = b.spawn_actor();
        const std::string owner = s.owner().to_string();
        if (!owner.empty() && owner != name_) continue;
        const std::string bp = s.blueprint().to_string();
        if (bp != "sensor.other.imu" && bp != "sensor.camera.rgb") continue;
        bool late = false;
        for (const auto& a : s.attributes()) late |= a.key().to_string() == "role_name" && a.value().to_string() == "late";
        sensors_[s.actor()] = {bp == "sensor.camera.rgb", late, s.parent()};
        if (bp == "sensor.camera.rgb") {  // a topic per camera, as the render service
          const std::string topic = topics::ImageTopicName(s.actor());
          images_[s.actor()] = Writer<msg::Image>(bus_, Topic<msg::Image>{topic.c_str(), QosKind::kImage});
        }
      } else if (b._d() == msg::CommandKind::CMD_DESTROY_ACTOR) {
        // As CARLA's: only the actor goes; a sensor attached to it stays, detached.
        const uint32_t doomed = b.destroy_actor().actor();
        images_.erase(doomed);
        sensors_.erase(doomed);
        for (auto& [id, s] : sensors_) {
          if (s.parent == doomed) s.parent = 0;
        }
      }
    }
    if (replaying()) return;
    msg::FrameStamp stamp;
    stamp.run(tick.run());
    stamp.frame(tick.frame());
    stamp.sim_time(tick.sim_time());
    for (const auto& [id, s] : sensors_) {
      if (s.late && tick.frame() == skip_frame_) continue;
      if (s.camera) {
        msg::Image im;
        im.sensor(id);
        im.stamp(stamp);
        im.width(8);
        im.height(4);
        im.step(32);
        im.encoding(static_cast<uint32_t>(msg::ImageEncoding::IMAGE_BGRA8));
        im.data(std::vector<uint8_t>(128, static_cast<uint8_t>(tick.frame() & 0xff)));
        images_.at(id).Write(im);
      } else {
        msg::Imu m;
        m.sensor(id);
        m.stamp(stamp);
        m.accelerometer().z(static_cast<double>(tick.frame()));  // the frame, so tests can check order
        imu_.Write(m);
      }
    }
  }

 private:
  struct Sensor {
    bool camera = false;
    bool late = false;
    uint32_t parent = 0;
  };
  Bus& bus_;
  std::string name_;
  uint64_t skip_frame_;
  std::map<uint32_t, Sensor> sensors_;
  Writer<msg::Imu> imu_;
  std::map<uint32_t, Writer<msg::Image>> images_;
  std::mutex hold_mu_;
  std::condition_variable hold_cv_;
  bool held_ = false;
};

}  // namespace lockstep::testing
