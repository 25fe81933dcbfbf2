// The Traffic Manager's conventions that CARLA's code fixes: the ignore percentages are
// drawn every tick (TrafficLightStage, CollisionStage), not once per junction, and the
// hybrid physics radius is 70 m by default (Parameters.h).
#include <gtest/gtest.h>

#include "lockstep/ground/world.h"
#include "test_towns.h"
#include "traffic_test_helpers.h"

namespace lockstep::ground {
namespace {

using testing::BeforeLight;
using testing::kDt;

// CARLA: every tick at a red light the car stops unless a draw falls below
// ignore_lights_percentage. At 50 % a car held at a frozen red light therefore creeps over
// the line sooner or later, whatever its random stream; a draw made once per junction
// leaves some waiting for ever (3 of these 12).
TEST(TmConventions, IgnoreLightsIsDrawnEveryTickSoEveryCarEventuallyRunsTheRed) {
  auto town = testing::Town01();
  const uint32_t light = 1;  // actor id of light index 0
  const Vec3 half = FindVehicle("vehicle.audi.tt")->half_extents;
  int ran = 0;
  const int worlds = 12;
  for (int seed = 1; seed <= worlds; ++seed) {
    World w(town, static_cast<uint64_t>(seed));
    ASSERT_EQ(w.SetTrafficLight(light, LightColor::kRed, -1, -1, -1, true), "");
    ASSERT_EQ(w.AddVehicle(50, "vehicle.audi.tt", {}, BeforeLight(*town, 0, 30, half.z())), "");
    ASSERT_EQ(w.SetAutopilot(50, true), "");
    ASSERT_EQ(w.SetTrafficManager(TmParam::kIgnoreLightsPercentage, 50, 50), "");
    for (int i = 0; i < 1200 && w.Vehicle(50)->infractions.red_lights == 0; ++i) w.Step(kDt);
    ran += w.Vehicle(50)->infractions.red_lights > 0;
  }
  EXPECT_EQ(ran, worlds) << "cars that ran the red light within 60 s";
}

// The same with 0 %: the draw never lets the car go (ARedLightStops... covers the stop).
TEST(TmConventions, WithoutThePercentageTheCarWaitsAtTheRed) {
  auto town = testing::Town01();
  const Vec3 half = FindVehicle("vehicle.audi.tt")->half_extents;
  World w(town, 3);
  ASSERT_EQ(w.SetTrafficLight(1, LightColor::kRed, -1, -1, -1, true), "");
  ASSERT_EQ(w.AddVehicle(50, "vehicle.audi.tt", {}, BeforeLight(*town, 0, 30, half.z())), "");
  ASSERT_EQ(w.SetAutopilot(50, true), "");
  for (int i = 0; i < 1200; ++i) w.Step(kDt);
  EXPECT_EQ(w.Vehicle(50)->infractions.red_lights, 0);
  EXPECT_LT(w.Vehicle(50)->velocity.norm(), 0.05);
}

// Hybrid mode: physics within 70 m of the hero (CARLA's default radius), kinematic beyond.
TEST(TmConventions, HybridPhysicsRadiusIsSeventyMetresByDefault) {
  World w(testing::TwoLaneTown(), 8);
  ASSERT_EQ(w.SetTrafficManager(TmParam::kHybridPhysicsMode, 0, 1), "");
  const Vec3 half = FindVehicle("vehicle.audi.tt")->half_extents;
  auto add = [&](uint32_t id, double x, bool hero) {
    std::map<std::string, std::string> attributes;
    if (hero) attributes["role_name"] = "hero";
    ASSERT_EQ(w.AddVehicle(id, "vehicle.audi.tt", attributes, Pose::FromYaw(Vec3(x, -1.75, half.z() + 0.02), 0)), "");
    ASSERT_EQ(w.SetAutopilot(id, true), "");
    ASSERT_EQ(w.SetTrafficManager(TmParam::kDesiredSpeed, id, 0.0), "");  // they stay where they are
  };
  add(1, 0, true);
  add(2, 60, false);   // inside 70 m, outside 50 m
  add(3, 85, false);   // outside 70 m
  for (int i = 0; i < 5; ++i) w.Step(kDt);
  EXPECT_FALSE(w.Vehicle(1)->kinematic) << "the hero";
  EXPECT_FALSE(w.Vehicle(2)->kinematic) << "60 m from the hero";
  EXPECT_TRUE(w.Vehicle(3)->kinematic) << "85 m from the hero";
}

}  // namespace
}  // namespace lockstep::ground
