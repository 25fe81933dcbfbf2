#include "lockstep/runtime/tick_log.h"

#include <utility>

namespace lockstep {

namespace ticklog {

msg::Tick Infer(msg::Tick from, uint64_t frame) {
  if (from.frame() < frame) from.commands({});
  while (from.frame() < frame) {
    from.frame(from.frame() + 1);
    from.sim_time(from.sim_time() + from.dt());
  }
  return from;
}

void Append(std::vector<msg::Tick>* log, const msg::Tick& tick) {
  if (log->empty() || !tick.commands().empty() || tick.dt() != log->back().dt()) log->push_back(tick);
}

void Trim(std::vector<msg::Tick>* log, uint64_t* first_frame, uint64_t keep_after) {
  if (keep_after <= *first_frame || log->empty()) return;
  // Tick keep_after + 1 from the last logged tick at or before it, inferred as replay does.
  size_t base = 0;
  while (base + 1 < log->size() && (*log)[base + 1].frame() <= keep_after + 1) ++base;
  if ((*log)[base].frame() > keep_after + 1) return;
  msg::Tick first = Infer((*log)[base], keep_after + 1);
  if (first.frame() != keep_after + 1) return;
  std::vector<msg::Tick> kept{std::move(first)};
  for (size_t i = base + 1; i < log->size(); ++i) {
    if ((*log)[i].frame() > keep_after + 1) kept.push_back((*log)[i]);
  }
  log->swap(kept);
  *first_frame = keep_after;
}

const msg::Tick& Cursor::At(uint64_t frame) {
  while (next_ < kept_.size() && kept_[next_].frame() <= frame) tick_ = kept_[next_++];
  if (tick_.frame() != frame) tick_ = Infer(tick_, frame);
  return tick_;
}

}  // namespace ticklog

}  // namespace lockstep
