#pragma once
// The tick log's rule, in one place: which completed ticks the coordinator keeps for a
// replacement (TickLog in clock.idl), how it forgets the ones no replacement needs, and
// which tick a replay steps for each frame. The coordinator appends and trims; a
// replacement's ServiceRunner replays through TickLogCursor. Both use these functions
// only, so what is left out and what replay infers cannot disagree.
#include <cstdint>
#include <vector>

#include "lockstep/runtime/messages.h"

namespace lockstep::ticklog {

// Tick `frame` as replay infers it from the last kept tick before it: no commands, the
// same dt, sim_time advanced by dt once per frame (the coordinator's own arithmetic).
msg::Tick Infer(msg::Tick from, uint64_t frame);

// Keeps a completed tick when replay cannot infer it: the first, one with commands, one
// whose dt differs from the kept tick before it.
void Append(std::vector<msg::Tick>* log, const msg::Tick& tick);

// Forgets the ticks up to `keep_after` (a replacement restores a snapshot of that frame or
// later): the first kept tick is then tick keep_after + 1, written out in full. Does
// nothing when keep_after is not after *first_frame or beyond the completed frames.
void Trim(std::vector<msg::Tick>* log, uint64_t* first_frame, uint64_t keep_after);

// The ticks of a log frame by frame, in increasing frames from first_frame + 1.
class Cursor {
 public:
  explicit Cursor(const std::vector<msg::Tick>& kept) : kept_(kept) {}
  // The tick of `frame` (kept or inferred); frames must not decrease between calls.
  const msg::Tick& At(uint64_t frame);

 private:
  const std::vector<msg::Tick>& kept_;
  size_t next_ = 0;
  msg::Tick tick_;
};

}  // namespace lockstep::ticklog
