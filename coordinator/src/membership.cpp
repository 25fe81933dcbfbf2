#include "lockstep/coordinator/membership.h"

#include <unistd.h>

#include <algorithm>
#include <cstdio>
#include <fstream>
#include <sstream>

#include "lockstep/runtime/log.h"

namespace lockstep {

Membership::Membership(const std::vector<std::string>& required, Clock::duration heartbeat_timeout)
    : required_(required), heartbeat_timeout_(heartbeat_timeout) {
  for (const auto& name : required_) members_[name].required = true;
}

ProcessState ProbeLocalProcess(const std::string& host, int32_t pid) {
  char name[256] = {};
  if (pid <= 0 || gethostname(name, sizeof name - 1) != 0 || host != name) return ProcessState::kUnknown;
  std::ifstream stat("/proc/" + std::to_string(pid) + "/stat");
  std::string line;
  if (!std::getline(stat, line)) return ProcessState::kGone;
  // "pid (comm) S ...": the state follows the last ')' (comm may hold spaces and parens).
  const auto close = line.rfind(')');
  if (close == std::string::npos || close + 2 >= line.size()) return ProcessState::kUnknown;
  switch (line[close + 2]) {
    case 'T':
    case 't':
      return ProcessState::kStopped;
    case 'Z':
    case 'X':
      return ProcessState::kGone;
    default:
      return ProcessState::kRunning;
  }
}

void Membership::SetProcessProbe(ProcessProbe probe, Clock::duration starved_timeout) {
  probe_ = std::move(probe);
  starved_timeout_ = starved_timeout;
}

void Membership::Refuse(const std::string& key, const std::string& why) {
  // Once per sender and kind: a participant that floods the topic does not flood the log.
  if (refused_.size() < 1024 && refused_.insert(key).second) spdlog::warn("{}", why);
}

bool Membership::OnAnnounce(const msg::ServiceAnnounce& a, Clock::time_point now) {
  const std::string name = a.service().to_string();
  if (auto it = members_.find(name); it != members_.end() && it->second.alive && it->second.pid != 0 &&
                                     (it->second.pid != a.pid() || it->second.host != a.host().to_string())) {
    // Another process under a live member's name: a second copy of a service, or a
    // participant that is not one. A replacement comes once the member failed, or while its
    // process is known gone (restarted faster than the heartbeat timeout).
    const Member& live = it->second;
    if ((probe_ ? probe_(live.host, live.pid) : ProcessState::kUnknown) != ProcessState::kGone) {
      Refuse("announce " + name + " " + std::to_string(a.pid()) + "@" + a.host().to_string(),
             "duplicate service name '" + name + "': pid " + std::to_string(a.pid()) + " on " + a.host().to_string() +
                 " (kind '" + a.kind().to_string() + "') announced it while pid " + std::to_string(live.pid) + " on " +
                 live.host + ", a live member, has it: ignored (service names are unique in a run)");
      return false;
    }
  }
  Member& m = members_[name];
  bool changed = false;
  m.kind = a.kind().to_string();
  m.last_heard = now;
  m.blueprints = a.blueprints();
  m.host = a.host().to_string();
  m.announced_frame = a.last_frame();
  m.ready_announced = a.state() == msg::ServiceState::SERVICE_READY;
  if (m.pid != 0 && m.pid != a.pid()) {
    // A replacement process: the stall and the failure were its predecessor's. (Kept, the
    // launcher would take the replacement, not yet ready, for hung and kill it too.)
    m.stalled_frame = 0;
    m.failure.clear();
  }
  if (a.state() == msg::ServiceState::SERVICE_READY && m.stalled_frame != 0) {
    // Heartbeats alone do not clear a stall: the service must finish the frame.
  } else if (a.state() == msg::ServiceState::SERVICE_READY && m.blueprints != 0 &&
             m.blueprints_received != static_cast<long>(m.blueprints)) {
    // Ready, but its declarations have not arrived: not alive yet (OnBlueprints).
    changed = m.alive;
    m.alive = false;
  } else if (a.state() == msg::ServiceState::SERVICE_READY) {
    if (!m.alive) {
      changed = true;
      spdlog::info("service '{}' ({}, pid {} on {}) joined at frame {} with {} blueprint(s)", name, m.kind, a.pid(),
                   a.host().to_string(), a.last_frame(), m.blueprints);
    }
    m.alive = true;
    m.failure.clear();
  } else {
    if (a.state() == msg::ServiceState::SERVICE_STOPPING && m.alive) {
      m.failure = a.reason().to_string().empty() ? "stopped (announced shutdown)" : "failed: " + a.reason().to_string();
      spdlog::warn("service '{}' {}", name, m.failure);
    }
    changed = changed || m.alive;
    m.alive = false;
  }
  if (m.pid != a.pid()) changed = true;
  m.pid = a.pid();
  return changed;
}

bool Membership::OnAck(const std::string& service, uint32_t current_run, const msg::Ack& a, uint64_t newest_tick) {
  auto found = members_.find(service);
  if (found == members_.end()) {
    Refuse("ack " + service, "ack of an unknown service '" + service + "' (neither required nor announced): ignored");
    return false;
  }
  if (a.run() == current_run && a.frame() > newest_tick) {
    Refuse("ack-future " + service, "ack of frame " + std::to_string(a.frame()) + " by '" + service + "' in run " +
                                        std::to_string(current_run) + ": no tick of that frame was sent (the newest is " +
                                        std::to_string(newest_tick) + "): ignored");
    return false;
  }
  Member& m = found->second;
  bool changed = false;
  if (m.stalled_frame != 0 && a.run() == current_run && a.frame() >= m.stalled_frame) {
    m.stalled_frame = 0;  // it caught up: healthy again
    m.alive = true;
    m.failure.clear();
    changed = true;
  }
  if (a.run() != current_run) return changed;
  if (m.run != current_run) {  // its first ack of this run: values of an older run go
    m.run = current_run;
    m.last_frame = 0;
    m.last_hash = 0;
    m.replay_from = 0;
    m.divergence.clear();
  }
  if (a.frame() == m.last_frame && m.last_frame != 0 && m.last_hash != 0 && a.state_hash() != 0 &&
      a.state_hash() != m.last_hash && m.divergence.empty()) {
    // The same frame acked twice with different states (a replacement that did not rebuild
    // what the failed process had): the run no longer follows its tick stream.
    char why[160];
    std::snprintf(why, sizeof why, "frame %llu acknowledged with state hash %016llx after %016llx",
                  static_cast<unsigned long long>(a.frame()), static_cast<unsigned long long>(a.state_hash()),
                  static_cast<unsigned long long>(m.last_hash));
    m.divergence = why;
    spdlog::error("service '{}' diverged in run {}: {}", service, current_run, m.divergence);
    changed = true;
  }
  if (a.frame() >= m.last_frame) {
    // A re-ack of the same frame without a hash (0 = none) keeps the hash we have: the
    // tick log's last_hash is what a replacement checks its replay against.
    if (a.frame() > m.last_frame || a.state_hash() != 0) m.last_hash = a.state_hash();
    m.last_frame = a.frame();
    m.last_step_us = a.step_wall_us();
    m.replay_from = a.replay_from();
  }
  if (!a.divergence().to_string().empty() && a.frame() < m.last_frame) {
    Refuse("ack-past " + service, "ack of frame " + std::to_string(a.frame()) + " by '" + service +
                                      "' reports a divergence but is older than its last acknowledged frame " +
                                      std::to_string(m.last_frame) + ": ignored");
  } else if (!a.divergence().to_string().empty() && m.divergence != a.divergence().to_string()) {
    m.divergence = a.divergence().to_string();
    spdlog::error("service '{}' diverged in run {}: {}", service, current_run, m.divergence);
    changed = true;
  }
  return changed;
}

bool Membership::OnBlueprints(const std::string& service, long count) {
  Member& m = members_[service];
  m.blueprints_received = count;
  if (m.ready_announced && !m.alive && m.stalled_frame == 0 && count == static_cast<long>(m.blueprints)) {
    m.alive = true;
    m.failure.clear();
    spdlog::info("service '{}' ({}, pid {} on {}) joined at frame {} with {} blueprint(s)", service, m.kind, m.pid, m.host,
                 m.announced_frame, count);
    return true;
  }
  return false;
}

bool Membership::CheckHeartbeats(Clock::time_point now) {
  // The caller runs at least every 100 ms: a longer gap is time it did not run itself
  // (starved or stopped), and the announcements of that time are still queued behind it.
  constexpr auto kPeriod = std::chrono::milliseconds(100);
  if (last_check_ && now - *last_check_ > 2 * kPeriod) {
    const auto credit = now - *last_check_ - kPeriod;
    for (auto& [name, m] : members_) m.last_heard = std::min(now, m.last_heard + credit);
  }
  last_check_ = now;
  // A member that missed a heartbeat or so is probed: a process known gone fails at once
  // (a kill -9 is noticed in about 0.2 s), others at their timeout.
  const auto missed = std::min<Clock::duration>(heartbeat_timeout_, std::chrono::milliseconds(150));
  bool changed = false;
  for (auto& [name, m] : members_) {
    if (!m.alive || now - m.last_heard <= missed) continue;
    const ProcessState process = probe_ ? probe_(m.host, m.pid) : ProcessState::kUnknown;
    if (process != ProcessState::kGone && now - m.last_heard <= heartbeat_timeout_) continue;
    if (process == ProcessState::kRunning && now - m.last_heard <= starved_timeout_) continue;
    m.alive = false;
    m.ready_announced = false;
    m.failure = "sent no heartbeat for " +
                std::to_string(std::chrono::duration_cast<std::chrono::milliseconds>(now - m.last_heard).count()) +
                " ms (" + (process == ProcessState::kGone      ? "its process is gone"
                           : process == ProcessState::kStopped ? "its process is stopped"
                           : process == ProcessState::kRunning ? "its process runs but is hung"
                                                               : "crashed, hung or stopped") +
                "; pid " + std::to_string(m.pid) + ")";
    spdlog::error("service '{}' {}", name, m.failure);
    changed = true;
  }
  return changed;
}

void Membership::MarkStalled(const std::string& service, uint64_t frame) {
  auto it = members_.find(service);
  if (it == members_.end()) return;
  it->second.alive = false;
  it->second.stalled_frame = frame;
  it->second.failure = "timed out on frame " + std::to_string(frame);
}

void Membership::NewRun(uint32_t run) {
  for (auto& [name, m] : members_) {
    m.run = run;
    m.last_frame = 0;
    m.last_hash = 0;
    m.replay_from = 0;
    m.divergence.clear();
  }
}

std::vector<std::pair<std::string, std::string>> Membership::Missing() const {
  std::vector<std::pair<std::string, std::string>> out;
  for (const auto& name : required_) {
    std::string why;
    auto it = members_.find(name);
    if (it != members_.end() && it->second.alive) continue;
    if (it == members_.end()) {
      why = "has not joined";
    } else {
      why = it->second.failure.empty() ? "has not announced ready" : it->second.failure;
    }
    out.emplace_back(name, why);
  }
  return out;
}

std::string Membership::FirstMissing(std::string* service) const {
  for (const auto& name : required_) {
    auto it = members_.find(name);
    if (it != members_.end() && it->second.alive) continue;
    *service = name;
    if (it == members_.end()) return "has not joined";
    return it->second.failure.empty() ? "has not announced ready" : it->second.failure;
  }
  return {};
}

std::vector<std::string> Membership::Waiting(const std::string& failed, uint32_t run, uint64_t open_frame) const {
  std::vector<std::string> out;
  for (const auto& [name, m] : members_) {
    if (name == failed || !m.alive || !m.required) continue;
    if (m.run != run || m.last_frame < open_frame) out.push_back(name);
  }
  return out;
}

std::string Membership::FaultReason(const std::string& reason, const std::string& failed, uint32_t run,
                                    uint64_t open_frame) const {
  const std::vector<std::string> waiting = Waiting(failed, run, open_frame);
  if (failed.empty() || waiting.empty()) return reason;
  std::string names;
  for (const auto& n : waiting) names += (names.empty() ? "" : ", ") + n;
  return reason + "; " + names + (waiting.size() == 1 ? " waits" : " wait") + " for its replacement's outputs of frame " +
         std::to_string(open_frame) + " (alive, not failed)";
}

const Member* Membership::Find(const std::string& service) const {
  auto it = members_.find(service);
  return it == members_.end() ? nullptr : &it->second;
}

}  // namespace lockstep
