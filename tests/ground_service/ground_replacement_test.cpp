// ground_sim killed mid-run (kill -9) and replaced: the replacement rebuilds the world by
// replaying the run's ticks and the run ends in exactly the state of a run that was
// never interrupted (Traffic Manager cars and a walker with its AI controller in Town01).
#include <gtest/gtest.h>
#include <signal.h>

#include <chrono>

#include "lockstep/runtime/messages.h"
#include "observer.h"
#include "process.h"
#include "replacement.h"

namespace lockstep::testing {
namespace {

using namespace std::chrono_literals;

std::string GroundConfig(int domain) {
  return "domain_id: " + std::to_string(domain) +
         "\nparticipant_profile: lockstep.participant.loopback\nseed: 13\nticks: 300\nmap: " LOCKSTEP_CARLA_MAPS_DIR
         "/Town01.xodr\n"
         "world:\n  real_time_factor: 10\n  service_timeout: 10\n"
         "services:\n  - {name: ground_sim, kind: ground_sim}\n"
         "scenario:\n"
         "  - {frame: 1, spawn: vehicle.tesla.model3, as: ego, at: [122.75, 1.75, 0.8], yaw: 3.1416, attributes: {role_name: hero}}\n"
         "  - {frame: 2, actor: ego, autopilot: true}\n"
         "  - {frame: 1, spawn: vehicle.audi.tt, as: car1, at: [207.75, 1.75, 0.8], yaw: 3.1416}\n"
         "  - {frame: 2, actor: car1, autopilot: true}\n"
         "  - {frame: 1, spawn: vehicle.nissan.micra, as: car2, at: [142.75, 18.25, 0.8], yaw: 1.5708}\n"
         "  - {frame: 2, actor: car2, autopilot: true}\n"
         "  - {frame: 1, spawn: walker.pedestrian.0001, as: walker0, at: [124.0, 5.0, 1.0]}\n"
         "  - {frame: 2, spawn: controller.ai.walker, as: walker0_ai, parent: walker0}\n"
         "  - {frame: 3, actor: walker0_ai, walker_ai: start}\n";
}

uint64_t FinalWorldHash(bool kill_midway, std::string* replacement_log) {
  const std::string config = WriteTempFile(kill_midway ? "ground-kill.yaml" : "ground-ref.yaml", GroundConfig(TestDomain()));
  const ReplacementRun run = RunWithReplacement(config, "lockstep_ground_sim", "ground_sim", kill_midway ? 120 : 0, 300);
  EXPECT_TRUE(run.error.empty()) << run.error;
  if (kill_midway) *replacement_log = run.replacement_log;
  return run.world_hash;
}

TEST(GroundReplacement, ReplayRestoresTheRunBitForBit) {
  std::string log;
  const uint64_t reference = FinalWorldHash(false, &log);
  const uint64_t recovered = FinalWorldHash(true, &log);
  ASSERT_NE(reference, 0u);
  EXPECT_NE(log.find("matches"), std::string::npos) << "the replacement did not verify its replay:\n" << log;
  EXPECT_EQ(recovered, reference) << "the interrupted run must end in the same state";
}

}  // namespace
}  // namespace lockstep::testing
