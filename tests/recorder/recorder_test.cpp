// The recorder service over the in-process bus with the real coordinator and physics:
// - perception alignment: in tick k the log holds the states of frame k (strict) or k-1
//   (pipelined), never "the latest", checked against every published AirState;
// - a run with cars (Traffic Manager), walkers, Town01's traffic lights and drones, recorded
//   from a client's start_recorder mid-run, re-simulated from the log: every frame's world
//   hash equal; with one command dropped from the tick stream the first differing frame and
//   service are named; a log of another map, seed or set of services is refused.
#include <gtest/gtest.h>
#include <unistd.h>

#include <zlib.h>

#include <filesystem>
#include <fstream>
#include <iterator>
#include <map>
#include <mutex>
#include <random>
#include <set>
#include <thread>

#include "air_service.h"
#include "ground_service.h"
#include "lockstep/coordinator/coordinator.h"
#include "lockstep/map/map.h"
#include "lockstep/recorder/log_reader.h"
#include "lockstep/recorder/log_writer.h"
#include "lockstep/recorder/resimulate.h"
#include "lockstep/recorder/sensor_export.h"
#include "lockstep/runtime/blueprint_builder.h"
#include "lockstep/runtime/command_builders.h"
#include "recorder.h"

namespace lockstep {
namespace {

using namespace std::chrono_literals;

const std::string kTown01 = std::string(LOCKSTEP_CARLA_MAPS_DIR) + "/Town01.xodr";

std::string TempDir(const std::string& name) {
  return (std::filesystem::temp_directory_path() / ("lockstep-recorder-" + std::to_string(getpid()) + "-" + name)).string();
}

ScheduledCommand Step(uint64_t frame, msg::CommandBody body, const std::string& alias = "", const std::string& actor_alias = "") {
  ScheduledCommand s;
  s.frame = frame;
  s.alias = alias;
  s.actor_alias = actor_alias;
  s.command.client("scenario");
  s.command.sequence_number(frame * 100 + 1);
  s.command.body(body);
  return s;
}

msg::CommandBody DroneBody(msg::DroneCommandKind kind) {
  msg::DroneCommand d;
  d.kind(kind);
  d.yaw().is_rate(true);
  msg::CommandBody b;
  b.drone(d);
  return b;
}

// Runs the coordinator with `config` and the cores of its services on one in-process bus
// until the config's ticks are done. `watch` is made on the bus before anything starts;
// `other` makes the cores of kinds not here.
using CoreFactory = std::function<std::unique_ptr<ServiceCore>(Bus&, const ServiceLaunch&)>;
void RunInProcess(const LaunchConfig& config, const RecorderOptions& recorder_options,
                  const std::function<void(Bus&)>& watch = {}, const std::function<void()>& after = {}, const CoreFactory& other = {}) {
  auto bus = CreateInProcessBus();
  if (watch) watch(*bus);
  Coordinator coordinator(*bus, config);
  std::vector<std::unique_ptr<ServiceCore>> cores;
  std::vector<std::unique_ptr<ServiceRunner>> runners;
  for (const auto& s : config.services) {
    std::unique_ptr<ServiceCore> core;
    if (s.kind == "air_sim") core = std::make_unique<AirService>(*bus, s.name);
    if (s.kind == "ground_sim") core = std::make_unique<GroundService>(*bus, s.name);
    if (s.kind == "recorder") core = std::make_unique<Recorder>(*bus, recorder_options);
    if (!core && other) core = other(*bus, s);
    ASSERT_NE(core, nullptr) << "no core of kind " << s.kind;
    cores.push_back(std::move(core));
    runners.push_back(std::make_unique<ServiceRunner>(*bus, ServiceOptions{s.name, s.kind, s.perception}, *cores.back()));
  }
  std::atomic<bool> stop{false};
  std::vector<std::thread> threads;
  for (auto& r : runners) threads.emplace_back([&r, &stop] { r->Run(stop); });
  coordinator.Run(stop);  // returns after config.ticks frames
  stop = true;
  for (auto& t : threads) t.join();
  runners.clear();
  cores.clear();  // the recorder closes its log
  if (after) after();
}

// Perception alignment: the log's drone pose in tick k is the AirState of frame k (strict)
// or k - 1 (pipelined).
void CheckAlignment(msg::PerceptionMode mode) {
  const std::string out = TempDir("align" + std::to_string(static_cast<int>(mode)));
  std::filesystem::remove_all(out);
  LaunchConfig c;
  c.world = DefaultWorldSettings();
  c.world.perception_mode(mode);
  c.world.service_timeout(30);
  c.ticks = 150;
  c.services.push_back({"air_sim", "air_sim", "", {}, true, false, "never"});
  c.services.push_back({"recorder", "recorder", "", {}, true, true, "never"});
  c.scenario.push_back(Step(1, SpawnBody("drone.generic_quad", MakePose(0, 0, 0)), "d"));
  c.scenario.push_back(Step(2, DroneBody(msg::DroneCommandKind::DRONE_ARM), "", "d"));
  c.scenario.push_back(Step(3, DroneBody(msg::DroneCommandKind::DRONE_TAKEOFF), "", "d"));
  RecorderOptions o;
  o.output_dir = out;
  o.record_run = true;
  std::mutex mu;
  std::map<uint64_t, double> published;  // frame -> drone z
  std::unique_ptr<Reader<msg::AirState>> states;
  RunInProcess(c, o, [&](Bus& bus) {
    states = std::make_unique<Reader<msg::AirState>>(bus, topics::kAirState, [&](const msg::AirState& a, const SampleInfo&) {
      std::lock_guard<std::mutex> lock(mu);
      if (!a.drones().empty()) published[a.stamp().frame()] = a.drones()[0].transform().position().z();
    });
  });
  states.reset();
  recorder::LogReader log(out + "/run1/recording.lslog");
  EXPECT_EQ(log.first_frame(), 1u);
  EXPECT_EQ(log.last_frame(), 150u);
  const bool pipelined = mode == msg::PerceptionMode::PERCEPTION_PIPELINED;
  uint64_t compared = 0;
  log.ForEach([&](const recorder::LogFrame& f) {
    EXPECT_EQ(f.state_frame, pipelined ? f.frame - 1 : f.frame);
    if (f.actors.empty()) return true;
    EXPECT_NEAR(f.actors[0].z, published.at(f.state_frame), 0.0005) << "tick " << f.frame;
    ++compared;
    return true;
  });
  EXPECT_GE(compared, 148u);
  // The drone climbs, so a shift by one frame would be caught (its pose is checked to half
  // a millimetre; these frames move it by more than 2 mm).
  int moving = 0;
  for (uint64_t k = 2; k <= 150; ++k) moving += std::abs(published.at(k) - published.at(k - 1)) > 0.002;
  EXPECT_GE(moving, 20);
  std::filesystem::remove_all(out);
}

TEST(PerceptionAlignment, StrictRecordsTheSameFrame) { CheckAlignment(msg::PerceptionMode::PERCEPTION_STRICT); }
TEST(PerceptionAlignment, PipelinedRecordsThePreviousFrame) { CheckAlignment(msg::PerceptionMode::PERCEPTION_PIPELINED); }

class Resimulation : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    dir_ = TempDir("resim");
    std::filesystem::remove_all(dir_);
    setenv("LOCKSTEP_RECORDINGS_DIR", dir_.c_str(), 1);
    config_ = Config();
    RecorderOptions o;
    o.config_text = "(test config)";
    RunInProcess(config_, o);
  }
  static void TearDownTestSuite() {
    std::filesystem::remove_all(dir_);
    unsetenv("LOCKSTEP_RECORDINGS_DIR");
  }

  // Cars under the Traffic Manager, walkers, Town01's lights, two drones; a client-like
  // start_recorder at frame 20 (so the log carries the ticks before it) and a stop at 170.
  static LaunchConfig Config() {
    LaunchConfig c;
    c.world = DefaultWorldSettings();
    c.world.service_timeout(60);
    c.map = kTown01;
    c.seed = 7;
    c.ticks = 180;
    c.services.push_back({"air_sim", "air_sim", "", {}, true, false, "never"});
    c.services.push_back({"ground_sim", "ground_sim", "", {}, true, false, "never"});
    c.services.push_back({"recorder", "recorder", "", {}, true, true, "never"});
    const map::Map town = map::Map::Load(kTown01);
    const uint32_t lights = static_cast<uint32_t>(town.TrafficLights().size());
    const auto& sp = town.SpawnPoints();
    uint32_t next = lights + 1;
    for (int i = 0; i < 3; ++i) {
      const auto& p = sp.at(static_cast<size_t>(i) * 7);
      c.scenario.push_back(Step(1, SpawnBody("vehicle.tesla.model3", MakePose(p.location.x(), p.location.y(), p.location.z() + 0.27, p.yaw)),
                                "car" + std::to_string(i)));
      ++next;
      msg::TrafficManagerCommand tm;
      tm.parameter(msg::TrafficManagerParameter::TM_AUTOPILOT);
      tm.value(1);
      msg::CommandBody b;
      b.traffic_manager(tm);
      c.scenario.push_back(Step(2, b, "", "car" + std::to_string(i)));
    }
    const auto walk = town.PedestrianSpawnPoints();
    for (int i = 0; i < 2; ++i) {
      const auto& p = walk.at(static_cast<size_t>(i) * 5);
      c.scenario.push_back(Step(1, SpawnBody("walker.pedestrian.0001", MakePose(p.location.x(), p.location.y(), p.location.z() + 0.42, 0))));
      walkers_.push_back(next++);
    }
    for (uint64_t frame : {3ull, 60ull, 120ull}) {
      for (size_t i = 0; i < walkers_.size(); ++i) {
        msg::WalkerControl w;
        w.actor(walkers_[i]);
        w.direction().x(frame == 60 ? 0.0 : 1.0);
        w.direction().y(frame == 60 ? 1.0 : 0.0);
        w.speed(1.2f + 0.2f * static_cast<float>(i));
        msg::CommandBody b;
        b.walker_control(w);
        c.scenario.push_back(Step(frame, b));
      }
    }
    for (int i = 0; i < 2; ++i) {
      const std::string d = "drone" + std::to_string(i);
      const auto& p = sp.at(50 + static_cast<size_t>(i));
      c.scenario.push_back(Step(1, SpawnBody("drone.generic_quad", MakePose(p.location.x(), p.location.y(), p.location.z() + 0.3, 0)), d));
      c.scenario.push_back(Step(5, DroneBody(msg::DroneCommandKind::DRONE_ARM), "", d));
      c.scenario.push_back(Step(30, DroneBody(msg::DroneCommandKind::DRONE_TAKEOFF), "", d));
    }
    c.scenario.push_back(Step(20, RecorderBody(msg::RecorderAction::RECORDER_START, "resim.lslog")));
    c.scenario.push_back(Step(170, RecorderBody(msg::RecorderAction::RECORDER_STOP)));
    std::stable_sort(c.scenario.begin(), c.scenario.end(), [](const auto& a, const auto& b) { return a.frame < b.frame; });
    return c;
  }

  static std::string LogPath() { return dir_ + "/resim.lslog"; }

  // Re-simulates `log` with `config` (the resimulation config, maybe edited) and checks it.
  static recorder::ResimulationResult Resimulate(recorder::LogReader& log, const LaunchConfig& config) {
    RecorderOptions o;
    o.read_only = true;  // never overwrite the log it replays
    std::unique_ptr<recorder::ResimulationCheck> check;
    recorder::ResimulationResult result;
    std::atomic<bool> never{false};
    std::thread waiter;
    RunInProcess(
        config, o,
        [&](Bus& bus) {
          check = std::make_unique<recorder::ResimulationCheck>(bus, log);
          waiter = std::thread([&] { result = check->Wait(120, never); });
        },
        [&] {
          waiter.join();
          check.reset();
        });
    return result;
  }

  static inline std::string dir_;
  static inline LaunchConfig config_;
  static inline std::vector<uint32_t> walkers_;
};

TEST_F(Resimulation, TheLogHoldsCarsWalkersLightsAndDronesWithHashes) {
  recorder::LogReader log(LogPath());
  EXPECT_FALSE(log.truncated());
  EXPECT_EQ(log.stop_reason(), "stopped");
  EXPECT_EQ(log.first_frame(), 20u);
  EXPECT_EQ(log.last_frame(), 169u);
  EXPECT_EQ(log.header().prelude_frames, 19u);
  EXPECT_FALSE(log.header().prelude.empty());
  EXPECT_EQ(log.header().map_name, "Town01");
  std::map<msg::ActorKind, int> kinds;
  for (const auto& [id, a] : log.actors()) ++kinds[a.kind];
  EXPECT_EQ(kinds[msg::ActorKind::ACTOR_VEHICLE], 3);
  EXPECT_EQ(kinds[msg::ActorKind::ACTOR_WALKER], 2);
  EXPECT_EQ(kinds[msg::ActorKind::ACTOR_DRONE], 2);
  EXPECT_GT(kinds[msg::ActorKind::ACTOR_TRAFFIC_LIGHT], 5);
  uint64_t hashed = 0;
  log.ForEach([&](const recorder::LogFrame& f) {
    if (f.hashes) {
      ++hashed;
      EXPECT_EQ(f.hashes->services.size(), 3u) << f.frame;
    }
    return true;
  });
  EXPECT_EQ(hashed, log.frame_count()) << "every frame has its FrameDone hash";
}

TEST_F(Resimulation, EveryFrameHashIsReproduced) {
  recorder::LogReader log(LogPath());
  const LaunchConfig c = recorder::ResimulationConfig(log, config_);
  const auto r = Resimulate(log, c);
  EXPECT_TRUE(r.ok()) << r.reason;
  EXPECT_EQ(r.frames_checked, log.frame_count());
  EXPECT_EQ(r.first_differing, 0u) << r.reason;
}

TEST_F(Resimulation, ADroppedCommandIsNamedWithItsFrameAndService) {
  recorder::LogReader log(LogPath());
  LaunchConfig c = recorder::ResimulationConfig(log, config_);
  // Drop the second drone's takeoff (frame 30): air_sim's state differs from that frame on.
  size_t dropped = 0;
  for (auto it = c.scenario.begin(); it != c.scenario.end(); ++it) {
    if (it->frame == 30 && it->command.body()._d() == msg::CommandKind::CMD_DRONE) {
      if (++dropped == 2) {
        c.scenario.erase(it);
        break;
      }
    }
  }
  ASSERT_EQ(dropped, 2u);
  const auto r = Resimulate(log, c);
  EXPECT_FALSE(r.ok());
  EXPECT_EQ(r.first_differing, 30u) << r.reason;
  EXPECT_NE(r.reason.find("differs"), std::string::npos) << r.reason;
}

TEST_F(Resimulation, ALogOfAnotherMapSeedOrServicesIsRefused) {
  recorder::LogReader log(LogPath());
  LaunchConfig other_map = config_;
  other_map.map = std::string(LOCKSTEP_CARLA_MAPS_DIR) + "/Town02.xodr";
  const std::string why = recorder::ResimulationRefusal(log, other_map);
  EXPECT_NE(why.find("recorded on map 'Town01'"), std::string::npos) << why;
  EXPECT_NE(why.find("'Town02'"), std::string::npos) << why;
  EXPECT_THROW(recorder::ResimulationConfig(log, other_map), recorder::LogError);
  LaunchConfig other_seed = config_;
  other_seed.seed = 8;
  EXPECT_NE(recorder::ResimulationRefusal(log, other_seed).find("seed 7"), std::string::npos);
  LaunchConfig other_services = config_;
  other_services.services.pop_back();
  EXPECT_NE(recorder::ResimulationRefusal(log, other_services).find("services"), std::string::npos);
  EXPECT_EQ(recorder::ResimulationRefusal(log, config_), "");
}

// Sensor outputs. FakeSensors stands in for the sensors and render services: it declares a
// camera and a LiDAR and, in every tick, publishes one sample of that frame per sensor
// with pseudo-random content of another size each frame (a padded image row, a varying
// point count), keeping what it published.
struct Published {
  std::mutex mu;
  std::map<uint32_t, std::string> roles;  // sensor -> role_name
  std::map<std::pair<uint32_t, uint64_t>, msg::Image> images;       // (sensor, frame)
  std::map<std::pair<uint32_t, uint64_t>, msg::PointCloud> clouds;
};

class FakeSensors final : public ServiceCore {
 public:
  FakeSensors(Bus& bus, std::shared_ptr<Published> out) : bus_(bus), out_(std::move(out)), clouds_(bus, topics::kPointCloud) {}
  void BeginRun(const msg::WorldInfo&) override {}
  std::vector<msg::BlueprintDeclaration> Blueprints() const override {
    return {blueprint::Make("sensor.camera.rgb", msg::ActorKind::ACTOR_SENSOR, {blueprint::String("role_name", "")}),
            blueprint::Make("sensor.lidar.ray_cast", msg::ActorKind::ACTOR_SENSOR, {blueprint::String("role_name", "")})};
  }
  void Step(const msg::Tick& tick) override {
    for (const auto& c : tick.commands()) {
      if (c.body()._d() != msg::CommandKind::CMD_SPAWN_ACTOR) continue;
      const auto& s = c.body().spawn_actor();
      std::string role;
      for (const auto& a : s.attributes()) {
        if (a.key().to_string() == "role_name") role = a.value().to_string();
      }
      {
        std::lock_guard<std::mutex> lock(out_->mu);
        out_->roles[s.actor()] = role;
      }
      if (s.blueprint().to_string() == "sensor.camera.rgb") {
        const std::string topic = topics::ImageTopicName(s.actor());
        cameras_[s.actor()] = std::make_unique<Writer<msg::Image>>(bus_, Topic<msg::Image>{topic.c_str(), QosKind::kImage});
      } else {
        lidars_.push_back(s.actor());
      }
    }
    const uint64_t k = tick.frame();
    std::mt19937 rng(static_cast<uint32_t>(k));
    auto bytes = [&](size_t n) {
      std::vector<uint8_t> v(n);
      for (auto& b : v) b = static_cast<uint8_t>(rng());
      return v;
    };
    msg::FrameStamp stamp;
    stamp.run(tick.run());
    stamp.frame(k);
    stamp.sim_time(tick.sim_time());
    for (auto& [id, w] : cameras_) {
      msg::Image im;
      im.sensor(id);
      im.stamp(stamp);
      im.sensor_pose(MakePose(static_cast<double>(k), 2, 3, 0.1 * static_cast<double>(id)));
      im.width(16 + static_cast<uint32_t>(k % 5));
      im.height(12);
      im.step(im.width() * 4 + 8);  // padded rows
      im.encoding(static_cast<uint32_t>(msg::ImageEncoding::IMAGE_BGRA8));
      im.fov(1.5);
      im.data(bytes(static_cast<size_t>(im.step()) * im.height()));
      w->Write(im);
      std::lock_guard<std::mutex> lock(out_->mu);
      out_->images[{id, k}] = im;
    }
    for (uint32_t id : lidars_) {
      msg::PointCloud pc;
      pc.sensor(id);
      pc.stamp(stamp);
      pc.format(msg::PointFormat::POINTS_XYZI);
      pc.point_count(100 + static_cast<uint32_t>(k % 37));
      pc.point_step(16);
      pc.points_per_channel({pc.point_count() / 2, pc.point_count() - pc.point_count() / 2});
      pc.data(bytes(static_cast<size_t>(pc.point_count()) * 16));
      clouds_.Write(pc);
      std::lock_guard<std::mutex> lock(out_->mu);
      out_->clouds[{id, k}] = pc;
    }
  }

 private:
  Bus& bus_;
  std::shared_ptr<Published> out_;
  Writer<msg::PointCloud> clouds_;
  std::map<uint32_t, std::unique_ptr<Writer<msg::Image>>> cameras_;
  std::vector<uint32_t> lidars_;
};

// A run with two cameras (role_name front and rear) and a LiDAR spawned at frame 2.
LaunchConfig SensorConfig(uint64_t ticks) {
  LaunchConfig c;
  c.world = DefaultWorldSettings();
  c.world.service_timeout(30);
  c.ticks = ticks;
  c.services.push_back({"sensors", "fake_sensors", "", {}, true, true, "never"});
  c.services.push_back({"recorder", "recorder", "", {}, true, true, "never"});
  c.scenario.push_back(Step(2, SpawnBody("sensor.camera.rgb", MakePose(0, 0, 2), {{"role_name", "front"}})));
  c.scenario.push_back(Step(2, SpawnBody("sensor.camera.rgb", MakePose(0, 0, 2), {{"role_name", "rear"}})));
  c.scenario.push_back(Step(2, SpawnBody("sensor.lidar.ray_cast", MakePose(0, 0, 2.4), {{"role_name", "roof"}})));
  return c;
}

std::shared_ptr<Published> RunWithSensors(const LaunchConfig& c, const RecorderOptions& o) {
  auto published = std::make_shared<Published>();
  RunInProcess(c, o, {}, {}, [&](Bus& bus, const ServiceLaunch& s) -> std::unique_ptr<ServiceCore> {
    if (s.kind != "fake_sensors") return nullptr;
    return std::make_unique<FakeSensors>(bus, published);
  });
  return published;
}

// The log's sensor samples by (sensor, frame); each must come once.
std::map<std::pair<uint32_t, uint64_t>, recorder::SensorRecord> Samples(recorder::LogReader& log) {
  std::map<std::pair<uint32_t, uint64_t>, recorder::SensorRecord> got;
  log.ForEach([&](const recorder::LogFrame& f) {
    for (const auto& s : f.sensors) {
      EXPECT_LE(s.frame, f.state_frame) << "a sample of a later frame in frame " << f.frame;
      EXPECT_TRUE(got.emplace(std::pair{s.sensor, s.frame}, s).second) << "sensor " << s.sensor << " frame " << s.frame << " twice";
    }
    return true;
  });
  return got;
}

// Every published sample of the chosen sensors within the log's frames is in the log, the
// message bit for bit (CDR) and decoded again field by field; no other sensor's is.
// `lidar_from`: a recording started mid-run subscribes to the shared sensor topics when it
// starts, so the LiDAR's sample of its first frame may have gone by (cameras keep theirs).
void ExpectRecordedAsPublished(recorder::LogReader& log, Published& p, const std::set<std::string>& chosen_roles, uint64_t lidar_from = 0) {
  const auto got = Samples(log);
  std::lock_guard<std::mutex> lock(p.mu);
  size_t expected = 0;
  for (const auto& [key, im] : p.images) {
    if (key.second < log.first_frame() || key.second > log.last_frame()) continue;
    auto it = got.find(key);
    if (!chosen_roles.count(p.roles.at(key.first))) {
      EXPECT_EQ(it, got.end()) << "camera " << p.roles.at(key.first) << " was not chosen";
      continue;
    }
    ++expected;
    ASSERT_NE(it, got.end()) << "camera " << key.first << " frame " << key.second << " missing";
    EXPECT_EQ(it->second.type, "Image");
    EXPECT_EQ(it->second.cdr, recorder::ToCdr(im)) << "camera " << key.first << " frame " << key.second << " altered";
    const auto back = recorder::FromCdr<msg::Image>(it->second.cdr);
    EXPECT_EQ(back.data(), im.data());
    EXPECT_EQ(back.width(), im.width());
    EXPECT_EQ(back.step(), im.step());
    EXPECT_EQ(back.stamp().frame(), key.second);
    EXPECT_EQ(back.sensor_pose().position().x(), im.sensor_pose().position().x());
  }
  for (const auto& [key, pc] : p.clouds) {
    if (key.second < log.first_frame() || key.second > log.last_frame()) continue;
    auto it = got.find(key);
    if (!chosen_roles.count(p.roles.at(key.first))) {
      EXPECT_EQ(it, got.end()) << "lidar " << key.first << " was not chosen";
      continue;
    }
    if (key.second < lidar_from && it == got.end()) continue;
    ++expected;
    ASSERT_NE(it, got.end()) << "lidar " << key.first << " frame " << key.second << " missing";
    EXPECT_EQ(it->second.type, "PointCloud");
    EXPECT_EQ(it->second.cdr, recorder::ToCdr(pc)) << "lidar " << key.first << " frame " << key.second << " altered";
    const auto back = recorder::FromCdr<msg::PointCloud>(it->second.cdr);
    EXPECT_EQ(back.data(), pc.data());
    EXPECT_EQ(back.point_count(), pc.point_count());
    EXPECT_EQ(back.points_per_channel(), pc.points_per_channel());
  }
  EXPECT_GT(expected, 0u);
  EXPECT_EQ(got.size(), expected) << "the log holds samples nobody published or chose";
  uint64_t counted = 0;
  for (const auto& st : log.sensor_stats()) counted += st.samples;
  EXPECT_EQ(counted, expected);
}

// PNG as EncodePng writes it: the pixels of its one IDAT chunk (filter 0 rows).
std::vector<uint8_t> PngPixels(const std::vector<uint8_t>& png, uint32_t* width, uint32_t* height) {
  auto be32 = [&](size_t at) {
    return static_cast<uint32_t>(png.at(at)) << 24 | static_cast<uint32_t>(png.at(at + 1)) << 16 | static_cast<uint32_t>(png.at(at + 2)) << 8 |
           png.at(at + 3);
  };
  std::vector<uint8_t> idat;
  for (size_t at = 8; at + 8 <= png.size();) {
    const uint32_t len = be32(at);
    const std::string type(png.begin() + static_cast<std::ptrdiff_t>(at + 4), png.begin() + static_cast<std::ptrdiff_t>(at + 8));
    if (type == "IHDR") {
      *width = be32(at + 8);
      *height = be32(at + 12);
    }
    if (type == "IDAT") idat.insert(idat.end(), png.begin() + static_cast<std::ptrdiff_t>(at + 8), png.begin() + static_cast<std::ptrdiff_t>(at + 8 + len));
    at += 12 + len;
  }
  std::vector<uint8_t> raw(static_cast<size_t>(*width * 4 + 1) * *height);
  uLongf size = raw.size();
  EXPECT_EQ(uncompress(raw.data(), &size, idat.data(), idat.size()), Z_OK);
  std::vector<uint8_t> rgba;
  for (uint32_t y = 0; y < *height; ++y) {
    EXPECT_EQ(raw[y * (*width * 4 + 1)], 0);
    rgba.insert(rgba.end(), raw.begin() + y * (*width * 4 + 1) + 1, raw.begin() + (y + 1) * (*width * 4 + 1));
  }
  return rgba;
}

std::vector<uint8_t> ReadFile(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  return std::vector<uint8_t>(std::istreambuf_iterator<char>(in), {});
}

// The launch config's selection (--record-sensors) on a whole-run recording: the front
// camera and every LiDAR, not the rear camera; `lockstep log export --sensors` gives the
// images back as PNG and the clouds as PLY with the published pixels and points.
TEST(SensorOutputs, ChosenCameraAndLidarFramesReadBackAsPublished) {
  const std::string out = TempDir("sensors");
  std::filesystem::remove_all(out);
  RecorderOptions o;
  o.output_dir = out;
  o.record_run = true;
  o.record_sensors = "role_name=front, sensor.lidar.*";
  auto published = RunWithSensors(SensorConfig(40), o);
  recorder::LogReader log(out + "/run1/recording.lslog");
  EXPECT_EQ(log.header().sensor_selection, "role_name=front, sensor.lidar.*");
  EXPECT_EQ(log.first_frame(), 1u);
  EXPECT_EQ(log.last_frame(), 40u);
  ExpectRecordedAsPublished(log, *published, {"front", "roof"});
  ASSERT_EQ(log.sensor_stats().size(), 2u);

  recorder::SensorExportOptions eo;
  const auto r = recorder::ExportSensors(log, out + "/export", eo);
  EXPECT_EQ(r.by_type.at("Image"), 39u);  // frames 2..40
  EXPECT_EQ(r.by_type.at("PointCloud"), 39u);
  std::lock_guard<std::mutex> lock(published->mu);
  for (const auto& [key, im] : published->images) {
    if (published->roles.at(key.first) != "front" || key.second % 9 != 0) continue;
    char name[64];
    std::snprintf(name, sizeof name, "/camera_%u/%06llu.png", key.first, static_cast<unsigned long long>(key.second));
    uint32_t w = 0, h = 0;
    const auto rgba = PngPixels(ReadFile(out + "/export" + name), &w, &h);
    ASSERT_EQ(w, im.width());
    ASSERT_EQ(h, im.height());
    for (uint32_t y = 0; y < h; ++y) {
      for (uint32_t x = 0; x < w; ++x) {
        const uint8_t* bgra = im.data().data() + y * im.step() + x * 4;
        const uint8_t* px = rgba.data() + (y * w + x) * 4;
        ASSERT_EQ(px[0], bgra[2]);
        ASSERT_EQ(px[1], bgra[1]);
        ASSERT_EQ(px[2], bgra[0]);
        ASSERT_EQ(px[3], bgra[3]);
      }
    }
  }
  for (const auto& [key, pc] : published->clouds) {
    if (key.second % 9 != 0) continue;
    char name[64];
    std::snprintf(name, sizeof name, "/lidar_%u/%06llu.ply", key.first, static_cast<unsigned long long>(key.second));
    const auto ply = ReadFile(out + "/export" + name);
    const std::string text(ply.begin(), ply.end());
    const size_t end = text.find("end_header\n");
    ASSERT_NE(end, std::string::npos);
    EXPECT_NE(text.find("element vertex " + std::to_string(pc.point_count()) + "\n"), std::string::npos);
    EXPECT_EQ(std::vector<uint8_t>(ply.begin() + static_cast<std::ptrdiff_t>(end + 11), ply.end()), pc.data());
  }
  std::filesystem::remove_all(out);
}

// CARLA's start_recorder(name, additional_data): without it a log holds no sensor output,
// with it every sensor's (the recorder has no selection of its own).
TEST(SensorOutputs, AdditionalDataRecordsEverySensor) {
  const std::string dir = TempDir("additional");
  std::filesystem::remove_all(dir);
  LaunchConfig c = SensorConfig(36);
  c.scenario.push_back(Step(4, RecorderBody(msg::RecorderAction::RECORDER_START, dir + "/plain.lslog")));
  c.scenario.push_back(Step(12, RecorderBody(msg::RecorderAction::RECORDER_START, dir + "/additional.lslog", true)));
  c.scenario.push_back(Step(30, RecorderBody(msg::RecorderAction::RECORDER_STOP)));
  std::stable_sort(c.scenario.begin(), c.scenario.end(), [](const auto& a, const auto& b) { return a.frame < b.frame; });
  auto published = RunWithSensors(c, RecorderOptions{});
  recorder::LogReader plain(dir + "/plain.lslog");
  EXPECT_EQ(plain.last_frame(), 11u);
  EXPECT_TRUE(plain.sensor_stats().empty());
  EXPECT_TRUE(Samples(plain).empty());
  recorder::LogReader additional(dir + "/additional.lslog");
  EXPECT_TRUE(additional.header().additional_data);
  EXPECT_EQ(additional.header().sensor_selection, "all");
  EXPECT_EQ(additional.header().sensors.size(), 3u) << "the sensors alive when it started";
  EXPECT_EQ(additional.first_frame(), 12u);
  EXPECT_EQ(additional.last_frame(), 29u);
  ExpectRecordedAsPublished(additional, *published, {"front", "rear", "roof"}, 13);
  std::filesystem::remove_all(dir);
}

}  // namespace
}  // namespace lockstep
