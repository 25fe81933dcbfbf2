// The walker AI (controller.ai.walker) in CARLA's Town01: its random choices come from the
// run seed and, after world.set_pedestrians_seed, from that seed too.
#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "lockstep/ground/world.h"
#include "test_towns.h"

namespace lockstep::ground {
namespace {

constexpr double kDt = 0.05;

// Ten AI walkers of Populate(seed 9) after 30 s; pedestrians_seed 0 = none sent.
std::vector<Vec3> WanderedPositions(uint64_t pedestrians_seed) {
  World w(testing::Town01(), 9);
  const auto rep = Populate(&w, 0, 10, 9, 10);
  EXPECT_EQ(rep.controllers.size(), 10u);
  if (pedestrians_seed) w.SetPedestriansSeed(pedestrians_seed);
  for (int i = 0; i < 600; ++i) w.Step(kDt);
  std::vector<Vec3> out;
  for (const auto& v : w.Walkers()) out.push_back(v.pose.position);
  return out;
}

TEST(GroundWalkerNav, ThePedestriansSeedDecidesTheWanderChoices) {
  const auto base = WanderedPositions(0), again = WanderedPositions(0);
  const auto seeded = WanderedPositions(77), seeded_again = WanderedPositions(77), other = WanderedPositions(78);
  ASSERT_EQ(base.size(), 10u);
  EXPECT_EQ(base, again);
  EXPECT_EQ(seeded, seeded_again);
  auto moved_apart = [](const std::vector<Vec3>& a, const std::vector<Vec3>& b) {
    int n = 0;
    for (size_t k = 0; k < a.size(); ++k) n += (a[k] - b[k]).norm() > 1.0;
    return n;
  };
  EXPECT_GE(moved_apart(base, seeded), 3) << "set_pedestrians_seed did not change the walkers' choices";
  EXPECT_GE(moved_apart(seeded, other), 3) << "another pedestrians seed made the same choices";
}

}  // namespace
}  // namespace lockstep::ground
