// The recorder service over the in-process bus with the real coordinator and physics:
// - perception alignment: in tick k the log holds the states of frame k (strict) or k-1
//   (pipelined), never "the latest", checked against every published AirState;
// - a run with cars (Traffic Manager), walkers, Town01's traffic lights and drones, recorded
//   from a client's start_recorder mid-run, re-simulated from the log: every frame's world
//   hash equal; with one command dropped from the tick stream the first differing frame and
//   service are named; a log of another map, seed or set of services is refused.
#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <map>
#include <mutex>
#include <thread>

#include "air_service.h"
#include "ground_service.h"
#include "lockstep/coordinator/coordinator.h"
#include "lockstep/map/map.h"
#include "lockstep/recorder/log_reader.h"
#include "lockstep/recorder/resimulate.h"
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

msg::CommandBody RecorderBody(msg::RecorderAction action, const std::string& name = "") {
  msg::RecorderCommand r;
  r.action(action);
  r.name(name);
  msg::CommandBody b;
  b.recorder(r);
  return b;
}

// Runs the coordinator with `config` and the cores of its services on one in-process bus
// until the config's ticks are done. `watch` is made on the bus before anything starts.
void RunInProcess(const LaunchConfig& config, const RecorderOptions& recorder_options,
                  const std::function<void(Bus&)>& watch = {}, const std::function<void()>& after = {}) {
  auto bus = CreateInProcessBus();
  if (watch) watch(*bus);
  Coordinator coordinator(*bus, config);
  std::vector<std::unique_ptr<ServiceCore>> cores;
  std::vector<std::unique_ptr<ServiceRunner>> runners;
  for (const auto& s : config.services) {
    if (s.kind == "air_sim") cores.push_back(std::make_unique<AirService>(*bus, s.name));
    if (s.kind == "ground_sim") cores.push_back(std::make_unique<GroundService>(*bus, s.name));
    if (s.kind == "recorder") cores.push_back(std::make_unique<Recorder>(*bus, recorder_options));
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

}  // namespace
}  // namespace lockstep
