// A render service restored from another one's snapshot publishes, frame for frame, the
// same images as the one it took over from (issue 21: a replacement render process resumes
// identical): an RGB camera whose auto-exposure is adapting and which moves (motion
// blur), a DVS camera that turns (its reference image), a debug box with a life that
// spans the snapshot. A service that starts the same cameras afresh instead publishes
// other images, so the snapshot is what makes them equal.
#include <gtest/gtest.h>

#include <chrono>
#include <condition_variable>
#include <list>
#include <map>
#include <memory>
#include <mutex>

#include "lockstep/runtime/command_builders.h"
#include "render_service.h"

namespace lockstep {
namespace {

using namespace std::chrono_literals;

constexpr uint32_t kRun = 1;
constexpr uint64_t kSeed = 7;
constexpr double kDt = 0.05;
constexpr uint32_t kRgb = 11, kDvs = 12;
constexpr uint64_t kSnapshotFrame = 10, kLastFrame = 16;

msg::WorldInfo World() {
  msg::WorldInfo w;
  w.run(kRun);
  w.seed(kSeed);
  w.settings().synchronous_mode(true);
  w.settings().fixed_delta_seconds(kDt);
  w.weather().sun_altitude_angle(60);
  return w;
}

msg::CommandBody Camera(uint32_t id, const std::string& bp, const msg::Pose& at) {
  // An exposure range wide enough that the scene's own EV100 is inside it: the camera adapts.
  msg::CommandBody b = SpawnBody(bp, at,
                                 {{"image_size_x", "48"}, {"image_size_y", "32"}, {"exposure_min_bright", "-10"}, {"exposure_max_bright", "20"}});
  b.spawn_actor().actor(id);
  b.spawn_actor().owner("render");
  return b;
}

// The commands of tick k: the cameras at frame 1, then each tick the RGB camera moves on
// and the DVS camera turns; a red debug box for 0.4 s from tick 8.
std::vector<msg::CommandBody> Commands(uint64_t k, bool spawn) {
  std::vector<msg::CommandBody> out;
  if (spawn) {
    out.push_back(Camera(kRgb, "sensor.camera.rgb", MakePose(0, 0, 2)));
    out.push_back(Camera(kDvs, "sensor.camera.dvs", MakePose(0, 0, 2)));
  }
  const double f = static_cast<double>(k);
  out.push_back(TransformBody(kRgb, MakePose(0.3 * f, 0, 2, 0.02 * f)));
  out.push_back(TransformBody(kDvs, MakePose(0, 0, 2, -0.05 * f)));
  if (k == 8) {
    msg::DebugShape box;
    box.kind(msg::DebugShapeKind::DEBUG_BOX);
    box.begin().x(12);
    box.begin().z(2);
    box.rotation().w(1);
    box.extent().x(1);
    box.extent().y(1);
    box.extent().z(1);
    box.size(0.3);
    box.r(255);
    box.a(255);
    box.life_time(0.4);
    msg::DebugDraw d;
    d.shapes({box});
    msg::CommandBody b;
    b.debug_draw(d);
    out.push_back(b);
  }
  return out;
}

msg::Tick Tick(uint64_t k, std::vector<msg::CommandBody> bodies) {
  msg::Tick t;
  t.run(kRun);
  t.frame(k);
  t.sim_time(kDt * static_cast<double>(k));
  t.dt(kDt);
  t.seed(kSeed);
  std::vector<msg::Command> commands;
  for (auto& b : bodies) {
    msg::Command c;
    c.body(std::move(b));
    commands.push_back(std::move(c));
  }
  t.commands(std::move(commands));
  return t;
}

// One render service on its own in-process bus, with readers of both cameras' images.
class Render {
 public:
  Render() : bus_(CreateInProcessBus()) {
    RenderOptions o;
    o.device = "cpu";
    service_ = std::make_unique<RenderService>(*bus_, "render", o);
    for (uint32_t id : {kRgb, kDvs}) {
      topics_.push_back(topics::ImageTopicName(id));
      readers_.emplace_back(*bus_, Topic<msg::Image>{topics_.back().c_str(), QosKind::kImage}, [this](const msg::Image& im, const SampleInfo&) {
        {
          std::lock_guard<std::mutex> lock(mu_);
          images_[{im.sensor(), im.stamp().frame()}] = im.data();
        }
        cv_.notify_all();
      });
    }
    service_->BeginRun(World());
  }
  RenderService& service() { return *service_; }
  // Steps tick k and waits for both cameras' images of frame k.
  void Step(uint64_t k, bool spawn) {
    service_->Step(Tick(k, Commands(k, spawn)));
    std::unique_lock<std::mutex> lock(mu_);
    ASSERT_TRUE(cv_.wait_for(lock, 20s, [&] { return images_.count({kRgb, k}) && images_.count({kDvs, k}); }))
        << "no images of frame " << k;
  }
  std::vector<uint8_t> Image(uint32_t id, uint64_t k) {
    std::lock_guard<std::mutex> lock(mu_);
    return images_.at({id, k});
  }

 private:
  std::unique_ptr<Bus> bus_;
  std::unique_ptr<RenderService> service_;
  std::list<std::string> topics_;
  std::list<Reader<msg::Image>> readers_;
  std::mutex mu_;
  std::condition_variable cv_;
  std::map<std::pair<uint32_t, uint64_t>, std::vector<uint8_t>> images_;
};

TEST(RenderSnapshot, ARestoredServicePublishesTheSameImagesAsTheOneItTookOverFrom) {
  Render original;
  for (uint64_t k = 1; k <= kSnapshotFrame; ++k) ASSERT_NO_FATAL_FAILURE(original.Step(k, k == 1));
  const std::vector<uint8_t> snapshot = original.service().SaveState();
  const uint64_t hash = original.service().StateHash();
  const double ev = original.service().state().cameras.at(kRgb).exposure.ev100();

  Render restored;
  restored.service().RestoreState(snapshot);
  EXPECT_EQ(restored.service().StateHash(), hash);
  ASSERT_EQ(restored.service().camera_count(), 2u);

  Render fresh;  // the same cameras, spawned at the snapshot's frame: no history
  for (uint64_t k = kSnapshotFrame + 1; k <= kLastFrame; ++k) {
    ASSERT_NO_FATAL_FAILURE(original.Step(k, false));
    ASSERT_NO_FATAL_FAILURE(restored.Step(k, false));
    ASSERT_NO_FATAL_FAILURE(fresh.Step(k, k == kSnapshotFrame + 1));
    EXPECT_EQ(restored.service().StateHash(), original.service().StateHash()) << "frame " << k;
  }
  // The history matters: the exposure was still adapting and the DVS camera turning.
  EXPECT_NE(original.service().state().cameras.at(kRgb).exposure.ev100(), ev) << "the exposure did not adapt: the test shows nothing";
  int differ_rgb = 0, differ_dvs = 0;
  for (uint64_t k = kSnapshotFrame + 1; k <= kLastFrame; ++k) {
    EXPECT_EQ(restored.Image(kRgb, k), original.Image(kRgb, k)) << "RGB image of frame " << k;
    EXPECT_EQ(restored.Image(kDvs, k), original.Image(kDvs, k)) << "DVS events of frame " << k;
    differ_rgb += fresh.Image(kRgb, k) != original.Image(kRgb, k);
    differ_dvs += fresh.Image(kDvs, k) != original.Image(kDvs, k);
  }
  EXPECT_GT(differ_rgb, 0) << "a camera without the history gives the same images: the test shows nothing";
  EXPECT_GT(differ_dvs, 0);
  EXPECT_NE(fresh.service().StateHash(), original.service().StateHash());
}

TEST(RenderSnapshot, ASnapshotThatIsNotOneIsRefusedNamingWhy) {
  Render r;
  ASSERT_NO_FATAL_FAILURE(r.Step(1, true));
  std::vector<uint8_t> bytes = r.service().SaveState();
  bytes.resize(bytes.size() / 2);
  try {
    r.service().RestoreState(bytes);
    FAIL() << "a truncated snapshot was accepted";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("render: render snapshot: "), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace lockstep
