#pragma once
// A test's own view of a running simulation over DDS: it records run status, frames
// and command replies, sends commands, and waits for conditions with a timeout.
#include <chrono>
#include <condition_variable>
#include <functional>
#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <vector>

#include "lockstep/runtime/bus.h"
#include "lockstep/runtime/messages.h"

namespace lockstep::testing {

class Observer {
 public:
  explicit Observer(Bus& bus, std::string client = "test-client");

  // Waits until `pred` holds (checked on every sample); false on timeout.
  bool WaitUntil(const std::function<bool()>& pred, std::chrono::milliseconds timeout);

  // Waits until the command writer and the reply reader matched the coordinator's
  // endpoints (a command written before that is lost: the topic is VOLATILE).
  bool WaitConnected(std::chrono::milliseconds timeout);

  // Sends a command; returns its sequence number.
  uint64_t Send(msg::CommandBody body);
  std::optional<msg::CommandReply> WaitReply(uint64_t sequence, std::chrono::milliseconds timeout);

  // Snapshot accessors (thread safe).
  std::optional<msg::RunStatus> status();
  uint64_t last_frame();
  std::map<uint64_t, msg::FrameDone> frames();

 private:
  Bus& bus_;
  std::string client_;
  uint64_t next_seq_ = 1;
  std::mutex mu_;
  std::condition_variable cv_;
  std::optional<msg::RunStatus> status_;
  std::map<uint64_t, msg::FrameDone> frames_;
  std::map<uint64_t, msg::CommandReply> replies_;
  Writer<msg::Command> commands_;
  Reader<msg::RunStatus> status_reader_;
  Reader<msg::FrameDone> frame_reader_;
  Reader<msg::CommandReply> reply_reader_;
};

}  // namespace lockstep::testing
