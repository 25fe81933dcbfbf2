#pragma once
// A run of one service under a real coordinator, optionally with that service killed
// (SIGKILL) mid-run and a replacement started: the recovery tests of air_sim and
// ground_sim compare the world hash of the interrupted run with an uninterrupted one.
#include <cstdint>
#include <string>
#include <vector>

namespace lockstep::testing {

struct ReplacementRun {
  uint64_t world_hash = 0;      // FrameDone.world_hash of the last frame; 0 if it never came
  std::string replacement_log;  // the replacement's output (empty without a kill)
  std::string error;            // which wait timed out, with the coordinator's output; empty if none
  bool diverged = false;        // FrameDone.diverged of the last frame
};

// `config` runs the coordinator and the service `name` (program `program` in the build's
// bin folder) for `last_frame` ticks on TestDomain(); with `kill_at` > 0 the service is
// killed once that frame is done and a replacement started.
ReplacementRun RunWithReplacement(const std::string& config, const std::string& program, const std::string& name,
                                  uint64_t kill_at, uint64_t last_frame);
// The same with the service's command lines given: `argv` starts the service, `replacement`
// (empty: `argv`) its replacement.
ReplacementRun RunWithReplacement(const std::string& config, const std::vector<std::string>& argv,
                                  const std::vector<std::string>& replacement, uint64_t kill_at, uint64_t last_frame);

}  // namespace lockstep::testing
