#include "lockstep/coordinator/membership.h"

#include <gtest/gtest.h>
#include <map>
#include <optional>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

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

// On a loaded machine a live service's heartbeat thread can starve: a process the OS
// shows running gets the longer lease; a stopped or vanished one fails at the timeout.
TEST(Membership, ARunningProcessGetsTheStarvedLeaseAStoppedOrGoneOneDoesNot) {
  for (const auto state : {ProcessState::kRunning, ProcessState::kStopped, ProcessState::kGone, ProcessState::kUnknown}) {
    Membership m({"air"}, 600ms);
    int32_t probed = 0;
    m.SetProcessProbe(
        [&](const std::string&, int32_t pid) {
          probed = pid;
          return state;
        },
        5s);
    const auto t0 = Clock::now();
    m.OnAnnounce(Announce("air", msg::ServiceState::SERVICE_READY, 10), t0);
    const bool failed_early = m.CheckHeartbeats(t0 + 601ms);
    EXPECT_EQ(probed, 10);
    EXPECT_EQ(failed_early, state != ProcessState::kRunning) << static_cast<int>(state);
    if (state == ProcessState::kRunning) {
      // Checked every 100 ms, as the coordinator does (a longer gap is its own absence).
      for (auto t = 700ms; t <= 5000ms; t += 100ms) EXPECT_FALSE(m.CheckHeartbeats(t0 + t)) << "the starved lease holds";
      EXPECT_TRUE(m.CheckHeartbeats(t0 + 5001ms));
      std::string who;
      EXPECT_NE(m.FirstMissing(&who).find("runs but is hung"), std::string::npos);
    }
  }
}

TEST(Membership, TheLocalProbeReadsProcStateAndIgnoresOtherHosts) {
  char host[256] = {};
  gethostname(host, sizeof host - 1);
  EXPECT_EQ(ProbeLocalProcess(host, getpid()), ProcessState::kRunning);
  EXPECT_EQ(ProbeLocalProcess("another-host-" + std::string(host), getpid()), ProcessState::kUnknown);
  const pid_t child = fork();
  ASSERT_GE(child, 0);
  if (child == 0) {
    pause();
    _exit(0);
  }
  kill(child, SIGSTOP);
  int st = 0;
  ASSERT_EQ(waitpid(child, &st, WUNTRACED), child);
  EXPECT_EQ(ProbeLocalProcess(host, child), ProcessState::kStopped);
  kill(child, SIGKILL);
  // Unreaped, it is a zombie: gone.
  siginfo_t info{};
  ASSERT_EQ(waitid(P_PID, static_cast<id_t>(child), &info, WEXITED | WNOWAIT), 0);
  EXPECT_EQ(ProbeLocalProcess(host, child), ProcessState::kGone);
  waitpid(child, &st, 0);
  EXPECT_EQ(ProbeLocalProcess(host, child), ProcessState::kGone);
}

// Checks every 100 ms, as the coordinator's loop does, from `from` to `to`; returns the
// first time a member was found dead (or nullopt).
std::optional<Clock::duration> FirstDeath(Membership& m, Clock::time_point t0, Clock::duration from, Clock::duration to) {
  for (auto t = from; t <= to; t += 100ms) {
    if (m.CheckHeartbeats(t0 + t)) return t;
  }
  return std::nullopt;
}

TEST(Membership, AGoneProcessFailsOnceItMissedAHeartbeat) {
  std::map<int32_t, ProcessState> processes{{10, ProcessState::kGone}, {11, ProcessState::kStopped}, {12, ProcessState::kRunning}};
  Membership m({"a", "b", "c", "d"}, 600ms);
  m.SetProcessProbe([&](const std::string&, int32_t pid) { return processes.count(pid) ? processes[pid] : ProcessState::kUnknown; },
                    5s);
  const auto t0 = Clock::now();
  m.OnAnnounce(Announce("a", msg::ServiceState::SERVICE_READY, 10), t0);
  m.OnAnnounce(Announce("b", msg::ServiceState::SERVICE_READY, 11), t0);
  m.OnAnnounce(Announce("c", msg::ServiceState::SERVICE_READY, 12), t0);
  m.OnAnnounce(Announce("d", msg::ServiceState::SERVICE_READY, 13), t0);
  EXPECT_EQ(FirstDeath(m, t0, 0ms, 9s), std::optional<Clock::duration>(200ms)) << "killed: dead at the first check after 150 ms";
  EXPECT_EQ(m.Find("a")->failure, "sent no heartbeat for 200 ms (its process is gone; pid 10)");
  EXPECT_TRUE(m.Find("b")->alive && m.Find("c")->alive && m.Find("d")->alive);
  EXPECT_EQ(FirstDeath(m, t0, 300ms, 9s), std::optional<Clock::duration>(700ms)) << "stopped and unknown: the timeout";
  EXPECT_FALSE(m.Find("b")->alive);
  EXPECT_FALSE(m.Find("d")->alive);
  EXPECT_EQ(FirstDeath(m, t0, 800ms, 9s), std::optional<Clock::duration>(5100ms)) << "running: the starved lease";
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

// Issue 7, 2.3: a frame acked again with another state (a replacement that did not rebuild
// what the failed process had) is a divergence, reported once; a re-ack with the same state
// is not.
TEST(Membership, AFrameAckedAgainWithAnotherStateIsADivergence) {
  Membership m({"air"}, 600ms);
  m.OnAnnounce(Announce("air", msg::ServiceState::SERVICE_READY, 10), Clock::now());
  m.OnAck("air", 1, AckOf(1, 7, 0xaaa));
  EXPECT_FALSE(m.OnAck("air", 1, AckOf(1, 7, 0xaaa))) << "the same state again";
  EXPECT_TRUE(m.Find("air")->divergence.empty());
  EXPECT_TRUE(m.OnAck("air", 1, AckOf(1, 7, 0xbbb)));
  EXPECT_NE(m.Find("air")->divergence.find("frame 7 acknowledged with state hash 0000000000000bbb after 0000000000000aaa"),
            std::string::npos)
      << m.Find("air")->divergence;
  EXPECT_FALSE(m.OnAck("air", 1, AckOf(1, 8, 0xccc))) << "reported once";
  m.NewRun(2);
  m.OnAck("air", 2, AckOf(2, 7, 0xddd));
  EXPECT_TRUE(m.Find("air")->divergence.empty()) << "a new run starts clean";
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
  // replay_from follows the newest ack: the coordinator trims its tick log by it.
  auto ack = AckOf(2, 6, 0xdef);
  ack.replay_from(6);
  m.OnAck("air", 2, ack);
  EXPECT_EQ(m.Find("air")->replay_from, 6u);
  ack = AckOf(2, 3, 0x1);
  ack.replay_from(3);
  m.OnAck("air", 2, ack);
  EXPECT_EQ(m.Find("air")->replay_from, 6u) << "a re-ack of an older frame leaves it";
}

// A re-sent tick is acked again; an ack without a hash (0 = none) must not erase the hash
// acknowledged for that frame: the tick log hands it to a replacement to check its replay.
TEST(Membership, AReAckWithoutAHashKeepsTheAcknowledgedHash) {
  Membership m({"air"}, 600ms);
  m.OnAck("air", 1, AckOf(1, 7, 0xabc));
  m.OnAck("air", 1, AckOf(1, 7, 0));
  EXPECT_EQ(m.Find("air")->last_frame, 7u);
  EXPECT_EQ(m.Find("air")->last_hash, 0xabcu);
  EXPECT_TRUE(m.Find("air")->divergence.empty());
  // A newer frame without a hash: the service keeps none for it.
  m.OnAck("air", 1, AckOf(1, 8, 0));
  EXPECT_EQ(m.Find("air")->last_frame, 8u);
  EXPECT_EQ(m.Find("air")->last_hash, 0u);
}

// Ready-state handling: only a READY announcement makes a member alive, and only one whose
// declarations are here; STARTING and STOPPING never do, and a member declared dead needs a
// new READY announcement before its declarations can revive it.
TEST(Membership, OnlyAReadyAnnouncementWithItsDeclarationsMakesAMemberAlive) {
  Membership m({"air"}, 600ms);
  const auto t0 = Clock::now();
  std::string who;
  auto starting = Announce("air", msg::ServiceState::SERVICE_STARTING, 10);
  starting.blueprints(2);
  m.OnAnnounce(starting, t0);
  EXPECT_FALSE(m.OnBlueprints("air", 2)) << "its set arrived while it was still starting";
  EXPECT_FALSE(m.Find("air")->alive);
  EXPECT_EQ(m.FirstMissing(&who), "has not announced ready");
  auto ready = Announce("air", msg::ServiceState::SERVICE_READY, 10);
  ready.blueprints(2);
  EXPECT_TRUE(m.OnAnnounce(ready, t0 + 100ms)) << "READY with its set already here";
  EXPECT_TRUE(m.Find("air")->alive);
  EXPECT_TRUE(m.Find("air")->ready_announced);
  // Back to STARTING (a re-join): not alive, and its set arriving again does not revive it.
  EXPECT_TRUE(m.OnAnnounce(starting, t0 + 200ms));
  EXPECT_FALSE(m.Find("air")->alive);
  EXPECT_FALSE(m.Find("air")->ready_announced);
  EXPECT_FALSE(m.OnBlueprints("air", 2));
  EXPECT_FALSE(m.Find("air")->alive);
  // READY again, then silence: dead, and no longer counted as having announced READY.
  EXPECT_TRUE(m.OnAnnounce(ready, t0 + 300ms));
  EXPECT_TRUE(m.CheckHeartbeats(t0 + 1s));
  EXPECT_FALSE(m.Find("air")->ready_announced);
  EXPECT_FALSE(m.OnBlueprints("air", 2));
  // READY without its set: alive only once the set is here, and a set of another size is not it.
  Membership n({"air"}, 600ms);
  n.OnAnnounce(ready, t0);
  EXPECT_FALSE(n.Find("air")->alive);
  EXPECT_FALSE(n.OnBlueprints("air", 1));
  EXPECT_FALSE(n.Find("air")->alive);
  EXPECT_TRUE(n.OnBlueprints("air", 2));
  EXPECT_TRUE(n.Find("air")->alive);
  EXPECT_EQ(n.FirstMissing(&who), "");
  // Alive, it announces a larger set than the one here: not alive until that set arrives.
  auto more = ready;
  more.blueprints(3);
  EXPECT_TRUE(n.OnAnnounce(more, t0 + 100ms));
  EXPECT_FALSE(n.Find("air")->alive);
  EXPECT_TRUE(n.OnBlueprints("air", 3));
  EXPECT_TRUE(n.Find("air")->alive);
}

TEST(Membership, AStallOfAnUnknownServiceIsIgnored) {
  Membership m({"air"}, 600ms);
  m.MarkStalled("ghost", 5);
  EXPECT_EQ(m.Find("ghost"), nullptr);
  EXPECT_EQ(m.members().size(), 1u);
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
