// Procedural actors: distinct models that fill their blueprints' boxes.
#include <gtest/gtest.h>

#include <set>

#include "lockstep/render/models.h"

namespace lockstep::render {
namespace {

Eigen::AlignedBox3d Bounds(const Model& m) {
  Eigen::AlignedBox3d b;
  for (const auto& v : m.vertices) b.extend(Vec3(v.position[0], v.position[1], v.position[2]));
  return b;
}

std::uint64_t Signature(const Model& m) {
  std::uint64_t h = 1469598103934665603ull;
  for (const auto& v : m.vertices) {
    for (float p : v.position) h = (h ^ static_cast<std::uint64_t>(std::lround(p * 1000))) * 1099511628211ull;
    for (auto c : v.rgba) h = (h ^ c) * 1099511628211ull;
  }
  return h;
}

TEST(Models, AtLeastSixteenDistinctVehiclesFillingTheirBoxes) {
  const auto& styles = VehicleStyles();
  ASSERT_GE(styles.size(), 16u);
  std::set<std::uint64_t> shapes;
  const Vec3 he(2.2, 0.95, 0.75);
  for (const auto& s : styles) {
    const Model m = BuildVehicle(s, he);
    ASSERT_GT(m.TriangleCount(), 20u) << s;
    const auto b = Bounds(m);
    for (int k = 0; k < 3; ++k) {
      EXPECT_LE(b.max()[k], he[k] + 0.03) << s << " axis " << k;
      EXPECT_GE(b.min()[k], -he[k] - 0.03) << s << " axis " << k;
      if (s != "motorbike" && s != "bicycle") {
        EXPECT_GT(b.max()[k] - b.min()[k], 1.6 * he[k]) << s << " fills its box along " << k;
      }
    }
    shapes.insert(Signature(m));
  }
  EXPECT_EQ(shapes.size(), styles.size()) << "every style is a different model";
  // A truck's box makes a bigger model than a microcar's.
  EXPECT_GT(Bounds(BuildVehicle("truck", Vec3(4, 1.2, 1.6))).volume(), 10 * Bounds(BuildVehicle("microcar", Vec3(1.2, 0.7, 0.7))).volume());
}

TEST(Models, BlueprintsMapToStylesAndClasses) {
  EXPECT_EQ(VehicleStyleFor("vehicle.lockstep.minivan"), "minivan");
  EXPECT_EQ(VehicleStyleFor("vehicle.carlamotors.firetruck"), "firetruck");
  EXPECT_EQ(VehicleStyleFor("vehicle.lockstep.bus"), "bus");
  EXPECT_EQ(VehicleTag("vehicle.lockstep.bus"), 16);
  EXPECT_EQ(VehicleTag("vehicle.lockstep.truck"), 15);
  EXPECT_EQ(VehicleTag("vehicle.yamaha.yzf"), 14);
  EXPECT_EQ(VehicleTag("vehicle.lockstep.motorbike"), 18);
  EXPECT_EQ(VehicleStyleFor("vehicle.tesla.model3"), VehicleStyleFor("vehicle.tesla.model3")) << "deterministic";
}

TEST(Models, FiftyDistinctPedestrians) {
  std::set<std::uint64_t> looks;
  for (int i = 0; i < 50; ++i) {
    const Model m = BuildWalker(i, Vec3(0.25, 0.25, 0.85 + 0.01 * (i % 10)));
    const auto b = Bounds(m);
    EXPECT_LE(b.max().z(), m.half_extents.z() + 1e-6);
    EXPECT_GE(b.min().z(), -m.half_extents.z() - 1e-6);
    EXPECT_GT(b.max().z() - b.min().z(), 1.9 * m.half_extents.z());
    looks.insert(Signature(m));
  }
  EXPECT_EQ(looks.size(), 50u);
  EXPECT_EQ(WalkerVariant("walker.pedestrian.0007"), 7);
}

TEST(Models, DronesHaveOneRotorPerArm) {
  DroneShape quad;
  EXPECT_EQ(BuildDrone(quad).rotors.size(), 4u);
  DroneShape hexa;
  hexa.frame = "hexa_x";
  const Model h = BuildDrone(hexa);
  EXPECT_EQ(h.rotors.size(), 6u);
  for (const auto& r : h.rotors) EXPECT_NEAR(r.hub.head<2>().norm(), hexa.arm_length, 1e-9);
}

}  // namespace
}  // namespace lockstep::render
