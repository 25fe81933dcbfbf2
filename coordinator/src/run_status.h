#pragma once
// RunStatus (lockstep/run_status): the run as `lockstep status`, clients and joining
// services see it, built from the coordinator's run state and its membership. No bus and
// no lock: the coordinator publishes what MakeRunStatus returns.
#include <chrono>
#include <cstdint>
#include <deque>
#include <string>

#include "lockstep/coordinator/membership.h"
#include "lockstep/runtime/messages.h"

namespace lockstep {

struct RunFacts {
  uint32_t run = 0;
  msg::RunState state = msg::RunState::RUN_WAITING_FOR_SERVICES;
  uint64_t frame = 0;          // last completed frame
  double sim_time = 0;         // s, of that frame
  double tick_rate_hz = 0;     // completed ticks per second, over the last second
  double fixed_delta_seconds = 0;
  bool diverged = false;       // a member of this run reported divergence
  std::string failed_service;
  std::string reason;          // why the run is faulted (cut to the wire's 511 characters here)
};

// The status: the facts, the real-time factor they give, and every member (its divergence
// only when it is of this run).
msg::RunStatus MakeRunStatus(const RunFacts& facts, const Membership& members);

// Ticks per second over the completion times in `recent` within the second before `now`
// (older ones are dropped); 0 with fewer than two.
double TickRate(std::deque<std::chrono::steady_clock::time_point>* recent, std::chrono::steady_clock::time_point now);

}  // namespace lockstep
