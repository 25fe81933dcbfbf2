#pragma once
// DDS writes the coordinator queues under its lock and performs with the lock released (a
// middleware thread may be waiting for the lock in a callback while a write needs that
// thread). Two threads flush (the main loop, and an ack callback that chained a tick):
// each flush takes a ticket under the lock and writes only in its turn, so writes leave in
// the order they were queued and FrameDone never goes backwards.
#include <condition_variable>
#include <cstdint>
#include <functional>
#include <mutex>
#include <vector>

namespace lockstep {

class OrderedOutbox {
 public:
  // Call with the owner's lock held.
  void Post(std::function<void()> write) { pending_.push_back(std::move(write)); }
  bool empty() const { return pending_.empty(); }
  // Call with `lock` (the owner's) held: releases it while writing, takes it back after.
  void Flush(std::unique_lock<std::mutex>& lock);

 private:
  std::vector<std::function<void()>> pending_;  // guarded by the owner's lock
  uint64_t next_ticket_ = 0;                    // guarded by the owner's lock
  std::mutex turn_mu_;
  std::condition_variable turn_cv_;
  uint64_t serving_ = 0;  // guarded by turn_mu_
};

}  // namespace lockstep
