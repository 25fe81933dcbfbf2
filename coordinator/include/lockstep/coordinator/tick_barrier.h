#pragma once
// The tick barrier as plain logic: which services still owe an ack for the current
// frame. No DDS, no clock; the coordinator feeds it acks.
#include <cstdint>
#include <map>
#include <string>
#include <vector>

namespace lockstep {

class TickBarrier {
 public:
  enum class AckResult {
    kCounted,    // first ack of this service for the open frame
    kDuplicate,  // the same ack again: counted once
    kStale,      // another run or frame: ignored
    kNotRequired // a service the barrier does not wait for
  };

  // Opens frame `frame` of run `run`, waiting for every service in `required`.
  void Open(uint32_t run, uint64_t frame, const std::vector<std::string>& required);
  AckResult OnAck(const std::string& service, uint32_t run, uint64_t frame, uint64_t state_hash);

  bool open() const { return open_; }
  bool Complete() const { return open_ && pending_ == 0; }
  uint32_t run() const { return run_; }
  uint64_t frame() const { return frame_; }
  std::vector<std::string> Missing() const;
  // FNV-1a over (name, state hash) in name order: one number for the world's state.
  uint64_t WorldHash() const;
  void Close() { open_ = false; }

 private:
  bool open_ = false;
  uint32_t run_ = 0;
  uint64_t frame_ = 0;
  size_t pending_ = 0;
  struct Entry {
    bool acked = false;
    uint64_t hash = 0;
  };
  std::map<std::string, Entry> entries_;  // ordered by name
};

}  // namespace lockstep
