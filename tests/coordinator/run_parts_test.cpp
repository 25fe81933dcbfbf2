// The coordinator's run parts as plain logic (coordinator/src): the actor roster it
// publishes on lockstep/actors, the launch config's scenario and the run status.
#include <gtest/gtest.h>

#include <chrono>
#include <deque>

#include "actor_roster.h"
#include "lockstep/runtime/command_builders.h"
#include "run_status.h"
#include "scenario.h"

namespace lockstep {
namespace {

msg::Command Spawn(uint32_t actor, uint32_t parent = 0) {
  msg::CommandBody b = SpawnBody("vehicle.lockstep.sedan", MakePose(1, 2, 0), {}, parent);
  b.spawn_actor().actor(actor);
  msg::Command c;
  c.body(b);
  return c;
}

msg::Command Destroy(uint32_t actor) {
  msg::DestroyActor d;
  d.actor(actor);
  msg::Command c;
  c.body().destroy_actor(d);
  return c;
}

msg::Tick TickOf(uint32_t run, uint64_t frame, std::vector<msg::Command> commands = {}) {
  msg::Tick t;
  t.run(run);
  t.frame(frame);
  t.commands(std::move(commands));
  return t;
}

std::vector<uint32_t> Ids(const msg::ActorList& l) {
  std::vector<uint32_t> out;
  for (const auto& a : l.actors()) out.push_back(a.spawn().actor());
  return out;
}

TEST(ActorRoster, ASpawnAddsADestroyRemovesOnlyThatActorAndANewRunStartsEmpty) {
  ActorRoster roster;
  auto first = roster.Apply(TickOf(1, 1));
  ASSERT_TRUE(first) << "the first tick publishes the (empty) roster";
  EXPECT_TRUE(first->actors().empty());
  auto spawned = roster.Apply(TickOf(1, 2, {Spawn(10), Spawn(11, 10)}));
  ASSERT_TRUE(spawned);
  EXPECT_EQ(Ids(*spawned), (std::vector<uint32_t>{10, 11}));
  EXPECT_EQ(spawned->frame(), 2u);
  EXPECT_EQ(spawned->actors()[1].frame(), 2u);
  EXPECT_FALSE(roster.Apply(TickOf(1, 3))) << "a tick without spawns or destroys changes nothing";
  // CARLA: destroying the parent leaves what was attached to it, detached where it was.
  auto destroyed = roster.Apply(TickOf(1, 4, {Destroy(10)}));
  ASSERT_TRUE(destroyed);
  EXPECT_EQ(Ids(*destroyed), std::vector<uint32_t>{11});
  EXPECT_EQ(destroyed->actors()[0].spawn().parent(), 10u);
  auto next_run = roster.Apply(TickOf(2, 1));
  ASSERT_TRUE(next_run);
  EXPECT_EQ(next_run->run(), 2u);
  EXPECT_TRUE(next_run->actors().empty());
}

TEST(Scenario, AliasesNameTheSpawnedActorsAndARestartBeginsAgain) {
  std::vector<ScheduledCommand> steps(4);
  steps[0].frame = 1;
  steps[0].alias = "car";
  steps[0].command = Spawn(0);
  steps[1].frame = 2;
  steps[1].actor_alias = "car";
  steps[1].command.body(AutopilotBody(0, true));
  steps[2].frame = 2;
  steps[2].actor_alias = "nobody";  // no spawn has this alias: left out
  steps[2].command.body(AutopilotBody(0, true));
  steps[3].frame = 4;
  steps[3].actor_alias = "car";  // a camera on the car
  steps[3].command = Spawn(0);
  Scenario scenario(steps);
  std::vector<msg::Command> submitted;
  uint32_t next_id = 42;
  auto submit = [&](const msg::Command& c) {
    submitted.push_back(c);
    msg::CommandReply r;
    r.accepted(true);
    if (c.body()._d() == msg::CommandKind::CMD_SPAWN_ACTOR) r.actor(next_id++);
    return r;
  };
  EXPECT_TRUE(scenario.Due(1));
  scenario.Submit(1, submit);
  ASSERT_EQ(submitted.size(), 1u);
  EXPECT_FALSE(scenario.Due(1));
  EXPECT_TRUE(scenario.Due(2));
  scenario.Submit(2, submit);
  ASSERT_EQ(submitted.size(), 2u);
  EXPECT_EQ(submitted[1].body().traffic_manager().actor(), 42u);
  EXPECT_FALSE(scenario.Due(3));
  scenario.Submit(4, submit);
  ASSERT_EQ(submitted.size(), 3u);
  EXPECT_EQ(submitted[2].body().spawn_actor().parent(), 42u);
  // A new run: the steps again from frame 1, the aliases of the last run forgotten.
  scenario.Restart();
  EXPECT_TRUE(scenario.Due(1));
  submitted.clear();
  scenario.Submit(2, submit);  // frame 1 is past (a reset at frame 2): skipped, so 'car' names nothing
  EXPECT_TRUE(submitted.empty());
}

TEST(RunStatus, TheTickRateCountsTheLastSecondAndTheStatusListsEveryMember) {
  using Clock = std::chrono::steady_clock;
  const Clock::time_point now = Clock::now();
  std::deque<Clock::time_point> done{now - std::chrono::milliseconds(1500), now - std::chrono::milliseconds(900),
                                     now - std::chrono::milliseconds(400), now};
  EXPECT_NEAR(TickRate(&done, now), 2 / 0.9, 1e-9) << "2 intervals over the 0.9 s of the last second";
  EXPECT_EQ(done.size(), 3u) << "the completion older than a second is dropped";
  std::deque<Clock::time_point> one{now};
  EXPECT_EQ(TickRate(&one, now), 0.0);

  Membership members({"ground_sim", "air_sim"}, std::chrono::milliseconds(600));
  RunFacts f;
  f.run = 3;
  f.state = msg::RunState::RUN_FAULTED;
  f.frame = 40;
  f.sim_time = 2.0;
  f.tick_rate_hz = 20;
  f.fixed_delta_seconds = 0.05;
  f.failed_service = "air_sim";
  f.reason = std::string(600, 'x');
  const msg::RunStatus s = MakeRunStatus(f, members);
  EXPECT_EQ(s.run(), 3u);
  EXPECT_EQ(s.state(), msg::RunState::RUN_FAULTED);
  EXPECT_EQ(s.frame(), 40u);
  EXPECT_DOUBLE_EQ(s.real_time_factor(), 1.0);
  EXPECT_EQ(s.failed_service().to_string(), "air_sim");
  EXPECT_EQ(s.reason().to_string().size(), 511u) << "cut to the wire's bound";
  ASSERT_EQ(s.members().size(), 2u);
  EXPECT_EQ(s.members()[0].service().to_string(), "air_sim");  // by name
  EXPECT_TRUE(s.members()[0].required());
  EXPECT_FALSE(s.members()[0].alive());
}

}  // namespace
}  // namespace lockstep
