// Walkers among walkers in CARLA's Town01: capsules never move into each other (under
// WalkerControl and under the AI controller), walkers spawned overlapping move apart, and
// AI walkers walking towards each other along a sidewalk pass and both arrive.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <vector>

#include "lockstep/ground/blueprints.h"
#include "lockstep/ground/world.h"
#include "test_towns.h"
#include "walker_test_helpers.h"

namespace lockstep::ground {
namespace {

using testing::AwayFrom;
using testing::Flat;

constexpr double kDt = 0.05;
constexpr double kTolerance = 1e-6;

// The smallest room between two walkers' capsules: centre distance minus the sum of
// their radii (< 0: they overlap).
double ClosestPair(const World& w) {
  const auto ws = w.Walkers();
  double closest = 1e9;
  for (size_t i = 0; i < ws.size(); ++i) {
    for (size_t j = i + 1; j < ws.size(); ++j) {
      const double radii = FindWalker(ws[i].blueprint)->radius + FindWalker(ws[j].blueprint)->radius;
      closest = std::min(closest, Flat(ws[i].pose.position, ws[j].pose.position) - radii);
    }
  }
  return closest;
}

// A straight stretch of a Town01 driving lane (open ground, no walls): its start and unit
// direction.
void OpenGround(const Town& town, Vec3* at, Vec3* dir) {
  const auto wp = town.Map().NearestWaypoint(Vec3(150, -55, 0));  // a long road in the south of the town
  ASSERT_TRUE(wp.has_value());
  *at = wp->transform.location;
  *dir = wp->transform.Forward();
  dir->z() = 0;
  dir->normalize();
}

// Two walkers walking straight at each other (head on, and 0.2 m off): frame by frame
// their capsules never overlap, and they do meet (come within 0.15 m of touching; then
// they slide round each other).
TEST(GroundWalkerCrowd, TwoWalkersWalkingAtEachOtherNeverOverlap) {
  const auto town = testing::Town01();
  Vec3 at = Vec3::Zero(), dir = Vec3::UnitX();
  OpenGround(*town, &at, &dir);
  const Vec3 side(-dir.y(), dir.x(), 0);
  for (const double offset : {0.0, 0.2}) {
    World w(town, 3);
    ASSERT_EQ(w.AddWalker(1, "walker.pedestrian.0001", {}, Pose::FromYaw(at - dir * 4 + Vec3(0, 0, 1.0), 0)), "");
    ASSERT_EQ(w.AddWalker(2, "walker.pedestrian.0002", {}, Pose::FromYaw(at + dir * 4 + side * offset + Vec3(0, 0, 1.0), 0)), "");
    ASSERT_EQ(w.ApplyWalkerControl(1, WalkerControl{dir, 1.4, false}), "");
    ASSERT_EQ(w.ApplyWalkerControl(2, WalkerControl{-dir, 1.4, false}), "");
    double closest = 1e9;
    for (int i = 0; i < 200; ++i) {
      w.Step(kDt);
      const double d = ClosestPair(w);
      ASSERT_GE(d, -kTolerance) << "capsules overlap, offset " << offset << ", step " << i;
      closest = std::min(closest, d);
    }
    EXPECT_LT(closest, 0.15) << "they never met";
  }
}

// Two AI walkers sent past each other along one sidewalk (~16 m): they never overlap, steer
// round each other (passing with over 0.2 m between the capsules) and both reach their goals.
TEST(GroundWalkerCrowd, TwoAiWalkersPassEachOtherOnASidewalkAndBothArrive) {
  const auto town = testing::Town01();
  const auto& g = town->WalkerNav();
  const auto& cw = town->Crosswalks().front();
  const int a = AwayFrom(g, cw.nodes[0], cw.centre, 4);
  const int b = AwayFrom(g, a, cw.centre, 8);
  const Vec3 pa = g.Position(a), pb = g.Position(b);
  ASSERT_GT(Flat(pa, pb), 12.0);
  World w(town, 3);
  ASSERT_EQ(w.AddWalker(1, "walker.pedestrian.0001", {}, Pose::FromYaw(pa + Vec3(0, 0, 1.0), 0)), "");
  ASSERT_EQ(w.AddWalker(2, "walker.pedestrian.0002", {}, Pose::FromYaw(pb + Vec3(0, 0, 1.0), 0)), "");
  ASSERT_EQ(w.AddWalkerController(11, 1), "");
  ASSERT_EQ(w.AddWalkerController(12, 2), "");
  for (uint32_t c : {11u, 12u}) ASSERT_EQ(w.ControllerStart(c), "");
  ASSERT_EQ(w.ControllerGoTo(11, pb), "");
  ASSERT_EQ(w.ControllerGoTo(12, pa), "");
  double closest = 1e9, left1 = 1e9, left2 = 1e9;
  for (int i = 0; i < 600; ++i) {
    w.Step(kDt);
    const double d = ClosestPair(w);
    ASSERT_GE(d, -kTolerance) << "capsules overlap, step " << i;
    closest = std::min(closest, d);
    left1 = std::min(left1, Flat(w.Walker(1)->pose.position, pb));
    left2 = std::min(left2, Flat(w.Walker(2)->pose.position, pa));
  }
  std::printf("passing: closest %.2f m between the capsules, goals reached within %.2f and %.2f m\n", closest, left1, left2);
  EXPECT_LT(closest, 1.0) << "they never met";
  EXPECT_GT(closest, 0.2) << "they brushed past each other (no avoidance)";
  EXPECT_LT(left1, 0.5);
  EXPECT_LT(left2, 0.5);
}

// Twenty walkers spawned 0.35 m apart in a 5 x 4 block on open ground (every neighbour
// overlapping) move apart: no two overlap after 3 s.
TEST(GroundWalkerCrowd, ACrowdSpawnedOverlappingSeparates) {
  const auto town = testing::Town01();
  Vec3 at = Vec3::Zero(), dir = Vec3::UnitX();
  OpenGround(*town, &at, &dir);
  World w(town, 3);
  uint32_t id = 1;
  for (int i = 0; i < 5; ++i) {
    for (int j = 0; j < 4; ++j, ++id) {
      ASSERT_EQ(w.AddWalker(id, "walker.pedestrian.0001", {}, Pose::FromYaw(at + Vec3(0.35 * (i - 2), 0.35 * (j - 1.5), 1.0), 0)), "");
    }
  }
  ASSERT_LT(ClosestPair(w), -0.2);
  for (int i = 0; i < 60; ++i) w.Step(kDt);
  EXPECT_GE(ClosestPair(w), -kTolerance) << "still overlapping after 3 s";
}

// Twenty AI walkers spawned close together along a sidewalk (two files, 0.72 m apart, the capsules 0.68 m wide)
// wander for a minute: no two ever overlap, and they keep walking (no jam).
TEST(GroundWalkerCrowd, TwentyAiWalkersSpawnedCloseTogetherNeverOverlap) {
  const auto town = testing::Town01();
  const auto& g = town->WalkerNav();
  const auto& cw = town->Crosswalks().front();
  const int a = AwayFrom(g, cw.nodes[0], cw.centre, 4);
  const int b = AwayFrom(g, a, cw.centre, 4);
  const Vec3 pa = g.Position(a);
  const Vec3 along = (g.Position(b) - pa).normalized();
  const Vec3 side(-along.y(), along.x(), 0);
  World w(town, 3);
  ASSERT_EQ(w.SetPedestriansCrossFactor(0), "");
  for (uint32_t k = 0; k < 20; ++k) {
    const Vec3 p = pa + along * (0.72 * (k / 2)) + side * (k % 2 ? 0.36 : -0.36);
    ASSERT_EQ(w.AddWalker(k + 1, "walker.pedestrian.0001", {}, Pose::FromYaw(p + Vec3(0, 0, 1.0), 0)), "");
    ASSERT_EQ(w.AddWalkerController(101 + k, k + 1), "");
    ASSERT_EQ(w.ControllerStart(101 + k), "");
  }
  ASSERT_GE(ClosestPair(w), 0.0);
  double travelled = 0;
  for (int i = 0; i < 1200; ++i) {
    w.Step(kDt);
    ASSERT_GE(ClosestPair(w), -kTolerance) << "capsules overlap, step " << i;
    for (const auto& v : w.Walkers()) travelled += v.velocity.head<2>().norm() * kDt;
  }
  std::printf("crowd: 20 walkers walked %.0f m in 60 s\n", travelled);
  EXPECT_GT(travelled, 20 * 40.0) << "the crowd is jammed";
}

}  // namespace
}  // namespace lockstep::ground
