#include <gtest/gtest.h>

#include <chrono>
#include <condition_variable>
#include <mutex>
#include <vector>

#include "lockstep/runtime/bus.h"
#include "lockstep/runtime/messages.h"

namespace lockstep {
namespace {

// Values appended from a delivery thread; the test waits for a count with a timeout.
template <class T>
class Collector {
 public:
  void Add(T v) {
    {
      std::lock_guard<std::mutex> lock(mu_);
      values_.push_back(std::move(v));
    }
    cv_.notify_all();
  }
  std::vector<T> WaitFor(size_t n, std::chrono::milliseconds timeout = std::chrono::seconds(5)) {
    std::unique_lock<std::mutex> lock(mu_);
    cv_.wait_for(lock, timeout, [&] { return values_.size() >= n; });
    return values_;
  }

 private:
  std::mutex mu_;
  std::condition_variable cv_;
  std::vector<T> values_;
};

msg::Tick TickOf(uint64_t frame) {
  msg::Tick t;
  t.frame(frame);
  return t;
}

TEST(InProcessBus, DeliversToEveryReader) {
  auto bus = CreateInProcessBus();
  Writer<msg::Tick> w(*bus, topics::kTick);
  Collector<uint64_t> a, b;
  Reader<msg::Tick> ra(*bus, topics::kTick, [&](const msg::Tick& t, const SampleInfo&) { a.Add(t.frame()); });
  Reader<msg::Tick> rb(*bus, topics::kTick, [&](const msg::Tick& t, const SampleInfo&) { b.Add(t.frame()); });
  for (uint64_t i = 1; i <= 3; ++i) w.Write(TickOf(i));
  EXPECT_EQ(a.WaitFor(3), (std::vector<uint64_t>{1, 2, 3}));
  EXPECT_EQ(b.WaitFor(3), (std::vector<uint64_t>{1, 2, 3}));
  EXPECT_EQ(w.MatchedReaders(), 2);
}

TEST(InProcessBus, LateReaderGetsTransientLocalHistoryOnly) {
  auto bus = CreateInProcessBus();
  Writer<msg::Tick> ticks(*bus, topics::kTick);        // clock family: depth 1, transient local
  Writer<msg::SimEvent> events(*bus, topics::kEvent);  // volatile
  for (uint64_t i = 1; i <= 5; ++i) ticks.Write(TickOf(i));
  events.Write(msg::SimEvent{});
  Collector<uint64_t> got;
  Collector<int> events_seen;
  Reader<msg::Tick> late(*bus, topics::kTick, [&](const msg::Tick& t, const SampleInfo&) { got.Add(t.frame()); });
  Reader<msg::SimEvent> late_events(*bus, topics::kEvent, [&](const msg::SimEvent&, const SampleInfo&) { events_seen.Add(1); });
  EXPECT_EQ(got.WaitFor(1), std::vector<uint64_t>{5}) << "a late joiner sees the current tick";
  // A marker written after the reader joined arrives; the old event never does.
  events.Write(msg::SimEvent{});
  EXPECT_EQ(events_seen.WaitFor(1).size(), 1u);
  EXPECT_EQ(events_seen.WaitFor(2, std::chrono::milliseconds(100)).size(), 1u) << "volatile topics replay nothing";
}

TEST(InProcessBus, ReportsTheWriterAndItsDeparture) {
  auto bus = CreateInProcessBus();
  Collector<uint64_t> seen_writer;
  Collector<LivelinessChange> changes_seen;
  Reader<msg::Ack> r(
      *bus, topics::kAck, [&](const msg::Ack&, const SampleInfo& i) { seen_writer.Add(i.writer_id); },
      [&](const LivelinessChange& c) { changes_seen.Add(c); });
  uint64_t id = 0;
  {
    Writer<msg::Ack> w(*bus, topics::kAck);
    id = w.id();
    w.Write(msg::Ack{});
  }
  EXPECT_EQ(seen_writer.WaitFor(1), std::vector<uint64_t>{id});
  auto changes = changes_seen.WaitFor(1);
  ASSERT_EQ(changes.size(), 1u);
  EXPECT_EQ(changes[0].writer_id, id);
  EXPECT_FALSE(changes[0].alive);
}

TEST(InProcessBus, OneTopicOneType) {
  auto bus = CreateInProcessBus();
  Writer<msg::Tick> w(*bus, Topic<msg::Tick>{"shared", QosKind::kClock});
  EXPECT_THROW((Writer<msg::Ack>(*bus, Topic<msg::Ack>{"shared", QosKind::kAck})), std::runtime_error);
}

}  // namespace
}  // namespace lockstep
