// Two render processes share one world's cameras (each renders those spawned for it)
// and every image carries the frame index of the physics state it shows: the pose of a
// camera on a climbing drone matches the drone's AirState of the image's frame.
#include <gtest/gtest.h>

#include <Eigen/Geometry>

#include <iostream>
#include <list>
#include <map>
#include <mutex>
#include <optional>
#include <set>
#include <sstream>

#include "lockstep/runtime/command_builders.h"
#include "lockstep/runtime/messages.h"
#include "observer.h"
#include "process.h"

namespace lockstep::testing {
namespace {

using namespace std::chrono_literals;
const char* kProfile = "lockstep.participant.loopback";

std::string Config() {
  return "domain_id: " + std::to_string(TestDomain()) + "\nparticipant_profile: " + kProfile +
         "\nmap: " + std::string(LOCKSTEP_TEST_TOWN_DIR) + "/LockstepTown1.xodr" +
         "\nworld:\n  synchronous_mode: true\n  fixed_delta_seconds: 0.05\n  service_timeout: 60\n"
         "services:\n  - {name: air_sim, kind: air_sim}\n"
         "  - {name: render_a, kind: render, perception: true}\n  - {name: render_b, kind: render, perception: true}\n";
}

struct Received {
  uint32_t sensor;
  uint64_t frame;
  msg::Pose pose;
  uint32_t width, height, encoding;
  std::size_t bytes;
  uint32_t fnv1a;  // of the pixel bytes
};

uint32_t Fnv1a(const std::vector<uint8_t>& d) {
  uint32_t h = 2166136261u;
  for (uint8_t b : d) {
    h ^= b;
    h *= 16777619u;
  }
  return h;
}

class RenderServiceTest : public ::testing::Test {
 protected:
  void SetUp() override {
    config_ = WriteTempFile("render.yaml", Config());
    coordinator_ = std::make_unique<Process>(std::vector<std::string>{Bin("lockstep_coordinator"), config_});
    air_sim_ = std::make_unique<Process>(std::vector<std::string>{Bin("lockstep_air_sim"), "--name", "air_sim", "--config", config_});
    for (const char* n : {"render_a", "render_b"}) {
      renders_.push_back(std::make_unique<Process>(
          std::vector<std::string>{Bin("lockstep_render"), "--device", "cpu", "--name", n, "--config", config_}));
    }
    bus_ = CreateDdsBus({TestDomain(), "", kProfile, "render-test"});
    observer_ = std::make_unique<Observer>(*bus_);
    air_reader_ = Reader<msg::AirState>(*bus_, topics::kAirState, [this](const msg::AirState& s, const SampleInfo&) {
      std::lock_guard<std::mutex> lock(mu_);
      air_[s.stamp().frame()] = s;
    });
  }
  void TearDown() override {
    if (HasFailure()) {
      std::cerr << "coordinator:\n" << coordinator_->Output();
      for (auto& r : renders_) std::cerr << "render:\n" << r->Output();
    }
    image_readers_.clear();
    air_reader_ = {};
    observer_.reset();
    bus_.reset();
  }
  msg::CommandReply Send(msg::CommandBody b) {
    auto r = observer_->WaitReply(observer_->Send(std::move(b)), 20s);
    EXPECT_TRUE(r.has_value());
    return r.value_or(msg::CommandReply{});
  }
  uint32_t SpawnCamera(const std::string& bp, uint32_t parent, const msg::Pose& rel, const std::string& owner) {
    msg::CommandBody b = SpawnBody(bp, rel, {{"image_size_x", "64"}, {"image_size_y", "48"}, {"fov", "90"}});
    b.spawn_actor().parent(parent);
    b.spawn_actor().owner(owner);
    auto r = Send(b);
    EXPECT_TRUE(r.accepted()) << r.reason();
    const uint32_t id = r.actor();
    topic_names_.push_back(topics::ImageTopicName(id));
    image_readers_.emplace_back(*bus_, Topic<msg::Image>{topic_names_.back().c_str(), QosKind::kImage},
                                [this](const msg::Image& im, const SampleInfo&) {
                                  std::lock_guard<std::mutex> lock(mu_);
                                  images_.push_back({im.sensor(), im.stamp().frame(), im.sensor_pose(), im.width(), im.height(),
                                                     im.encoding(), im.data().size(), Fnv1a(im.data())});
                                });
    return id;
  }
  void Drone(uint32_t actor, msg::DroneCommandKind kind, uint64_t id) {
    msg::DroneCommand d;
    d.actor(actor);
    d.kind(kind);
    d.command_id(id);
    d.velocity(3);
    msg::CommandBody b;
    b.drone(d);
    EXPECT_TRUE(Send(b).accepted());
  }

  std::string config_;
  std::unique_ptr<Process> coordinator_, air_sim_;
  std::vector<std::unique_ptr<Process>> renders_;
  std::unique_ptr<Bus> bus_;
  std::unique_ptr<Observer> observer_;
  std::mutex mu_;
  std::map<uint64_t, msg::AirState> air_;
  std::vector<Received> images_;
  std::list<std::string> topic_names_;
  std::list<Reader<msg::Image>> image_readers_;
  Reader<msg::AirState> air_reader_;
};

TEST_F(RenderServiceTest, TwoRenderProcessesShowTheFrameOfThePhysicsState) {
  ASSERT_TRUE(observer_->WaitUntil([&] { return observer_->status() && observer_->status()->state() == msg::RunState::RUN_READY; }, 60s))
      << "the run never became ready";
  auto spawn = Send(SpawnBody("drone.generic_quad", MakePose(47.75, 1.75, 0), {}));
  ASSERT_TRUE(spawn.accepted()) << spawn.reason();
  const uint32_t drone = spawn.actor();
  // render_a: a forward camera under the drone; render_b: a depth camera on the drone and
  // a semantic camera standing in the world.
  const msg::Pose below = MakePose(0.1, 0, -0.1);
  const uint32_t rgb = SpawnCamera("sensor.camera.rgb", drone, below, "render_a");
  const uint32_t depth = SpawnCamera("sensor.camera.depth", drone, below, "render_b");
  const uint32_t world_cam = SpawnCamera("sensor.camera.semantic_segmentation", 0, MakePose(30, 1.75, 3), "render_b");
  Drone(drone, msg::DroneCommandKind::DRONE_ARM, 1);
  Drone(drone, msg::DroneCommandKind::DRONE_TAKEOFF, 2);
  // Let the image readers match the writers the render processes create on the spawns.
  msg::TickRequest t;
  t.count(1);
  msg::CommandBody tb;
  tb.tick_request(t);
  ASSERT_TRUE(Send(tb).accepted());
  ASSERT_TRUE(observer_->WaitUntil([&] { return observer_->last_frame() >= 1; }, 60s));
  ASSERT_TRUE(observer_->WaitUntil([&] {
    for (auto& r : image_readers_) {
      if (r.MatchedWriters() < 1) return false;
    }
    return true;
  }, 30s)) << "image writers never matched";
  // Our readers see the writers, but a writer may not see our reader yet (discovery goes
  // both ways): tick one frame at a time until one frame's images arrive from every camera.
  auto has_images_of = [&](uint64_t f) {
    std::lock_guard<std::mutex> lock(mu_);
    std::set<uint32_t> from;
    for (const auto& im : images_)
      if (im.frame == f) from.insert(im.sensor);
    return from.size() == 3;
  };
  // (Frame 1's images may come from the writers' history on matching, so tick at least once.)
  uint64_t warm = 1;
  for (int i = 0; i < 30 && (warm == 1 || !has_images_of(warm)); ++i) {
    t.count(1);
    tb.tick_request(t);
    auto r = Send(tb);
    ASSERT_TRUE(r.accepted());
    warm = r.frame();
    observer_->WaitUntil([&] { return has_images_of(warm); }, 2s);
  }
  ASSERT_TRUE(has_images_of(warm)) << "no frame's images came from every camera";
  t.count(20);
  tb.tick_request(t);
  auto reply = Send(tb);
  ASSERT_TRUE(reply.accepted());
  const uint64_t last = reply.frame();
  const uint64_t first = warm + 1;
  auto complete = [&] {
    std::lock_guard<std::mutex> lock(mu_);
    std::set<std::pair<uint32_t, uint64_t>> got;
    for (const auto& im : images_) got.insert({im.sensor, im.frame});
    for (uint64_t f = first; f <= last; ++f) {
      for (uint32_t s : {rgb, depth, world_cam}) {
        if (!got.count({s, f}) || !air_.count(f)) return false;
      }
    }
    return true;
  };
  auto what_came = [&] {
    std::lock_guard<std::mutex> lock(mu_);
    std::map<uint32_t, std::set<uint64_t>> frames;
    for (const auto& im : images_) frames[im.sensor].insert(im.frame);
    std::ostringstream out;
    out << "air states of frames";
    for (const auto& [f, s] : air_) out << ' ' << f;
    for (const auto& [sensor, fs] : frames) {
      out << "; camera " << sensor << ':';
      for (auto f : fs) out << ' ' << f;
    }
    out << "; last frame done " << observer_->last_frame();
    return out.str();
  };
  ASSERT_TRUE(observer_->WaitUntil(complete, 90s)) << "images of frames " << first << ".." << last << " missing: " << what_came();
  std::lock_guard<std::mutex> lock(mu_);
  std::map<std::pair<uint32_t, uint64_t>, int> count;
  double climbed = 0;
  for (const auto& im : images_) {
    ++count[{im.sensor, im.frame}];
    EXPECT_EQ(im.width, 64u);
    EXPECT_EQ(im.height, 48u);
    EXPECT_EQ(im.bytes, 64u * 48u * 4u);
    if (im.sensor == world_cam) {
      EXPECT_EQ(im.encoding, static_cast<uint32_t>(msg::ImageEncoding::IMAGE_SEMANTIC_BGRA8));
      EXPECT_NEAR(im.pose.position().x(), 30, 1e-9);
      continue;
    }
    EXPECT_EQ(im.encoding, static_cast<uint32_t>(im.sensor == rgb ? msg::ImageEncoding::IMAGE_BGRA8
                                                                    : msg::ImageEncoding::IMAGE_DEPTH_CARLA_BGRA8));
    // The camera sits 0.1 m below the drone's centre in the AirState of the same frame.
    auto a = air_.find(im.frame);
    ASSERT_NE(a, air_.end());
    ASSERT_EQ(a->second.drones().size(), 1u);
    // The mount (0.1, 0, -0.1) is in the drone's body frame, which tilts as it climbs.
    const auto& p = a->second.drones()[0].transform().position();
    const auto& o = a->second.drones()[0].transform().orientation();
    const Eigen::Vector3d expected =
        Eigen::Vector3d(p.x(), p.y(), p.z()) + Eigen::Quaterniond(o.w(), o.x(), o.y(), o.z()) * Eigen::Vector3d(0.1, 0, -0.1);
    EXPECT_NEAR(im.pose.position().x(), expected.x(), 1e-6) << "frame " << im.frame;
    EXPECT_NEAR(im.pose.position().y(), expected.y(), 1e-6) << "frame " << im.frame;
    EXPECT_NEAR(im.pose.position().z(), expected.z(), 1e-6) << "frame " << im.frame;
    if (im.frame == last) climbed = p.z() - air_.at(first).drones()[0].transform().position().z();
  }
  EXPECT_GT(climbed, 0.05) << "the drone moves, so a frame mismatch would show in the poses";
  for (const auto& [key, n] : count) EXPECT_EQ(n, 1) << "camera " << key.first << " frame " << key.second << ": one process renders it";
}

// The image topics' QoS and type serve a client on another DDS vendor too: a Cyclone DDS
// reader (tests/render_service/cyclone_image_reader.c) receives the render service's
// frames over UDP, byte for byte what a Fast DDS reader of the same camera got.
TEST_F(RenderServiceTest, ACycloneDdsClientReceivesTheFrames) {
#ifndef LOCKSTEP_HAVE_CYCLONE
  GTEST_SKIP() << "Cyclone DDS (lockstep_msgs_c) not built";
#else
  ASSERT_TRUE(observer_->WaitUntil([&] { return observer_->status() && observer_->status()->state() == msg::RunState::RUN_READY; }, 60s))
      << "the run never became ready";
  const uint32_t cam = SpawnCamera("sensor.camera.rgb", 0, MakePose(30, 1.75, 3), "render_a");
  Process cyclone({Bin("cyclone_image_reader"), "--domain", std::to_string(TestDomain()), "--topic", topics::ImageTopicName(cam),
                   "--count", "3", "--timeout-s", "60"},
                  {{"CYCLONEDDS_URI", "file://" + SourceDir() + "/client/cyclone_c/cyclone_loopback.xml"}});
  ASSERT_TRUE(observer_->WaitUntil([&] { return cyclone.Output().find("ready") != std::string::npos; }, 30s)) << cyclone.Output();
  msg::TickRequest t;
  t.count(1);
  msg::CommandBody tb;
  tb.tick_request(t);
  // Step until the Cyclone reader has its three frames (discovery across vendors takes a
  // second or two; TRANSIENT_LOCAL hands it the last two frames it missed).
  std::optional<int> exit;
  for (int i = 0; i < 200 && !exit; ++i) {
    ASSERT_TRUE(Send(tb).accepted());
    exit = cyclone.Wait(100ms);
  }
  ASSERT_EQ(exit, std::optional<int>(0)) << "the Cyclone reader got no frames:\n" << cyclone.Output();
  std::istringstream lines(cyclone.Output());
  std::string word;
  int compared = 0;
  while (lines >> word) {
    if (word != "image") continue;
    uint32_t sensor = 0, w = 0, h = 0, encoding = 0, bytes = 0, hash = 0;
    uint64_t frame = 0;
    lines >> sensor >> frame >> w >> h >> encoding >> bytes >> hash;
    EXPECT_EQ(sensor, cam);
    EXPECT_EQ(w, 64u);
    EXPECT_EQ(h, 48u);
    EXPECT_EQ(encoding, static_cast<uint32_t>(msg::ImageEncoding::IMAGE_BGRA8));
    EXPECT_EQ(bytes, 64u * 48u * 4u);
    ASSERT_TRUE(observer_->WaitUntil([&] {
      std::lock_guard<std::mutex> lock(mu_);
      for (const auto& im : images_) {
        if (im.sensor == sensor && im.frame == frame) return true;
      }
      return false;
    }, 20s)) << "the Fast DDS reader never got frame " << frame;
    std::lock_guard<std::mutex> lock(mu_);
    for (const auto& im : images_) {
      if (im.sensor != sensor || im.frame != frame) continue;
      EXPECT_EQ(im.fnv1a, hash) << "frame " << frame << ": the same bytes over both vendors";
      ++compared;
    }
  }
  EXPECT_EQ(compared, 3);
#endif
}

}  // namespace
}  // namespace lockstep::testing
