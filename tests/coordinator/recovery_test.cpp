// Recovery over the in-process bus: what a failure, a replacement or a reset leaves behind.
// Each test failed before the fix it names (issue 7, part 2).
#include <gtest/gtest.h>

#include <map>
#include <memory>
#include <mutex>
#include <thread>

#include "lockstep/coordinator/coordinator.h"
#include "lockstep/runtime/frame_buffer.h"
#include "lockstep/runtime/noop_core.h"
#include "lockstep/runtime/service.h"
#include "observer.h"

namespace lockstep {
namespace {

using namespace std::chrono_literals;

// A ServiceRunner on its own thread; Stop() ends it as a process that exits would.
struct RunningService {
  RunningService(Bus& bus, ServiceOptions options, std::unique_ptr<ServiceCore> c)
      : core(std::move(c)), runner(std::make_unique<ServiceRunner>(bus, std::move(options), *core)) {
    thread = std::thread([this] {
      try {
        runner->Run(stop);
      } catch (const std::exception& e) {
        std::lock_guard<std::mutex> lock(mu);
        error = e.what();
      }
    });
  }
  ~RunningService() { Stop(); }
  void Stop() {
    stop = true;
    if (thread.joinable()) thread.join();
    runner.reset();  // announces SERVICE_STOPPING
  }
  std::string Error() {
    std::lock_guard<std::mutex> lock(mu);
    return error;
  }
  std::unique_ptr<ServiceCore> core;
  std::unique_ptr<ServiceRunner> runner;
  std::atomic<bool> stop{false};
  std::thread thread;
  std::mutex mu;
  std::string error;
};

class Recovery : public ::testing::Test {
 protected:
  void StartCoordinator(const std::vector<std::string>& required) {
    LaunchConfig c;
    c.world = DefaultWorldSettings();
    c.world.service_timeout(30);
    for (const auto& name : required) c.services.push_back({name, "noop", "", {}, true, false, "never"});
    coordinator_ = std::make_unique<Coordinator>(*bus_, c);
    coordinator_thread_ = std::thread([this] { coordinator_->Run(stop_); });
  }
  RunningService& Start(const std::string& name, std::unique_ptr<ServiceCore> core = std::make_unique<NoopCore>(),
                        uint64_t snapshot_period = 200) {
    ServiceOptions o{name, "noop", false};
    o.snapshot_period = snapshot_period;
    services_.push_back(std::make_unique<RunningService>(*bus_, o, std::move(core)));
    return *services_.back();
  }
  void TearDown() override {
    services_.clear();
    stop_ = true;
    if (coordinator_thread_.joinable()) coordinator_thread_.join();
  }
  bool WaitFrame(uint64_t frame, std::chrono::milliseconds timeout = 20s) {
    return obs_.WaitUntil([&] { return obs_.last_frame() >= frame; }, timeout);
  }
  bool WaitState(msg::RunState state, std::chrono::milliseconds timeout = 20s) {
    return obs_.WaitUntil([&] { return obs_.status() && obs_.status()->state() == state; }, timeout);
  }
  std::optional<msg::MemberStatus> Member(const std::string& name) {
    auto s = obs_.status();
    if (!s) return std::nullopt;
    for (const auto& m : s->members()) {
      if (m.service().to_string() == name) return m;
    }
    return std::nullopt;
  }

  std::unique_ptr<Bus> bus_ = CreateInProcessBus();
  testing::Observer obs_{*bus_};
  std::unique_ptr<Coordinator> coordinator_;
  std::thread coordinator_thread_;
  std::atomic<bool> stop_{false};
  std::vector<std::unique_ptr<RunningService>> services_;
};

// Collects every TickLog, per failed service.
struct TickLogs {
  explicit TickLogs(Bus& bus)
      : reader(bus, topics::kTickLog, [this](const msg::TickLog& l, const SampleInfo&) {
          std::lock_guard<std::mutex> lock(mu);
          logs[l.service().to_string()] = l;
        }) {}
  std::optional<msg::TickLog> Of(const std::string& service) {
    std::lock_guard<std::mutex> lock(mu);
    auto it = logs.find(service);
    return it == logs.end() ? std::nullopt : std::optional<msg::TickLog>(it->second);
  }
  std::mutex mu;
  std::map<std::string, msg::TickLog> logs;
  Reader<msg::TickLog> reader;
};

// 2.1: the second failure during a fault used to get no tick log.
TEST_F(Recovery, EveryFailedServiceGetsATickLogAlsoWhenTheRunIsAlreadyFaulted) {
  TickLogs logs(*bus_);
  StartCoordinator({"a", "b", "c"});
  Start("a");
  auto& b = Start("b");
  auto& c = Start("c");
  ASSERT_TRUE(WaitFrame(20));
  b.Stop();
  ASSERT_TRUE(WaitState(msg::RunState::RUN_FAULTED));
  c.Stop();
  EXPECT_TRUE(obs_.WaitUntil([&] { return logs.Of("b") && logs.Of("c"); }, 10s))
      << "b: " << logs.Of("b").has_value() << ", c: " << logs.Of("c").has_value();
  // Both replacements rebuild their state from their own log, and the run goes on.
  Start("b");
  Start("c");
  ASSERT_TRUE(WaitState(msg::RunState::RUN_RUNNING));
  const uint64_t resumed = obs_.last_frame();
  ASSERT_TRUE(WaitFrame(resumed + 10));
  EXPECT_FALSE(obs_.frames().rbegin()->second.diverged());
}

// 2.3: a replay whose hash differs used to be logged only, with FrameDone looking healthy.
class ForgetfulCore : public NoopCore {
 public:
  // A replacement that cannot rebuild the state: it steps as if from another seed and its
  // restore does nothing.
  void BeginRun(const msg::WorldInfo& w) override {
    msg::WorldInfo other = w;
    other.seed(w.seed() + 1);
    NoopCore::BeginRun(other);
  }
  void RestoreState(const std::vector<uint8_t>&) override {}
};

TEST_F(Recovery, ADivergentReplayIsReportedInTheAckTheRunStatusAndFrameDone) {
  StartCoordinator({"a", "b"});
  Start("a");
  auto& b = Start("b");
  ASSERT_TRUE(WaitFrame(20));
  EXPECT_FALSE(obs_.frames().rbegin()->second.diverged());
  b.Stop();
  ASSERT_TRUE(WaitState(msg::RunState::RUN_FAULTED));
  Start("b", std::make_unique<ForgetfulCore>());
  ASSERT_TRUE(WaitState(msg::RunState::RUN_RUNNING));
  const uint64_t resumed = obs_.last_frame();
  ASSERT_TRUE(WaitFrame(resumed + 2));
  EXPECT_TRUE(obs_.frames().rbegin()->second.diverged()) << "FrameDone must not look healthy";
  ASSERT_TRUE(obs_.WaitUntil([&] { return obs_.status()->diverged(); }, 5s));
  auto m = Member("b");
  ASSERT_TRUE(m);
  // Found by the replacement's replay check, or by the coordinator when the re-sent frame
  // comes back with another state than the failed process acknowledged for it.
  EXPECT_TRUE(m->divergence().to_string().find("differs from the acknowledged") != std::string::npos ||
              m->divergence().to_string().find("acknowledged with state hash") != std::string::npos)
      << m->divergence();
  EXPECT_TRUE(Member("a")->divergence().to_string().empty());
  // A new run starts clean.
  msg::ResetWorld r;
  msg::CommandBody body;
  body.reset(r);
  ASSERT_TRUE(obs_.WaitReply(obs_.Send(body), 10s));
  ASSERT_TRUE(obs_.WaitUntil([&] { return obs_.status()->run() == 2 && obs_.status()->frame() >= 3; }, 10s));
  EXPECT_FALSE(obs_.status()->diverged());
}

// 2.6: an exception in a step on the receive thread used to call std::terminate.
class ThrowingCore : public NoopCore {
 public:
  void Step(const msg::Tick& tick) override {
    if (tick.frame() == 10) throw std::runtime_error("wheel fell off");
    NoopCore::Step(tick);
  }
};

TEST_F(Recovery, AStepThatThrowsStopsTheServiceWithItsReason) {
  StartCoordinator({"a", "b"});
  Start("a");
  auto& b = Start("b", std::make_unique<ThrowingCore>());
  ASSERT_TRUE(WaitState(msg::RunState::RUN_FAULTED));
  EXPECT_EQ(obs_.status()->failed_service().to_string(), "b");
  EXPECT_NE(obs_.status()->reason().to_string().find("step failed at frame 10: wheel fell off"), std::string::npos)
      << obs_.status()->reason();
  b.Stop();
  EXPECT_EQ(b.Error(), "step failed at frame 10: wheel fell off");
  EXPECT_EQ(obs_.last_frame(), 9u);
}

// 2.5: the tick log used to keep every tick with a command, for ever.
TEST_F(Recovery, ASnapshotBoundsTheTickLogAndTheReplacementReplaysOnlyFromIt) {
  TickLogs logs(*bus_);
  StartCoordinator({"a", "b"});
  Start("a", std::make_unique<NoopCore>(), 20);
  auto& b = Start("b", std::make_unique<NoopCore>(), 20);
  ASSERT_TRUE(WaitState(msg::RunState::RUN_RUNNING));
  // A client that sends a command every few frames, as a controller would.
  for (int i = 0; i < 4000 && obs_.last_frame() <= 120; ++i) {
    msg::WeatherParameters w;
    w.cloudiness(static_cast<float>(i % 100));
    w.fog_distance(0.75f);
    w.scattering_intensity(1);
    msg::CommandBody body;
    body.weather(w);
    auto r = obs_.WaitReply(obs_.Send(body), 10s);
    ASSERT_TRUE(r && r->accepted()) << (r ? r->reason().to_string() : "no reply");
  }
  const uint64_t sent_until = obs_.last_frame();
  ASSERT_GT(sent_until, 100u);
  b.Stop();
  ASSERT_TRUE(obs_.WaitUntil([&] { return logs.Of("b").has_value(); }, 10s));
  const msg::TickLog log = *logs.Of("b");
  EXPECT_GE(log.first_frame(), 20u) << "ticks before the last snapshot are forgotten";
  ASSERT_FALSE(log.ticks().empty());
  EXPECT_EQ(log.ticks().front().frame(), log.first_frame() + 1);
  EXPECT_LE(log.ticks().size(), log.frames() - log.first_frame());
  // The log starts at the newest snapshot the coordinator holds a copy of when it trims
  // (two periods back at most once the copy is in), so a replacement replays about one
  // period. The copy travels on its own topic and may arrive a few frames after the acks
  // on a loaded machine: one period of slack for it.
  EXPECT_LE(log.frames() - log.first_frame(), 3 * 20u) << "a replacement replays at most about one snapshot period";
  Start("b", std::make_unique<NoopCore>(), 20);  // restores the coordinator's copy of b's snapshot, replays the rest
  ASSERT_TRUE(WaitState(msg::RunState::RUN_RUNNING));
  const uint64_t resumed = obs_.last_frame();
  ASSERT_TRUE(WaitFrame(resumed + 5));
  EXPECT_FALSE(obs_.frames().rbegin()->second.diverged()) << Member("b")->divergence();
}


// Issue 21, item 3: a service waiting for the input of a failed producer used to time out,
// fail and be restarted (the cascade that ended the full stack's run). It must wait, alive,
// while the run is faulted, and the run status must say who waits for whom.
class Producer : public NoopCore {
 public:
  Producer(Bus& bus, uint64_t fail_at) : writer_(bus, topics::kGroundState), fail_at_(fail_at) {}
  void Step(const msg::Tick& tick) override {
    if (tick.frame() == fail_at_) throw std::runtime_error("producer crashed");
    NoopCore::Step(tick);
    if (replaying()) return;
    msg::GroundState g;
    g.stamp().run(tick.run());
    g.stamp().frame(tick.frame());
    writer_.Write(g);
  }

 private:
  Writer<msg::GroundState> writer_;
  uint64_t fail_at_;
};

// Reads the producer's output of the frame it steps (as perception does).
class Consumer : public NoopCore {
 public:
  explicit Consumer(Bus& bus) : inputs_(bus, topics::kGroundState) {}
  bool StepNeverWaits() const override { return false; }
  void Step(const msg::Tick& tick) override {
    NoopCore::Step(tick);
    if (replaying()) return;
    auto got = AwaitInput([&](std::chrono::milliseconds slice) { return inputs_.WaitFor(tick.run(), tick.frame(), slice); },
                          std::chrono::milliseconds(300));
    if (!got) throw MissingInput("no input of frame " + std::to_string(tick.frame()));
  }

 private:
  FrameBuffer<msg::GroundState> inputs_;
};

TEST_F(Recovery, AServiceWaitingForAFailedProducerWaitsAndIsNotFailed) {
  StartCoordinator({"a", "b"});
  auto& a = Start("a", std::make_unique<Producer>(*bus_, 30));
  auto& b = Start("b", std::make_unique<Consumer>(*bus_));
  ASSERT_TRUE(WaitState(msg::RunState::RUN_FAULTED));
  EXPECT_EQ(obs_.status()->failed_service().to_string(), "a");
  // b waits beyond its own input timeout (300 ms) for frame 30, held by the fault.
  ASSERT_TRUE(obs_.WaitUntil([&] { return b.core->held_by_fault() || !b.Error().empty(); }, 10s));
  EXPECT_EQ(b.Error(), "") << "the consumer failed while its producer was being replaced";
  EXPECT_TRUE(b.core->held_by_fault());
  EXPECT_EQ(obs_.status()->failed_service().to_string(), "a") << obs_.status()->reason();
  EXPECT_NE(obs_.status()->reason().to_string().find("b waits for its replacement's outputs of frame 30"), std::string::npos)
      << obs_.status()->reason();
  auto mb = Member("b");
  ASSERT_TRUE(mb);
  EXPECT_TRUE(mb->alive());
  EXPECT_EQ(mb->failure().to_string(), "");
  // The replacement of a rebuilds its state and publishes frame 30: b goes on, the run too.
  a.Stop();
  Start("a", std::make_unique<Producer>(*bus_, 0));
  ASSERT_TRUE(WaitFrame(40));
  EXPECT_EQ(b.Error(), "");
  EXPECT_FALSE(obs_.frames().rbegin()->second.diverged());
}

}  // namespace
}  // namespace lockstep
