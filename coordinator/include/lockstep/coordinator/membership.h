#pragma once
// Who is in the run and who is alive, as plain logic: the coordinator feeds it
// announcements (heartbeats, every 100 ms) and acks, and asks it which required
// service, if any, is missing and why. No DDS inside; the clock is passed in.
#include <chrono>
#include <cstdint>
#include <functional>
#include <map>
#include <optional>
#include <set>
#include <string>
#include <vector>

#include "lockstep/msg/clock.h"

namespace lockstep {

struct Member {
  std::string kind;
  bool required = false;
  bool alive = false;          // ready and heard from within the heartbeat timeout
  uint64_t stalled_frame = 0;  // missed the per-tick timeout on this frame: alive again only once it acks it
  int32_t pid = 0;
  std::string host;
  uint64_t announced_frame = 0;  // last_frame in its last announcement
  std::chrono::steady_clock::time_point last_heard;  // last announcement
  uint32_t run = 0;            // run of the values below
  uint64_t last_frame = 0;     // last frame acked in `run`
  uint64_t last_hash = 0;      // state hash acked with last_frame
  uint64_t replay_from = 0;    // Ack.replay_from: it needs no logged tick up to this frame
  std::string divergence;      // Ack.divergence in `run`
  double last_step_us = 0;     // wall time of its last step
  std::string failure;         // why it is not alive, if it failed
  uint32_t blueprints = 0;     // how many it says it declared (ServiceAnnounce.blueprints)
  long blueprints_received = -1;  // how many its BlueprintSet holds; -1: none arrived yet
  bool ready_announced = false;   // its last announcement said READY (cleared when it is declared dead)
};

// What the operating system says of a member's process, where it can tell.
enum class ProcessState { kUnknown, kRunning, kStopped, kGone };
// (host, pid) -> state; kUnknown for a process on another host.
using ProcessProbe = std::function<ProcessState(const std::string& host, int32_t pid)>;
// Reads /proc for a process on this host (by the host name services announce).
ProcessState ProbeLocalProcess(const std::string& host, int32_t pid);

class Membership {
 public:
  using Clock = std::chrono::steady_clock;
  Membership(const std::vector<std::string>& required, Clock::duration heartbeat_timeout);
  // A member silent for the heartbeat timeout whose process the probe sees running (a
  // machine so loaded that its heartbeat thread was not scheduled) fails only after
  // `starved_timeout`; a stopped or vanished one, or one the probe cannot see, at once.
  void SetProcessProbe(ProcessProbe probe, Clock::duration starved_timeout);

  // Each returns true when something a status report shows has changed.
  bool OnAnnounce(const msg::ServiceAnnounce& a, Clock::time_point now);
  // Acks are refused (a warning, once per sender and kind) from a service that is neither
  // required nor announced, for a frame of this run no tick was sent for (`newest_tick`),
  // and a divergence reported for a frame older than the member's last; announcements of a
  // live member's name by another process (pid, host) whose member's process is not gone.
  bool OnAck(const std::string& service, uint32_t current_run, const msg::Ack& a,
             uint64_t newest_tick = UINT64_MAX);
  // Its BlueprintSet arrived with `count` declarations. A member that announced READY
  // is alive only once the set it announced is here (the library must hold its blueprints).
  bool OnBlueprints(const std::string& service, long count);
  // A new run (reset, map load): per-run values start again.
  void NewRun(uint32_t run);
  // Marks members silent for longer than the timeout as dead (crashed or stopped); one
  // whose process the probe sees gone as soon as it missed a heartbeat (150 ms). Time the
  // caller itself did not run (a gap of over 200 ms between two calls: it was starved or
  // stopped) counts as heard from: the announcements of that time are still queued.
  bool CheckHeartbeats(Clock::time_point now);
  // A member that did not finish `frame` in time; it stays dead until it acks it.
  void MarkStalled(const std::string& service, uint64_t frame);

  // The first required service that is not alive, and why; empty reason if all are.
  std::string FirstMissing(std::string* service) const;
  // Every required service that is not alive, with why, in the order of the config.
  std::vector<std::pair<std::string, std::string>> Missing() const;
  const Member* Find(const std::string& service) const;
  const std::map<std::string, Member>& members() const { return members_; }
  // While the run is faulted by `failed`: the live members that have not finished the open
  // frame `open_frame` of run `run`, waiting for inputs the failed service's replacement will
  // publish. They are not failed and must not be restarted (issue 21, no cascade).
  std::vector<std::string> Waiting(const std::string& failed, uint32_t run, uint64_t open_frame) const;
  // The status line of a fault: `reason`, and who waits for the failed service meanwhile.
  std::string FaultReason(const std::string& reason, const std::string& failed, uint32_t run, uint64_t open_frame) const;

 private:
  std::vector<std::string> required_;
  Clock::duration heartbeat_timeout_;
  ProcessProbe probe_;
  Clock::duration starved_timeout_{};
  std::optional<Clock::time_point> last_check_;  // of CheckHeartbeats
  std::map<std::string, Member> members_;  // ordered by name
  std::set<std::string> refused_;           // senders and kinds of refused samples already logged
  void Refuse(const std::string& key, const std::string& why);
};

}  // namespace lockstep
