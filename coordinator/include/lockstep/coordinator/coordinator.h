#pragma once
// The coordinator process's logic over any Bus: it owns the clock, the barrier,
// membership and failure detection, and the command stream. Runs the same over
// Fast DDS and over the in-process bus (tests).
#include <atomic>
#include <cstdint>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "lockstep/runtime/bus.h"
#include "lockstep/runtime/launch_config.h"

namespace lockstep {

struct CoordinatorStats {
  uint64_t frames = 0;          // frames completed in the current run
  double tick_rate_hz = 0;      // recent completed ticks per wall second
  double mean_barrier_us = 0;   // mean wall time from publishing a tick to its last ack
  std::vector<double> barrier_us;  // per completed tick (at most the last 100000)
};

class Coordinator {
 public:
  Coordinator(Bus& bus, LaunchConfig config);
  ~Coordinator();
  Coordinator(const Coordinator&) = delete;
  Coordinator& operator=(const Coordinator&) = delete;

  // Runs until `stop` is set, or until config.ticks frames are done (free-running).
  // Returns 0 when it stopped normally.
  int Run(const std::atomic<bool>& stop);
  CoordinatorStats stats() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace lockstep
