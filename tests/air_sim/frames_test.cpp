#include <gtest/gtest.h>

#include <numbers>

#include "lockstep/air/frames.h"

namespace lockstep::air {
namespace {

constexpr double kPi = std::numbers::pi;

TEST(air_frames, EnuNedPositionsRelativeToSpawn) {
  const Vec3 spawn(10, 20, 1);
  const Vec3 p_world(13, 21, 3);  // 3 m east, 1 m north, 2 m up of spawn
  const Vec3 ned = WorldToAirSimPosition(p_world, spawn);
  EXPECT_TRUE(ned.isApprox(Vec3(1, 3, -2)));
  EXPECT_TRUE(AirSimToWorldPosition(ned, spawn).isApprox(p_world));
}

TEST(air_frames, EulerRoundTripAndSigns) {
  const Quat q = FromEuler(0.1, -0.2, 1.0);
  const Euler e = ToEuler(q);
  EXPECT_NEAR(e.roll, 0.1, 1e-12);
  EXPECT_NEAR(e.pitch, -0.2, 1e-12);
  EXPECT_NEAR(e.yaw, 1.0, 1e-12);
  // Positive FLU pitch tilts the thrust axis forward (nose down).
  const Vec3 up = FromEuler(0, 0.3, 0) * Vec3::UnitZ();
  EXPECT_GT(up.x(), 0.2);
  // Positive roll: right wing down, thrust tilts to the right (-y).
  const Vec3 up2 = FromEuler(0.3, 0, 0) * Vec3::UnitZ();
  EXPECT_LT(up2.y(), -0.2);
}

TEST(air_frames, OrientationToAirSim) {
  // Facing north in ENU (yaw pi/2) is yaw 0 in NED.
  EXPECT_NEAR(EnuYawToNedYaw(kPi / 2), 0, 1e-12);
  EXPECT_NEAR(EnuYawToNedYaw(0), kPi / 2, 1e-12);  // east
  const Euler enu{0.1, 0.2, 0.7};
  const Quat q_ned = EnuFluToNedFrd(FromEuler(enu));
  const Euler ned = ToEuler(q_ned);  // same Z-Y-X formula in NED/FRD
  const Euler expect = EnuEulerToNedEuler(enu);
  EXPECT_NEAR(ned.roll, expect.roll, 1e-12);
  EXPECT_NEAR(ned.pitch, expect.pitch, 1e-12);
  EXPECT_NEAR(ned.yaw, expect.yaw, 1e-12);
  EXPECT_NEAR(ned.pitch, -0.2, 1e-12);
  // Body forward axis maps to the same physical direction.
  const Vec3 fwd_enu = FromEuler(enu) * Vec3::UnitX();
  const Vec3 fwd_ned = q_ned * Vec3::UnitX();
  EXPECT_TRUE(EnuToNed(fwd_enu).isApprox(fwd_ned, 1e-12));
  EXPECT_TRUE(NedFrdToEnuFlu(q_ned).isApprox(FromEuler(enu), 1e-12) ||
              NedFrdToEnuFlu(q_ned).coeffs().isApprox(-FromEuler(enu).coeffs(), 1e-12));
  const Euler back = NedEulerToEnuEuler(expect);
  EXPECT_NEAR(back.yaw, 0.7, 1e-12);
}

TEST(air_frames, WrapAngle) {
  EXPECT_NEAR(WrapAngle(3 * kPi), kPi, 1e-12);
  EXPECT_NEAR(WrapAngle(-kPi / 2 - 2 * kPi), -kPi / 2, 1e-12);
  EXPECT_NEAR(WrapAngle(0.3), 0.3, 1e-15);
}

}  // namespace
}  // namespace lockstep::air
