// Issue 21: the full stack (ground_sim, air_sim, sensors under `lockstep up`, every service
// restarted on failure) with each service killed once with SIGKILL at a different frame ends
// with every frame's world hash and every sensor sample identical to an undisturbed run.
// Each replacement restores its last snapshot and replays the ticks after it with the inputs
// the state topics kept (GroundState, AirState, PhysicsEvents); without them the sensors'
// or air_sim's replay has nothing to read and the run faults. While one service is being
// replaced the others wait for its outputs: none of them is restarted (no cascade).
#include <gtest/gtest.h>
#include <signal.h>

#include <algorithm>
#include <chrono>
#include <filesystem>
#include <fstream>
#include <map>
#include <mutex>

#include "lockstep/runtime/hash.h"
#include "lockstep/runtime/messages.h"
#include "observer.h"
#include "process.h"

namespace lockstep::testing {
namespace {

using namespace std::chrono_literals;

constexpr uint64_t kTicks = 260;

std::string StackConfig(int domain) {
  return "name: stack-recovery\ndomain_id: " + std::to_string(domain) +
         "\nparticipant_profile: lockstep.participant.loopback\nseed: 21\nticks: " + std::to_string(kTicks) +
         "\nsnapshot_period: 40\nrecorder: false\nmap: " LOCKSTEP_CARLA_MAPS_DIR "/Town01.xodr\n"
         "world:\n  real_time_factor: 2\n  service_timeout: 20\n"
         "services:\n"
         "  - {name: ground_sim, kind: ground_sim, restart: on-failure}\n"
         "  - {name: air_sim, kind: air_sim, restart: on-failure}\n"
         "  - {name: sensors, kind: sensors, perception: true, restart: on-failure}\n"
         "scenario:\n"
         "  - {frame: 1, spawn: vehicle.tesla.model3, as: ego, at: [122.75, 1.75, 0.8], yaw: 3.1416, attributes: {role_name: hero}}\n"
         "  - {frame: 2, actor: ego, autopilot: true}\n"
         "  - {frame: 1, spawn: vehicle.audi.tt, as: car1, at: [207.75, 1.75, 0.8], yaw: 3.1416}\n"
         "  - {frame: 2, actor: car1, autopilot: true}\n"
         "  - {frame: 1, spawn: walker.pedestrian.0001, as: walker0, at: [124.0, 5.0, 1.0]}\n"
         "  - {frame: 2, spawn: controller.ai.walker, as: walker0_ai, parent: walker0}\n"
         "  - {frame: 3, actor: walker0_ai, walker_ai: start}\n"
         "  - {frame: 1, spawn: drone.generic_quad, as: drone, at: [100.0, -2.0, 0]}\n"
         "  - {frame: 2, actor: drone, drone: arm}\n"
         "  - {frame: 3, actor: drone, drone: takeoff}\n"
         "  - {frame: 40, actor: drone, drone: move_to_position, target: [130, 10, 12], velocity: 4}\n"
         "  - {frame: 2, spawn: sensor.lidar.ray_cast, as: ego_lidar, parent: ego, at: [0, 0, 2.4],\n"
         "     attributes: {channels: 16, range: 40, points_per_second: 20000, rotation_frequency: 10, noise_stddev: 0.02,"
         " dropoff_general_rate: 0.1}}\n"
         "  - {frame: 2, spawn: sensor.other.imu, as: ego_imu, parent: ego, attributes: {noise_accel_stddev_x: 0.1}}\n"
         "  - {frame: 2, spawn: sensor.other.gnss, as: drone_gnss, parent: drone, attributes: {noise_lat_stddev: 0.00001}}\n";
}

// Every sensor sample, by (sensor, frame): a hash of its bytes.
struct SensorTap {
  explicit SensorTap(Bus& bus)
      : clouds(bus, topics::kPointCloud,
               [this](const msg::PointCloud& m, const SampleInfo&) {
                 Put(m.sensor(), m.stamp().frame(), Fnv1a64().Bytes(m.data().data(), m.data().size()).Add(m.point_count()).value());
               }),
        imu(bus, topics::kImu,
            [this](const msg::Imu& m, const SampleInfo&) {
              Put(m.sensor(), m.stamp().frame(),
                  Fnv1a64().Add(m.accelerometer().x()).Add(m.accelerometer().y()).Add(m.accelerometer().z())
                      .Add(m.gyroscope().x()).Add(m.gyroscope().y()).Add(m.gyroscope().z()).Add(m.compass()).value());
            }),
        gnss(bus, topics::kGnss, [this](const msg::Gnss& m, const SampleInfo&) {
          Put(m.sensor(), m.stamp().frame(), Fnv1a64().Add(m.latitude()).Add(m.longitude()).Add(m.altitude()).value());
        }) {}
  void Put(uint32_t sensor, uint64_t frame, uint64_t hash) {
    std::lock_guard<std::mutex> lock(mu);
    auto [it, fresh] = samples.emplace(std::make_pair(sensor, frame), hash);
    if (!fresh && it->second != hash) changed.push_back(std::to_string(sensor) + "@" + std::to_string(frame));
  }
  std::map<std::pair<uint32_t, uint64_t>, uint64_t> Samples() {
    std::lock_guard<std::mutex> lock(mu);
    return samples;
  }
  std::mutex mu;
  std::map<std::pair<uint32_t, uint64_t>, uint64_t> samples;
  std::vector<std::string> changed;  // a frame published twice with different data
  Reader<msg::PointCloud> clouds;
  Reader<msg::Imu> imu;
  Reader<msg::Gnss> gnss;
};

// The pid of the running program whose path ends with `program` and whose command line
// names `config`; 0 if none.
int32_t ProcessOf(const std::string& program, const std::string& config) {
  for (const auto& entry : std::filesystem::directory_iterator("/proc")) {
    const std::string name = entry.path().filename().string();
    if (name.find_first_not_of("0123456789") != std::string::npos) continue;
    std::ifstream in(entry.path() / "cmdline");
    std::string cmdline((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    std::vector<std::string> args;
    for (size_t at = 0; at < cmdline.size();) {
      const size_t end = cmdline.find('\0', at);
      args.push_back(cmdline.substr(at, end == std::string::npos ? std::string::npos : end - at));
      at = end == std::string::npos ? cmdline.size() : end + 1;
    }
    const bool named = !args.empty() && args[0].size() >= program.size() &&
                       args[0].compare(args[0].size() - program.size(), program.size(), program) == 0;
    if (named && std::find(args.begin(), args.end(), config) != args.end()) return std::stoi(name);
  }
  return 0;
}

struct StackRun {
  std::map<uint64_t, msg::FrameDone> frames;
  std::map<std::pair<uint32_t, uint64_t>, uint64_t> samples;
  std::vector<std::string> republished_differently;
  std::string launcher_output;
  std::string error;
};

// kills: frame -> the service killed (SIGKILL) once that frame is done. Twice real time, so
// each kill lands within a frame or two of the one asked for.
StackRun RunStack(const std::string& tag, const std::map<uint64_t, std::string>& kills) {
  StackRun r;
  const std::string config = WriteTempFile(tag + ".yaml", StackConfig(TestDomain()));
  auto bus = CreateDdsBus({TestDomain(), "", "lockstep.participant.loopback", "stack-recovery-" + tag});
  Observer obs(*bus);
  SensorTap tap(*bus);
  Process up({Bin("lockstep"), "up", config});
  auto fail = [&](const std::string& what) {
    if (r.error.empty()) r.error = what;
  };
  for (const auto& [frame, service] : kills) {
    if (!obs.WaitUntil([&, f = frame] { return obs.last_frame() >= f; }, 120s)) {
      fail("frame " + std::to_string(frame) + " never done");
      break;
    }
    // The service's process: the one started with this config (its path is this test's own).
    const int32_t pid = ProcessOf("/lockstep_" + service, config);
    if (pid <= 0) {
      fail(std::string("no process of ").append(service));
      break;
    }
    kill(pid, SIGKILL);
    // The run faults, the launcher starts a replacement, the run resumes past the kill.
    if (!obs.WaitUntil([&, f = frame] { return obs.last_frame() > f + 2; }, 60s)) {
      fail("the run did not resume after " + service + " was killed at frame " + std::to_string(frame));
      break;
    }
  }
  if (r.error.empty() && !obs.WaitUntil([&] { return obs.frames().count(kTicks) > 0; }, 180s)) fail("the last frame never done");
  const auto code = up.Wait(30s);
  if (r.error.empty() && (!code || *code != 0)) fail("lockstep up did not end with 0");
  // Late samples of the last frames.
  obs.WaitUntil([&] { return tap.Samples().size() >= 3; }, 2s);
  r.frames = obs.frames();
  r.samples = tap.Samples();
  {
    std::lock_guard<std::mutex> lock(tap.mu);
    r.republished_differently = tap.changed;
  }
  r.launcher_output = up.Output();
  return r;
}

TEST(StackRecovery, EveryServiceKilledOnceTheRunIsIdenticalToAnUndisturbedOne) {
  const StackRun reference = RunStack("reference", {});
  ASSERT_TRUE(reference.error.empty()) << reference.error << "\n" << reference.launcher_output;
  // Each killed at a different frame, more than a snapshot period (40) apart, none at one.
  const StackRun killed = RunStack("killed", {{70, "ground_sim"}, {147, "air_sim"}, {223, "sensors"}});
  ASSERT_TRUE(killed.error.empty()) << killed.error << "\n" << killed.launcher_output;
  const std::string& out = killed.launcher_output;
  // Each replacement rebuilt its state from its snapshot and checked its replay's hash.
  // The launcher's lines are "<name padded> | ...".
  auto said = [&](const std::string& service, const std::string& text) {
    for (size_t at = 0; (at = out.find(text, at)) != std::string::npos; ++at) {
      const size_t line = out.rfind('\n', at);
      if (out.compare(line == std::string::npos ? 0 : line + 1, service.size() + 1, service + " ") == 0) return true;
    }
    return false;
  };
  for (const std::string s : {"ground_sim", "air_sim", "sensors"}) {
    EXPECT_TRUE(said(s, "| failed (137): starting a replacement (1 of 5)")) << s << "\n" << out;
    EXPECT_FALSE(said(s, "starting a replacement (2 of 5)")) << s << " restarted twice\n" << out;
    EXPECT_TRUE(said(s, "| info: restored the snapshot of frame")) << s << "\n" << out;
  }
  EXPECT_EQ(out.find("diverged"), std::string::npos) << out;
  EXPECT_EQ(out.find("hung"), std::string::npos) << "a waiting service was taken for hung\n" << out;
  // Every frame both runs saw: the same world hash, never marked diverged.
  size_t compared = 0;
  for (const auto& [frame, done] : killed.frames) {
    auto it = reference.frames.find(frame);
    if (it == reference.frames.end()) continue;
    ++compared;
    EXPECT_EQ(done.world_hash(), it->second.world_hash()) << "frame " << frame;
    EXPECT_FALSE(done.diverged()) << "frame " << frame;
  }
  EXPECT_GT(compared, kTicks * 3 / 4);
  ASSERT_TRUE(killed.frames.count(kTicks) && reference.frames.count(kTicks));
  EXPECT_EQ(killed.frames.at(kTicks).world_hash(), reference.frames.at(kTicks).world_hash());
  // Every sensor sample: the same bytes, before and after each replacement.
  EXPECT_TRUE(killed.republished_differently.empty()) << killed.republished_differently.front();
  size_t samples = 0;
  for (const auto& [key, hash] : killed.samples) {
    auto it = reference.samples.find(key);
    if (it == reference.samples.end()) continue;
    ++samples;
    EXPECT_EQ(hash, it->second) << "sensor " << key.first << " frame " << key.second;
  }
  EXPECT_GT(samples, static_cast<size_t>(2 * (kTicks - 250)));
  bool after_sensors_kill = false;
  for (const auto& [key, hash] : killed.samples) after_sensors_kill |= key.second > 230 && reference.samples.count(key);
  EXPECT_TRUE(after_sensors_kill) << "no sample after the sensors' replacement took over";
}

}  // namespace
}  // namespace lockstep::testing
