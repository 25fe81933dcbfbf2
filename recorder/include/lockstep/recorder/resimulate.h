#pragma once
// Re-simulation: a log's tick stream re-drives the real services (the log's config and
// seed), and every frame's world hash is compared with the recorded one; the first frame
// that differs is named with the service whose state hash differed (docs/recorder.md).
#include <atomic>
#include <cstdint>
#include <functional>
#include <memory>
#include <string>

#include "lockstep/recorder/log_reader.h"
#include "lockstep/runtime/bus.h"
#include "lockstep/runtime/launch_config.h"

namespace lockstep::recorder {

// FNV-1a 64 of a map file's OpenDRIVE text and its <stem>.scene.yaml (if any): the
// coordinator's WorldInfo.map_hash. 0 for no map.
uint64_t MapDigest(const std::string& xodr_path);

// Empty when `config` can re-simulate `log`, else why not: another map (digest), seed or
// set of services, or a log that starts mid-run without the ticks before it.
std::string ResimulationRefusal(const LogReader& log, const LaunchConfig& config);

// `config` re-driven by the log: each recorded command (the prelude's too) becomes a
// scenario step at its frame, in order, the world free-running as fast as it goes
// (synchronous mode and pacing in recorded settings commands are turned off: no client
// ticks a re-simulation), up to the log's last frame. Throws LogError with the refusal.
LaunchConfig ResimulationConfig(LogReader& log, const LaunchConfig& config);

struct ResimulationResult {
  uint64_t frames_checked = 0;   // frames whose world hash was compared
  uint64_t frames_unchecked = 0; // frames the log has no hash for, or whose FrameDone was not seen
  uint64_t first_differing = 0;  // 0 = none
  std::string service;           // the first service (name order) whose state hash differed there
  std::string reason;            // what differed, or why the check stopped
  bool ok() const { return first_differing == 0 && reason.empty() && frames_checked > 0; }
};

// Watches a re-simulation on `bus` (Tick, Ack, FrameDone) and compares it with the log.
class ResimulationCheck {
 public:
  ResimulationCheck(Bus& bus, LogReader& log);
  ~ResimulationCheck();
  // Until the log's last frame is compared, a frame differs, `stop` is set, or no frame
  // comes for `timeout_s`. `progress(done, total)` now and then.
  ResimulationResult Wait(double timeout_s, const std::atomic<bool>& stop,
                          const std::function<void(uint64_t, uint64_t)>& progress = {});

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace lockstep::recorder
