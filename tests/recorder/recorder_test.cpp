// Perception-phase alignment: the recorder (a perception member of the barrier) records,
// in tick k, the AirState of frame k (strict) or k-1 (pipelined): never "the latest".
// Misalignment is zero frames in both modes, checked against every published AirState.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <map>
#include <mutex>
#include <sstream>
#include <thread>

#include "air_service.h"
#include "lockstep/coordinator/coordinator.h"
#include "observer.h"
#include "recorder.h"

namespace lockstep {
namespace {

using namespace std::chrono_literals;

// Runs coordinator + air_sim + recorder for `ticks` frames; returns frames.csv rows
// (frame -> recorded air hash) and every AirState hash by frame.
void RunRecorded(msg::PerceptionMode mode, uint64_t ticks, std::map<uint64_t, std::string>* recorded, std::map<uint64_t, uint64_t>* published) {
  const std::string out = std::filesystem::temp_directory_path() / ("lockstep-recorder-" + std::to_string(getpid()) + "-" + std::to_string(static_cast<int>(mode)));
  std::filesystem::remove_all(out);
  LaunchConfig c;
  c.world = DefaultWorldSettings();
  c.world.perception_mode(mode);
  c.world.service_timeout(30);
  c.ticks = ticks;
  c.services.push_back({"air_sim", "air_sim", "", {}, true, false, "never"});
  c.services.push_back({"recorder", "recorder", "", {}, true, true, "never"});
  ScheduledCommand spawn;
  spawn.frame = 1;
  spawn.alias = "d";
  msg::SpawnActor s;
  s.blueprint("drone.generic_quad");
  s.transform().orientation().w(1);
  msg::CommandBody b;
  b.spawn_actor(s);
  spawn.command.body(b);
  c.scenario.push_back(spawn);
  for (auto [frame, kind] : {std::pair{2ull, msg::DroneCommandKind::DRONE_ARM}, std::pair{3ull, msg::DroneCommandKind::DRONE_TAKEOFF}}) {
    ScheduledCommand step;
    step.frame = frame;
    step.actor_alias = "d";
    msg::DroneCommand d;
    d.kind(kind);
    msg::CommandBody db;
    db.drone(d);
    step.command.body(db);
    c.scenario.push_back(step);
  }
  auto bus = CreateInProcessBus();
  std::mutex mu;
  Reader<msg::AirState> states(*bus, topics::kAirState, [&](const msg::AirState& a, const SampleInfo&) {
    std::lock_guard<std::mutex> lock(mu);
    (*published)[a.stamp().frame()] = a.state_hash();
  });
  testing::Observer obs(*bus);
  Coordinator coordinator(*bus, c);
  AirService air(*bus);
  Recorder recorder(*bus, RecorderOptions{out, true, 10});
  ServiceRunner air_runner(*bus, ServiceOptions{"air_sim", "air_sim", false}, air);
  ServiceRunner rec_runner(*bus, ServiceOptions{"recorder", "recorder", true}, recorder);
  std::atomic<bool> stop{false};
  std::thread a([&] { air_runner.Run(stop); });
  std::thread r([&] { rec_runner.Run(stop); });
  coordinator.Run(stop);  // returns after `ticks` frames
  stop = true;
  a.join();
  r.join();
  std::ifstream in(out + "/run1/frames.csv");
  std::string line;
  std::getline(in, line);  // header
  while (std::getline(in, line)) {
    std::stringstream ss(line);
    std::string frame, time, commands, shown, hash;
    std::getline(ss, frame, ',');
    std::getline(ss, time, ',');
    std::getline(ss, commands, ',');
    std::getline(ss, shown, ',');
    std::getline(ss, hash, ',');
    EXPECT_EQ(std::stoull(shown), mode == msg::PerceptionMode::PERCEPTION_PIPELINED ? std::stoull(frame) - 1 : std::stoull(frame));
    (*recorded)[std::stoull(frame)] = hash;
  }
  std::filesystem::remove_all(out);
}

std::string Hex(uint64_t v) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%016llx", static_cast<unsigned long long>(v));
  return buf;
}

TEST(PerceptionAlignment, StrictRecordsTheSameFrame) {
  std::map<uint64_t, std::string> recorded;
  std::map<uint64_t, uint64_t> published;
  RunRecorded(msg::PerceptionMode::PERCEPTION_STRICT, 150, &recorded, &published);
  ASSERT_EQ(recorded.size(), 150u);
  for (uint64_t k = 1; k <= 150; ++k) EXPECT_EQ(recorded[k], Hex(published.at(k))) << "tick " << k;
}

TEST(PerceptionAlignment, PipelinedRecordsThePreviousFrame) {
  std::map<uint64_t, std::string> recorded;
  std::map<uint64_t, uint64_t> published;
  RunRecorded(msg::PerceptionMode::PERCEPTION_PIPELINED, 150, &recorded, &published);
  ASSERT_EQ(recorded.size(), 150u);
  EXPECT_EQ(recorded[1], Hex(0)) << "nothing to show yet in the first tick";
  for (uint64_t k = 2; k <= 150; ++k) EXPECT_EQ(recorded[k], Hex(published.at(k - 1))) << "tick " << k;
  // The hashes change while the drone flies, so a shift by one frame would be caught.
  EXPECT_NE(published.at(100), published.at(101));
}

}  // namespace
}  // namespace lockstep
