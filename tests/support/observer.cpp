#include "observer.h"

namespace lockstep::testing {

Observer::Observer(Bus& bus, std::string client) : bus_(bus), client_(std::move(client)) {
  commands_ = Writer<msg::Command>(bus_, topics::kCommand);
  status_reader_ = Reader<msg::RunStatus>(bus_, topics::kRunStatus, [this](const msg::RunStatus& s, const SampleInfo&) {
    {
      std::lock_guard<std::mutex> lock(mu_);
      status_ = s;
    }
    cv_.notify_all();
  });
  frame_reader_ = Reader<msg::FrameDone>(bus_, topics::kFrameDone, [this](const msg::FrameDone& f, const SampleInfo&) {
    {
      std::lock_guard<std::mutex> lock(mu_);
      frames_[f.frame()] = f;
    }
    cv_.notify_all();
  });
  reply_reader_ = Reader<msg::CommandReply>(bus_, topics::kCommandReply, [this](const msg::CommandReply& r, const SampleInfo&) {
    if (r.client().to_string() != client_) return;
    {
      std::lock_guard<std::mutex> lock(mu_);
      replies_[r.sequence_number()] = r;
    }
    cv_.notify_all();
  });
}

bool Observer::WaitUntil(const std::function<bool()>& pred, std::chrono::milliseconds timeout) {
  std::unique_lock<std::mutex> lock(mu_);
  const auto deadline = std::chrono::steady_clock::now() + timeout;
  while (true) {
    lock.unlock();
    if (pred()) return true;
    lock.lock();
    // Re-check at least every 20 ms: a predicate may depend on state other than samples.
    if (cv_.wait_until(lock, std::min(deadline, std::chrono::steady_clock::now() + std::chrono::milliseconds(20))) ==
            std::cv_status::timeout &&
        std::chrono::steady_clock::now() >= deadline) {
      lock.unlock();
      return pred();
    }
  }
}

bool Observer::WaitConnected(std::chrono::milliseconds timeout) {
  return WaitUntil([&] { return commands_.MatchedReaders() > 0 && reply_reader_.MatchedWriters() > 0; }, timeout);
}

uint64_t Observer::Send(msg::CommandBody body) {
  msg::Command c;
  c.client(client_);
  c.sequence_number(next_seq_++);
  c.body(std::move(body));
  commands_.Write(c);
  return c.sequence_number();
}

std::optional<msg::CommandReply> Observer::WaitReply(uint64_t sequence, std::chrono::milliseconds timeout) {
  std::optional<msg::CommandReply> out;
  WaitUntil(
      [&] {
        std::lock_guard<std::mutex> lock(mu_);
        auto it = replies_.find(sequence);
        if (it == replies_.end()) return false;
        out = it->second;
        return true;
      },
      timeout);
  return out;
}

std::optional<msg::RunStatus> Observer::status() {
  std::lock_guard<std::mutex> lock(mu_);
  return status_;
}

uint64_t Observer::last_frame() {
  std::lock_guard<std::mutex> lock(mu_);
  return frames_.empty() ? 0 : frames_.rbegin()->first;
}

std::map<uint64_t, msg::FrameDone> Observer::frames() {
  std::lock_guard<std::mutex> lock(mu_);
  return frames_;
}

}  // namespace lockstep::testing
