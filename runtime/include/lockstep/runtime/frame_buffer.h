#pragma once
// Samples of one topic indexed by frame, for a consumer that needs the inputs of a
// given frame (never "the latest": DDS may deliver an Ack before the same service's
// outputs). Strict perception waits for frame k; pipelined uses frame k-1.
#include <chrono>
#include <condition_variable>
#include <map>
#include <mutex>
#include <optional>

#include "lockstep/runtime/bus.h"
#include "lockstep/runtime/messages.h"

namespace lockstep {

template <class T>
class FrameBuffer {
 public:
  FrameBuffer(Bus& bus, const Topic<T>& topic, size_t capacity = 8)
      : capacity_(capacity), reader_(bus, topic, [this](const T& s, const SampleInfo&) { Push(s); }) {}

  // The sample of (run, frame), waiting up to `timeout`. nullopt on timeout.
  std::optional<T> WaitFor(uint32_t run, uint64_t frame, std::chrono::milliseconds timeout) {
    std::unique_lock<std::mutex> lock(mu_);
    const Key key{run, frame};
    if (!cv_.wait_for(lock, timeout, [&] { return samples_.count(key) > 0; })) return std::nullopt;
    return samples_.at(key);
  }

  std::optional<T> Latest() const {
    std::lock_guard<std::mutex> lock(mu_);
    if (samples_.empty()) return std::nullopt;
    return samples_.rbegin()->second;
  }

 private:
  using Key = std::pair<uint32_t, uint64_t>;
  void Push(const T& s) {
    {
      std::lock_guard<std::mutex> lock(mu_);
      samples_[Key{s.stamp().run(), s.stamp().frame()}] = s;
      while (samples_.size() > capacity_) samples_.erase(samples_.begin());
    }
    cv_.notify_all();
  }

  size_t capacity_;
  mutable std::mutex mu_;
  std::condition_variable cv_;
  std::map<Key, T> samples_;
  Reader<T> reader_;  // last: its callback uses the members above
};

// Which frame perception renders during tick `tick_frame`.
inline uint64_t PerceptionFrame(msg::PerceptionMode mode, uint64_t tick_frame) {
  return mode == msg::PerceptionMode::PERCEPTION_PIPELINED ? tick_frame - 1 : tick_frame;
}

}  // namespace lockstep
