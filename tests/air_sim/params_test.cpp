#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

#include "lockstep/air/params.h"

namespace lockstep::air {
namespace {

std::string ErrorOf(const std::function<void()>& f) {
  try {
    f();
  } catch (const std::invalid_argument& e) {
    return e.what();
  }
  return "<no error>";
}

TEST(air_params, GenericQuadDerivedValuesMatchAirSim) {
  const MultirotorParams p;
  const DerivedParams d = DeriveParams(p);
  ASSERT_EQ(d.rotors.size(), 4u);
  // Max thrust and torque per rotor from C_T rho n^2 D^4 and C_P rho n^2 D^5 / (2 pi).
  EXPECT_NEAR(d.max_thrust_per_rotor, 4.179, 0.002);
  EXPECT_NEAR(d.max_torque_per_rotor, 0.0556, 0.0002);
  // Hover near 59 % throttle.
  EXPECT_NEAR(d.hover_throttle, 0.587, 0.005);
  // Inertia: box of 0.78 kg + four 0.055 kg point masses at 0.2275 m, X layout, 2.5 cm low.
  const double mb = 0.78, a = 0.2275 / std::sqrt(2.0);
  const double rz = 0.025;  // hubs below the centre of mass
  const double ixx = mb / 12 * (0.11 * 0.11 + 0.04 * 0.04) + 4 * 0.055 * (a * a + rz * rz);
  const double izz = mb / 12 * (0.18 * 0.18 + 0.11 * 0.11) + 4 * 0.055 * 0.2275 * 0.2275;
  EXPECT_NEAR(d.inertia(0, 0), ixx, 1e-12);
  EXPECT_NEAR(d.inertia(2, 2), izz, 1e-12);
  EXPECT_NEAR(d.inertia(0, 1), 0, 1e-12);
  // Mixer: X layout, roll from y, pitch from -x, yaw opposite the spin; balanced.
  double sr = 0, sp = 0, sy = 0;
  for (const RotorGeometry& r : d.rotors) {
    EXPECT_NEAR(std::abs(r.mix_roll), 1.0, 1e-12);
    EXPECT_NEAR(std::abs(r.mix_pitch), 1.0, 1e-12);
    sr += r.mix_roll;
    sp += r.mix_pitch;
    sy += r.mix_yaw;
  }
  EXPECT_NEAR(sr, 0, 1e-12);
  EXPECT_NEAR(sp, 0, 1e-12);
  EXPECT_NEAR(sy, 0, 1e-12);
  // AirSim's six drag faces at +-body_box with the rotors folded in.
  ASSERT_EQ(d.faces.size(), 6u);
  const double pi = std::numbers::pi, dia = 0.2286, hgt = 0.01;
  for (const DragFace& f : d.faces) {
    const int axis = f.normal.x() != 0 ? 0 : (f.normal.y() != 0 ? 1 : 2);
    const double expect[3] = {0.11 * 0.04 + 4 * pi * dia * hgt, 0.18 * 0.04 + 4 * pi * dia * hgt, 0.18 * 0.11 + 4 * pi * dia * dia};
    EXPECT_NEAR(f.area, expect[axis], 1e-12);
    EXPECT_TRUE(f.position.isApprox(f.normal * p.body_box[axis]));
  }
  // Hubs 2.5 cm below the centre of mass (AirSim rotor_z, FRD +0.025).
  EXPECT_NEAR(d.rotors[0].position.z(), -0.025, 1e-12);
  EXPECT_NEAR(RestHeight(d), p.contact_radius + 0.025, 1e-12);
}

TEST(air_params, HexaAndPlusLayouts) {
  MultirotorParams p;
  p.frame = FrameType::kHexaX;
  DerivedParams d = DeriveParams(p);
  EXPECT_EQ(d.rotors.size(), 6u);
  double sy = 0;
  for (const RotorGeometry& r : d.rotors) sy += r.mix_yaw;
  EXPECT_NEAR(sy, 0, 1e-12);
  EXPECT_LT(d.hover_throttle, 0.587);  // 6 rotors carry the same mass (minus nothing)
  p.frame = FrameType::kQuadPlus;
  d = DeriveParams(p);
  EXPECT_EQ(d.rotors.size(), 4u);
  EXPECT_NEAR(d.rotors[0].position.x(), 0.2275, 1e-12);
  EXPECT_EQ(d.rotors[0].position.y(), 0.0);
  EXPECT_EQ(d.rotors[0].mix_roll, 0.0);
}

TEST(air_params, YamlLoadsNestedAndDottedKeys) {
  const MultirotorParams p = LoadParamsYaml(
      "frame: hexa_x\n"
      "mass: 1.5\n"
      "body_box: [0.2, 0.2, 0.05]\n"
      "rotor:\n"
      "  max_rpm: 7000\n"
      "gains.velocity_p_xy: 0.3\n"
      "gains:\n"
      "  angle_rate_p: [0.3, 0.3, 0.2]\n");
  EXPECT_EQ(p.frame, FrameType::kHexaX);
  EXPECT_DOUBLE_EQ(p.mass, 1.5);
  EXPECT_DOUBLE_EQ(p.body_box.x(), 0.2);
  EXPECT_DOUBLE_EQ(p.rotor.max_rpm, 7000);
  EXPECT_DOUBLE_EQ(p.gains.velocity_p_xy, 0.3);
  EXPECT_DOUBLE_EQ(p.gains.angle_rate_p.z(), 0.2);
  EXPECT_DOUBLE_EQ(p.arm_length, 0.2275);  // untouched default
}

TEST(air_params, YamlContactSpheres) {
  const MultirotorParams p = LoadParamsYaml(
      "contact_spheres:\n"
      "  - {center: [0, 0, -0.05], radius: 0.1}\n"
      "  - {center: [0.2, 0, 0], radius: 0.03}\n");
  ASSERT_EQ(p.contact_spheres.size(), 2u);
  EXPECT_DOUBLE_EQ(p.contact_spheres[0].center.z(), -0.05);
  EXPECT_DOUBLE_EQ(p.contact_spheres[1].radius, 0.03);
  EXPECT_NEAR(RestHeight(DeriveParams(p)), 0.15, 1e-12);
  const std::string e = ErrorOf([] { LoadParamsYaml("contact_spheres:\n  - {center: [0, 0, 0], radus: 1}\n"); });
  EXPECT_NE(e.find("line 2"), std::string::npos) << e;
  EXPECT_NE(e.find("contact_spheres.radus"), std::string::npos) << e;
}

TEST(air_params, YamlUnknownKeyNamedWithLine) {
  const std::string e = ErrorOf([] { LoadParamsYaml("mass: 1.2\n\nmasss: 3\n"); });
  EXPECT_NE(e.find("line 3"), std::string::npos) << e;
  EXPECT_NE(e.find("'masss'"), std::string::npos) << e;
  const std::string e2 = ErrorOf([] { LoadParamsYaml("rotor:\n  max_rpm: 6000\n  bogus: 1\n"); });
  EXPECT_NE(e2.find("line 3"), std::string::npos) << e2;
  EXPECT_NE(e2.find("rotor.bogus"), std::string::npos) << e2;
}

TEST(air_params, YamlBadValueNamedWithLine) {
  const std::string e = ErrorOf([] { LoadParamsYaml("frame: quad_x\nmass: heavy\n"); });
  EXPECT_NE(e.find("line 2"), std::string::npos) << e;
  EXPECT_NE(e.find("mass"), std::string::npos) << e;
  EXPECT_NE(e.find("heavy"), std::string::npos) << e;
  const std::string e2 = ErrorOf([] { LoadParamsYaml("frame: octo\n"); });
  EXPECT_NE(e2.find("line 1"), std::string::npos) << e2;
  EXPECT_NE(e2.find("octo"), std::string::npos) << e2;
  const std::string e3 = ErrorOf([] { LoadParamsYaml("body_box: [1, 2]\n"); });
  EXPECT_NE(e3.find("body_box"), std::string::npos) << e3;
  // Semantic check after loading.
  const std::string e4 = ErrorOf([] { LoadParamsYaml("mass: 0.1\n"); });
  EXPECT_NE(e4.find("mass"), std::string::npos) << e4;
  const std::string e5 = ErrorOf([] { LoadParamsYaml("mass: [1\n"); });
  EXPECT_NE(e5.find("line"), std::string::npos) << e5;
}

TEST(air_params, BlueprintAttributes) {
  const MultirotorParams p = ParamsFromAttributes(
      {{"mass", "1.2"}, {"frame", "hexa_x"}, {"body_box", "0.2,0.12,0.05"}, {"rotor.max_rpm", "7000"}});
  EXPECT_DOUBLE_EQ(p.mass, 1.2);
  EXPECT_EQ(p.frame, FrameType::kHexaX);
  EXPECT_DOUBLE_EQ(p.body_box.y(), 0.12);
  EXPECT_DOUBLE_EQ(p.rotor.max_rpm, 7000);
  std::string e = ErrorOf([] { ParamsFromAttributes({{"wingspan", "2"}}); });
  EXPECT_NE(e.find("unknown multirotor attribute 'wingspan'"), std::string::npos) << e;
  e = ErrorOf([] { ParamsFromAttributes({{"mass", "1.2kg"}}); });
  EXPECT_NE(e.find("'mass'"), std::string::npos) << e;
  EXPECT_NE(e.find("1.2kg"), std::string::npos) << e;
  e = ErrorOf([] { ParamsFromAttributes({{"mass", "nan"}}); });
  EXPECT_NE(e.find("'mass'"), std::string::npos) << e;
  e = ErrorOf([] { ParamsFromAttributes({{"frame", "tri"}}); });
  EXPECT_NE(e.find("quad_x, quad_plus or hexa_x"), std::string::npos) << e;
  e = ErrorOf([] { ParamsFromAttributes({{"mass", "50"}}); });
  EXPECT_NE(e.find("too heavy"), std::string::npos) << e;
  e = ErrorOf([] { ParamsFromAttributes({{"restitution", "1.5"}}); });
  EXPECT_NE(e.find("restitution"), std::string::npos) << e;
  const auto keys = ParamKeys();
  EXPECT_NE(std::find(keys.begin(), keys.end(), "gains.velocity_p_xy"), keys.end());
}

}  // namespace
}  // namespace lockstep::air
