// The wire contract is vendor neutral: a Cyclone DDS participant written in C
// (client/cyclone_c) joins a tick barrier run by the Fast DDS coordinator as a required
// service, reads WorldInfo and the world state, and the frames complete only with it.
#include <gtest/gtest.h>

#include <csignal>
#include <fstream>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "lockstep/runtime/service.h"
#include "observer.h"
#include "process.h"

namespace lockstep::testing {
namespace {

using namespace std::chrono_literals;

constexpr uint64_t kFrames = 100;
const char* kProfile = "lockstep.participant.loopback";

// Stands in for ground_sim and air_sim: each step publishes a GroundState and an AirState
// stamped with the tick's frame (before the runner acks it).
class StatePublisher final : public ServiceCore {
 public:
  explicit StatePublisher(Bus& bus) : ground_(bus, topics::kGroundState), air_(bus, topics::kAirState) {}
  void BeginRun(const msg::WorldInfo&) override {}
  void Step(const msg::Tick& tick) override {
    msg::FrameStamp stamp;
    stamp.run(tick.run());
    stamp.frame(tick.frame());
    stamp.sim_time(tick.sim_time());
    msg::GroundState g;
    g.stamp(stamp);
    g.state_hash(tick.frame());
    ground_.Write(g);
    msg::AirState a;
    a.stamp(stamp);
    a.state_hash(tick.frame());
    air_.Write(a);
  }

 private:
  Writer<msg::GroundState> ground_;
  Writer<msg::AirState> air_;
};

// A ServiceRunner on its own thread, stopped and joined on destruction (also on failure).
class ServiceThread {
 public:
  ServiceThread(Bus& bus, const std::string& name, ServiceCore& core)
      : runner_(bus, ServiceOptions{name, "state_pub", false}, core), thread_([this] {
          try {
            runner_.Run(stop_);
          } catch (const std::exception& e) {
            error_ = e.what();
          }
        }) {}
  ~ServiceThread() {
    stop_ = true;
    thread_.join();
  }
  const std::string& error() const { return error_; }

 private:
  std::atomic<bool> stop_{false};
  std::string error_;
  ServiceRunner runner_;
  std::thread thread_;
};

std::string ReadFile(const std::string& path) {
  std::ifstream in(path);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

std::vector<std::string> Lines(const std::string& text, const std::string& prefix) {
  std::vector<std::string> out;
  std::istringstream in(text);
  for (std::string line; std::getline(in, line);) {
    if (line.rfind(prefix, 0) == 0) out.push_back(line);
  }
  return out;
}

struct TickLine {
  uint32_t run = 0;
  uint64_t frame = 0;
  uint32_t commands = 0;
  uint64_t ground = 0;
  uint64_t air = 0;
};

// "tick <run> <frame> <n_commands> ground_frame=<g> air_frame=<a>"
// "done <run> <frame> ground_frame=<g> air_frame=<a>"
TickLine Parse(const std::string& line) {
  TickLine t;
  unsigned long long frame = 0, ground = 0, air = 0;
  unsigned run = 0, commands = 0;
  if (line.rfind("tick ", 0) == 0) {
    EXPECT_EQ(std::sscanf(line.c_str(), "tick %u %llu %u ground_frame=%llu air_frame=%llu", &run, &frame, &commands, &ground,
                          &air),
              5)
        << line;
  } else {
    EXPECT_EQ(std::sscanf(line.c_str(), "done %u %llu ground_frame=%llu air_frame=%llu", &run, &frame, &ground, &air), 4)
        << line;
  }
  t.run = run;
  t.frame = frame;
  t.commands = commands;
  t.ground = ground;
  t.air = air;
  return t;
}

bool Alive(const msg::RunStatus& s, const std::string& name) {
  for (const auto& m : s.members()) {
    if (m.service().to_string() == name) return m.alive();
  }
  return false;
}

TEST(CycloneParticipant, JoinsTheFastDdsBarrierAndReadsWorldState) {
  const int domain = TestDomain();
  const std::string config = WriteTempFile("cyclone.yaml",
                                           "domain_id: " + std::to_string(domain) + "\n"
                                           "participant_profile: " + kProfile + "\n"
                                                                                      "seed: 7\n"
                                           "world:\n"
                                           "  synchronous_mode: false\n"
                                           "  service_timeout: 5.0\n"
                                           "services:\n"
                                           "  - {name: alpha, kind: noop}\n"
                                           "  - {name: cyc, kind: cyclone_c}\n"
                                           "  - {name: state_pub, kind: state_pub}\n");
  auto bus = CreateDdsBus({domain, "", kProfile, "cyclone_test"});
  Observer observer(*bus);

  Process coordinator({Bin("lockstep_coordinator"), config});
  Process alpha({Bin("lockstep_noop"), "--name", "alpha", "--config", config});
  StatePublisher state_core(*bus);
  ServiceThread state_pub(*bus, "state_pub", state_core);

  // (a) Both Fast DDS services are alive, the Cyclone one is not there yet: the coordinator
  // waits for it and no frame completes.
  ASSERT_TRUE(observer.WaitUntil(
      [&] {
        auto s = observer.status();
        return s && Alive(*s, "alpha") && Alive(*s, "state_pub");
      },
      20s))
      << "coordinator:\n" << coordinator.Output() << "\nalpha:\n" << alpha.Output();
  EXPECT_FALSE(observer.WaitUntil([&] { return observer.last_frame() > 0; }, 1500ms))
      << "a frame completed without the required Cyclone participant";
  {
    auto s = observer.status();
    ASSERT_TRUE(s);
    EXPECT_EQ(s->state(), msg::RunState::RUN_WAITING_FOR_SERVICES);
    EXPECT_FALSE(Alive(*s, "cyc"));
    EXPECT_EQ(s->frame(), 0u);
  }

  // (b) The Cyclone participant joins: frames complete, and it stepped each exactly once.
  // The run is free-running with no tick limit and stopped by the test once kFrames are
  // done and seen by everyone: a coordinator that exits on its own after N ticks tears its
  // writers down at once, and the last FrameDone can be lost in flight.
  const std::string ticks_file = WriteTempFile("cyc_ticks.txt", "");
  Process cyc({Bin("lockstep_cyclone_participant"), "--name", "cyc", "--domain", std::to_string(domain), "--ticks-file",
               ticks_file, "--wait-state"},
              {{"CYCLONEDDS_URI", "file://" + SourceDir() + "/client/cyclone_c/cyclone_loopback.xml"}});
  auto diagnostics = [&] {
    return "coordinator:\n" + coordinator.Output() + "\ncyc:\n" + cyc.Output() + "\ncyc ticks:\n" + ReadFile(ticks_file) +
           "\nstate_pub: " + state_pub.error();
  };
  ASSERT_TRUE(observer.WaitUntil([&] { return observer.last_frame() >= kFrames; }, 40s)) << diagnostics();
  // FrameDone reached the Cyclone participant too (over Cyclone, from the Fast DDS writer).
  ASSERT_TRUE(observer.WaitUntil(
      [&] {
        const auto done = Lines(ReadFile(ticks_file), "done ");
        return !done.empty() && Parse(done.back()).frame >= kFrames;
      },
      10s))
      << diagnostics();

  // (d) Its own blueprint: the participant declares prop.cyclone.beacon; a client spawns
  // one, the coordinator checks it against the declaration, and the tick hands it to the
  // participant as its owner.
  auto beacon = [](const std::string& period) {
    msg::SpawnActor sp;
    sp.blueprint("prop.cyclone.beacon");
    sp.transform().orientation().w(1);
    msg::BlueprintAttribute a;
    a.key("period");
    a.value(period);
    sp.attributes({a});
    msg::CommandBody b;
    b.spawn_actor(sp);
    return b;
  };
  auto too_long = observer.WaitReply(observer.Send(beacon("100")), 10s);
  ASSERT_TRUE(too_long) << diagnostics();
  EXPECT_FALSE(too_long->accepted());
  EXPECT_NE(too_long->reason().to_string().find("attribute 'period' (float): out of range [0.1, 60]"), std::string::npos)
      << too_long->reason();
  auto spawned = observer.WaitReply(observer.Send(beacon("2.5")), 10s);
  ASSERT_TRUE(spawned) << diagnostics();
  ASSERT_TRUE(spawned->accepted()) << spawned->reason();
  const std::string own = "own 1 " + std::to_string(spawned->frame()) + " " + std::to_string(spawned->actor()) + " prop.cyclone.beacon";
  ASSERT_TRUE(observer.WaitUntil([&] { return !Lines(ReadFile(ticks_file), own).empty(); }, 10s))
      << "expected '" << own << "'\n" << diagnostics();
  const uint64_t spawn_frame = spawned->frame();
  ASSERT_TRUE(observer.WaitUntil([&] { return observer.last_frame() >= spawn_frame + 1; }, 10s)) << diagnostics();

  coordinator.Signal(SIGINT);
  ASSERT_EQ(coordinator.Wait(10s), std::optional<int>(0)) << diagnostics();
  cyc.Signal(SIGTERM);
  ASSERT_EQ(cyc.Wait(10s), std::optional<int>(0)) << diagnostics();
  EXPECT_NE(cyc.Output().find("stopping after frame"), std::string::npos) << diagnostics();

  const std::string out = ReadFile(ticks_file);
  // It read WorldInfo: run, seed and the barrier's members.
  const auto world = Lines(out, "world ");
  ASSERT_FALSE(world.empty()) << out;
  EXPECT_EQ(world.front(), "world run=1 map= seed=7 dt=0.05 sync=0 required=alpha,cyc,state_pub");

  const auto ticks = Lines(out, "tick ");
  ASSERT_GE(ticks.size(), kFrames) << out;
  for (uint64_t k = 1; k <= ticks.size(); ++k) {
    const TickLine t = Parse(ticks[k - 1]);
    EXPECT_EQ(t.run, 1u);
    ASSERT_EQ(t.frame, k) << "frames missing, out of order or repeated:\n" << out;
    EXPECT_EQ(t.commands, t.frame == spawn_frame ? 1u : 0u) << "only the accepted spawn reaches a tick";
    // (c) World state. state_pub wrote state k-1 before acking k-1, and tick k starts only
    // after that ack, but DDS orders samples per writer only, so the participant waits for
    // state k-1 (--wait-state) before stepping k. State k may already be there, never k+1.
    EXPECT_GE(t.ground, k - 1) << ticks[k - 1];
    EXPECT_LE(t.ground, k) << ticks[k - 1];
    EXPECT_GE(t.air, k - 1) << ticks[k - 1];
    EXPECT_LE(t.air, k) << ticks[k - 1];
  }
  // FrameDone k means all outputs of k are complete: the participant waits for the state
  // of k itself before reporting it (later states may be there too: FrameDone k and
  // tick k+1 come from different writers, so the participant may step on first).
  const auto done = Lines(out, "done ");
  ASSERT_FALSE(done.empty()) << out;
  uint64_t previous = 0;
  for (const auto& line : done) {
    const TickLine d = Parse(line);
    EXPECT_EQ(d.run, 1u);
    EXPECT_GT(d.frame, previous) << line;
    EXPECT_GE(d.ground, d.frame) << line;
    EXPECT_GE(d.air, d.frame) << line;
    previous = d.frame;
  }
  EXPECT_GE(previous, kFrames);
  EXPECT_NE(coordinator.Output().find("service 'cyc' (cyclone_c"), std::string::npos) << coordinator.Output();
}

}  // namespace
}  // namespace lockstep::testing
