// The Traffic Manager's lane offsets, collision detection and respawn of dormant vehicles,
// as CARLA's TM does them (Parameters.cpp, MotionPlanStage.cpp, CollisionStage.cpp,
// InMemoryMap::GetWaypointsInDelta).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

#include "lockstep/ground/world.h"
#include "test_towns.h"
#include "traffic_test_helpers.h"

namespace lockstep::ground {
namespace {

using testing::kDt;

constexpr const char* kCar = "vehicle.audi.tt";

Pose OnLane(double x, double y = -1.75) { return Pose::FromYaw(Vec3(x, y, FindVehicle(kCar)->half_extents.z() + 0.02), 0); }

// Mean y of vehicle `id` over `n` steps (after `settle` steps).
double MeanY(World* w, uint32_t id, int settle, int n) {
  for (int i = 0; i < settle; ++i) w->Step(kDt);
  double sum = 0;
  for (int i = 0; i < n; ++i) {
    w->Step(kDt);
    sum += w->Vehicle(id)->pose.position.y();
  }
  return sum / n;
}

// CARLA's lane offset moves the car's target point along the lane's right vector: > 0 to
// the right. An eastbound car on lane -1 (centre y = -1.75) with a global offset of 1 m
// drives at y = -2.75; a vehicle offset of -0.5 m overrides the global one (y = -1.25).
TEST(TmFeatures, LaneOffsetDrivesRightOfTheLaneCentreAndTheVehicleValueWins) {
  World w(testing::StraightTown(), 4);
  ASSERT_EQ(w.AddVehicle(5, kCar, {}, OnLane(-90)), "");
  ASSERT_EQ(w.SetAutopilot(5, true), "");
  EXPECT_NEAR(MeanY(&w, 5, 100, 40), -1.75, 0.1);  // no offset: the lane centre
  ASSERT_EQ(w.SetTrafficManager(TmParam::kLaneOffset, 0, 1.0), "");
  EXPECT_NEAR(MeanY(&w, 5, 200, 40), -2.75, 0.1);
  ASSERT_EQ(w.SetTrafficManager(TmParam::kLaneOffset, 5, -0.5), "");
  EXPECT_NEAR(MeanY(&w, 5, 200, 40), -1.25, 0.1);
  EXPECT_DOUBLE_EQ(w.TrafficManager().lane_offset, 1.0);
}

// A parked car 60 m ahead on the lane: the TM car stops behind it. collision_detection(car,
// parked, False) makes it drive into it (CARLA's CollisionStage skips the other actor);
// True again restores the stop. The parked car still has its own hazards (one way).
TEST(TmFeatures, CollisionDetectionOffIgnoresTheOtherActor) {
  for (int mode : {0, 1, 2}) {  // 0 default, 1 ignore, 2 ignore then detect again
    World w(testing::StraightTown(), 9);
    ASSERT_EQ(w.AddVehicle(5, kCar, {}, OnLane(-60)), "");
    ASSERT_EQ(w.AddVehicle(6, kCar, {}, OnLane(0)), "");  // parked: no autopilot
    ASSERT_EQ(w.SetAutopilot(5, true), "");
    if (mode >= 1) {
      ASSERT_EQ(w.SetCollisionDetection(5, 6, false), "");
    }
    if (mode == 2) {
      ASSERT_EQ(w.SetCollisionDetection(5, 6, true), "");
    }
    bool hit = false;
    for (int i = 0; i < 400 && !hit; ++i) {
      w.Step(kDt);
      for (const auto& c : w.Collisions()) hit |= c.actor == 5 && c.other_actor == 6;
    }
    EXPECT_EQ(hit, mode == 1) << "mode " << mode;
    if (mode != 1) {
      EXPECT_LT(w.Vehicle(5)->pose.position.x(), -4.0) << "mode " << mode;
    }
  }
  World w(testing::StraightTown(), 9);
  ASSERT_EQ(w.AddVehicle(5, kCar, {}, OnLane(0)), "");
  EXPECT_NE(w.SetCollisionDetection(77, 5, false), "");  // not a vehicle
  EXPECT_NE(w.SetCollisionDetection(5, 0, false), "");
}

// CARLA: a dormant vehicle (farther than actor_active_distance, 2 km, from the hero) with
// respawn_dormant_vehicles is teleported to a lane point of the square ring around the hero
// at a distance drawn between the bounds (default 100..1000 m; the ring is 25 m wide).
TEST(TmFeatures, DormantVehicleRespawnsWithinTheBoundsAroundTheHero) {
  World w(testing::LongRoadTown(), 11);
  ASSERT_EQ(w.AddVehicle(1, kCar, {{"role_name", "hero"}}, OnLane(0)), "");
  ASSERT_EQ(w.AddVehicle(5, kCar, {}, OnLane(2600)), "");
  ASSERT_EQ(w.SetAutopilot(5, true), "");
  for (int i = 0; i < 10; ++i) w.Step(kDt);
  EXPECT_GT(w.Vehicle(5)->pose.position.x(), 2500);  // respawn off: it drives on, dormant
  EXPECT_TRUE(w.Vehicle(5)->kinematic);              // moved by the TM, no physics (CARLA)
  ASSERT_EQ(w.SetTrafficManager(TmParam::kRespawnDormantVehicles, 0, 1), "");
  w.Step(kDt);
  double d = std::abs(w.Vehicle(5)->pose.position.x() - w.Vehicle(1)->pose.position.x());
  EXPECT_GT(d, 100.0);
  EXPECT_LT(d, 1000.0 + 25.0 + 1.0);
  EXPECT_FALSE(w.Vehicle(5)->kinematic);
  // Bounds clamp to [20 m, actor_active_distance] (CARLA's SetMaxBoundaries(20, 2000)).
  ASSERT_EQ(w.SetRespawnBoundaries(5, 9000), "");
  EXPECT_DOUBLE_EQ(w.TrafficManager().respawn_lower_bound, 20.0);
  EXPECT_DOUBLE_EQ(w.TrafficManager().respawn_upper_bound, 2000.0);
  ASSERT_EQ(w.SetRespawnBoundaries(40, 60), "");
  ASSERT_EQ(w.SetTransform(5, OnLane(3500)), "");
  w.Step(kDt);
  d = std::abs(w.Vehicle(5)->pose.position.x() - w.Vehicle(1)->pose.position.x());
  EXPECT_GT(d, 40.0);
  EXPECT_LT(d, 60.0 + 25.0 + 1.0);
  EXPECT_NE(w.SetRespawnBoundaries(std::nan(""), 60), "");
}

// Without a hero nothing is dormant: the far car drives on, on physics.
TEST(TmFeatures, WithoutAHeroNothingIsDormant) {
  World w(testing::LongRoadTown(), 11);
  ASSERT_EQ(w.AddVehicle(5, kCar, {}, OnLane(2600)), "");
  ASSERT_EQ(w.AddVehicle(6, kCar, {}, OnLane(0)), "");
  ASSERT_EQ(w.SetAutopilot(5, true), "");
  ASSERT_EQ(w.SetTrafficManager(TmParam::kRespawnDormantVehicles, 0, 1), "");
  for (int i = 0; i < 10; ++i) w.Step(kDt);
  EXPECT_GT(w.Vehicle(5)->pose.position.x(), 2590);
  EXPECT_FALSE(w.Vehicle(5)->kinematic);
}

// The new settings are state: a saved world continues bit for bit.
TEST(TmFeatures, SettingsSurviveSaveAndRestore) {
  World w(testing::StraightTown(), 4);
  ASSERT_EQ(w.AddVehicle(5, kCar, {}, OnLane(-90)), "");
  ASSERT_EQ(w.AddVehicle(6, kCar, {}, OnLane(-40)), "");
  ASSERT_EQ(w.SetAutopilot(5, true), "");
  ASSERT_EQ(w.SetTrafficManager(TmParam::kLaneOffset, 5, 0.7), "");
  ASSERT_EQ(w.SetCollisionDetection(5, 6, false), "");
  ASSERT_EQ(w.SetRespawnBoundaries(30, 300), "");
  for (int i = 0; i < 20; ++i) w.Step(kDt);
  auto copy = World::Restore(testing::StraightTown(), w.Save());
  EXPECT_DOUBLE_EQ(copy->TrafficManager().respawn_upper_bound, 300.0);
  for (int i = 0; i < 200; ++i) {
    w.Step(kDt);
    copy->Step(kDt);
  }
  EXPECT_EQ(w.StateHash(), copy->StateHash());
  EXPECT_LT(w.Vehicle(5)->pose.position.y(), -2.2);  // the offset went along
}

}  // namespace
}  // namespace lockstep::ground
