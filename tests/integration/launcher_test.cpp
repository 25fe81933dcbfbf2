// `lockstep up` end to end: it starts the coordinator and services as processes, prefixes
// their logs, runs the scenario, writes the record, and two runs with one seed produce
// byte-identical records. Ctrl-C stops every process.
#include <gtest/gtest.h>
#include <signal.h>

#include <filesystem>
#include <fstream>
#include <sstream>

#include "process.h"

namespace lockstep::testing {
namespace {

using namespace std::chrono_literals;

std::string Read(const std::string& path) {
  std::ifstream in(path);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

std::string Config(const std::string& out, uint64_t ticks, uint64_t seed = 5, const std::string& extra_steps = "") {
  return "name: launcher-test\ndomain_id: " + std::to_string(TestDomain()) +
         "\nparticipant_profile: lockstep.participant.loopback\nseed: " + std::to_string(seed) + "\nticks: " + std::to_string(ticks) +
         "\noutput_dir: " + out +
         "\nservices:\n  - {name: air_sim, kind: air_sim}\n  - {name: recorder, kind: recorder, perception: true, args: [--record-run]}\n"
         "scenario:\n"
         "  - {frame: 1, spawn: drone.generic_quad, as: d, at: [1, 2, 0]}\n"
         "  - {frame: 2, actor: d, drone: arm}\n"
         "  - {frame: 3, actor: d, drone: takeoff}\n"
         "  - {frame: 60, actor: d, drone: move_to_position, target: [6, 2, 3], velocity: 3}\n" +
         extra_steps;
}

// The recorder's log of run 1 as CSV (`lockstep log export --csv`): air_state.csv, frames.csv.
std::pair<std::string, std::string> ExportCsv(const std::string& out) {
  Process exp({Bin("lockstep"), "log", "export", out + "/run1/recording.lslog", "--csv", out + "/csv"});
  auto code = exp.Wait(60s);
  EXPECT_TRUE(code && *code == 0) << exp.Output();
  return {Read(out + "/csv/air_state.csv"), Read(out + "/csv/frames.csv")};
}

// Issue 7, part 3: determinism with a control. With a seeded model switched on (wind
// turbulence: Gauss-Markov gusts drawn from the run seed, on top of the seeded sensor
// noise of the flight controller), the same seed gives the same
// frames and world hashes, and another seed different ones; so a run that ignored its
// seed, or drew from an unseeded source, would fail one of the two checks.
TEST(Launcher, WithTurbulenceTheSameSeedRepeatsAndAnotherSeedDiffers) {
  const std::string gusts = "  - {frame: 1, weather: {wind_intensity: 40}}\n";
  auto run = [&](uint64_t seed, int i, const std::string& steps) -> std::pair<std::string, std::string> {
    const std::string out = std::filesystem::temp_directory_path() / ("lockstep-seeded-" + std::to_string(getpid()) + "-" + std::to_string(i));
    std::filesystem::remove_all(out);
    const std::string config = WriteTempFile("seeded" + std::to_string(i) + ".yaml", Config(out, 120, seed, steps));
    Process up({Bin("lockstep"), "up", config});
    auto code = up.Wait(60s);
    EXPECT_TRUE(code && *code == 0) << up.Output();
    std::pair<std::string, std::string> r = ExportCsv(out);
    std::filesystem::remove_all(out);
    return r;
  };
  const auto a = run(5, 0, gusts), b = run(5, 1, gusts), c = run(6, 2, gusts);
  ASSERT_EQ(std::count(a.first.begin(), a.first.end(), '\n'), 121) << "one drone, every frame";
  // (EXPECT_TRUE, not EXPECT_EQ: a mismatch would print two whole records.)
  EXPECT_TRUE(a.first == b.first) << "same seed: the same flight through the same gusts";
  EXPECT_TRUE(a.second == b.second) << "same seed: the same frames and world hashes";
  EXPECT_TRUE(a.first != c.first) << "another seed: other gusts, another flight";
  EXPECT_TRUE(a.second != c.second) << "another seed: other world hashes";
  // The seeded model is on: in still air the same seed flies otherwise.
  const auto calm = run(5, 3, "");
  EXPECT_TRUE(calm.first != a.first) << "the gusts reach the physics";
}

TEST(Launcher, RunsTheScenarioAndRecordsEveryFrameDeterministically) {
  std::vector<std::string> records;
  for (int i = 0; i < 2; ++i) {
    const std::string out = std::filesystem::temp_directory_path() / ("lockstep-launcher-" + std::to_string(getpid()) + "-" + std::to_string(i));
    std::filesystem::remove_all(out);
    const std::string config = WriteTempFile("launcher" + std::to_string(i) + ".yaml", Config(out, 200));
    Process up({Bin("lockstep"), "up", config});
    auto code = up.Wait(60s);
    ASSERT_TRUE(code) << "lockstep up did not finish:\n" << up.Output();
    ASSERT_EQ(*code, 0) << up.Output();
    const std::string log = up.Output();
    EXPECT_NE(log.find("coordinator | info: finished 200 ticks"), std::string::npos) << log;
    EXPECT_NE(log.find("air_sim     | info: stopping after frame 200"), std::string::npos) << log;
    const auto [air, frames] = ExportCsv(out);
    EXPECT_EQ(std::count(frames.begin(), frames.end(), '\n'), 201) << "a header and one line per frame";
    EXPECT_EQ(std::count(air.begin(), air.end(), '\n'), 201) << "one drone, every frame";
    // The drone reached its target: last line's position.
    const std::string last = air.substr(air.rfind('\n', air.size() - 2) + 1);
    double x = 0, y = 0, z = 0;
    ASSERT_EQ(std::sscanf(last.c_str(), "%*u,%*f,%*u,%lf,%lf,%lf", &x, &y, &z), 3) << last;
    EXPECT_NEAR(x, 6, 0.5);
    EXPECT_NEAR(y, 2, 0.5);
    EXPECT_NEAR(z, 3, 0.5);
    records.push_back(air + frames);
    std::filesystem::remove_all(out);
  }
  EXPECT_EQ(records[0], records[1]) << "same seed, same scenario: byte-identical records";
}

// Issue 22: the run's log re-drives the real services (processes over DDS) through
// `lockstep log replay --resimulate`, every frame's world hash equal; a config with
// another seed is refused with the reason.
TEST(Launcher, ARecordedRunReSimulatesWithEveryWorldHashEqual) {
  const std::string out = std::filesystem::temp_directory_path() / ("lockstep-resim-" + std::to_string(getpid()));
  std::filesystem::remove_all(out);
  const std::string config = WriteTempFile("resim.yaml", Config(out, 120));
  Process up({Bin("lockstep"), "up", config});
  auto code = up.Wait(60s);
  ASSERT_TRUE(code && *code == 0) << up.Output();
  const std::string log = out + "/run1/recording.lslog";
  Process replay({Bin("lockstep"), "log", "replay", "--resimulate", log});
  code = replay.Wait(90s);
  ASSERT_TRUE(code) << replay.Output();
  EXPECT_EQ(*code, 0) << replay.Output();
  EXPECT_NE(replay.Output().find("re-simulation of frames 1..120: every world hash equal (120 frames compared"), std::string::npos)
      << replay.Output();
  const std::string other = WriteTempFile("resim-other.yaml", Config(out, 120, 6));
  Process refused({Bin("lockstep"), "log", "replay", "--resimulate", log, "--config", other});
  code = refused.Wait(30s);
  ASSERT_TRUE(code) << refused.Output();
  EXPECT_EQ(*code, 3) << refused.Output();
  EXPECT_NE(refused.Output().find("refused: the log's run used seed 5, the config's seed is 6"), std::string::npos) << refused.Output();
  std::filesystem::remove_all(out);
}

TEST(Launcher, CtrlCStopsEveryProcess) {
  const std::string out = std::filesystem::temp_directory_path() / ("lockstep-launcher-int-" + std::to_string(getpid()));
  const std::string config = WriteTempFile("forever.yaml", Config(out, 0));
  Process up({Bin("lockstep"), "up", config});
  // Wait for the run to be under way: the recorder has written frames.
  const std::string frames = out + "/run1/recording.lslog";
  const auto deadline = std::chrono::steady_clock::now() + 30s;
  while (std::chrono::steady_clock::now() < deadline) {
    if (std::filesystem::exists(frames) && std::filesystem::file_size(frames) > 200) break;
    ASSERT_TRUE(up.Running()) << up.Output();
    up.Wait(20ms);  // a bounded wait on the process itself, not a sleep
  }
  up.Signal(SIGINT);
  auto code = up.Wait(15s);
  ASSERT_TRUE(code) << "lockstep up did not stop on Ctrl-C";
  EXPECT_EQ(*code, 0) << up.Output();
  const std::string log = up.Output();
  EXPECT_NE(log.find("air_sim     | info: stopping after frame"), std::string::npos) << log;
  EXPECT_NE(log.find("recorder    | info: stopping after frame"), std::string::npos) << log;
  std::filesystem::remove_all(out);
}

TEST(Launcher, MissingServiceProgramIsNamed) {
  const std::string config = WriteTempFile("missing.yaml", "domain_id: 3\nservices:\n  - {name: x, kind: teleporter}\n");
  Process up({Bin("lockstep"), "up", config});
  auto code = up.Wait(10s);
  ASSERT_TRUE(code);
  EXPECT_EQ(*code, 2);
  EXPECT_NE(up.Output().find("service 'x' of kind 'teleporter': no program"), std::string::npos) << up.Output();
}

}  // namespace
}  // namespace lockstep::testing

namespace lockstep::testing {
namespace {

using namespace std::chrono_literals;

std::string NoopConfig(const std::string& restart) {
  return "name: supervise\ndomain_id: " + std::to_string(TestDomain()) +
         "\nparticipant_profile: lockstep.participant.loopback\nworld:\n  real_time_factor: 1\n"
         "services:\n  - {name: steady, kind: noop}\n  - {name: fragile, kind: noop, restart: " + restart + "}\n";
}

// Waits until `text` appears in the process's output.
bool WaitOutput(Process& p, const std::string& text, std::chrono::milliseconds timeout) {
  const auto deadline = std::chrono::steady_clock::now() + timeout;
  while (std::chrono::steady_clock::now() < deadline) {
    if (p.Output().find(text) != std::string::npos) return true;
    if (!p.Running()) return p.Output().find(text) != std::string::npos;
    p.Wait(20ms);
  }
  return false;
}

TEST(Launcher, StatusShowsMembersFrameAndRate) {
  Process up({Bin("lockstep"), "up", WriteTempFile("status.yaml", NoopConfig("never"))});
  ASSERT_TRUE(WaitOutput(up, "waiting for services -> running", 30s)) << up.Output();
  Process status({Bin("lockstep"), "status", "--domain", std::to_string(TestDomain()), "--participant-profile",
                  "lockstep.participant.loopback", "--json"});
  auto code = status.Wait(15s);
  ASSERT_TRUE(code);
  ASSERT_EQ(*code, 0) << status.Output();
  const std::string out = status.Output();
  EXPECT_NE(out.find("\"state\":\"running\""), std::string::npos) << out;
  EXPECT_NE(out.find("\"service\":\"steady\""), std::string::npos) << out;
  EXPECT_NE(out.find("\"service\":\"fragile\""), std::string::npos) << out;
  EXPECT_NE(out.find("\"tick_rate_hz\":"), std::string::npos) << out;
  up.Signal(SIGINT);
  EXPECT_TRUE(up.Wait(15s));
}

// The pid of a service, from the coordinator's "joined" line in the merged log.
pid_t JoinedPid(const std::string& log, const std::string& name, size_t nth = 0) {
  const std::string key = "service '" + name + "' (noop, pid ";
  size_t pos = 0;
  for (size_t i = 0; i <= nth; ++i) {
    pos = log.find(key, pos);
    if (pos == std::string::npos) return 0;
    pos += key.size();
  }
  return static_cast<pid_t>(std::stol(log.substr(pos)));
}

TEST(Launcher, AServiceThatDiesStopsTheSimulation) {
  Process up({Bin("lockstep"), "up", WriteTempFile("fail.yaml", NoopConfig("never"))});
  ASSERT_TRUE(WaitOutput(up, "waiting for services -> running", 30s)) << up.Output();
  const pid_t fragile = JoinedPid(up.Output(), "fragile");
  ASSERT_GT(fragile, 0) << up.Output();
  kill(fragile, SIGKILL);
  auto code = up.Wait(20s);
  ASSERT_TRUE(code) << "lockstep up must stop when a service fails hard";
  EXPECT_NE(*code, 0);
  EXPECT_NE(up.Output().find("fragile     | exited with 137: stopping the simulation"), std::string::npos) << up.Output();
  EXPECT_NE(kill(JoinedPid(up.Output(), "steady"), 0), 0) << "the other service was stopped too";
}

TEST(Launcher, RestartOnFailureStartsAReplacementAndTheRunResumes) {
  Process up({Bin("lockstep"), "up", WriteTempFile("restart.yaml", NoopConfig("on-failure"))});
  ASSERT_TRUE(WaitOutput(up, "waiting for services -> running", 30s)) << up.Output();
  const pid_t fragile = JoinedPid(up.Output(), "fragile");
  ASSERT_GT(fragile, 0);
  kill(fragile, SIGKILL);
  ASSERT_TRUE(WaitOutput(up, "starting a replacement (1 of 5)", 20s)) << up.Output();
  ASSERT_TRUE(WaitOutput(up, "faulted -> running", 30s)) << up.Output();
  EXPECT_GT(JoinedPid(up.Output(), "fragile", 1), 0) << "the replacement joined";
  EXPECT_TRUE(up.Running());
  up.Signal(SIGINT);
  auto code = up.Wait(15s);
  ASSERT_TRUE(code);
  EXPECT_EQ(*code, 0);
}

// Issue 7, 2.4: a hung service (SIGSTOP) used to leave `lockstep up` faulted for ever.
TEST(Launcher, AHungServiceIsKilledAndReplacedLikeACrashedOne) {
  Process up({Bin("lockstep"), "up", WriteTempFile("hang.yaml", NoopConfig("on-failure"))});
  ASSERT_TRUE(WaitOutput(up, "waiting for services -> running", 30s)) << up.Output();
  const pid_t fragile = JoinedPid(up.Output(), "fragile");
  ASSERT_GT(fragile, 0);
  kill(fragile, SIGSTOP);  // alive to the kernel, silent to the run
  // Silent with its process running: hung (no heartbeat for 3 s, or no ack of the tick
  // within service_timeout, whichever comes first).
  ASSERT_TRUE(WaitOutput(up, "fragile     | hung (", 20s)) << up.Output();
  ASSERT_TRUE(WaitOutput(up, "starting a replacement (1 of 5)", 20s)) << up.Output();
  ASSERT_TRUE(WaitOutput(up, "faulted -> running", 30s)) << up.Output();
  EXPECT_GT(JoinedPid(up.Output(), "fragile", 1), 0) << "the replacement joined";
  EXPECT_NE(kill(fragile, 0), 0) << "the hung process is gone";
  up.Signal(SIGINT);
  auto code = up.Wait(15s);
  ASSERT_TRUE(code);
  EXPECT_EQ(*code, 0) << up.Output();
}

// Issue 7, part 4: `lockstep map info --json FILE` used to fail (options had to follow the file).
TEST(Launcher, MapToolsTakeOptionsAnywhere) {
  const std::string town = SourceDir() + "/../shared/maps/carla/Town02.xodr";
  for (const auto& args : {std::vector<std::string>{"map", "info", "--json", town}, std::vector<std::string>{"map", "info", town, "--json"}}) {
    std::vector<std::string> argv{Bin("lockstep")};
    argv.insert(argv.end(), args.begin(), args.end());
    Process map(argv);
    auto code = map.Wait(30s);
    ASSERT_TRUE(code);
    EXPECT_EQ(*code, 0) << map.Output();
    EXPECT_EQ(map.Output().rfind("{\"name\":\"Town02\"", 0), 0u) << map.Output();
  }
}

}  // namespace
}  // namespace lockstep::testing
