#include "hashes.h"

#include <chrono>
#include <condition_variable>
#include <cstdio>
#include <mutex>
#include <thread>

#include "lockstep/runtime/bus.h"
#include "lockstep/runtime/messages.h"

namespace lockstep::launcher {

int PrintFrameHashes(const HashesOptions& o, const std::atomic<bool>& stop) {
  auto bus = CreateDdsBus({o.domain, "", o.participant_profile, "lockstep-hashes"});
  std::mutex mu;
  std::condition_variable cv;
  uint64_t last = 0;
  bool reached = false;
  Reader<msg::FrameDone> reader(*bus, topics::kFrameDone, [&](const msg::FrameDone& d, const SampleInfo&) {
    std::lock_guard<std::mutex> lock(mu);
    if (d.frame() <= last) return;  // a late joiner's TRANSIENT_LOCAL copy, or a repeat
    last = d.frame();
    std::printf("%llu %.6f %016llx%s\n", static_cast<unsigned long long>(d.frame()), d.sim_time(),
                static_cast<unsigned long long>(d.world_hash()), d.diverged() ? " diverged" : "");
    std::fflush(stdout);
    if (o.until > 0 && d.frame() >= o.until) reached = true;
    cv.notify_all();
  });
  using Clock = std::chrono::steady_clock;
  // Announce readiness once the coordinator's writer matched: a run started after this
  // line loses no frame (reliable, and the reader keeps up with one sample per tick).
  const auto wait_match_until = Clock::now() + std::chrono::duration<double>(o.timeout_s);
  while (reader.MatchedWriters() == 0 && !stop) {
    if (Clock::now() > wait_match_until) {
      std::fprintf(stderr, "lockstep hashes: no coordinator on DDS domain %d within %.0f s\n", o.domain, o.timeout_s);
      return 1;
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
  std::fprintf(stderr, "lockstep hashes: listening on DDS domain %d\n", o.domain);
  std::fflush(stderr);
  std::unique_lock<std::mutex> lock(mu);
  uint64_t seen = last;
  auto idle_since = Clock::now();
  while (!reached && !stop) {
    cv.wait_for(lock, std::chrono::milliseconds(100));
    if (last != seen) {
      seen = last;
      idle_since = Clock::now();
    } else if (Clock::now() - idle_since > std::chrono::duration<double>(o.timeout_s)) {
      std::fprintf(stderr, "lockstep hashes: no frame completed for %.0f s (last frame %llu)\n", o.timeout_s,
                   static_cast<unsigned long long>(last));
      return 1;
    }
  }
  return 0;
}

}  // namespace lockstep::launcher
