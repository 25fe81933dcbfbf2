#include "lockstep/coordinator/command_processor.h"
#include "lockstep/runtime/blueprint_builder.h"
#include "lockstep/runtime/command_builders.h"
#include "stand_in_blueprints.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <map>

namespace lockstep {
namespace {

msg::Command Make(msg::CommandBody body, uint64_t seq = 1) {
  msg::Command c;
  c.client("test");
  c.sequence_number(seq);
  c.body(std::move(body));
  return c;
}

msg::Command Spawn(const std::string& blueprint, const AttributeList& attrs = {}, uint32_t parent = 0) {
  return Make(SpawnBody(blueprint, MakePose(0, 0, 0), attrs, parent));
}

msg::Command Control(uint32_t actor, float throttle, float steer) {
  msg::VehicleControl v;
  v.actor(actor);
  v.throttle(throttle);
  v.steer(steer);
  msg::CommandBody b;
  b.vehicle_control(v);
  return Make(b);
}

msg::BlueprintSet Declare(const std::string& service, std::vector<msg::BlueprintDeclaration> blueprints) {
  msg::BlueprintSet set;
  set.service(service);
  set.blueprints(std::move(blueprints));
  return set;
}

class CommandProcessorTest : public ::testing::Test {
 protected:
  CommandProcessorTest() {
    p.library().Declare(Declare("ground", testing::StandInBlueprints()));
    p.library().Declare(Declare("air", {blueprint::Make("drone.generic_quad", msg::ACTOR_DRONE, {blueprint::String("role_name", "")})}));
  }
  CommandProcessor p;
  msg::CommandReply Submit(const msg::Command& c, bool sync = false, const OwnerCheck& check = {}) {
    return p.Submit(c, 1, 10, sync, check);
  }
};

TEST_F(CommandProcessorTest, SpawnAssignsIncreasingActorIds) {
  auto a = Submit(Spawn("vehicle.lockstep.sedan"));
  auto b = Submit(Spawn("drone.generic_quad"));
  ASSERT_TRUE(a.accepted()) << a.reason();
  ASSERT_TRUE(b.accepted()) << b.reason();
  EXPECT_EQ(a.actor(), 1u);
  EXPECT_EQ(b.actor(), 2u);
  auto batch = p.TakePending();
  ASSERT_EQ(batch.size(), 2u);
  EXPECT_EQ(batch[0].body().spawn_actor().actor(), 1u) << "the tick carries the assigned id";
  EXPECT_EQ(batch[1].body().spawn_actor().actor(), 2u);
}

TEST_F(CommandProcessorTest, UnknownBlueprintIsRejectedWithItsName) {
  auto r = Submit(Spawn("vehicle.nonexistent.car"));
  EXPECT_FALSE(r.accepted());
  EXPECT_NE(r.reason().to_string().find("unknown blueprint 'vehicle.nonexistent.car'"), std::string::npos) << r.reason();
  EXPECT_FALSE(p.HasPending());
}

TEST_F(CommandProcessorTest, AttributeOfWrongTypeIsRejected) {
  auto r = Submit(Spawn("sensor.camera.rgb", {{"image_size_x", "wide"}}));
  EXPECT_FALSE(r.accepted());
  EXPECT_NE(r.reason().to_string().find("image_size_x"), std::string::npos) << r.reason();
  EXPECT_NE(r.reason().to_string().find("integer"), std::string::npos) << r.reason();
  auto f = Submit(Spawn("sensor.camera.rgb", {{"fov", "1e400"}}));
  EXPECT_FALSE(f.accepted()) << "overflowing float";
  auto rgb = Submit(Spawn("vehicle.lockstep.sedan", {{"color", "255,0"}}));
  EXPECT_FALSE(rgb.accepted());
  auto fixed = Submit(Spawn("sensor.other.obstacle", {{"generation", "3"}}));
  EXPECT_FALSE(fixed.accepted());
  EXPECT_NE(fixed.reason().to_string().find("'generation' of blueprint 'sensor.other.obstacle' cannot be set"), std::string::npos)
      << fixed.reason();
  auto unknown = Submit(Spawn("vehicle.lockstep.sedan", {{"colour", "1,2,3"}}));
  EXPECT_FALSE(unknown.accepted());
  EXPECT_NE(unknown.reason().to_string().find("no attribute 'colour'"), std::string::npos) << unknown.reason();
  auto ok = Submit(Spawn("vehicle.lockstep.sedan", {{"color", "255,0,10"}, {"role_name", "hero"}}));
  EXPECT_TRUE(ok.accepted()) << ok.reason();
}

TEST_F(CommandProcessorTest, RestrictedValuesMustBeAmongTheRecommended) {
  p.library().Declare(Declare("air", {blueprint::Make("drone.generic_quad", msg::ACTOR_DRONE,
                                                      {blueprint::String("frame", "quad_x", {"quad_x", "hexa_x"}, true)})}));
  auto bad = Submit(Spawn("drone.generic_quad", {{"frame", "octo"}}));
  EXPECT_FALSE(bad.accepted());
  EXPECT_NE(bad.reason().to_string().find("expected one of quad_x, hexa_x"), std::string::npos) << bad.reason();
  EXPECT_TRUE(Submit(Spawn("drone.generic_quad", {{"frame", "hexa_x"}})).accepted());
}

TEST_F(CommandProcessorTest, TheTickNamesTheOwnerAndSpawnsAreBalancedAmongDeclarers) {
  p.library().Declare(Declare("render_a", {blueprint::Make("sensor.camera.rgb", msg::ACTOR_SENSOR, {})}));
  p.library().Declare(Declare("render_b", {blueprint::Make("sensor.camera.rgb", msg::ACTOR_SENSOR, {})}));
  p.library().SetAlive("ground", false);  // ground also declares cameras: only the two renders count
  std::map<std::string, int> owners;
  for (int i = 0; i < 6; ++i) ASSERT_TRUE(Submit(Spawn("sensor.camera.rgb")).accepted());
  for (const auto& c : p.TakePending()) ++owners[c.body().spawn_actor().owner().to_string()];
  EXPECT_EQ(owners["render_a"], 3);
  EXPECT_EQ(owners["render_b"], 3);
  auto named = Spawn("sensor.camera.rgb");
  named.body().spawn_actor().owner("render_b");
  ASSERT_TRUE(Submit(named).accepted());
  EXPECT_EQ(p.TakePending().at(0).body().spawn_actor().owner().to_string(), "render_b") << "the spawn may name its owner";
  named.body().spawn_actor().owner("air");
  auto wrong = Submit(named);
  EXPECT_FALSE(wrong.accepted());
  EXPECT_NE(wrong.reason().to_string().find("owner 'air' does not declare blueprint 'sensor.camera.rgb'"), std::string::npos)
      << wrong.reason();
}

TEST_F(CommandProcessorTest, ABlueprintLeavesWithItsService) {
  ASSERT_TRUE(Submit(Spawn("drone.generic_quad")).accepted());
  p.library().SetAlive("air", false);
  auto r = Submit(Spawn("drone.generic_quad"));
  EXPECT_FALSE(r.accepted());
  EXPECT_NE(r.reason().to_string().find("unknown blueprint 'drone.generic_quad': declared only by 'air', which is not alive"),
            std::string::npos)
      << r.reason();
  auto never = Submit(Spawn("drone.imaginary"));
  EXPECT_NE(never.reason().to_string().find("no live service declares it"), std::string::npos) << never.reason();
}

TEST_F(CommandProcessorTest, TheOwnersCheckDecidesTheReply) {
  std::vector<std::string> asked;
  auto check = [&](const msg::SpawnActor& s) -> std::string {
    asked.push_back(s.owner().to_string());
    return s.attributes().empty() ? "" : "mass too small for its motors";
  };
  auto bad = Submit(Spawn("drone.generic_quad", {{"role_name", "x"}}), false, check);
  EXPECT_FALSE(bad.accepted());
  EXPECT_EQ(bad.reason().to_string(), "owner 'air' rejected the spawn: mass too small for its motors");
  EXPECT_EQ(bad.actor(), 0u);
  EXPECT_FALSE(p.HasPending()) << "a spawn its owner rejects never reaches a tick";
  EXPECT_TRUE(Submit(Spawn("drone.generic_quad"), false, check).accepted());
  EXPECT_EQ(asked, (std::vector<std::string>{"air", "air"}));
}

TEST_F(CommandProcessorTest, ControlOfUnknownActorIsRejected) {
  auto r = Submit(Control(42, 0.5f, 0));
  EXPECT_FALSE(r.accepted());
  EXPECT_EQ(r.reason().to_string(), "unknown actor 42");
}

TEST_F(CommandProcessorTest, NanAndOutOfRangeControlsAreRejected) {
  const uint32_t car = Submit(Spawn("vehicle.lockstep.sedan")).actor();
  auto nan = Submit(Control(car, std::numeric_limits<float>::quiet_NaN(), 0));
  EXPECT_FALSE(nan.accepted());
  EXPECT_NE(nan.reason().to_string().find("throttle is NaN"), std::string::npos) << nan.reason();
  auto range = Submit(Control(car, 0.5f, 1.5f));
  EXPECT_FALSE(range.accepted());
  EXPECT_NE(range.reason().to_string().find("steer"), std::string::npos);
  EXPECT_TRUE(Submit(Control(car, 0.5f, -0.2f)).accepted());
}

TEST_F(CommandProcessorTest, ControlOfTheWrongKindOfActorIsRejected) {
  const uint32_t drone = Submit(Spawn("drone.generic_quad")).actor();
  auto r = Submit(Control(drone, 0.5f, 0));
  EXPECT_FALSE(r.accepted());
  EXPECT_NE(r.reason().to_string().find("is a drone"), std::string::npos) << r.reason();
}

TEST_F(CommandProcessorTest, DroneCommandsAreChecked) {
  const uint32_t drone = Submit(Spawn("drone.generic_quad")).actor();
  msg::DroneCommand d;
  d.actor(drone);
  d.kind(msg::DroneCommandKind::DRONE_MOVE_BY_MOTOR_PWMS);
  d.values({0.5, 0.5, 1.5, 0.5});
  msg::CommandBody b;
  b.drone(d);
  auto r = Submit(Make(b));
  EXPECT_FALSE(r.accepted());
  EXPECT_NE(r.reason().to_string().find("pwm"), std::string::npos) << r.reason();
  d.kind(msg::DroneCommandKind::DRONE_MOVE_TO_POSITION);
  d.values({});
  d.velocity(5);
  msg::Vector3 t;
  t.x(std::nan(""));
  d.target(t);
  b.drone(d);
  EXPECT_FALSE(Submit(Make(b)).accepted());
  t.x(10);
  d.target(t);
  b.drone(d);
  EXPECT_TRUE(Submit(Make(b)).accepted());
}

TEST_F(CommandProcessorTest, NonUnitQuaternionIsRejected) {
  auto c = Spawn("vehicle.lockstep.sedan");
  c.body().spawn_actor().transform().orientation().w(2.0);
  auto r = Submit(c);
  EXPECT_FALSE(r.accepted());
  EXPECT_NE(r.reason().to_string().find("unit quaternion"), std::string::npos) << r.reason();
}

// CARLA destroys only the actor; Unreal detaches its children keeping their world
// transform (UWorld::DestroyActor): the camera lives on, unattached.
TEST_F(CommandProcessorTest, DestroyDetachesAttachedSensors) {
  const uint32_t car = Submit(Spawn("vehicle.lockstep.sedan")).actor();
  const uint32_t cam = Submit(Spawn("sensor.camera.rgb", {}, car)).actor();
  msg::DestroyActor d;
  d.actor(car);
  msg::CommandBody b;
  b.destroy_actor(d);
  EXPECT_TRUE(Submit(Make(b)).accepted());
  EXPECT_EQ(p.actors().count(car), 0u);
  ASSERT_EQ(p.actors().count(cam), 1u);
  EXPECT_EQ(p.actors().at(cam).parent, 0u);
  EXPECT_FALSE(Submit(Make(b)).accepted()) << "destroying twice";
  d.actor(cam);
  b.destroy_actor(d);
  EXPECT_TRUE(Submit(Make(b)).accepted()) << "the detached camera is destroyed on its own";
}

TEST_F(CommandProcessorTest, TickRequestsNeedSynchronousMode) {
  msg::TickRequest t;
  t.count(3);
  msg::CommandBody b;
  b.tick_request(t);
  auto free_running = Submit(Make(b), false);
  EXPECT_FALSE(free_running.accepted());
  EXPECT_NE(free_running.reason().to_string().find("synchronous_mode"), std::string::npos);
  auto sync = Submit(Make(b), true);
  EXPECT_TRUE(sync.accepted());
  EXPECT_EQ(sync.frame(), 12u) << "next frame 10 plus two more";
  EXPECT_FALSE(p.HasPending()) << "services never see tick requests";
  // Count 0 is a ping (a client checks that replies reach it): answered in either mode.
  t.count(0);
  b.tick_request(t);
  EXPECT_TRUE(Submit(Make(b), false).accepted());
  EXPECT_TRUE(Submit(Make(b), true).accepted());
  EXPECT_FALSE(p.HasPending());
}

TEST_F(CommandProcessorTest, AcceptedCommandsKeepAcceptanceOrder) {
  std::vector<uint64_t> seqs;
  const uint32_t car = Submit(Spawn("vehicle.lockstep.sedan")).actor();
  p.TakePending();
  for (uint64_t i = 0; i < 20; ++i) {
    auto c = Control(car, 0.05f * static_cast<float>(i), 0);
    c.sequence_number(100 + i);
    if (i % 5 == 3) c.body().vehicle_control().brake(2.0f);  // rejected, must leave no gap
    if (Submit(c).accepted()) seqs.push_back(100 + i);
  }
  auto batch = p.TakePending();
  ASSERT_EQ(batch.size(), seqs.size());
  for (size_t i = 0; i < batch.size(); ++i) EXPECT_EQ(batch[i].sequence_number(), seqs[i]);
}

TEST_F(CommandProcessorTest, BadWorldSettingsAreRejected) {
  msg::WorldSettings s;
  s.fixed_delta_seconds(-0.1);
  s.max_substeps(10);
  s.max_substep_delta_time(0.01);
  s.service_timeout(1);
  msg::CommandBody b;
  b.world_settings(s);
  auto r = Submit(Make(b));
  EXPECT_FALSE(r.accepted());
  EXPECT_NE(r.reason().to_string().find("fixed_delta_seconds"), std::string::npos) << r.reason();
}

}  // namespace
}  // namespace lockstep

namespace lockstep {
namespace {

msg::DebugShape Box(double life_time = 1.0) {
  msg::DebugShape s;
  s.kind(msg::DebugShapeKind::DEBUG_BOX);
  s.begin().x(10);
  s.extent().x(1);
  s.extent().y(1);
  s.extent().z(1);
  s.rotation().w(1);
  s.size(0.1);
  s.life_time(life_time);
  return s;
}

msg::Command Draw(std::vector<msg::DebugShape> shapes) {
  msg::DebugDraw d;
  d.shapes(std::move(shapes));
  msg::CommandBody b;
  b.debug_draw(d);
  return Make(b);
}

TEST_F(CommandProcessorTest, DebugShapesGoIntoTheTickAndBadOnesAreRejectedWithTheirFault) {
  ASSERT_TRUE(Submit(Draw({Box()})).accepted());
  auto pending = p.TakePending();
  ASSERT_EQ(pending.size(), 1u);
  EXPECT_EQ(pending[0].body()._d(), msg::CommandKind::CMD_DEBUG_DRAW);
  EXPECT_FALSE(Submit(Draw({})).accepted()) << "a draw without shapes";
  // AirSim's simFlushPersistentMarkers: a flush with no shapes goes into the tick.
  msg::DebugDraw flush;
  flush.flush_persistent(true);
  msg::CommandBody fb;
  fb.debug_draw(flush);
  ASSERT_TRUE(Submit(Make(fb)).accepted());
  pending = p.TakePending();
  ASSERT_EQ(pending.size(), 1u);
  EXPECT_TRUE(pending[0].body().debug_draw().flush_persistent());
  msg::DebugShape nan = Box();
  nan.end().y(std::numeric_limits<double>::quiet_NaN());
  auto r = Submit(Draw({Box(), nan}));
  EXPECT_FALSE(r.accepted());
  EXPECT_NE(r.reason().to_string().find("debug shape 1: a location has a NaN"), std::string::npos) << r.reason();
  msg::DebugShape tilted = Box();
  tilted.rotation().w(2);
  r = Submit(Draw({tilted}));
  EXPECT_FALSE(r.accepted());
  EXPECT_NE(r.reason().to_string().find("unit quaternion"), std::string::npos) << r.reason();
  msg::DebugShape thick = Box();
  thick.size(-1);
  r = Submit(Draw({thick}));
  EXPECT_FALSE(r.accepted());
  EXPECT_NE(r.reason().to_string().find("size = -1"), std::string::npos) << r.reason();
  EXPECT_FALSE(p.HasPending());
}

TEST_F(CommandProcessorTest, UpdateVehicleLightsNeedsAVehicle) {
  const uint32_t car = Submit(Spawn("vehicle.lockstep.sedan")).actor();
  msg::TrafficManagerCommand tm;
  tm.parameter(msg::TrafficManagerParameter::TM_UPDATE_VEHICLE_LIGHTS);
  tm.value(1);
  msg::CommandBody b;
  b.traffic_manager(tm);
  auto r = Submit(Make(b));
  EXPECT_FALSE(r.accepted());
  EXPECT_NE(r.reason().to_string().find("needs a vehicle"), std::string::npos) << r.reason();
  b.traffic_manager().actor(car);
  EXPECT_TRUE(Submit(Make(b)).accepted());
}

}  // namespace
}  // namespace lockstep

namespace lockstep {
namespace {

msg::Command V2XSend(uint32_t sensor, const std::string& text) {
  msg::V2XSend v;
  v.sensor(sensor);
  v.data(text);
  msg::CommandBody b;
  b.v2x_send(v);
  return Make(b);
}

TEST_F(CommandProcessorTest, V2XSendGoesOnlyToACustomV2XSensor) {
  p.library().Declare(Declare("sensors", {blueprint::Make("sensor.other.v2x_custom", msg::ACTOR_SENSOR, {blueprint::String("role_name", "")}),
                                          blueprint::Make("sensor.other.v2x", msg::ACTOR_SENSOR, {blueprint::String("role_name", "")})}));
  auto custom = Submit(Spawn("sensor.other.v2x_custom"));
  auto cam = Submit(Spawn("sensor.other.v2x"));
  ASSERT_TRUE(custom.accepted()) << custom.reason();
  ASSERT_TRUE(cam.accepted()) << cam.reason();
  p.TakePending();
  auto r = Submit(V2XSend(custom.actor(), "hello"));
  ASSERT_TRUE(r.accepted()) << r.reason();
  auto pending = p.TakePending();
  ASSERT_EQ(pending.size(), 1u);
  EXPECT_EQ(pending[0].body().v2x_send().data().to_string(), "hello");
  r = Submit(V2XSend(cam.actor(), "hello"));
  EXPECT_FALSE(r.accepted());
  EXPECT_NE(r.reason().to_string().find("is a sensor.other.v2x, not a sensor.other.v2x_custom"), std::string::npos) << r.reason();
  r = Submit(V2XSend(999, "hello"));
  EXPECT_FALSE(r.accepted());
  EXPECT_NE(r.reason().to_string().find("unknown actor 999"), std::string::npos) << r.reason();
  EXPECT_TRUE(p.TakePending().empty());
}

}  // namespace
}  // namespace lockstep
