#pragma once
// `lockstep log info|collisions|blocked|export|replay|diff`: the Lockstep log on the
// command line (docs/recorder.md).
#include <atomic>
#include <string>
#include <vector>

namespace lockstep::launcher {

// args: what follows `lockstep log`. Returns the exit code (0 ok, 1 logs differ or a
// re-simulation diverged, 2 bad input, 3 refused).
int LogCommand(const std::vector<std::string>& args, const std::atomic<bool>& stop);

}  // namespace lockstep::launcher
