#include "lockstep/coordinator/membership.h"

#include <gtest/gtest.h>

#include <map>
#include <optional>

namespace lockstep {
namespace {

using namespace std::chrono_literals;
using Clock = Membership::Clock;

msg::ServiceAnnounce Announce(const std::string& name, msg::ServiceState state, int32_t pid) {
  msg::ServiceAnnounce a;
  a.service(name);
  a.kind("noop");
  a.state(state);
  a.pid(pid);
  return a;
}

msg::Ack AckOf(uint32_t run, uint64_t frame, uint64_t hash = 0) {
  msg::Ack a;
  a.run(run);
  a.frame(frame);
  a.state_hash(hash);
  return a;
}

TEST(Membership, RequiredServicesMustJoinAndAnnounceReady) {
  Membership m({"air", "ground"}, 600ms);
  const auto t0 = Clock::now();
  std::string who;
  EXPECT_EQ(m.FirstMissing(&who), "has not announced ready");
  EXPECT_EQ(who, "air");
  EXPECT_TRUE(m.OnAnnounce(Announce("air", msg::ServiceState::SERVICE_STARTING, 10), t0));
  EXPECT_FALSE(m.FirstMissing(&who).empty());
  EXPECT_TRUE(m.OnAnnounce(Announce("air", msg::ServiceState::SERVICE_READY, 10), t0));
  EXPECT_TRUE(m.OnAnnounce(Announce("ground", msg::ServiceState::SERVICE_READY, 11), t0));
  EXPECT_EQ(m.FirstMissing(&who), "");
  EXPECT_FALSE(m.OnAnnounce(Announce("air", msg::ServiceState::SERVICE_READY, 10), t0 + 100ms)) << "a heartbeat changes nothing";
}

TEST(Membership, SilenceLongerThanTheTimeoutIsAFailure) {
  Membership m({"air"}, 600ms);
  const auto t0 = Clock::now();
  m.OnAnnounce(Announce("air", msg::ServiceState::SERVICE_READY, 10), t0);
  EXPECT_FALSE(m.CheckHeartbeats(t0 + 600ms)) << "exactly the timeout is still alive";
  EXPECT_TRUE(m.CheckHeartbeats(t0 + 601ms));
  std::string who;
  const std::string why = m.FirstMissing(&who);
  EXPECT_EQ(who, "air");
  EXPECT_NE(why.find("sent no heartbeat for 601 ms"), std::string::npos) << why;
  EXPECT_NE(why.find("pid 10"), std::string::npos) << why;
  // A replacement joins.
  EXPECT_TRUE(m.OnAnnounce(Announce("air", msg::ServiceState::SERVICE_READY, 20), t0 + 2s));
  EXPECT_EQ(m.FirstMissing(&who), "");
}

// Checks every 100 ms, as the coordinator's loop does, from `from` to `to`; returns the
// first time a member was found dead (or nullopt).
std::optional<Clock::duration> FirstDeath(Membership& m, Clock::time_point t0, Clock::duration from, Clock::duration to) {
  for (auto t = from; t <= to; t += 100ms) {
    if (m.CheckHeartbeats(t0 + t)) return t;
  }
  return std::nullopt;
}

TEST(Membership, AGoneProcessIsDeadAtOnceARunningOneOnlyAfterTheHangTimeout) {
  std::map<int32_t, ProcessState> processes{{10, ProcessState::kGone}, {11, ProcessState::kRunning}};
  HeartbeatTimeouts timeouts;
  timeouts.silence = 600ms;
  timeouts.hang = 3s;
  timeouts.missed = 150ms;
  Membership m({"a", "b", "c"}, timeouts, [&](const std::string& host, int32_t pid) {
    return host == "here" && processes.count(pid) ? processes[pid] : ProcessState::kUnknown;
  });
  const auto t0 = Clock::now();
  auto announce = [&](const std::string& name, int32_t pid, const std::string& host) {
    auto a = Announce(name, msg::ServiceState::SERVICE_READY, pid);
    a.host(host);
    m.OnAnnounce(a, t0);
  };
  announce("a", 10, "here");
  announce("b", 11, "here");
  announce("c", 12, "there");
  std::string who;
  EXPECT_EQ(FirstDeath(m, t0, 0ms, 5s), std::optional<Clock::duration>(200ms)) << "killed: dead once a heartbeat is missed";
  EXPECT_EQ(m.FirstMissing(&who), "process 10 is gone (crashed or killed; silent for 200 ms)");
  EXPECT_EQ(FirstDeath(m, t0, 300ms, 5s), std::optional<Clock::duration>(700ms)) << "another host: heartbeats only";
  EXPECT_NE(m.Find("c")->failure.find("sent no heartbeat for 700 ms (crashed, hung or stopped; pid 12)"), std::string::npos)
      << m.Find("c")->failure;
  EXPECT_EQ(FirstDeath(m, t0, 800ms, 5s), std::optional<Clock::duration>(3100ms)) << "running but silent: hung after 3 s";
  EXPECT_NE(m.Find("b")->failure.find("sent no heartbeat for 3100 ms while its process runs (hung or stopped; pid 11)"),
            std::string::npos)
      << m.Find("b")->failure;
}

// `lockstep up` kills a member reported failed whose pid still runs: a replacement that
// is still starting must not inherit its predecessor's failure.
TEST(Membership, AReplacementProcessDoesNotInheritTheFailureOfTheOneItReplaces) {
  Membership m({"air"}, 600ms);
  const auto t0 = Clock::now();
  m.OnAnnounce(Announce("air", msg::ServiceState::SERVICE_READY, 10), t0);
  m.MarkStalled("air", 5);
  EXPECT_EQ(m.Find("air")->failure, "timed out on frame 5");
  m.OnAnnounce(Announce("air", msg::ServiceState::SERVICE_STARTING, 11), t0 + 1s);
  EXPECT_FALSE(m.Find("air")->alive);
  EXPECT_EQ(m.Find("air")->failure, "");
  std::string who;
  EXPECT_EQ(m.FirstMissing(&who), "has not announced ready");
  m.OnAnnounce(Announce("air", msg::ServiceState::SERVICE_READY, 11), t0 + 1100ms);
  EXPECT_EQ(m.FirstMissing(&who), "") << "no stall of its predecessor holds it back";
}

TEST(Membership, TimeTheCoordinatorItselfDidNotRunIsNotSilence) {
  Membership m({"air"}, 600ms);
  const auto t0 = Clock::now();
  m.OnAnnounce(Announce("air", msg::ServiceState::SERVICE_READY, 10), t0);
  EXPECT_FALSE(m.CheckHeartbeats(t0 + 100ms));
  // The coordinator was stopped or starved for a second: the heartbeats of that second
  // are still queued behind it, so 900 ms of it count as heard from.
  EXPECT_FALSE(m.CheckHeartbeats(t0 + 1100ms));
  EXPECT_EQ(FirstDeath(m, t0, 1200ms, 3s), std::optional<Clock::duration>(1600ms)) << "then 600 ms of real silence";
}

TEST(Membership, AStalledServiceNeedsToFinishTheFrameNotJustHeartbeat) {
  Membership m({"render"}, 600ms);
  const auto t0 = Clock::now();
  m.OnAnnounce(Announce("render", msg::ServiceState::SERVICE_READY, 7), t0);
  m.MarkStalled("render", 42);
  std::string who;
  EXPECT_EQ(m.FirstMissing(&who), "timed out on frame 42");
  m.OnAnnounce(Announce("render", msg::ServiceState::SERVICE_READY, 7), t0 + 100ms);
  EXPECT_FALSE(m.FirstMissing(&who).empty()) << "heartbeats alone do not revive it";
  EXPECT_FALSE(m.OnAck("render", 1, AckOf(1, 41)));
  EXPECT_FALSE(m.FirstMissing(&who).empty()) << "an older frame does not either";
  EXPECT_TRUE(m.OnAck("render", 1, AckOf(1, 42)));
  EXPECT_EQ(m.FirstMissing(&who), "");
}

TEST(Membership, AReplacementProcessClearsAStall) {
  Membership m({"render"}, 600ms);
  const auto t0 = Clock::now();
  m.OnAnnounce(Announce("render", msg::ServiceState::SERVICE_READY, 7), t0);
  m.MarkStalled("render", 42);
  m.OnAnnounce(Announce("render", msg::ServiceState::SERVICE_READY, 8), t0 + 1s);
  std::string who;
  EXPECT_EQ(m.FirstMissing(&who), "");
}

TEST(Membership, AcksOfTheCurrentRunTrackTheLastFrameAndHash) {
  Membership m({"air"}, 600ms);
  m.OnAck("air", 2, AckOf(2, 5, 0xabc));
  m.OnAck("air", 2, AckOf(1, 900, 0xdead));  // an older run
  m.OnAck("air", 2, AckOf(2, 4, 0x111));     // a re-ack of an older frame
  ASSERT_NE(m.Find("air"), nullptr);
  EXPECT_EQ(m.Find("air")->last_frame, 5u);
  EXPECT_EQ(m.Find("air")->last_hash, 0xabcu);
}

TEST(Membership, AnAnnouncedShutdownIsAFailureWithItsReason) {
  Membership m({"air"}, 600ms);
  const auto t0 = Clock::now();
  m.OnAnnounce(Announce("air", msg::ServiceState::SERVICE_READY, 10), t0);
  EXPECT_TRUE(m.OnAnnounce(Announce("air", msg::ServiceState::SERVICE_STOPPING, 10), t0));
  std::string who;
  EXPECT_EQ(m.FirstMissing(&who), "stopped (announced shutdown)");
}

TEST(Membership, AServiceIsAliveOnlyOnceItsDeclarationsArrived) {
  Membership m({"air"}, 600ms);
  const auto t0 = Clock::now();
  auto ready = Announce("air", msg::ServiceState::SERVICE_READY, 10);
  ready.blueprints(3);
  m.OnAnnounce(ready, t0);
  std::string who;
  EXPECT_FALSE(m.FirstMissing(&who).empty()) << "ready, but the library does not hold its blueprints yet";
  EXPECT_TRUE(m.OnBlueprints("air", 3));
  EXPECT_EQ(m.FirstMissing(&who), "");
  // It dies; the set of the dead process must not make it alive again.
  EXPECT_TRUE(m.CheckHeartbeats(t0 + 700ms));
  EXPECT_FALSE(m.OnBlueprints("air", 3));
  EXPECT_FALSE(m.FirstMissing(&who).empty());
  // The replacement announces ready again with its set already here.
  ready.pid(11);
  EXPECT_TRUE(m.OnAnnounce(ready, t0 + 800ms));
  EXPECT_EQ(m.FirstMissing(&who), "");
}

// Issue 7, 2.2: last_frame used to survive a reset, so status and the replay check used
// the previous run's values.
TEST(Membership, ANewRunStartsEveryMembersFramesAgain) {
  Membership m({"air"}, 600ms);
  m.OnAnnounce(Announce("air", msg::ServiceState::SERVICE_READY, 10), Clock::now());
  m.OnAck("air", 1, AckOf(1, 100, 0xabc));
  EXPECT_EQ(m.Find("air")->last_frame, 100u);
  m.NewRun(2);
  EXPECT_EQ(m.Find("air")->last_frame, 0u);
  EXPECT_EQ(m.Find("air")->last_hash, 0u);
  m.OnAck("air", 2, AckOf(2, 5, 0xdef));
  EXPECT_EQ(m.Find("air")->last_frame, 5u);
  EXPECT_EQ(m.Find("air")->last_hash, 0xdefu);
  m.OnAck("air", 2, AckOf(1, 101, 0x111));
  EXPECT_EQ(m.Find("air")->last_frame, 5u) << "a late ack of the old run changes nothing";
  // Without NewRun (another coordinator path), the first ack of a run still starts afresh.
  m.OnAck("air", 3, AckOf(3, 1, 0x222));
  EXPECT_EQ(m.Find("air")->last_frame, 1u);
}

}  // namespace
}  // namespace lockstep
