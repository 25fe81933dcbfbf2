#include "run_status.h"

#include <vector>

namespace lockstep {

msg::RunStatus MakeRunStatus(const RunFacts& f, const Membership& members) {
  msg::RunStatus s;
  s.run(f.run);
  s.state(f.state);
  s.frame(f.frame);
  s.sim_time(f.sim_time);
  s.tick_rate_hz(f.tick_rate_hz);
  s.real_time_factor(f.tick_rate_hz * f.fixed_delta_seconds);
  std::vector<msg::MemberStatus> list;
  for (const auto& [name, m] : members.members()) {
    msg::MemberStatus ms;
    ms.service(name);
    ms.kind(m.kind);
    ms.alive(m.alive);
    ms.required(m.required);
    ms.last_frame(m.last_frame);
    ms.last_step_wall_us(m.last_step_us);
    ms.pid(m.pid);
    ms.failure(m.failure.substr(0, 255));
    if (m.run == f.run) ms.divergence(m.divergence.substr(0, 255));
    list.push_back(ms);
  }
  s.members(list);
  s.diverged(f.diverged);
  s.failed_service(f.failed_service);
  s.reason(f.reason.substr(0, 511));
  return s;
}

double TickRate(std::deque<std::chrono::steady_clock::time_point>* recent, std::chrono::steady_clock::time_point now) {
  while (!recent->empty() && now - recent->front() > std::chrono::seconds(1)) recent->pop_front();
  if (recent->size() < 2) return 0;
  const double span = std::chrono::duration<double>(recent->back() - recent->front()).count();
  return span > 0 ? static_cast<double>(recent->size() - 1) / span : 0;
}

}  // namespace lockstep
