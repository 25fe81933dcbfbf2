// Flight controller: mixer alone, then every command in the world.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <numbers>

#include "sim_fixture.h"

namespace lockstep::air {
namespace {
using testing::Sim;
constexpr double kPi = std::numbers::pi;

TEST(air_controller, MixerKeepsThrustAndLimitsYaw) {
  const DerivedParams d = DeriveParams(MultirotorParams{});
  std::array<double, kMaxRotors> m{};
  Mix(d, 0.6, Vec3(0.1, 0, 0), &m);
  for (int i = 0; i < 4; ++i) {
    EXPECT_NEAR(m[i], 0.6 + 0.1 * d.rotors[i].mix_roll, 1e-12);
  }
  // Huge yaw request at hover: yaw is limited so no motor leaves [0, 1] and the sum is kept.
  Mix(d, 0.6, Vec3(0, 0, 5.0), &m);
  double sum = 0;
  for (int i = 0; i < 4; ++i) {
    EXPECT_GE(m[i], 0.0);
    EXPECT_LE(m[i], 1.0);
    sum += m[i];
  }
  EXPECT_NEAR(sum, 2.4, 1e-12);
  EXPECT_NEAR(m[0] - 0.6, 0.4 * d.rotors[0].mix_yaw, 1e-12);
  // Throttle above 1 with roll: shifted down, roll difference kept.
  Mix(d, 1.0, Vec3(0.2, 0, 0), &m);
  double hi = 0, lo = 1;
  for (int i = 0; i < 4; ++i) {
    hi = std::max(hi, m[i]);
    lo = std::min(lo, m[i]);
  }
  EXPECT_NEAR(hi, 1.0, 1e-12);
  EXPECT_NEAR(hi - lo, 0.4, 1e-12);
}

TEST(air_controller, ControllerAloneLevelsTheDrone) {
  // Controller in isolation: a tilted drone asked to hold level gets a restoring torque.
  const MultirotorParams p;
  const DerivedParams d = DeriveParams(p);
  ControllerState st;
  st.gains = p.gains;
  ControlGoal g;
  g.horizontal = ControlGoal::Horizontal::kAngle;
  g.vertical = ControlGoal::Vertical::kThrottle;
  g.throttle = 0.6;
  g.yaw_is_rate = true;
  KinematicsView k{Vec3::Zero(), FromEuler(0.2, -0.1, 0), Vec3::Zero(), Vec3::Zero()};
  std::array<double, kMaxRotors> m{};
  ControllerUpdate(p, d, g, k, 9.80665, 1.0, 0.001, &st, &m);
  EXPECT_LT(st.rate_goal.x(), 0);  // roll back
  EXPECT_GT(st.rate_goal.y(), 0);  // pitch back
  // AirSim's effective angle loop: clip(2.5 e, -1, 1) * max_angle_rate 2.5 rad/s.
  EXPECT_NEAR(st.rate_goal.x(), -2.5 * 0.2 * 2.5, 0.05);
  double tau_x = 0;
  for (int i = 0; i < 4; ++i) tau_x += d.rotors[i].position.y() * m[i];
  EXPECT_LT(tau_x, 0);
}

TEST(air_controller, TakeoffSettlesAtTwoMetres) {
  Sim sim;
  sim.Add(1);
  const double z0 = sim.D(1).position.z();
  sim.Send(1, cmd::Arm{});
  const CommandId t = sim.Send(1, cmd::Takeoff{});
  sim.Tick();
  EXPECT_EQ(sim.Status(t), CommandStatus::kRunning);
  // Within 0.1 m of z0 + 2 before 5 s, and stays there.
  double settled_at = -1;
  double max_z = 0;
  for (int i = 1; i < 200; ++i) {
    sim.Tick();
    const double err = std::abs(sim.D(1).position.z() - (z0 + 2.0));
    max_z = std::max(max_z, sim.D(1).position.z() - z0);
    if (err < 0.1 && settled_at < 0) settled_at = sim.state.time;
    if (err >= 0.1) settled_at = -1;
  }
  std::printf("takeoff: settled within 0.1 m at %.2f s, peak %.3f m\n", settled_at, max_z);
  EXPECT_GT(settled_at, 0);
  EXPECT_LT(settled_at, 5.0);
  EXPECT_LT(max_z, 2.1);
  EXPECT_EQ(sim.Status(t), CommandStatus::kCompleted);
  EXPECT_EQ(sim.D(1).landed, LandedState::kFlying);
  // AirSim view: z = -2 NED relative to spawn.
  EXPECT_NEAR(ToAirSim(sim.model.drones[0], sim.D(1)).position.z(), -2.0, 0.05);
}

TEST(air_controller, MoveToPositionTenMetres) {
  Sim sim;
  sim.Add(1);
  sim.TakeOff(1);
  const Vec3 start = sim.D(1).position;
  const Vec3 goal = start + Vec3(8, 6, 0);  // 10 m away
  const CommandId m = sim.Send(1, cmd::MoveToPosition{goal, 5.0});
  double overshoot = 0;
  const Vec3 dir = (goal - start).normalized();
  ASSERT_TRUE(sim.RunUntil(
      [&] {
        overshoot = std::max(overshoot, (sim.D(1).position - goal).dot(dir));
        return sim.Done(m);
      },
      20));
  EXPECT_EQ(sim.Status(m), CommandStatus::kCompleted);
  sim.Run(2.0);
  overshoot = std::max(overshoot, (sim.D(1).position - goal).dot(dir));
  std::printf("move 10 m: final error %.3f m, overshoot %.3f m\n", (sim.D(1).position - goal).norm(), overshoot);
  EXPECT_LT((sim.D(1).position - goal).norm(), 0.5);
  EXPECT_LT(overshoot, 1.0);
  EXPECT_LT(std::abs(sim.D(1).position.z() - goal.z()), 0.3);
}

TEST(air_controller, YawStepSettles) {
  Sim sim;
  sim.Add(1);
  sim.TakeOff(1);
  const CommandId r = sim.Send(1, cmd::RotateToYaw{kPi / 2, 10.0, 0.02});
  ASSERT_TRUE(sim.RunUntil([&] { return sim.Done(r); }, 10));
  EXPECT_EQ(sim.Status(r), CommandStatus::kCompleted);
  sim.Run(2.0);
  const double err = WrapAngle(YawOf(sim.D(1).orientation) - kPi / 2);
  std::printf("yaw step 90 deg: done at %.2f s, error %.3f deg\n", sim.last_report[r].time, err * 180 / kPi);
  EXPECT_LT(std::abs(err), 2 * kPi / 180);
  // And back the other way, across the +-pi seam.
  const CommandId r2 = sim.Send(1, cmd::RotateToYaw{-3.0, 10.0, 0.02});
  ASSERT_TRUE(sim.RunUntil([&] { return sim.Done(r2); }, 10));
  sim.Run(2.0);
  EXPECT_LT(std::abs(WrapAngle(YawOf(sim.D(1).orientation) + 3.0)), 2 * kPi / 180);
}

TEST(air_controller, VelocityCommandsWorldAndBody) {
  Sim sim;
  sim.Add(1, {}, Vec3::Zero(), kPi / 2);  // facing north
  sim.TakeOff(1);
  const CommandId v = sim.Send(1, cmd::MoveByVelocity{Vec3(2, 0, 0), 3.0});
  sim.Run(2.5);
  EXPECT_NEAR(sim.D(1).velocity.x(), 2.0, 0.2);
  EXPECT_NEAR(sim.D(1).velocity.y(), 0.0, 0.2);
  sim.Run(1.0);
  EXPECT_EQ(sim.Status(v), CommandStatus::kCompleted);
  // Body frame: forward while facing north = +y world.
  cmd::MoveByVelocity b{Vec3(2, 0, 0), 3.0};
  b.frame = VelocityFrame::kBody;
  sim.Send(1, b);
  sim.Run(2.5);
  EXPECT_NEAR(sim.D(1).velocity.y(), 2.0, 0.2);
  EXPECT_NEAR(sim.D(1).velocity.x(), 0.0, 0.2);
  // After the duration the drone hovers.
  sim.Run(4.0);
  EXPECT_LT(sim.D(1).velocity.norm(), 0.2);
}

TEST(air_controller, VelocityZHoldsAltitudeAndForwardOnlyTurns) {
  Sim sim;
  sim.Add(1);
  sim.TakeOff(1);
  cmd::MoveByVelocityZ c;
  c.vx = 0;
  c.vy = 3;
  c.z = 5;
  c.duration = 5;
  c.drivetrain = Drivetrain::kForwardOnly;
  c.yaw_mode = YawMode{false, 0};
  sim.Send(1, c);
  sim.Run(4.5);
  EXPECT_NEAR(sim.D(1).position.z(), 5.0, 0.2);
  EXPECT_NEAR(sim.D(1).velocity.y(), 3.0, 0.3);
  EXPECT_NEAR(WrapAngle(YawOf(sim.D(1).orientation) - kPi / 2), 0, 0.05);  // nose along travel
}

TEST(air_controller, AttitudeAndRateCommands) {
  Sim sim;
  sim.Add(1);
  sim.TakeOff(1);
  const double z = sim.D(1).position.z();
  // Pitch nose-down 0.1 rad at constant altitude: accelerates forward (east).
  sim.Send(1, cmd::MoveByRollPitchYawZ{0, 0.1, 0, z, 1.5});
  sim.Run(1.4);
  Euler e = ToEuler(sim.D(1).orientation);
  EXPECT_NEAR(e.pitch, 0.1, 0.02);
  EXPECT_GT(sim.D(1).velocity.x(), 0.5);
  EXPECT_NEAR(sim.D(1).position.z(), z, 0.15);
  sim.Send(1, cmd::Hover{});
  sim.Run(5);
  // Roll right with throttle: drifts towards -y; throttle 0.7 > hover climbs.
  sim.Send(1, cmd::MoveByRollPitchYawThrottle{0.1, 0, 0, 0.7, 1.0});
  const double y0 = sim.D(1).position.y(), z1 = sim.D(1).position.z();
  sim.Run(0.9);
  e = ToEuler(sim.D(1).orientation);
  EXPECT_NEAR(e.roll, 0.1, 0.02);
  EXPECT_LT(sim.D(1).position.y(), y0);
  EXPECT_GT(sim.D(1).position.z(), z1);
  sim.Send(1, cmd::Hover{});
  sim.Run(5);
  // Yaw rate with angle-rate command at altitude: turns CCW at about 0.5 rad/s.
  sim.Send(1, cmd::MoveByAngleRatesZ{Vec3(0, 0, 0.5), sim.D(1).position.z(), 2.0});
  sim.Run(1.5);
  EXPECT_NEAR(sim.D(1).angular_velocity.z(), 0.5, 0.1);
  sim.Send(1, cmd::MoveByAngleRatesThrottle{Vec3(0, 0, -0.5), 0.6, 1.0});
  sim.Run(0.9);
  EXPECT_NEAR(sim.D(1).angular_velocity.z(), -0.5, 0.1);
  sim.Send(1, cmd::MoveByRollPitchYawrateThrottle{0, 0, 0.4, 0.6, 1.5});
  sim.Run(1.4);
  EXPECT_NEAR(sim.D(1).angular_velocity.z(), 0.4, 0.1);
  const double yaw0 = YawOf(sim.D(1).orientation);
  sim.Send(1, cmd::RotateByYawRate{-0.3, 2.0});
  sim.Run(2.0);
  EXPECT_NEAR(WrapAngle(YawOf(sim.D(1).orientation) - yaw0), -0.3 * 2.0, 0.25);
}

TEST(air_controller, PathGoHomeAndLand) {
  Sim sim;
  sim.Add(1);
  sim.TakeOff(1);
  const Vec3 s = sim.D(1).position;
  const CommandId p = sim.Send(1, cmd::MoveOnPath{{s + Vec3(5, 0, 0), s + Vec3(5, 5, 1), s + Vec3(0, 5, 1)}, 3.0});
  double max_dev = 0;
  ASSERT_TRUE(sim.RunUntil(
      [&] {
        // Distance to the nearest path segment stays small.
        const Vec3 q = sim.D(1).position;
        const Vec3 pts[4] = {s, s + Vec3(5, 0, 0), s + Vec3(5, 5, 1), s + Vec3(0, 5, 1)};
        double best = 1e9;
        for (int i = 0; i < 3; ++i) {
          const Vec3 ab = pts[i + 1] - pts[i];
          const double u = std::clamp((q - pts[i]).dot(ab) / ab.squaredNorm(), 0.0, 1.0);
          best = std::min(best, (q - pts[i] - u * ab).norm());
        }
        max_dev = std::max(max_dev, best);
        return sim.Done(p);
      },
      30));
  EXPECT_EQ(sim.Status(p), CommandStatus::kCompleted);
  std::printf("path: max deviation %.3f m\n", max_dev);
  EXPECT_LT(max_dev, 1.0);
  EXPECT_LT((sim.D(1).position - (s + Vec3(0, 5, 1))).norm(), 0.3);
  const CommandId h = sim.Send(1, cmd::GoHome{});
  ASSERT_TRUE(sim.RunUntil([&] { return sim.Done(h); }, 20));
  EXPECT_EQ(sim.Status(h), CommandStatus::kCompleted);
  EXPECT_LT((sim.D(1).position.head<2>() - sim.model.drones[0].spawn.position.head<2>()).norm(), 0.3);
  const CommandId l = sim.Send(1, cmd::Land{});
  ASSERT_TRUE(sim.RunUntil([&] { return sim.Done(l); }, 20));
  EXPECT_EQ(sim.Status(l), CommandStatus::kCompleted);
  EXPECT_EQ(sim.D(1).landed, LandedState::kLanded);
  sim.Run(1.0);
  EXPECT_NEAR(sim.D(1).position.z(), sim.model.drones[0].spawn.position.z(), 0.01);
  EXPECT_LT(sim.D(1).total_thrust, 0.01);  // motors idle after landing
}

TEST(air_controller, TimeoutAndCancellation) {
  Sim sim;
  sim.Add(1);
  sim.TakeOff(1);
  const Vec3 far = sim.D(1).position + Vec3(100, 0, 0);
  const CommandId a = sim.Send(1, cmd::MoveToPosition{far, 5.0, 1.0});
  sim.Run(1.5);
  EXPECT_EQ(sim.Status(a), CommandStatus::kTimedOut);
  const CommandId b = sim.Send(1, cmd::MoveToPosition{far, 5.0});
  sim.Run(0.5);
  EXPECT_EQ(sim.Status(b), CommandStatus::kRunning);
  const CommandId c = sim.Send(1, cmd::MoveByVelocity{Vec3(0, 1, 0), 0.5});
  sim.Tick();
  EXPECT_EQ(sim.Status(b), CommandStatus::kCancelled);
  EXPECT_NE(sim.last_report[b].message.find("move_by_velocity"), std::string::npos);
  sim.Run(1.0);
  EXPECT_EQ(sim.Status(c), CommandStatus::kCompleted);
  // Runtime gains: a much softer velocity loop changes the response.
  ControllerGains soft = sim.model.drones[0].params.gains;
  soft.velocity_p_xy = 0.02;
  const CommandId gsc = sim.Send(1, cmd::SetGains{soft});
  sim.Tick();
  EXPECT_EQ(sim.Status(gsc), CommandStatus::kCompleted);
  EXPECT_DOUBLE_EQ(sim.D(1).controller.gains.velocity_p_xy, 0.02);
  sim.Send(1, cmd::MoveByVelocity{Vec3(2, 0, 0), 1.0});
  sim.Run(1.0);
  EXPECT_LT(sim.D(1).velocity.x(), 1.0);  // default gains reach ~2 m/s in 1 s
}

}  // namespace
}  // namespace lockstep::air

namespace lockstep::air {
namespace {

TEST(air_controller, LongPathAndForwardOnlyHeading) {
  // A 2,000-point polyline (a gentle arc) followed nose-first.
  Sim sim;
  sim.Add(1);
  sim.TakeOff(1);
  const Vec3 c = sim.D(1).position;
  cmd::MoveOnPath p;
  for (int i = 1; i <= 2000; ++i) {
    const double a = 0.5 * kPi * i / 2000.0;
    p.path.push_back(c + Vec3(10 * std::sin(a), 10 - 10 * std::cos(a), 0));
  }
  p.velocity = 3;
  p.drivetrain = Drivetrain::kForwardOnly;
  p.yaw_mode = YawMode{false, 0};
  const CommandId id = sim.Send(1, p);
  double max_heading_err = 0;
  int samples = 0;
  ASSERT_TRUE(sim.RunUntil(
      [&] {
        const DroneState& d = sim.D(1);
        if (d.velocity.head<2>().norm() > 2.0) {  // cruising: nose along the velocity
          const double course = std::atan2(d.velocity.y(), d.velocity.x());
          max_heading_err = std::max(max_heading_err, std::abs(WrapAngle(YawOf(d.orientation) - course)));
          ++samples;
        }
        return sim.Done(id);
      },
      20));
  EXPECT_EQ(sim.Status(id), CommandStatus::kCompleted);
  EXPECT_GT(samples, 20);
  EXPECT_LT(max_heading_err, 0.35);
  EXPECT_LT((sim.D(1).position - p.path.back()).norm(), 0.3);
}

}  // namespace
}  // namespace lockstep::air
