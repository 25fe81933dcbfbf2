// The infractions CARLA users and the 2017 benchmark count reach GroundState: each
// VehicleState carries the core's cumulative counts (stop signs, lane invasions, collisions by
// kind, opposite-lane and off-road onsets, distance driven) as the core counted them.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

#include "../ground_sim/test_towns.h"
#include "lockstep/ground/world.h"
#include "wire.h"

namespace lockstep::ground {
namespace {

constexpr double kDt = 0.05;
constexpr uint32_t kCar = 7;

msg::VehicleState Wire(const World& w) { return ground_wire::ToWire(*w.Vehicle(kCar)); }

// A car driven by Ackermann control across the solid centre line into the opposite lane,
// back across it and off the road on its right: two onsets of the benchmark's intersections,
// the lane invasions counted tick by tick, the distance it drove.
TEST(GroundInfractionsWire, LaneInvasionsOppositeLaneOffroadAndDistance) {
  World w(testing::StraightTown(), 1);
  const Vec3 half = FindVehicle("vehicle.tesla.model3")->half_extents;
  ASSERT_EQ(w.AddVehicle(kCar, "vehicle.tesla.model3", {}, Pose::FromYaw(Vec3(0, -1.75, half.z() + 0.02), 0)), "");
  AckermannControl a;
  a.speed = 5;
  int invasion_ticks = 0;
  double path = 0, max_opposite = 0, max_offroad = 0;
  Vec3 last = w.Vehicle(kCar)->pose.position;
  auto steer_to = [&](double y_goal, int ticks) {
    for (int i = 0; i < ticks; ++i) {
      const auto v = *w.Vehicle(kCar);
      a.steer = std::clamp(-2.0 * v.pose.Yaw() - 0.3 * (v.pose.position.y() - y_goal), -0.1, 0.1);
      ASSERT_EQ(w.ApplyAckermann(kCar, a), "");
      w.Step(kDt);
      for (const auto& inv : w.LaneInvasions()) invasion_ticks += inv.actor == kCar;
      const auto now = *w.Vehicle(kCar);
      path += (now.pose.position - last).head<2>().norm();
      last = now.pose.position;
      max_opposite = std::max(max_opposite, now.opposite_lane);
      max_offroad = std::max(max_offroad, now.offroad);
      const msg::VehicleState m = ground_wire::ToWire(now);
      EXPECT_DOUBLE_EQ(m.opposite_lane_fraction(), now.opposite_lane);
      EXPECT_DOUBLE_EQ(m.offroad_fraction(), now.offroad);
    }
  };
  steer_to(-1.75, 20);
  msg::VehicleState m = Wire(w);
  EXPECT_EQ(m.lane_invasions(), 0u);
  EXPECT_EQ(m.opposite_lane_infractions(), 0u);
  EXPECT_EQ(m.offroad_infractions(), 0u);
  steer_to(1.75, 200);  // into the opposite lane
  m = Wire(w);
  EXPECT_GT(max_opposite, 0.9);
  EXPECT_EQ(m.opposite_lane_infractions(), 1u) << "one onset, however long it stays there";
  EXPECT_GE(m.lane_invasions(), 1u);
  steer_to(-6.5, 300);  // back over the centre line and off the road on the right
  m = Wire(w);
  EXPECT_GT(max_offroad, 0.9);
  EXPECT_EQ(m.opposite_lane_infractions(), 1u);
  EXPECT_EQ(m.offroad_infractions(), 1u);
  EXPECT_EQ(m.lane_invasions(), static_cast<uint32_t>(invasion_ticks));
  EXPECT_GE(m.lane_invasions(), 3u) << "centre line twice, the right edge line once";
  EXPECT_NEAR(m.distance_driven(), path, 0.01 * path);
  EXPECT_GT(m.distance_driven(), 100.0);
  EXPECT_EQ(m.stop_sign_infractions(), 0u);
  EXPECT_EQ(m.collision_infractions(), 0u);
}

// A Traffic-Manager car told to ignore every sign runs the stop sign: one stop-sign
// infraction on the wire; one that obeys it has none.
TEST(GroundInfractionsWire, StopSignRunsReachTheWire) {
  for (bool ignore : {false, true}) {
    World w(testing::StopSignTown(), 4);
    const Vec3 half = FindVehicle("vehicle.audi.tt")->half_extents;
    ASSERT_EQ(w.AddVehicle(kCar, "vehicle.audi.tt", {}, Pose::FromYaw(Vec3(40, -1.75, half.z() + 0.02), 0)), "");
    ASSERT_EQ(w.SetAutopilot(kCar, true), "");
    if (ignore) {
      ASSERT_EQ(w.SetTrafficManager(TmParam::kIgnoreSignsPercentage, kCar, 100), "");
    }
    for (int i = 0; i < 500; ++i) w.Step(kDt);
    const msg::VehicleState m = Wire(w);
    EXPECT_GT(m.transform().position().x(), 115.0) << "through the junction";
    EXPECT_EQ(m.stop_sign_infractions(), ignore ? 1u : 0u) << "ignore " << ignore;
    EXPECT_EQ(m.red_light_infractions(), 0u);
    EXPECT_GT(m.distance_driven(), 75.0);
  }
}

// Driving into a wall and pushing on: one collision infraction with a static object per
// contact (not one per tick of the contact), counted in the total.
TEST(GroundInfractionsWire, AWallContactCountsOncePerContact) {
  World w(testing::StraightTown(40.0), 1);
  const Vec3 half = FindVehicle("vehicle.tesla.model3")->half_extents;
  ASSERT_EQ(w.AddVehicle(kCar, "vehicle.tesla.model3", {}, Pose::FromYaw(Vec3(0, -1.75, half.z() + 0.02), 0)), "");
  VehicleControl c;
  c.throttle = 0.6;
  ASSERT_EQ(w.ApplyControl(kCar, c), "");
  int contact_ticks = 0, onsets = 0;
  bool touching = false;
  for (int i = 0; i < 200; ++i) {
    w.Step(kDt);
    bool now = false;
    for (const auto& col : w.Collisions()) now |= col.actor == kCar;
    contact_ticks += now;
    onsets += now && !touching;
    touching = now;
  }
  const msg::VehicleState m = Wire(w);
  ASSERT_GE(onsets, 1) << "it never reached the wall";
  ASSERT_GT(contact_ticks, onsets) << "it keeps pushing against the wall";
  EXPECT_EQ(m.other_collisions(), static_cast<uint32_t>(onsets));
  EXPECT_EQ(m.vehicle_collisions(), 0u);
  EXPECT_EQ(m.walker_collisions(), 0u);
  EXPECT_EQ(m.collision_infractions(), static_cast<uint32_t>(onsets));
}

}  // namespace
}  // namespace lockstep::ground
