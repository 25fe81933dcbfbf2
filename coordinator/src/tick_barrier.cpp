#include "lockstep/coordinator/tick_barrier.h"

#include "lockstep/runtime/hash.h"

namespace lockstep {

void TickBarrier::Open(uint32_t run, uint64_t frame, const std::vector<std::string>& required) {
  open_ = true;
  run_ = run;
  frame_ = frame;
  // Every tick opens the barrier for the same services: reset in place, no allocation.
  bool same = entries_.size() == required.size();
  for (size_t i = 0; same && i < required.size(); ++i) same = entries_.count(required[i]) > 0;
  if (same) {
    for (auto& [name, e] : entries_) e = Entry{};
  } else {
    entries_.clear();
    for (const auto& name : required) entries_[name] = Entry{};
  }
  pending_ = entries_.size();
}

TickBarrier::AckResult TickBarrier::OnAck(const std::string& service, uint32_t run, uint64_t frame,
                                          uint64_t state_hash) {
  if (!open_ || run != run_ || frame != frame_) return AckResult::kStale;
  auto it = entries_.find(service);
  if (it == entries_.end()) return AckResult::kNotRequired;
  if (it->second.acked) return AckResult::kDuplicate;
  it->second.acked = true;
  it->second.hash = state_hash;
  --pending_;
  return AckResult::kCounted;
}

std::vector<std::string> TickBarrier::Missing() const {
  std::vector<std::string> out;
  for (const auto& [name, e] : entries_) {
    if (!e.acked) out.push_back(name);
  }
  return out;
}

uint64_t TickBarrier::WorldHash() const {
  Fnv1a64 h;
  for (const auto& [name, e] : entries_) h.Add(std::string_view(name)).Add(e.hash);
  return h.value();
}

}  // namespace lockstep
