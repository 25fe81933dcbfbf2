// The wire contract is vendor neutral: a Cyclone DDS participant written in C
// (client/cyclone_c) joins a tick barrier run by the Fast DDS coordinator as a required
// service, reads WorldInfo and the world state, and the frames complete only with it.
#include <gtest/gtest.h>

#include <csignal>
#include <cstdio>
#include <fstream>
#include <map>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "lockstep/runtime/noop_core.h"
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

// "tick <run> <frame> <n_commands> ground_frame=<g> air_frame=<a> hash=<h> commands=<list>"
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


// ---- Commands with bodies from both vendors ----

// "<kind>/<client>/<sequence>/<digest>", as the participant prints a tick's commands.
std::string Describe(const msg::Command& c) {
  char digest[17];
  std::snprintf(digest, sizeof digest, "%016llx", static_cast<unsigned long long>(CommandBodyDigest(c.body())));
  std::string out = std::to_string(static_cast<int>(c.body()._d()));
  out.append("/").append(c.client().to_string()).append("/").append(std::to_string(c.sequence_number()));
  out.append("/").append(digest);
  return out;
}

std::string Describe(const std::vector<msg::Command>& commands) {
  if (commands.empty()) return "-";
  std::string out;
  for (const auto& c : commands) {
    if (!out.empty()) out.append(",");
    out.append(Describe(c));
  }
  return out;
}

struct CycloneTick {
  uint64_t hash = 0;
  std::string commands;
};

// frame -> (hash, command list) of the participant's tick lines of run 1.
std::map<uint64_t, CycloneTick> CycloneTicks(const std::string& text) {
  std::map<uint64_t, CycloneTick> out;
  for (const auto& line : Lines(text, "tick 1 ")) {
    unsigned long long frame = 0, hash = 0;
    char list[4096] = {0};
    if (std::sscanf(line.c_str(), "tick 1 %llu %*u ground_frame=%*u air_frame=%*u hash=%llx commands=%4095s", &frame, &hash,
                    list) != 3) {
      ADD_FAILURE() << "unparsable tick line: " << line;
      continue;
    }
    EXPECT_FALSE(out.count(frame)) << "frame " << frame << " stepped twice";
    out[frame] = CycloneTick{hash, list};
  }
  return out;
}

// frame -> state hash of the noop witness's ledger ("<run> <frame> <start> <end> <hash>") of run 1.
std::map<uint64_t, uint64_t> NoopHashes(const std::string& text) {
  std::map<uint64_t, uint64_t> out;
  std::istringstream in(text);
  for (std::string line; std::getline(in, line);) {
    unsigned run = 0;
    unsigned long long frame = 0, hash = 0;
    if (std::sscanf(line.c_str(), "%u %llu %*d %*d %llu", &run, &frame, &hash) == 3 && run == 1) out[frame] = hash;
  }
  return out;
}

msg::CommandBody Weather(float cloudiness) {
  msg::WeatherParameters w;
  w.cloudiness(cloudiness);
  msg::CommandBody b;
  b.weather(w);
  return b;
}

msg::CommandBody TmDistance(double metres) {
  msg::TrafficManagerCommand t;
  t.parameter(msg::TrafficManagerParameter::TM_DISTANCE_TO_LEADING_VEHICLE);
  t.value(metres);
  msg::CommandBody b;
  b.traffic_manager(t);
  return b;
}

// Issue 7 §3: commands with bodies from a Fast DDS client and from the Cyclone participant
// (so the command union crosses vendors) go into one tick, in acceptance order, and every
// receiver sees the same frame, order and bodies: the coordinator's published ticks, the
// Cyclone participant (its tick lines and its state hash) and a Fast DDS noop service
// (its hash chain folds each command's client, sequence, kind and body digest).
TEST(CycloneParticipant, CommandsFromBothVendorsLandInTheSameFrameInTheSameOrder) {
  const int domain = TestDomain();
  const std::string config = WriteTempFile("cyclone_commands.yaml",
                                           "domain_id: " + std::to_string(domain) + "\n"
                                           "participant_profile: " + kProfile + "\n"
                                           "seed: 11\n"
                                           "world:\n"
                                           "  synchronous_mode: true\n"
                                           "  service_timeout: 5.0\n"
                                           "services:\n"
                                           "  - {name: alpha, kind: noop}\n"
                                           "  - {name: cyc, kind: cyclone_c}\n");
  auto bus = CreateDdsBus({domain, "", kProfile, "cyclone_commands_test"});
  Observer observer(*bus);
  std::mutex mu;
  std::map<uint64_t, msg::Tick> published;  // the coordinator's ticks of run 1, by frame
  std::optional<msg::WorldInfo> world;
  Reader<msg::Tick> tick_reader(*bus, topics::kTick, [&](const msg::Tick& t, const SampleInfo&) {
    std::lock_guard<std::mutex> lock(mu);
    if (t.run() == 1) published[t.frame()] = t;
  });
  Reader<msg::WorldInfo> world_reader(*bus, topics::kWorldInfo, [&](const msg::WorldInfo& w, const SampleInfo&) {
    std::lock_guard<std::mutex> lock(mu);
    if (w.run() == 1 && !world) world = w;
  });

  const std::string ledger = WriteTempFile("alpha.ledger", "");
  const std::string ticks_file = WriteTempFile("cyc_command_ticks.txt", "");
  Process coordinator({Bin("lockstep_coordinator"), config});
  Process alpha({Bin("lockstep_noop"), "--name", "alpha", "--config", config}, {{"LOCKSTEP_NOOP_LEDGER", ledger}});
  // Two commands due once frame 2 is stepped (so in tick 3: the test ticks only after
  // their replies), one sent when the test signals (SIGUSR1), in frame 5.
  Process cyc({Bin("lockstep_cyclone_participant"), "--name", "cyc", "--domain", std::to_string(domain), "--ticks-file",
               ticks_file, "--command", "3:weather=37.5", "--command", "3:tm_distance=12.25", "--command",
               "signal:weather=81.5"},
              {{"CYCLONEDDS_URI", "file://" + SourceDir() + "/client/cyclone_c/cyclone_loopback.xml"}});
  auto diagnostics = [&] {
    return "coordinator:\n" + coordinator.Output() + "\nalpha:\n" + alpha.Output() + "\ncyc:\n" + cyc.Output() +
           "\ncyc ticks:\n" + ReadFile(ticks_file) + "\nalpha ledger:\n" + ReadFile(ledger);
  };
  auto has_line = [&](const std::string& line) { return !Lines(ReadFile(ticks_file), line).empty(); };
  auto tick = [&](uint64_t frame) {
    msg::TickRequest r;
    r.count(1);
    msg::CommandBody b;
    b.tick_request(r);
    auto reply = observer.WaitReply(observer.Send(b), 10s);
    ASSERT_TRUE(reply && reply->accepted()) << diagnostics();
    ASSERT_EQ(reply->frame(), frame);
    ASSERT_TRUE(observer.WaitUntil([&] { return observer.last_frame() >= frame; }, 20s)) << diagnostics();
  };
  auto send = [&](msg::CommandBody body, uint64_t frame) {
    auto reply = observer.WaitReply(observer.Send(std::move(body)), 10s);
    ASSERT_TRUE(reply) << diagnostics();
    ASSERT_TRUE(reply->accepted()) << reply->reason();
    EXPECT_EQ(reply->frame(), frame);
  };

  ASSERT_TRUE(observer.WaitUntil(
      [&] {
        auto s = observer.status();
        return s && s->state() == msg::RunState::RUN_READY && Alive(*s, "alpha") && Alive(*s, "cyc");
      },
      30s))
      << diagnostics();
  tick(1);
  tick(2);
  // Frame 3: the participant's two commands, then two of ours.
  ASSERT_TRUE(observer.WaitUntil([&] { return has_line("reply 1 accepted=1 run=1 frame=3") && has_line("reply 2 accepted=1 run=1 frame=3"); }, 10s))
      << diagnostics();
  send(Weather(11.25f), 3);
  send(TmDistance(7.5), 3);
  tick(3);
  tick(4);
  // Frame 5 interleaves: ours, the participant's (on our signal), ours.
  send(TmDistance(3.0), 5);
  cyc.Signal(SIGUSR1);
  ASSERT_TRUE(observer.WaitUntil([&] { return has_line("reply 3 accepted=1 run=1 frame=5"); }, 10s)) << diagnostics();
  send(Weather(64.0f), 5);
  tick(5);
  tick(6);
  ASSERT_TRUE(observer.WaitUntil(
      [&] {
        std::lock_guard<std::mutex> lock(mu);
        return published.count(6) && world && CycloneTicks(ReadFile(ticks_file)).count(6) &&
               NoopHashes(ReadFile(ledger)).count(6);
      },
      10s))
      << diagnostics();

  std::map<uint64_t, msg::Tick> ticks;
  msg::WorldInfo info;
  {
    std::lock_guard<std::mutex> lock(mu);
    ticks = published;
    info = *world;
  }
  // The coordinator's ticks: frames 3 and 5 carry the commands in acceptance order, with
  // the bodies sent (the participant's set_weather crossed from Cyclone intact).
  ASSERT_EQ(ticks.size(), 6u) << diagnostics();
  const auto& f3 = ticks.at(3).commands();
  ASSERT_EQ(f3.size(), 4u) << Describe(f3);
  EXPECT_EQ(f3[0].client().to_string(), "cyc");
  EXPECT_EQ(f3[0].body()._d(), msg::CommandKind::CMD_SET_WEATHER);
  EXPECT_EQ(f3[0].body().weather().cloudiness(), 37.5f);
  EXPECT_EQ(f3[1].client().to_string(), "cyc");
  EXPECT_EQ(f3[1].body()._d(), msg::CommandKind::CMD_TRAFFIC_MANAGER);
  EXPECT_EQ(f3[1].body().traffic_manager().value(), 12.25);
  EXPECT_EQ(f3[2].client().to_string(), "test-client");
  EXPECT_EQ(f3[2].body().weather().cloudiness(), 11.25f);
  EXPECT_EQ(f3[3].body().traffic_manager().value(), 7.5);
  const auto& f5 = ticks.at(5).commands();
  ASSERT_EQ(f5.size(), 3u) << Describe(f5);
  EXPECT_EQ(f5[0].client().to_string(), "test-client");
  EXPECT_EQ(f5[0].body().traffic_manager().value(), 3.0);
  EXPECT_EQ(f5[1].client().to_string(), "cyc");
  EXPECT_EQ(f5[1].body().weather().cloudiness(), 81.5f);
  EXPECT_EQ(f5[2].client().to_string(), "test-client");
  EXPECT_EQ(f5[2].body().weather().cloudiness(), 64.0f);

  // Every receiver agrees, frame by frame: the participant printed the same list, and its
  // state hash, the noop's and NoopCore's over the published ticks are one hash chain.
  const auto cyclone = CycloneTicks(ReadFile(ticks_file));
  const auto noop = NoopHashes(ReadFile(ledger));
  NoopCore expected;
  expected.BeginRun(info);
  for (uint64_t k = 1; k <= 6; ++k) {
    const msg::Tick& t = ticks.at(k);
    EXPECT_EQ(t.commands().empty(), k != 3 && k != 5) << "frame " << k;
    expected.Step(t);
    ASSERT_TRUE(cyclone.count(k)) << "the participant did not step frame " << k << "\n" << diagnostics();
    ASSERT_TRUE(noop.count(k)) << "alpha did not step frame " << k << "\n" << diagnostics();
    EXPECT_EQ(cyclone.at(k).commands, Describe(t.commands())) << "frame " << k << ": the Cyclone participant saw another list";
    EXPECT_EQ(noop.at(k), expected.StateHash()) << "frame " << k << ": alpha's hash chain differs from the published ticks";
    EXPECT_EQ(cyclone.at(k).hash, expected.StateHash()) << "frame " << k << ": the Cyclone participant's hash chain differs";
  }
  coordinator.Signal(SIGINT);
  EXPECT_EQ(coordinator.Wait(10s), std::optional<int>(0)) << diagnostics();
  cyc.Signal(SIGTERM);
  EXPECT_EQ(cyc.Wait(10s), std::optional<int>(0)) << diagnostics();
}

}  // namespace
}  // namespace lockstep::testing
