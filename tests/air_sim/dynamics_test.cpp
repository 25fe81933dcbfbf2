// Rigid-body, rotor and drag physics against closed-form results.
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

#include "sim_fixture.h"

namespace lockstep::air {
namespace {
using testing::NoDrag;
using testing::Sim;

TEST(air_dynamics, FreeFallMatchesGravity) {
  Sim sim;
  sim.model.statics.has_ground = false;
  sim.Add(1, NoDrag());
  DroneState& d = sim.D(1);
  d.position = Vec3(0, 0, 100);
  const double z0 = d.position.z();
  const double g = sim.model.gravity;
  for (int tick = 1; tick <= 40; ++tick) {
    sim.Tick();
    const double t = tick * sim.dt;
    // Fitted acceleration from z(t) = z0 - a t^2 / 2 and from v(t) = -a t.
    const double a_pos = 2 * (z0 - d.position.z()) / (t * t);
    const double a_vel = -d.velocity.z() / t;
    ASSERT_NEAR(a_pos, g, 1e-3 * g) << "t=" << t;
    ASSERT_NEAR(a_vel, g, 1e-3 * g) << "t=" << t;
    ASSERT_NEAR(d.position.x(), 0, 1e-12);
  }
  EXPECT_EQ(d.landed, LandedState::kFlying);
}

// AirSim's drag factor of a face (MultiRotorPhysicsBody::createDragVertices), computed here
// from AirSim's formulas: (box face + rotors folded in) * C_d / 2; force = factor rho v^2.
double AirSimDragFactor(const MultirotorParams& p, int axis) {
  const double d = p.rotor.propeller_diameter, h = p.rotor.propeller_height, n = 4;
  const Vec3& b = p.body_box;
  const double area[3] = {b.y() * b.z() + n * std::numbers::pi * d * h, b.x() * b.z() + n * std::numbers::pi * d * h,
                          b.x() * b.y() + n * std::numbers::pi * d * d};
  return area[axis] * p.linear_drag_coefficient / 2;
}

TEST(air_dynamics, TerminalVelocityMatchesAirSim) {
  // Motors off, falling level: AirSim's bottom face (body + 4 pi D^2) balances the weight at
  // v_t = sqrt(m g / (factor rho)) = 8.5 m/s for the generic quad (Lockstep's earlier bare-face
  // model gave 16.4 m/s).
  Sim sim;
  sim.model.statics.has_ground = false;
  MultirotorParams p;
  sim.Add(1, p);
  DroneState& d = sim.D(1);
  d.position = Vec3(0, 0, 1000);
  const double g = sim.model.gravity, rho = sim.env.air_density;
  const double vt = std::sqrt(p.mass * g / (AirSimDragFactor(p, 2) * rho));
  EXPECT_NEAR(vt, 8.5, 0.05);
  // Closed form of the fall: v(t) = v_t tanh(g t / v_t).
  sim.Run(1.0);
  EXPECT_NEAR(-d.velocity.z(), vt * std::tanh(g * 1.0 / vt), 0.01 * vt);
  sim.Run(9.0);
  EXPECT_NEAR(-d.velocity.z(), vt, 0.005 * vt) << "analytic v_t " << vt;
  EXPECT_LT(d.angular_velocity.norm(), 1e-6);
}

TEST(air_dynamics, TerminalVelocityOfTheFacesOption) {
  // drag_model: faces (Lockstep's earlier model): body top + 4 rotor discs pi D^2 / 4.
  Sim sim;
  sim.model.statics.has_ground = false;
  MultirotorParams p;
  p.drag_model = DragModel::kFaces;
  sim.Add(1, p);
  DroneState& d = sim.D(1);
  d.position = Vec3(0, 0, 1000);
  const double g = sim.model.gravity, rho = sim.env.air_density, cd = p.linear_drag_coefficient;
  const double area = p.body_box.x() * p.body_box.y() + 4 * std::numbers::pi * std::pow(p.rotor.propeller_diameter, 2) / 4;
  const double vt = std::sqrt(2 * p.mass * g / (rho * cd * area));
  EXPECT_NEAR(vt, 16.4, 0.1);
  sim.Run(15.0);
  EXPECT_NEAR(-d.velocity.z(), vt, 0.005 * vt);
}

TEST(air_dynamics, FrontalDragMatchesAirSim) {
  // A 5 m/s head wind on a level drone, motors off: at the first sub-step the x-acceleration is
  // AirSim's front face (body y z + 4 pi D h) * C_d / 2 * rho v^2 / m.
  Sim sim;
  sim.model.statics.has_ground = false;
  MultirotorParams p;
  sim.Add(1, p);
  sim.D(1).position = Vec3(0, 0, 100);
  sim.env.wind = Vec3(-5, 0, 0);  // air moving west: the drone's +x face meets it
  sim.dt = 0.001;
  sim.Tick();
  const double drag = AirSimDragFactor(p, 0) * sim.env.air_density * 25;
  EXPECT_NEAR(drag, 0.1648, 0.001);  // N, AirSim's frontal drag at 5 m/s
  EXPECT_NEAR(sim.D(1).acceleration.x(), -drag / p.mass, 1e-3 * drag / p.mass);
}

TEST(air_dynamics, NoDragBelowAirSimThreshold) {
  // AirSim drags a face only above 0.1 m/s of face speed.
  Sim sim;
  sim.model.statics.has_ground = false;
  sim.Add(1);
  sim.D(1).position = Vec3(0, 0, 100);
  sim.env.wind = Vec3(-0.09, 0, 0);
  sim.dt = 0.001;
  sim.Tick();
  EXPECT_EQ(sim.D(1).acceleration.x(), 0.0);
  sim.env.wind = Vec3(-0.2, 0, 0);
  sim.Tick();
  EXPECT_LT(sim.D(1).acceleration.x(), -1e-4);
}

TEST(air_dynamics, RotationalDragOfBothModels) {
  // AirSim's combined face velocity v + w x r: its face centres lie on their normals, so a pure
  // spin feels no drag. The faces option's rotor discs sit off-axis and damp it: each disc's
  // face turning into the air gets ca A (w y)^2 at lever |y|.
  for (DragModel model : {DragModel::kAirSim, DragModel::kFaces}) {
    Sim sim;
    sim.model.statics.has_ground = false;
    MultirotorParams p;
    p.drag_model = model;
    sim.Add(1, p);
    DroneState& d = sim.D(1);
    d.position = Vec3(0, 0, 100);
    d.angular_velocity = Vec3(10, 0, 0);  // rad/s about body x
    sim.dt = 0.001;
    sim.Tick();
    const double ixx = sim.model.drones[0].derived.inertia(0, 0);
    if (model == DragModel::kAirSim) {
      EXPECT_EQ(d.angular_acceleration.x(), 0.0);
      continue;
    }
    const double y = 0.2275 / std::sqrt(2.0), area = std::numbers::pi * 0.2286 * 0.2286 / 4;
    const double ca = 0.5 * sim.env.air_density * p.angular_drag_coefficient;
    const double torque = 4 * ca * area * std::pow(10 * y, 2) * y;
    EXPECT_NEAR(d.angular_acceleration.x(), -torque / ixx, 0.02 * torque / ixx);
  }
}

TEST(air_dynamics, MotorLagIsFirstOrder) {
  Sim sim;
  sim.model.statics.has_ground = false;
  sim.Add(1, NoDrag());
  sim.D(1).position = Vec3(0, 0, 100);
  sim.dt = 0.005;  // one time constant
  sim.Send(1, cmd::Arm{});
  sim.Send(1, cmd::MoveByMotorPwms{{1, 1, 1, 1}, 1.0});
  sim.Tick();
  EXPECT_NEAR(sim.D(1).rotors[0].signal, 1 - std::exp(-1.0), 1e-9);
  sim.Tick();
  EXPECT_NEAR(sim.D(1).rotors[0].signal, 1 - std::exp(-2.0), 1e-9);
  EXPECT_NEAR(sim.D(1).rotors[0].thrust, (1 - std::exp(-2.0)) * 4.179, 0.01);
}

TEST(air_dynamics, DifferentialThrustRollsTheRightWay) {
  // Left rotors (y > 0) at full thrust, right ones off: positive roll torque tau_x = sum y T.
  Sim sim;
  sim.model.statics.has_ground = false;
  sim.Add(1, NoDrag());
  sim.D(1).position = Vec3(0, 0, 100);
  const DerivedParams& dp = sim.model.drones[0].derived;
  std::vector<double> pwm;
  double tau = 0;
  for (const RotorGeometry& r : dp.rotors) {
    pwm.push_back(r.position.y() > 0 ? 1.0 : 0.0);
  }
  sim.dt = 0.02;
  sim.Send(1, cmd::Arm{});
  sim.Send(1, cmd::MoveByMotorPwms{pwm, 1.0});
  sim.Tick();
  for (std::size_t i = 0; i < dp.rotors.size(); ++i) tau += dp.rotors[i].position.y() * sim.D(1).rotors[i].thrust;
  EXPECT_GT(tau, 0);
  EXPECT_GT(sim.D(1).angular_velocity.x(), 0.1);
  EXPECT_NEAR(sim.D(1).angular_velocity.y(), 0, 1e-9);
}

// Hover against AirSim's rotor constants (not DeriveParams): see
// air_fidelity.HoverThrottleFromAirSimsRotorConstants.

void HoverFrame(FrameType frame) {
  Sim sim;
  MultirotorParams p;
  p.frame = frame;
  sim.Add(1, p);
  sim.TakeOff(1);
  sim.Run(4.0);
  const DroneState& d = sim.D(1);
  EXPECT_NEAR(d.position.z(), sim.model.drones[0].spawn.position.z() + 2.0, 0.1) << ToString(frame);
  EXPECT_LT(d.velocity.norm(), 0.05) << ToString(frame);
  const Euler e = ToEuler(d.orientation);
  EXPECT_LT(std::abs(e.roll) + std::abs(e.pitch), 0.01) << ToString(frame);
  EXPECT_NEAR(d.total_thrust, p.mass * sim.model.gravity, 0.01 * p.mass * sim.model.gravity);
}

TEST(air_dynamics, HexaXHovers) { HoverFrame(FrameType::kHexaX); }
TEST(air_dynamics, QuadPlusHovers) { HoverFrame(FrameType::kQuadPlus); }

TEST(air_dynamics, ThinAirNeedsMoreThrottle) {
  Sim sim;
  sim.Add(1);
  sim.env.air_density = 1.0;
  sim.TakeOff(1);
  sim.Run(3.0);
  double signal = 0;
  for (int i = 0; i < 4; ++i) signal += sim.D(1).rotors[i].signal / 4;
  EXPECT_NEAR(signal, sim.model.drones[0].derived.hover_throttle * 1.225, 0.01);
}

}  // namespace
}  // namespace lockstep::air
