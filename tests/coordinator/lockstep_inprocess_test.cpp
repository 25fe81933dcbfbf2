// The coordinator and several services in one process over the in-process bus: the
// barrier's guarantees, command sequencing and rejection, synchronous mode, reset.
#include <gtest/gtest.h>

#include <condition_variable>
#include <fstream>
#include <sstream>
#include <limits>
#include <map>
#include <mutex>
#include <thread>

#include "lockstep/coordinator/coordinator.h"
#include "lockstep/runtime/blueprint_builder.h"
#include "lockstep/runtime/noop_core.h"
#include "lockstep/runtime/service.h"
#include "observer.h"
#include "stand_in_blueprints.h"

namespace lockstep {
namespace {

using namespace std::chrono_literals;

// Shared record of what every service did, checked on each step.
struct Ledger {
  std::mutex mu;
  std::map<std::string, std::pair<uint32_t, uint64_t>> completed;  // last (run, frame) stepped, per service
  std::map<std::string, std::vector<std::vector<uint64_t>>> commands;  // per service: per frame, command seqs
  std::vector<std::string> violations;
};

class RecordingCore : public NoopCore {
 public:
  // The first service declares the stand-in vehicles, walkers and sensors.
  RecordingCore(std::string name, Ledger& ledger, std::vector<std::string> all)
      : NoopCore(name == all.front() ? testing::StandInBlueprints() : std::vector<msg::BlueprintDeclaration>{}),
        name_(std::move(name)), ledger_(ledger), all_(std::move(all)) {}
  void Step(const msg::Tick& tick) override {
    {
      std::lock_guard<std::mutex> lock(ledger_.mu);
      // Each service acks k only after its step k returns, so if the coordinator waited
      // for every ack of k, every service has finished step k when any step k+1 begins.
      // (A tick of an older run, still in flight when a reset started a new one, is not
      // compared: the barrier of that run was abandoned.)
      for (const auto& other : all_) {
        const auto [run, frame] = ledger_.completed[other];
        const bool behind = run < tick.run() ? tick.frame() >= 2 : run == tick.run() && frame + 1 < tick.frame();
        if (behind) {
          ledger_.violations.push_back(name_ + " got tick " + std::to_string(tick.frame()) + " of run " + std::to_string(tick.run()) +
                                       " while " + other + " had finished only frame " + std::to_string(frame) +
                                       " of run " + std::to_string(run));
        }
      }
      std::vector<uint64_t> seqs;
      for (const auto& c : tick.commands()) seqs.push_back(c.sequence_number());
      auto& frames = ledger_.commands[name_];
      if (frames.size() < tick.frame()) frames.resize(tick.frame());
      frames[tick.frame() - 1] = seqs;
    }
    NoopCore::Step(tick);
    std::lock_guard<std::mutex> lock(ledger_.mu);
    ledger_.completed[name_] = {tick.run(), tick.frame()};
  }

 private:
  std::string name_;
  Ledger& ledger_;
  std::vector<std::string> all_;
};

class InProcessLockstep : public ::testing::Test {
 protected:
  void Start(LaunchConfig config) {
    config.world.service_timeout(30);  // a loaded CI machine must not fault this test
    bus_ = CreateInProcessBus();
    observer_ = std::make_unique<testing::Observer>(*bus_);
    coordinator_ = std::make_unique<Coordinator>(*bus_, config);
    for (const auto& s : config.services) names_.push_back(s.name);
    for (const auto& name : names_) {
      cores_.push_back(std::make_unique<RecordingCore>(name, ledger_, names_));
      runners_.push_back(std::make_unique<ServiceRunner>(*bus_, ServiceOptions{name, "recording", false}, *cores_.back()));
    }
    for (auto& r : runners_) threads_.emplace_back([&r, this] { r->Run(stop_); });
    coordinator_thread_ = std::thread([this] { coordinator_->Run(stop_); });
  }
  void TearDown() override {
    stop_ = true;
    if (coordinator_thread_.joinable()) coordinator_thread_.join();
    for (auto& t : threads_) {
      if (t.joinable()) t.join();
    }
    runners_.clear();
    coordinator_.reset();
  }
  static LaunchConfig Config(int services, bool sync) {
    LaunchConfig c;
    c.world = DefaultWorldSettings();
    c.world.synchronous_mode(sync);
    for (int i = 0; i < services; ++i) c.services.push_back({"svc" + std::to_string(i), "noop", "", {}, true, false, "never"});
    return c;
  }
  uint32_t SpawnCar() {
    // The library holds what live services declare: wait until the declarer has joined.
    EXPECT_TRUE(observer_->WaitUntil(
        [&] {
          auto st = observer_->status();
          return st && (st->state() == msg::RunState::RUN_RUNNING || st->state() == msg::RunState::RUN_READY);
        },
        10s));
    msg::SpawnActor s;
    s.blueprint("vehicle.lockstep.sedan");
    s.transform().orientation().w(1);
    msg::CommandBody b;
    b.spawn_actor(s);
    auto r = observer_->WaitReply(observer_->Send(b), 5s);
    EXPECT_TRUE(r && r->accepted());
    return r ? r->actor() : 0;
  }
  msg::CommandBody Throttle(uint32_t actor, float throttle) {
    msg::VehicleControl v;
    v.actor(actor);
    v.throttle(throttle);
    msg::CommandBody b;
    b.vehicle_control(v);
    return b;
  }

  Ledger ledger_;
  std::unique_ptr<Bus> bus_;
  std::unique_ptr<testing::Observer> observer_;
  std::unique_ptr<Coordinator> coordinator_;
  std::vector<std::string> names_;
  std::vector<std::unique_ptr<RecordingCore>> cores_;
  std::vector<std::unique_ptr<ServiceRunner>> runners_;
  std::vector<std::thread> threads_;
  std::thread coordinator_thread_;
  std::atomic<bool> stop_{false};
};

TEST_F(InProcessLockstep, NoServiceSeesTickKPlusOneBeforeAllAckedK) {
  auto config = Config(4, false);
  config.ticks = 400;
  Start(config);
  ASSERT_TRUE(observer_->WaitUntil([&] { return observer_->last_frame() >= 400; }, 60s)) << "frame " << observer_->last_frame();
  std::lock_guard<std::mutex> lock(ledger_.mu);
  EXPECT_TRUE(ledger_.violations.empty()) << ledger_.violations.front();
  for (const auto& name : names_) EXPECT_EQ(ledger_.completed[name].second, 400u) << name;
}

TEST_F(InProcessLockstep, CommandsReachEveryServiceInTheSameFrameAndOrder) {
  Start(Config(3, false));
  const uint32_t car = SpawnCar();
  std::vector<uint64_t> sent;
  for (int i = 0; i < 50; ++i) sent.push_back(observer_->Send(Throttle(car, 0.01f * static_cast<float>(i))));
  for (uint64_t seq : sent) ASSERT_TRUE(observer_->WaitReply(seq, 10s)) << seq;
  const uint64_t target = observer_->last_frame() + 3;
  ASSERT_TRUE(observer_->WaitUntil([&] { return observer_->last_frame() >= target; }, 20s));
  stop_ = true;
  TearDown();
  std::lock_guard<std::mutex> lock(ledger_.mu);
  const auto& reference = ledger_.commands[names_[0]];
  std::vector<uint64_t> seen;
  for (const auto& frame : reference) seen.insert(seen.end(), frame.begin(), frame.end());
  ASSERT_GE(seen.size(), sent.size() + 1);
  EXPECT_EQ(std::vector<uint64_t>(seen.end() - static_cast<long>(sent.size()), seen.end()), sent) << "acceptance order";
  for (const auto& name : names_) {
    const auto& mine = ledger_.commands[name];
    const size_t n = std::min(mine.size(), reference.size());
    for (size_t f = 0; f < n; ++f) EXPECT_EQ(mine[f], reference[f]) << name << " frame " << f + 1;
  }
  // The state hashes (a chain over frames and commands) agree too.
  for (size_t i = 1; i < cores_.size(); ++i) {
    if (cores_[i]->frames() == cores_[0]->frames()) {
      EXPECT_EQ(cores_[i]->StateHash(), cores_[0]->StateHash());
    }
  }
}

TEST_F(InProcessLockstep, BadCommandsAreRejectedWithAReasonAndTheRunGoesOn) {
  Start(Config(2, false));
  const uint32_t car = SpawnCar();
  auto unknown = observer_->WaitReply(observer_->Send(Throttle(999, 0.5f)), 5s);
  ASSERT_TRUE(unknown);
  EXPECT_FALSE(unknown->accepted());
  EXPECT_EQ(unknown->reason().to_string(), "unknown actor 999");
  auto nan = observer_->WaitReply(observer_->Send(Throttle(car, std::numeric_limits<float>::quiet_NaN())), 5s);
  ASSERT_TRUE(nan);
  EXPECT_FALSE(nan->accepted());
  EXPECT_NE(nan->reason().to_string().find("NaN"), std::string::npos);
  msg::SpawnActor s;
  s.blueprint("drone.imaginary");
  s.transform().orientation().w(1);
  msg::CommandBody b;
  b.spawn_actor(s);
  auto bp = observer_->WaitReply(observer_->Send(b), 5s);
  ASSERT_TRUE(bp);
  EXPECT_FALSE(bp->accepted());
  EXPECT_NE(bp->reason().to_string().find("unknown blueprint"), std::string::npos);
  const uint64_t now = observer_->last_frame();
  EXPECT_TRUE(observer_->WaitUntil([&] { return observer_->last_frame() >= now + 20; }, 20s)) << "the run continues";
  EXPECT_TRUE(observer_->WaitUntil([&] { return observer_->status() && observer_->status()->state() == msg::RunState::RUN_RUNNING; }, 5s));
}

TEST_F(InProcessLockstep, SynchronousModeStepsExactlyTheTicksAskedFor) {
  Start(Config(2, true));
  ASSERT_TRUE(observer_->WaitUntil([&] { return observer_->status() && observer_->status()->state() == msg::RunState::RUN_READY; }, 10s));
  EXPECT_EQ(observer_->last_frame(), 0u) << "no tick without a request";
  msg::TickRequest t;
  t.count(7);
  msg::CommandBody b;
  b.tick_request(t);
  auto reply = observer_->WaitReply(observer_->Send(b), 5s);
  ASSERT_TRUE(reply && reply->accepted()) << (reply ? reply->reason().to_string() : "no reply");
  EXPECT_EQ(reply->frame(), 7u);
  ASSERT_TRUE(observer_->WaitUntil([&] { return observer_->last_frame() == 7; }, 10s));
  ASSERT_TRUE(observer_->WaitUntil([&] { return observer_->status()->state() == msg::RunState::RUN_READY; }, 10s));
  EXPECT_EQ(observer_->last_frame(), 7u) << "and then it waits";
  const auto frames = observer_->frames();
  EXPECT_DOUBLE_EQ(frames.at(7).sim_time(), 7 * 0.05);
}

TEST_F(InProcessLockstep, ResetStartsANewRunFromFrameOne) {
  Start(Config(2, false));
  ASSERT_TRUE(observer_->WaitUntil([&] { return observer_->last_frame() >= 10; }, 10s));
  msg::ResetWorld r;
  r.seed(777);
  msg::CommandBody b;
  b.reset(r);
  auto reply = observer_->WaitReply(observer_->Send(b), 5s);
  ASSERT_TRUE(reply && reply->accepted());
  EXPECT_EQ(reply->run(), 2u);
  ASSERT_TRUE(observer_->WaitUntil([&] { return observer_->status() && observer_->status()->run() == 2 && observer_->status()->frame() >= 5; }, 10s));
  // Every service restarted its hash chain from the new seed: they agree again.
  std::lock_guard<std::mutex> lock(ledger_.mu);
  EXPECT_TRUE(ledger_.violations.empty()) << ledger_.violations.front();
}

}  // namespace
}  // namespace lockstep

namespace lockstep {
namespace {

using namespace std::chrono_literals;

// A step that blocks until released: the service keeps its heartbeats (it is alive) but
// does not finish the frame, so only the per-tick timeout can catch it.
class StuckCore : public NoopCore {
 public:
  void Step(const msg::Tick& tick) override {
    if (tick.frame() == stuck_at) {
      std::unique_lock<std::mutex> lock(mu);
      cv.wait(lock, [&] { return released; });
    }
    NoopCore::Step(tick);
  }
  bool StepNeverWaits() const override { return false; }
  void Release() {
    {
      std::lock_guard<std::mutex> lock(mu);
      released = true;
    }
    cv.notify_all();
  }
  uint64_t stuck_at = 30;
  std::mutex mu;
  std::condition_variable cv;
  bool released = false;
};

TEST(ServiceTimeout, AStuckStepFaultsTheRunUntilTheFrameIsDone) {
  LaunchConfig c;
  c.world.service_timeout(0.3);
  c.services.push_back({"fine", "noop", "", {}, true, false, "never"});
  c.services.push_back({"stuck", "noop", "", {}, true, false, "never"});
  auto bus = CreateInProcessBus();
  testing::Observer obs(*bus);
  Coordinator coordinator(*bus, c);
  NoopCore fine;
  StuckCore stuck;
  ServiceRunner r1(*bus, ServiceOptions{"fine", "noop", false}, fine);
  ServiceRunner r2(*bus, ServiceOptions{"stuck", "noop", false}, stuck);
  std::atomic<bool> stop{false};
  std::thread t1([&] { r1.Run(stop); });
  std::thread t2([&] { r2.Run(stop); });
  std::thread tc([&] { coordinator.Run(stop); });
  auto faulted = [&] {
    auto s = obs.status();
    return s && s->state() == msg::RunState::RUN_FAULTED && s->failed_service().to_string() == "stuck";
  };
  EXPECT_TRUE(obs.WaitUntil(faulted, 10s));
  EXPECT_NE(obs.status()->reason().to_string().find("did not acknowledge frame 30"), std::string::npos) << obs.status()->reason();
  // Its heartbeats go on, yet the run stays faulted while the frame is unfinished.
  EXPECT_FALSE(obs.WaitUntil([&] { return !faulted(); }, 1s)) << "a live but stuck service must not resume the run";
  EXPECT_EQ(obs.last_frame(), 29u);
  stuck.Release();
  EXPECT_TRUE(obs.WaitUntil([&] { return obs.last_frame() >= 60; }, 10s)) << "resumes once the frame is done";
  stop = true;
  stuck.Release();
  tc.join();
  t1.join();
  t2.join();
}

}  // namespace
}  // namespace lockstep

namespace lockstep {
namespace {

using namespace std::chrono_literals;

std::string ReadText(const std::string& path) {
  std::ifstream in(path);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

TEST_F(InProcessLockstep, LoadMapChecksTheMapAndItsTrafficLightsBecomeActors) {
  Start(Config(1, false));
  msg::LoadMap bad;
  bad.name("broken");
  bad.opendrive("<OpenDRIVE>\n<header revMajor=\"1\" revMinor=\"4\"/>\n<road length=\"x\" id=\"1\" junction=\"-1\"></road>\n</OpenDRIVE>");
  msg::CommandBody b;
  b.load_map(bad);
  auto rejected = observer_->WaitReply(observer_->Send(b), 10s);
  ASSERT_TRUE(rejected);
  EXPECT_FALSE(rejected->accepted());
  EXPECT_NE(rejected->reason().to_string().find("broken.xodr:3"), std::string::npos) << rejected->reason();
  ASSERT_TRUE(observer_->WaitUntil([&] { return observer_->status().has_value(); }, 10s));
  EXPECT_EQ(observer_->status()->run(), 1u) << "a rejected map leaves the run alone";

  msg::LoadMap town;
  town.name("Town02");
  town.opendrive(ReadText(std::string(LOCKSTEP_TEST_SHARED_DIR) + "/maps/carla/Town02.xodr"));
  b.load_map(town);
  auto accepted = observer_->WaitReply(observer_->Send(b), 10s);
  ASSERT_TRUE(accepted && accepted->accepted()) << (accepted ? accepted->reason().to_string() : "no reply");
  EXPECT_EQ(accepted->run(), 2u);
  // Traffic lights are actors 1..n: a command to light 1 is accepted, a car is not a light.
  msg::TrafficLightCommand light;
  light.actor(1);
  light.state(msg::TrafficLightColor::LIGHT_GREEN);
  light.green_time(10);
  light.yellow_time(-1);
  light.red_time(-1);
  msg::CommandBody lb;
  lb.traffic_light(light);
  auto ok = observer_->WaitReply(observer_->Send(lb), 10s);
  ASSERT_TRUE(ok);
  EXPECT_TRUE(ok->accepted()) << ok->reason();
  const uint32_t car = SpawnCar();
  EXPECT_GT(car, 1u) << "spawned actors come after the map's lights";
  light.actor(car);
  lb.traffic_light(light);
  auto wrong = observer_->WaitReply(observer_->Send(lb), 10s);
  ASSERT_TRUE(wrong);
  EXPECT_FALSE(wrong->accepted());
}

}  // namespace
}  // namespace lockstep

namespace lockstep {
namespace {

using namespace std::chrono_literals;

// A service that declares one blueprint, checks its spawns itself (a box may not be
// larger than 10 m) and records the spawns the ticks give it to own.
class BoxCore : public NoopCore {
 public:
  BoxCore()
      : NoopCore({blueprint::Make("prop.test.box", msg::ACTOR_PROP,
                                  {blueprint::Float("size", 1, 0, 100), blueprint::String("role_name", "")})}) {}
  std::string CheckSpawn(const msg::SpawnActor& spawn) const override {
    for (const auto& a : spawn.attributes()) {
      if (a.key().to_string() == "size" && std::stod(a.value().to_string()) > 10) return "a box of " + a.value().to_string() + " m is too big";
    }
    return {};
  }
  void Step(const msg::Tick& tick) override {
    for (const auto& c : tick.commands()) {
      if (c.body()._d() != msg::CommandKind::CMD_SPAWN_ACTOR) continue;
      {
        std::lock_guard<std::mutex> lock(mu);
        owners[c.body().spawn_actor().actor()] = c.body().spawn_actor().owner().to_string();
      }
      cv.notify_all();
    }
    NoopCore::Step(tick);
  }
  std::mutex mu;
  std::condition_variable cv;
  std::map<uint32_t, std::string> owners;  // spawned actor -> owner named in the tick
};

msg::CommandBody SpawnBox(const std::string& size) {
  msg::SpawnActor s;
  s.blueprint("prop.test.box");
  s.transform().orientation().w(1);
  msg::BlueprintAttribute a;
  a.key("size");
  a.value(size);
  s.attributes({a});
  msg::CommandBody b;
  b.spawn_actor(s);
  return b;
}

// The declaring service is not required: it joins and leaves while the run goes on.
TEST(BlueprintDeclarations, TheOwnerChecksASpawnBeforeTheSingleReplyAndLeavingTakesItsBlueprints) {
  LaunchConfig c;
  c.world = DefaultWorldSettings();
  c.world.service_timeout(30);
  c.services.push_back({"clock", "noop", "", {}, true, false, "never"});
  auto bus = CreateInProcessBus();
  testing::Observer obs(*bus);
  Coordinator coordinator(*bus, c);
  NoopCore clock;
  ServiceRunner r1(*bus, ServiceOptions{"clock", "noop", false}, clock);
  BoxCore boxes;
  auto r2 = std::make_unique<ServiceRunner>(*bus, ServiceOptions{"boxes", "box", false}, boxes);
  std::atomic<bool> stop{false}, stop_boxes{false};
  std::thread t1([&] { r1.Run(stop); });
  std::thread t2([&] { r2->Run(stop_boxes); });
  std::thread tc([&] { coordinator.Run(stop); });
  struct Join {  // also when an assertion returns early
    std::atomic<bool>& stop;
    std::atomic<bool>& stop_boxes;
    std::vector<std::thread*> threads;
    ~Join() {
      stop = stop_boxes = true;
      for (auto* t : threads) {
        if (t->joinable()) t->join();
      }
    }
  } join{stop, stop_boxes, {&t2, &tc, &t1}};
  auto boxes_alive = [&] {
    auto s = obs.status();
    if (!s) return false;
    for (const auto& m : s->members()) {
      if (m.service().to_string() == "boxes") return m.alive();
    }
    return false;
  };
  ASSERT_TRUE(obs.WaitUntil(boxes_alive, 10s));

  auto big = obs.WaitReply(obs.Send(SpawnBox("12")), 10s);
  ASSERT_TRUE(big);
  EXPECT_FALSE(big->accepted());
  EXPECT_EQ(big->reason().to_string(), "owner 'boxes' rejected the spawn: a box of 12 m is too big");
  auto ok = obs.WaitReply(obs.Send(SpawnBox("2")), 10s);
  ASSERT_TRUE(ok);
  ASSERT_TRUE(ok->accepted()) << ok->reason();
  const uint32_t id = ok->actor();
  {
    // boxes is not required (the barrier does not wait for it): wait for its step.
    std::unique_lock<std::mutex> lock(boxes.mu);
    ASSERT_TRUE(boxes.cv.wait_for(lock, 10s, [&] { return !boxes.owners.empty(); }));
    ASSERT_EQ(boxes.owners.size(), 1u) << "only the accepted spawn reaches the ticks";
    EXPECT_EQ(boxes.owners[id], "boxes") << "the tick names the owner";
  }
  ASSERT_TRUE(obs.WaitUntil([&] { return obs.last_frame() >= ok->frame() + 5; }, 10s));
  {
    std::lock_guard<std::mutex> lock(boxes.mu);
    EXPECT_EQ(boxes.owners.size(), 1u) << "only the accepted spawn reaches the ticks";
  }

  stop_boxes = true;
  t2.join();
  r2.reset();  // announces that it stops
  ASSERT_TRUE(obs.WaitUntil([&] { return !boxes_alive(); }, 10s));
  auto gone = obs.WaitReply(obs.Send(SpawnBox("2")), 10s);
  ASSERT_TRUE(gone);
  EXPECT_FALSE(gone->accepted());
  EXPECT_NE(gone->reason().to_string().find("declared only by 'boxes', which is not alive"), std::string::npos) << gone->reason();
}

}  // namespace
}  // namespace lockstep
