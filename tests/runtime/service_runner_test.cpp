// The service runner against a hand-driven coordinator over the in-process bus.
#include <gtest/gtest.h>

#include <condition_variable>
#include <map>
#include <mutex>
#include <thread>

#include "lockstep/runtime/noop_core.h"
#include "lockstep/runtime/service.h"

namespace lockstep {
namespace {

using namespace std::chrono_literals;

msg::WorldInfo World(uint32_t run) {
  msg::WorldInfo w;
  w.run(run);
  w.seed(run);
  return w;
}

msg::Tick TickOf(uint32_t run, uint64_t frame) {
  msg::Tick t;
  t.run(run);
  t.frame(frame);
  t.dt(0.05);
  t.sim_time(0.05 * static_cast<double>(frame));
  return t;
}

// Issue 7, 2.7: a tick of a run superseded by two quick resets used to block the service
// in a wait for that run's world info (world_info_timeout_s), and then force a re-join.
TEST(ServiceRunner, ATickOfASupersededRunIsSkipped) {
  auto bus = CreateInProcessBus();
  Writer<msg::WorldInfo> world(*bus, topics::kWorldInfo);
  Writer<msg::Tick> ticks(*bus, topics::kTick);
  Writer<msg::RunStatus> status(*bus, topics::kRunStatus);
  std::mutex mu;
  std::condition_variable cv;
  std::map<std::pair<uint32_t, uint64_t>, int> acks;  // (run, frame) -> count
  Reader<msg::Ack> ack_reader(*bus, topics::kAck, [&](const msg::Ack& a, const SampleInfo&) {
    {
      std::lock_guard<std::mutex> lock(mu);
      ++acks[{a.run(), a.frame()}];
    }
    cv.notify_all();
  });
  auto acked = [&](uint32_t run, uint64_t frame) {
    std::unique_lock<std::mutex> lock(mu);
    return cv.wait_for(lock, 5s, [&] { return acks.count({run, frame}) > 0; });
  };
  msg::RunStatus st;
  st.run(1);
  status.Write(st);
  world.Write(World(1));
  NoopCore core;
  ServiceOptions options{"svc", "noop", false};
  options.world_info_timeout_s = 60;
  ServiceRunner runner(*bus, options, core);
  std::atomic<bool> stop{false};
  std::thread t([&] { runner.Run(stop); });
  ticks.Write(TickOf(1, 1));
  EXPECT_TRUE(acked(1, 1));
  // Two resets: run 2 is over before its first tick reaches the service.
  world.Write(World(3));
  ticks.Write(TickOf(2, 1));
  ticks.Write(TickOf(3, 1));
  EXPECT_TRUE(acked(3, 1)) << "the service must not wait for the world info of a superseded run";
  {
    std::lock_guard<std::mutex> lock(mu);
    EXPECT_EQ(acks.count({2, 1}), 0u) << "nor step it";
  }
  stop = true;
  t.join();
}

}  // namespace
}  // namespace lockstep
