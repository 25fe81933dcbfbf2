// Issue 21, item 6, the refusals themselves (fast, no DDS): the coordinator's command checks
// refuse values that would send a body out of the world or carry NaN into the physics, and
// its membership refuses acks and announcements that do not come from the member they name.
// tests/fault/hostile_test.cpp runs the same samples through a whole simulation.
#include <gtest/gtest.h>

#include <cmath>

#include "lockstep/coordinator/command_processor.h"
#include "lockstep/coordinator/membership.h"
#include "lockstep/runtime/blueprint_builder.h"
#include "lockstep/runtime/command_builders.h"
#include "stand_in_blueprints.h"

namespace lockstep {
namespace {

msg::Command Make(msg::CommandBody body) {
  msg::Command c;
  c.client("hostile");
  c.sequence_number(1);
  c.body(std::move(body));
  return c;
}

class HostileCommands : public ::testing::Test {
 protected:
  HostileCommands() {
    msg::BlueprintSet set;
    set.service("ground");
    set.blueprints(testing::StandInBlueprints());
    p.library().Declare(set);
    auto r = p.Submit(Make(SpawnBody("vehicle.lockstep.sedan", MakePose(0, 0, 0), {}, 0)), 1, 10, false, {});
    EXPECT_TRUE(r.accepted()) << r.reason();
    car = r.actor();
  }
  std::string Reason(msg::CommandBody b) {
    auto r = p.Submit(Make(std::move(b)), 1, 10, false, {});
    return r.accepted() ? std::string() : r.reason().to_string();
  }
  CommandProcessor p;
  uint32_t car = 0;
};

TEST_F(HostileCommands, PositionsFarOutOfTheWorldAreRefused) {
  msg::SetTransform t;
  t.actor(car);
  t.transform(MakePose(1e300, 0, 0));
  msg::CommandBody b;
  b.set_transform(t);
  EXPECT_NE(Reason(b).find("more than 1e+06 m from the map's origin"), std::string::npos) << Reason(b);
  t.transform(MakePose(999999, -999999, 10));  // far, but in range: accepted
  b.set_transform(t);
  EXPECT_EQ(Reason(b), "");
  EXPECT_NE(Reason(SpawnBody("vehicle.lockstep.sedan", MakePose(0, -3e9, 0.5), {}, 0)).find("spawn transform position"),
            std::string::npos);
}

TEST_F(HostileCommands, PhysicsValuesBeyondAnyTownAreRefused) {
  msg::ActorPhysicsCommand a;
  a.actor(car);
  a.kind(msg::ActorPhysicsKind::PHYSICS_SET_TARGET_VELOCITY);
  a.value().x(1e300);
  msg::CommandBody b;
  b.actor_physics(a);
  EXPECT_NE(Reason(b).find("target velocity"), std::string::npos);
  a.value().x(30);
  b.actor_physics(a);
  EXPECT_EQ(Reason(b), "");
  a.kind(msg::ActorPhysicsKind::PHYSICS_ADD_IMPULSE);
  a.value().x(-1e200);
  b.actor_physics(a);
  EXPECT_NE(Reason(b).find("impulse"), std::string::npos);
}

TEST_F(HostileCommands, VehiclePhysicsWithANanAnywhereIsRefused) {
  msg::VehiclePhysicsCommand v;
  v.actor(car);
  v.physics().mass(1500);
  msg::CurvePoint c;
  c.x(1000);
  c.y(300);
  v.physics().torque_curve({c, c});
  msg::CommandBody b;
  b.vehicle_physics(v);
  EXPECT_EQ(Reason(b), "");
  v.physics().torque_curve()[1].y(std::nan(""));
  b.vehicle_physics(v);
  EXPECT_NE(Reason(b).find("torque curve"), std::string::npos);
  v.physics().torque_curve()[1].y(300);
  v.physics().center_of_mass().z(std::nan(""));
  b.vehicle_physics(v);
  EXPECT_NE(Reason(b).find("center_of_mass"), std::string::npos);
  v.physics().center_of_mass().z(0);
  v.physics().wheel_radius(-INFINITY);
  b.vehicle_physics(v);
  EXPECT_NE(Reason(b).find("NaN or infinite"), std::string::npos);
}

msg::ServiceAnnounce Announce(const std::string& name, int32_t pid, msg::ServiceState state = msg::ServiceState::SERVICE_READY) {
  msg::ServiceAnnounce a;
  a.service(name);
  a.kind("noop");
  a.state(state);
  a.pid(pid);
  a.host("host");
  return a;
}

msg::Ack MakeAck(const std::string& name, uint32_t run, uint64_t frame, uint64_t hash, const std::string& divergence = "") {
  msg::Ack a;
  a.service(name);
  a.run(run);
  a.frame(frame);
  a.state_hash(hash);
  a.divergence(divergence);
  return a;
}

TEST(HostileMembership, ADuplicateNameCannotFailOrReplaceALiveMember) {
  Membership m({"alpha"}, std::chrono::milliseconds(600));
  m.SetProcessProbe([](const std::string&, int32_t pid) { return pid == 100 ? ProcessState::kRunning : ProcessState::kGone; },
                    std::chrono::seconds(3));
  const auto now = Membership::Clock::now();
  m.OnAnnounce(Announce("alpha", 100), now);
  ASSERT_TRUE(m.Find("alpha")->alive);
  // Another process announces the name, ready, then stopping with a failure: ignored.
  EXPECT_FALSE(m.OnAnnounce(Announce("alpha", 200), now));
  EXPECT_FALSE(m.OnAnnounce(Announce("alpha", 200, msg::ServiceState::SERVICE_STOPPING), now));
  EXPECT_TRUE(m.Find("alpha")->alive);
  EXPECT_EQ(m.Find("alpha")->pid, 100);
  EXPECT_TRUE(m.Find("alpha")->failure.empty());
  // A replacement is taken once the member's process is gone (pid 100 exits).
  Membership m2({"alpha"}, std::chrono::milliseconds(600));
  m2.SetProcessProbe([](const std::string&, int32_t) { return ProcessState::kGone; }, std::chrono::seconds(3));
  m2.OnAnnounce(Announce("alpha", 100), now);
  m2.OnAnnounce(Announce("alpha", 300), now);
  EXPECT_EQ(m2.Find("alpha")->pid, 300);
}

TEST(HostileMembership, ForeignAcksChangeNothing) {
  Membership m({"alpha"}, std::chrono::milliseconds(600));
  const auto now = Membership::Clock::now();
  m.OnAnnounce(Announce("alpha", 100), now);
  ASSERT_TRUE(m.OnAck("alpha", 1, MakeAck("alpha", 1, 10, 0xabc), 10) || m.Find("alpha")->last_frame == 10);
  // An ack of a service nobody announced makes no member.
  m.OnAck("intruder", 1, MakeAck("intruder", 1, 11, 1), 10);
  EXPECT_EQ(m.Find("intruder"), nullptr);
  // A frame no tick was sent for moves nothing (last_frame, replay_from).
  msg::Ack future = MakeAck("alpha", 1, 1000000, 7);
  future.replay_from(1000000);
  m.OnAck("alpha", 1, future, 10);
  EXPECT_EQ(m.Find("alpha")->last_frame, 10u);
  EXPECT_EQ(m.Find("alpha")->replay_from, 0u);
  // A divergence reported for a past frame does not mark the member diverged.
  m.OnAck("alpha", 1, MakeAck("alpha", 1, 7, 0xbad, "hostile"), 10);
  EXPECT_TRUE(m.Find("alpha")->divergence.empty());
  EXPECT_EQ(m.Find("alpha")->last_hash, 0xabcu);
}

}  // namespace
}  // namespace lockstep
