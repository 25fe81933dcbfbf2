#pragma once
// `lockstep hashes`: prints each completed frame's world hash (FrameDone) of a running
// simulation, so two deployments of one launch config (one machine, containers,
// Kubernetes) can be checked to compute the same world: same tick stream, same hashes.
#include <atomic>
#include <cstdint>
#include <string>

namespace lockstep::launcher {

struct HashesOptions {
  int domain = 0;
  std::string participant_profile = "lockstep.participant";
  uint64_t until = 0;      // stop after this frame (0: until Ctrl-C)
  double timeout_s = 60;   // give up when no frame completes for this long
};

// Prints "lockstep hashes: listening ..." once the coordinator's FrameDone writer matched,
// then one line per frame: "<frame> <sim_time> <world_hash hex>". Returns 0 when `until`
// was reached (or on stop), 1 on a timeout (naming the last frame seen).
int PrintFrameHashes(const HashesOptions& options, const std::atomic<bool>& stop);

}  // namespace lockstep::launcher
