// render killed mid-run (kill -9) and replaced (issues 21 and 25): the replacement restores
// the render state's snapshot, replays the ticks after it (rendering the cameras whose
// images change their state: auto-exposure), and its state hash matches the one the killed
// process acknowledged; the run ends in the state of a run never interrupted. A replacement
// that drifts (started with the custom prop three times larger, so its camera sees other
// images and adapts its exposure otherwise) is detected by the hash check.
#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "process.h"
#include "replacement.h"

namespace lockstep::testing {
namespace {

constexpr uint64_t kKillAt = 70, kLastFrame = 160;

// A unit cube (OBJ).
std::string CubeObj() {
  std::string s;
  for (int i = 0; i < 8; ++i) {
    s += "v " + std::string(i & 1 ? "0.5" : "-0.5") + (i & 2 ? " 0.5" : " -0.5") + (i & 4 ? " 0.5" : " -0.5") + "\n";
  }
  // Faces (1-based): -x, +x, -y, +y, -z, +z, two triangles each, outward.
  s += "f 1 5 7\nf 1 7 3\nf 2 4 8\nf 2 8 6\nf 1 2 6\nf 1 6 5\nf 3 7 8\nf 3 8 4\nf 1 3 4\nf 1 4 2\nf 5 6 8\nf 5 8 7\n";
  return s;
}

std::string Config(int domain) {
  return "domain_id: " + std::to_string(domain) +
         "\nparticipant_profile: lockstep.participant.loopback\nseed: 5\nticks: " + std::to_string(kLastFrame) +
         "\nsnapshot_period: 25\n"
         "world:\n  real_time_factor: 10\n  service_timeout: 10\n"
         "services:\n  - {name: render, kind: render, perception: true}\n"
         "scenario:\n"
         "  - {frame: 1, spawn: custom.box, as: box, at: [6, 0, 1]}\n"
         // Exposure adapting over the run: a wide range, slow speeds.
         "  - {frame: 1, spawn: sensor.camera.rgb, as: cam, at: [0, 0, 1], attributes: {image_size_x: \"48\", image_size_y: \"32\","
         " exposure_min_bright: \"-10\", exposure_max_bright: \"20\", exposure_speed_up: \"0.2\", exposure_speed_down: \"0.2\"}}\n";
}

// The coordinator and one render process (asset scale `scale`); with `replacement_scale` > 0
// the process is killed once frame kKillAt is done and a replacement with that scale started.
ReplacementRun RunRender(const std::string& name, double scale, double replacement_scale) {
  const std::string obj = WriteTempFile(name + "-cube.obj", CubeObj());
  const std::string config = WriteTempFile(name + ".yaml", Config(TestDomain()));
  auto argv = [&](double s) {
    return std::vector<std::string>{Bin("lockstep_render"), "--device", "cpu", "--name", "render", "--config", config,
                                    "--asset", "box=" + obj + ",Static," + std::to_string(s)};
  };
  return RunWithReplacement(config, argv(scale), argv(replacement_scale), replacement_scale > 0 ? kKillAt : 0, kLastFrame);
}

TEST(RenderReplacement, ReplayRestoresTheRunBitForBitAndADriftingReplacementIsDetected) {
  const ReplacementRun reference = RunRender("render-ref", 1, 0);
  ASSERT_TRUE(reference.error.empty()) << reference.error;
  ASSERT_NE(reference.world_hash, 0u);
  EXPECT_FALSE(reference.diverged);

  const ReplacementRun same = RunRender("render-same", 1, 1);
  ASSERT_TRUE(same.error.empty()) << same.error;
  // From its snapshot (every 25 frames), not from frame 1, checked by the state hash.
  EXPECT_NE(same.replacement_log.find("restored the snapshot of frame"), std::string::npos) << same.replacement_log;
  EXPECT_NE(same.replacement_log.find("matches"), std::string::npos) << "the replacement did not verify its replay:\n"
                                                                     << same.replacement_log;
  EXPECT_FALSE(same.diverged) << same.replacement_log;
  EXPECT_EQ(same.world_hash, reference.world_hash) << "the interrupted run must end in the same state";

  const ReplacementRun drifting = RunRender("render-drift", 1, 3);
  ASSERT_TRUE(drifting.error.empty()) << drifting.error;
  EXPECT_NE(drifting.replacement_log.find("differs from the acknowledged"), std::string::npos)
      << "a replacement whose camera sees another scene was not detected:\n"
      << drifting.replacement_log;
  EXPECT_TRUE(drifting.diverged) << "FrameDone must say the run diverged";
  EXPECT_NE(drifting.world_hash, reference.world_hash);
}

}  // namespace
}  // namespace lockstep::testing
