// Issue 21, item 6: hostile input. A foreign DDS participant (Cyclone DDS C,
// tests/fault/hostile_participant.c) publishes malformed and extreme samples on every
// command, membership, clock and state topic of a running simulation (air_sim, ground_sim,
// the recorder and, when built, sensors): NaN, infinities, sequences at their bounds and of
// 100k elements, unknown ids and kinds, frames from the past and the future, another run's
// id, a duplicate of a live service's name. Nothing crashes or restarts, every command is
// refused with a reason, the samples on the other topics are refused with a reason in the
// coordinator's log, and every frame's world hash is the one of the same run undisturbed.
#include <gtest/gtest.h>

#include <iostream>
#include <map>
#include <mutex>
#include <sstream>
#include <string>

#include "lockstep/runtime/bus.h"
#include "lockstep/runtime/messages.h"
#include "process.h"

namespace lockstep::testing {
namespace {

using namespace std::chrono_literals;
const char* kProfile = "lockstep.participant.loopback";
constexpr uint64_t kTicks = 400;

std::string Config() {
  std::string services = "  - {name: air_sim, kind: air_sim}\n  - {name: ground_sim, kind: ground_sim}\n";
#ifdef LOCKSTEP_HOSTILE_WITH_SENSORS
  services += "  - {name: sensors, kind: sensors, perception: true}\n";
#endif
  return "name: hostile\ndomain_id: " + std::to_string(TestDomain()) + "\nparticipant_profile: " + kProfile +
         "\nseed: 9\nticks: " + std::to_string(kTicks) + "\nmap: " + std::string(LOCKSTEP_TEST_TOWN_DIR) +
         "/LockstepTown1.xodr\nworld:\n  synchronous_mode: false\n  fixed_delta_seconds: 0.05\n  real_time_factor: 4\n"
         "  service_timeout: 20\nservices:\n" + services +
         "scenario:\n"
         "  - {frame: 1, spawn: vehicle.tesla.model3, as: car, at: [122.75, 1.75, 0.8], yaw: 3.1416}\n"
         "  - {frame: 2, actor: car, autopilot: true}\n"
         "  - {frame: 1, spawn: drone.generic_quad, as: d, at: [47.75, 1.75, 0]}\n"
         "  - {frame: 2, actor: d, drone: arm}\n"
         "  - {frame: 3, actor: d, drone: takeoff}\n"
         "  - {frame: 60, actor: d, drone: move_to_position, target: [60, 1.75, 6], velocity: 3}\n"
         "  - {frame: 1, spawn: sensor.other.imu, as: imu, parent: d}\n";
}

struct Frames {
  std::mutex mu;
  std::map<uint64_t, uint64_t> hash;
  bool diverged = false;
};

std::map<uint64_t, uint64_t> RunOnce(const std::string& config, bool hostile, std::string* hostile_out, std::string* up_out,
                                 bool* diverged) {
  auto bus = CreateDdsBus({TestDomain(), "", kProfile, "hostile-test"});
  Frames frames;
  Reader<msg::FrameDone> reader(*bus, topics::kFrameDone, [&](const msg::FrameDone& f, const SampleInfo&) {
    std::lock_guard<std::mutex> lock(frames.mu);
    frames.hash[f.frame()] = f.world_hash();
    frames.diverged = frames.diverged || f.diverged();
  });
  Process up({Bin("lockstep"), "up", config});
  std::unique_ptr<Process> attacker;
  if (hostile) {
    attacker = std::make_unique<Process>(
        std::vector<std::string>{Bin("lockstep_hostile_participant"), "--domain", std::to_string(TestDomain()), "--after",
                                 "20", "--timeout", "40"},
        std::map<std::string, std::string>{
            {"CYCLONEDDS_URI", "file://" + SourceDir() + "/client/cyclone_c/cyclone_loopback.xml"}});
    auto code = attacker->Wait(90s);
    *hostile_out = attacker->Output();
    EXPECT_TRUE(code && *code == 0) << "the hostile participant did not run its list:\n" << *hostile_out;
  }
  auto code = up.Wait(120s);
  *up_out = up.Output();
  EXPECT_TRUE(code && *code == 0) << *up_out;
  std::lock_guard<std::mutex> lock(frames.mu);
  *diverged = frames.diverged;
  return frames.hash;
}

TEST(Hostile, ForeignSamplesAreRefusedAndTheRunIsUnchanged) {
  const std::string config = WriteTempFile("hostile.yaml", Config());
  std::string quiet_out, up_out, attack_out;
  bool diverged = false;
  const auto undisturbed = RunOnce(config, false, &attack_out, &quiet_out, &diverged);
  ASSERT_GE(undisturbed.size(), kTicks) << quiet_out;
  ASSERT_FALSE(diverged);
  const auto attacked = RunOnce(config, true, &attack_out, &up_out, &diverged);

  // Every command was answered, and refused with a reason.
  std::istringstream in(attack_out);
  int sent = 0, refused = 0;
  std::map<std::string, std::string> labels;
  for (std::string line; std::getline(in, line);) {
    if (line.rfind("sent ", 0) == 0) {
      ++sent;
      const auto sp = line.find(' ', 5);
      labels[line.substr(5, sp - 5)] = line.substr(sp + 1);
    }
    if (line.rfind("reply ", 0) == 0) {
      const auto sp = line.find(' ', 6);
      const std::string seq = line.substr(6, sp - 6);
      if (labels[seq].rfind("[service] ", 0) == 0 && line.find("accepted=1") != std::string::npos) {
        // Passed by the coordinator: the owning service refuses it with a reason in its log.
        EXPECT_NE(up_out.find("physics control rejected"), std::string::npos) << labels[seq] << ":\n" << up_out;
        ++refused;
        continue;
      }
      EXPECT_NE(line.find("accepted=0 reason="), std::string::npos) << "accepted: " << labels[seq] << ": " << line;
      const std::string reason = line.substr(line.find("reason=") + 7);
      EXPECT_FALSE(reason.empty()) << "refused without a reason: " << labels[seq];
      ++refused;
      std::cout << "refused: " << labels[seq] << ": " << reason << "\n";
    }
    EXPECT_EQ(line.rfind("missing ", 0), std::string::npos) << "no reply: " << line;
    EXPECT_EQ(line.rfind("unpublished ", 0), std::string::npos) << line;
    EXPECT_EQ(line.rfind("unsent ", 0), std::string::npos) << line;
  }
  EXPECT_GE(sent, 50) << attack_out;
  EXPECT_EQ(refused, sent) << attack_out;

  // Nothing crashed, hung or restarted; the run never faulted.
  EXPECT_EQ(up_out.find("replacement"), std::string::npos) << up_out;
  EXPECT_EQ(up_out.find("faulted"), std::string::npos) << up_out;
  for (size_t at = up_out.find("exited with "); at != std::string::npos; at = up_out.find("exited with ", at + 1)) {
    EXPECT_EQ(up_out.compare(at, 14, "exited with 0\n"), 0) << "a process failed:\n" << up_out;
  }
  // The samples on the other topics were refused with a reason in the log.
  for (const char* reason : {"duplicate service name", "ack of an unknown service", "ack of frame", "while the live member announced"}) {
    EXPECT_NE(up_out.find(reason), std::string::npos) << "no '" << reason << "' in the log:\n" << up_out;
  }

  // The run's state: every frame's world hash is the undisturbed run's, none diverged.
  EXPECT_FALSE(diverged);
  ASSERT_GE(attacked.size(), kTicks) << up_out;
  for (uint64_t f = 1; f <= kTicks; ++f) {
    ASSERT_TRUE(undisturbed.count(f) && attacked.count(f)) << "frame " << f;
    ASSERT_EQ(attacked.at(f), undisturbed.at(f)) << "frame " << f << " differs under hostile input";
  }
}

}  // namespace
}  // namespace lockstep::testing
