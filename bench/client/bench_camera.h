#pragma once
// bench_client's camera service: declares sensor.camera.rgb and publishes one 720p BGRA
// frame per tick per spawned camera, with the steady-clock publication time (s) in
// sensor_pose.position.x (bench only).
#include <atomic>
#include <chrono>
#include <map>
#include <string>
#include <vector>

#include "lockstep/runtime/blueprint_builder.h"
#include "lockstep/runtime/service.h"

namespace lockstep::bench {

class BenchCamera final : public ServiceCore {
 public:
  explicit BenchCamera(Bus& bus) : bus_(bus) {}
  std::vector<msg::BlueprintDeclaration> Blueprints() const override {
    namespace bp = blueprint;
    return {bp::Make("sensor.camera.rgb", msg::ActorKind::ACTOR_SENSOR,
                     {bp::String("role_name", ""), bp::Int("image_size_x", 1280, 1, 3840), bp::Int("image_size_y", 720, 1, 2160)})};
  }
  void BeginRun(const msg::WorldInfo&) override {
    images_.clear();
    cameras_ = 0;
  }
  // How many cameras it publishes (read by the bench from another thread).
  size_t cameras() const { return cameras_; }
  bool StepNeverWaits() const override { return true; }
  void Step(const msg::Tick& tick) override {
    for (const auto& c : tick.commands()) {
      if (c.body()._d() == msg::CommandKind::CMD_SPAWN_ACTOR) {
        const uint32_t id = c.body().spawn_actor().actor();
        const std::string topic = topics::ImageTopicName(id);  // one topic per camera
        images_.emplace(id, Writer<msg::Image>(bus_, Topic<msg::Image>{topic.c_str(), QosKind::kImage}));
        cameras_ = images_.size();
      }
    }
    for (auto& [id, writer] : images_) {
      msg::Image im;
      im.sensor(id);
      im.stamp().run(tick.run());
      im.stamp().frame(tick.frame());
      im.stamp().sim_time(tick.sim_time());
      im.width(1280);
      im.height(720);
      im.step(1280 * 4);
      im.encoding(static_cast<uint32_t>(msg::ImageEncoding::IMAGE_BGRA8));
      im.data().assign(1280 * 720 * 4, static_cast<uint8_t>(tick.frame()));
      im.sensor_pose().position().x(
          std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count());
      writer.Write(im);
    }
  }

 private:
  Bus& bus_;
  std::map<uint32_t, Writer<msg::Image>> images_;
  std::atomic<size_t> cameras_{0};
};

}  // namespace lockstep::bench
