// Many drones, determinism, robustness and command validation.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>

#include "sim_fixture.h"

namespace lockstep::air {
namespace {
using testing::Sim;

TEST(air_world, TenDronesFlyAtOnce) {
  Sim sim;
  for (DroneId id = 10; id > 0; --id) {  // added out of order: stored and stepped by id
    MultirotorParams p;
    if (id % 3 == 0) p.frame = FrameType::kHexaX;
    if (id % 3 == 1) p.mass = 1.2;
    sim.Add(id, p, Vec3(3.0 * id, 0, 0));
  }
  ASSERT_EQ(sim.model.drones.size(), 10u);
  for (std::size_t i = 1; i < sim.model.drones.size(); ++i) EXPECT_LT(sim.model.drones[i - 1].id, sim.model.drones[i].id);
  std::map<DroneId, Vec3> goals;
  for (DroneId id = 1; id <= 10; ++id) {
    sim.Send(id, cmd::Arm{});
    goals[id] = Vec3(3.0 * id, 5.0 + id, 3.0 + 0.5 * id);
    sim.Send(id, cmd::MoveToPosition{goals[id], 3.0});
  }
  sim.Run(15.0);
  for (DroneId id = 1; id <= 10; ++id) {
    EXPECT_LT((sim.D(id).position - goals[id]).norm(), 0.5) << "drone " << id;
    EXPECT_EQ(sim.D(id).landed, LandedState::kFlying);
  }
}

std::vector<std::uint64_t> FlyScripted(std::uint64_t seed, double sigma, Vec3* end = nullptr) {
  Sim sim;
  sim.model.seed = seed;
  sim.env.turbulence_sigma = sigma;
  sim.env.wind = Vec3(1.0, -0.5, 0);
  sim.Add(1);
  sim.Add(2, {}, Vec3(5, 0, 0));
  std::vector<std::uint64_t> hashes;
  sim.Send(1, cmd::Arm{});
  sim.Send(2, cmd::Arm{});
  sim.Send(1, cmd::Takeoff{});
  sim.Send(2, cmd::MoveToPosition{Vec3(5, 10, 4), 4.0});
  for (int i = 0; i < 120; ++i) {
    if (i == 60) sim.Send(1, cmd::MoveByVelocity{Vec3(1, 1, 0.5), 2.0});
    sim.Tick();
    hashes.push_back(StateHash(sim.state));
  }
  if (end != nullptr) *end = sim.D(2).position;
  return hashes;
}

TEST(air_world, SameSeedAndCommandsGiveIdenticalTrajectories) {
  const auto a = FlyScripted(7, 0.8);
  const auto b = FlyScripted(7, 0.8);
  EXPECT_EQ(a, b);
  // The seed matters (turbulence is seeded per drone) ...
  const auto c = FlyScripted(8, 0.8);
  EXPECT_NE(a.back(), c.back());
  // ... and without noise the seed changes only the generator state, not the flight.
  Vec3 e7, e8;
  EXPECT_NE(FlyScripted(7, 0, &e7).back(), FlyScripted(8, 0, &e8).back());
  EXPECT_EQ(e7, e8);
}

TEST(air_world, NonFiniteStateResetsDroneAndRaisesEvent) {
  Sim sim;
  sim.allow_resets = true;
  sim.Add(1);
  sim.Add(2, {}, Vec3(4, 0, 0));
  sim.TakeOff(1);
  sim.Send(2, cmd::Arm{});
  const CommandId t2 = sim.Send(2, cmd::Takeoff{});
  const CommandId m = sim.Send(1, cmd::MoveToPosition{Vec3(10, 0, 3), 2.0});
  sim.Run(1.0);
  sim.D(1).velocity.x() = std::numeric_limits<double>::quiet_NaN();
  sim.Tick();
  bool reset = false;
  for (const AirEvent& e : sim.state.events) {
    if (e.kind == EventKind::kReset && e.drone == 1) {
      reset = true;
      EXPECT_NE(e.message.find("not finite"), std::string::npos) << e.message;
    }
  }
  EXPECT_TRUE(reset);
  EXPECT_EQ(sim.D(1).reset_count, 1u);
  EXPECT_LT((sim.D(1).position - sim.model.drones[0].spawn.position).norm(), 1e-3);
  EXPECT_FALSE(sim.D(1).armed);
  EXPECT_EQ(sim.Status(m), CommandStatus::kCancelled);
  // Stepping continues; the other drone is unaffected; drone 1 can fly again.
  sim.Run(6.0);
  EXPECT_EQ(sim.Status(t2), CommandStatus::kCompleted);
  EXPECT_TRUE(sim.D(1).position.allFinite());
  sim.TakeOff(1);
  EXPECT_EQ(sim.D(1).reset_count, 1u);
}

std::string Rejection(Sim& sim, DroneId drone, CommandBody body) {
  const CommandId id = sim.Send(drone, std::move(body));
  sim.Tick();
  const auto it = sim.last_report.find(id);
  if (it == sim.last_report.end() || it->second.status != CommandStatus::kRejected) return "<accepted>";
  return it->second.message;
}

TEST(air_world, BadCommandsAreRejectedWithReasons) {
  Sim sim;
  sim.Add(1);
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const double inf = std::numeric_limits<double>::infinity();
  EXPECT_NE(Rejection(sim, 99, cmd::Arm{}).find("unknown drone id"), std::string::npos);
  EXPECT_NE(Rejection(sim, 1, cmd::Takeoff{}).find("disarmed"), std::string::npos);
  EXPECT_NE(Rejection(sim, 1, cmd::Hover{}).find("disarmed"), std::string::npos);
  EXPECT_NE(Rejection(sim, 1, cmd::MoveByVelocity{Vec3(1, 0, 0), 1.0}).find("disarmed"), std::string::npos);
  sim.Send(1, cmd::Arm{});
  sim.Tick();
  EXPECT_NE(Rejection(sim, 1, cmd::MoveByVelocity{Vec3(nan, 0, 0), 1.0}).find("velocity is not finite"), std::string::npos);
  EXPECT_NE(Rejection(sim, 1, cmd::MoveToPosition{Vec3(1, 2, inf), 2.0}).find("position is not finite"), std::string::npos);
  EXPECT_NE(Rejection(sim, 1, cmd::MoveToPosition{Vec3(1, 2, 3), -1.0}).find("velocity must be > 0"), std::string::npos);
  EXPECT_NE(Rejection(sim, 1, cmd::MoveByRollPitchYawThrottle{0, 0, 0, 1.5, 1.0}).find("throttle 1.5"), std::string::npos);
  EXPECT_NE(Rejection(sim, 1, cmd::MoveByRollPitchYawZ{1.2, 0, 0, 2, 1.0}).find("exceeds max_tilt"), std::string::npos);
  EXPECT_NE(Rejection(sim, 1, cmd::MoveByMotorPwms{{0.5, 0.5, 0.5}, 1.0}).find("4 rotors"), std::string::npos);
  EXPECT_NE(Rejection(sim, 1, cmd::MoveByMotorPwms{{0.5, 0.5, 0.5, 2.0}, 1.0}).find("pwm 2"), std::string::npos);
  EXPECT_NE(Rejection(sim, 1, cmd::MoveByVelocity{Vec3(1, 0, 0), 0.0}).find("duration must be > 0"), std::string::npos);
  EXPECT_NE(Rejection(sim, 1, cmd::MoveOnPath{}).find("path is empty"), std::string::npos);
  cmd::MoveToPosition fwd{Vec3(5, 0, 2), 2.0};
  fwd.drivetrain = Drivetrain::kForwardOnly;  // with the default yaw_mode (is_rate = true)
  EXPECT_NE(Rejection(sim, 1, fwd).find("ForwardOnly"), std::string::npos);
  ControllerGains g;
  g.velocity_p_xy = -1;
  EXPECT_NE(Rejection(sim, 1, cmd::SetGains{g}).find("gains"), std::string::npos);
  EXPECT_NE(Rejection(sim, 1, cmd::RotateToYaw{nan}).find("yaw is not finite"), std::string::npos);
  EXPECT_NE(Rejection(sim, 1, cmd::MoveByVelocity{Vec3(500, 0, 0), 1.0}).find("exceeds 100"), std::string::npos);
  // A valid command in the same batch after rejected ones still runs.
  const CommandId ok = sim.Send(1, cmd::Takeoff{});
  sim.Tick();
  EXPECT_EQ(sim.Status(ok), CommandStatus::kRunning);
  // ValidateCommand is callable directly (the coordinator validates before sequencing).
  Command c{1, 1, cmd::Land{-1}};
  EXPECT_NE(ValidateCommand(sim.model, sim.state, c).find("timeout must be > 0"), std::string::npos);
  EXPECT_THROW(Step(sim.model, &sim.state, {}, sim.env, 0.0), std::invalid_argument);
  EXPECT_THROW(Step(sim.model, &sim.state, {}, sim.env, nan), std::invalid_argument);
}

TEST(air_world, MalformedVehiclesAreIgnored) {
  Sim sim;
  sim.Add(1);
  sim.TakeOff(1);
  VehicleBox nan_car;
  nan_car.id = 1;
  nan_car.pose.position = Vec3(std::numeric_limits<double>::quiet_NaN(), 0, 0);
  VehicleBox flat;
  flat.id = 2;
  flat.pose.position = sim.D(1).position;  // would contain the drone, but has no extent
  flat.half_extents = Vec3(1, 1, 0);
  VehicleBox wall;  // a real one the drone touches
  wall.id = 3;
  wall.pose.position = sim.D(1).position + Vec3(0.5, 0, 0);
  wall.half_extents = Vec3(0.3, 2, 2);
  sim.env.vehicles = {nan_car, flat, wall};
  sim.Run(1.0);
  EXPECT_TRUE(sim.D(1).position.allFinite());
  EXPECT_EQ(sim.D(1).reset_count, 0u);
  EXPECT_EQ(sim.D(1).collision.kind, ObjectKind::kVehicle);
  EXPECT_EQ(sim.D(1).collision.object_id, 3u);
}

TEST(air_world, AirSimViewOfAFlyingDrone) {
  Sim sim;
  sim.Add(1, {}, Vec3(10, 20, 0));
  sim.TakeOff(1);
  sim.Send(1, cmd::MoveByVelocity{Vec3(0, 2, 0), 3.0});  // north
  sim.Run(2.5);
  const AirSimKinematics k = ToAirSim(sim.model.drones[0], sim.D(1));
  EXPECT_NEAR(k.linear_velocity.x(), 2.0, 0.2);   // NED x = north
  EXPECT_NEAR(k.linear_velocity.y(), 0.0, 0.2);
  EXPECT_NEAR(k.position.z(), -2.0, 0.2);         // 2 m up = -2 NED
  EXPECT_GT(k.position.x(), 2.0);
  const AirSimCollisionInfo c = ToAirSim(sim.model.drones[0], sim.D(1).collision);
  EXPECT_TRUE(c.has_collided);                    // the ground, before take-off
  EXPECT_EQ(c.object_name, "ground");
  EXPECT_NEAR(c.normal.z(), -1.0, 1e-12);          // up = -z NED
}

TEST(air_world, AddRemoveAndBadParams) {
  World model;
  WorldState state;
  AddDrone(&model, &state, 3, {}, Pose{});
  EXPECT_THROW(AddDrone(&model, &state, 3, {}, Pose{}), std::invalid_argument);
  MultirotorParams bad;
  bad.mass = -1;
  try {
    AddDrone(&model, &state, 4, bad, Pose{});
    FAIL();
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("mass"), std::string::npos);
  }
  EXPECT_TRUE(RemoveDrone(&model, &state, 3));
  EXPECT_FALSE(RemoveDrone(&model, &state, 3));
  EXPECT_TRUE(state.drones.empty());
}

TEST(air_world, WindIsRejectedByTheController) {
  Sim sim;
  sim.Add(1);
  sim.env.wind = Vec3(4, 0, 0);
  sim.TakeOff(1);
  sim.Run(10.0);
  const Vec3 target = sim.model.drones[0].spawn.position + Vec3(0, 0, 2);
  // Position P with no velocity integrator leaves a steady offset downwind, but bounded.
  EXPECT_LT((sim.D(1).position - target).norm(), 1.5);
  EXPECT_GT(sim.D(1).position.x() - target.x(), 0.0);
  EXPECT_LT(ToEuler(sim.D(1).orientation).pitch, 0.0);  // leaning into the wind (nose up)
}

}  // namespace
}  // namespace lockstep::air

namespace lockstep::air {
namespace {

struct HeadOn {
  Vec3 a_pos, b_pos;
  bool crossed = false;
  int events_ab = 0, events_ba = 0;
  double min_gap = 1e9;
};

// Drones `ia` (west) and `ib` (east) fly head-on at 2 m/s each at the same altitude.
HeadOn FlyHeadOn(DroneId ia, DroneId ib) {
  Sim sim;
  sim.Add(ia, {}, Vec3(0, 0, 0));
  sim.Add(ib, {}, Vec3(6, 0, 0));
  for (DroneId id : {ia, ib}) sim.Send(id, cmd::Arm{});
  sim.Send(ia, cmd::Takeoff{});
  sim.Send(ib, cmd::Takeoff{});
  sim.Run(4.0);
  sim.Send(ia, cmd::MoveByVelocity{Vec3(2, 0, 0), 3.0});
  sim.Send(ib, cmd::MoveByVelocity{Vec3(-2, 0, 0), 3.0});
  HeadOn r;
  for (int i = 0; i < 80; ++i) {
    sim.Tick();
    const double gap = sim.D(ib).position.x() - sim.D(ia).position.x();
    r.min_gap = std::min(r.min_gap, gap);
    r.crossed |= gap < 0;
    for (const AirEvent& e : sim.state.events) {
      if (e.kind != EventKind::kCollision || e.object_kind != ObjectKind::kDrone) continue;
      if (e.drone == ia && e.object_id == ib) ++r.events_ab;
      if (e.drone == ib && e.object_id == ia) ++r.events_ba;
    }
  }
  r.a_pos = sim.D(ia).position;
  r.b_pos = sim.D(ib).position;
  return r;
}

TEST(air_world, DronesCollideWithEachOther) {
  const HeadOn r = FlyHeadOn(1, 2);
  EXPECT_FALSE(r.crossed);
  EXPECT_GE(r.events_ab, 1);
  EXPECT_GE(r.events_ba, 1);
  // Arms (0.16 m) plus contact spheres (0.06 m) on each side keep them apart.
  EXPECT_GT(r.min_gap, 0.3);
  EXPECT_LT(r.min_gap, 0.5);
  // Jacobi coupling is order-independent: swapping the ids (and so the stepping order) gives
  // bit-identical trajectories.
  const HeadOn s = FlyHeadOn(2, 1);
  EXPECT_EQ(r.a_pos, s.a_pos);
  EXPECT_EQ(r.b_pos, s.b_pos);
}

}  // namespace
}  // namespace lockstep::air

namespace lockstep::air {
namespace {

// Drone 2 flies at 6 m/s into hovering drone 1. Each sees the other at its tick-start pose
// moved by its tick-start velocity, so both detect the contact at the same sub-step; a
// hovering drone that saw the other frozen at its tick-start pose would notice it a tick late.
TEST(air_world, BothDronesSeeTheirContactAtTheSameSubStep) {
  Sim sim;
  sim.Add(1, {}, Vec3(0, 0, 0));
  sim.Add(2, {}, Vec3(-12, 0, 0));
  sim.Send(1, cmd::Arm{});
  sim.Send(2, cmd::Arm{});
  sim.Send(1, cmd::Takeoff{});
  sim.Send(2, cmd::Takeoff{});
  sim.Run(7.0);
  sim.Send(2, cmd::MoveByVelocity{Vec3(6, 0, 0), 5.0});
  double t1 = -1, t2 = -1;
  for (int i = 0; i < 100 && (t1 < 0 || t2 < 0); ++i) {
    sim.Tick();
    for (const AirEvent& e : sim.state.events) {
      if (e.kind != EventKind::kCollision || e.object_kind != ObjectKind::kDrone) continue;
      if (e.drone == 1 && t1 < 0) t1 = e.time;
      if (e.drone == 2 && t2 < 0) t2 = e.time;
    }
  }
  std::printf("contact seen by the hovering drone at %.4f s, by the moving one at %.4f s\n", t1, t2);
  ASSERT_GT(t1, 0);
  ASSERT_GT(t2, 0);
  EXPECT_NEAR(t1, t2, 0.0025);
  EXPECT_GT(sim.D(1).velocity.x(), 0.5) << "the hovering drone was pushed";
}


// AirSim's rules without API control (simple_flight refuses the goals; MultirotorApiBase's
// waiters run on): arm and disarm are refused, a move steers nothing and ends with its
// duration (COMPLETED) or its timeout (TIMED_OUT), land completes when the drone does not
// descend, and releasing control in flight leaves the drone to zero throttle.
TEST(air_world, WithoutApiControlCommandsSteerNothingAndRunOutTheirTime) {
  Sim sim;
  sim.Add(1);
  sim.Run(0.5);
  const Vec3 rest = sim.D(1).position;
  EXPECT_TRUE(sim.D(1).api_control);  // Lockstep's own commands find it on
  sim.Send(1, cmd::SetApiControl{false});
  const CommandId arm = sim.Send(1, cmd::Arm{});
  sim.Tick();
  EXPECT_FALSE(sim.D(1).api_control);
  EXPECT_EQ(sim.Status(arm), CommandStatus::kRejected);
  EXPECT_NE(sim.last_report[arm].message.find("API has not been given control"), std::string::npos);
  EXPECT_FALSE(sim.D(1).armed);
  // A timed move: accepted (disarmed or not), RUNNING for its duration, then COMPLETED; no motion.
  const CommandId v = sim.Send(1, cmd::MoveByVelocity{Vec3(2, 0, 1), 1.0});
  sim.Tick();
  EXPECT_EQ(sim.Status(v), CommandStatus::kRunning);
  sim.Run(0.9);
  EXPECT_EQ(sim.Status(v), CommandStatus::kRunning);
  sim.Run(0.15);
  EXPECT_EQ(sim.Status(v), CommandStatus::kCompleted);
  EXPECT_NEAR(sim.last_report[v].time, 1.55, 1e-9);  // started at 0.55 s (the tick after 0.5 s)
  // A goal: never reached, TIMED_OUT at its timeout; a newer command cancels a running one.
  const CommandId m = sim.Send(1, cmd::MoveToPosition{rest + Vec3(10, 0, 3), 3.0, 2.0});
  sim.Run(1.0);
  EXPECT_EQ(sim.Status(m), CommandStatus::kRunning);
  sim.Run(1.05);
  EXPECT_EQ(sim.Status(m), CommandStatus::kTimedOut);
  const CommandId t = sim.Send(1, cmd::Takeoff{0, 5.0});
  sim.Tick();
  const CommandId l = sim.Send(1, cmd::Land{60});
  sim.Tick();
  EXPECT_EQ(sim.Status(t), CommandStatus::kCancelled);
  // Land: AirSim's "not descending for more than 10 command periods" holds at once on the ground.
  sim.Run(0.3);
  EXPECT_EQ(sim.Status(l), CommandStatus::kCompleted);
  const CommandId h = sim.Send(1, cmd::Hover{});
  sim.Tick();
  EXPECT_EQ(sim.Status(h), CommandStatus::kCompleted);
  EXPECT_LT((sim.D(1).position - rest).norm(), 1e-3) << "a command without API control moved the drone";
  // Taken back, the drone flies again.
  sim.Send(1, cmd::SetApiControl{true});
  sim.Send(1, cmd::Arm{});
  const CommandId up = sim.Send(1, cmd::Takeoff{});
  ASSERT_TRUE(sim.RunUntil([&] { return sim.Done(up); }, 10));
  EXPECT_EQ(sim.Status(up), CommandStatus::kCompleted);
  // Released in flight: the running move goes on unsteered to its timeout and the drone gets
  // simple_flight's goal without an RC (zero throttle): it falls.
  const double z = sim.D(1).position.z();
  const CommandId far = sim.Send(1, cmd::MoveToPosition{sim.D(1).position + Vec3(0, 20, 0), 2.0, 3.0});
  sim.Tick();
  sim.Send(1, cmd::SetApiControl{false});
  sim.Run(0.5);
  EXPECT_EQ(sim.Status(far), CommandStatus::kRunning);
  EXPECT_LT(sim.D(1).position.z(), z - 0.3);
  EXPECT_LT(sim.D(1).velocity.z(), -1.0);
  ASSERT_TRUE(sim.RunUntil([&] { return sim.Done(far); }, 4));
  EXPECT_EQ(sim.Status(far), CommandStatus::kTimedOut);
}

// AirSim 1.8 (MultirotorApiBase's loops, SimpleFlightApi::enableApiControl): releasing API
// control cancels nothing; the call's loop keeps sending its goals, refused until control is
// taken back, then accepted: the command steers again and completes, its timeout or duration
// counted from the call.
TEST(air_world, ApiControlTakenBackResumesTheRunningCommand) {
  Sim sim;
  sim.Add(1);
  sim.Run(0.5);
  sim.TakeOff(1);
  const CommandId up = sim.Send(1, cmd::MoveToPosition{sim.D(1).position + Vec3(0, 0, 8), 3.0, 20.0});
  ASSERT_TRUE(sim.RunUntil([&] { return sim.Done(up); }, 15));
  ASSERT_EQ(sim.Status(up), CommandStatus::kCompleted);
  // Released mid-run: unsteered (it falls), RUNNING; taken back: it reaches its goal.
  const Vec3 goal = sim.D(1).position + Vec3(12, 0, 0);
  const CommandId m = sim.Send(1, cmd::MoveToPosition{goal, 3.0, 30.0});
  sim.Run(1.0);
  const double x_released = sim.D(1).position.x();
  sim.Send(1, cmd::SetApiControl{false});
  sim.Run(0.4);
  EXPECT_EQ(sim.Status(m), CommandStatus::kRunning);
  EXPECT_LT(sim.D(1).velocity.z(), -1.0) << "zero throttle without API control";
  sim.Send(1, cmd::SetApiControl{true});
  ASSERT_TRUE(sim.RunUntil([&] { return sim.Done(m); }, 20));
  EXPECT_EQ(sim.Status(m), CommandStatus::kCompleted);
  EXPECT_LT((sim.D(1).position - goal).norm(), 0.25);
  EXPECT_GT(sim.D(1).position.x(), x_released + 5);
  // Issued without API control: it steers nothing until control is taken back, then flies to its goal.
  sim.Send(1, cmd::SetApiControl{false});
  sim.Tick();
  const Vec3 goal2 = sim.D(1).position + Vec3(0, 8, 0);
  const CommandId m2 = sim.Send(1, cmd::MoveToPosition{goal2, 3.0, 30.0});
  sim.Run(0.3);
  EXPECT_EQ(sim.Status(m2), CommandStatus::kRunning);
  EXPECT_LT(sim.D(1).position.y() - (goal2.y() - 8), 0.05) << "no steering without API control";
  sim.Send(1, cmd::SetApiControl{true});
  ASSERT_TRUE(sim.RunUntil([&] { return sim.Done(m2); }, 20));
  EXPECT_EQ(sim.Status(m2), CommandStatus::kCompleted);
  EXPECT_LT((sim.D(1).position - goal2).norm(), 0.25);
  // A timed move keeps the duration from its call: issued without control at t0, it ends at t0 + 2 s.
  sim.Send(1, cmd::SetApiControl{false});
  sim.Tick();
  const CommandId v = sim.Send(1, cmd::MoveByVelocity{Vec3(1, 0, 0), 2.0});
  sim.Tick();
  const double t0 = sim.last_report[v].time;
  sim.Run(0.5);
  sim.Send(1, cmd::SetApiControl{true});
  const double x0 = sim.D(1).position.x();
  ASSERT_TRUE(sim.RunUntil([&] { return sim.Done(v); }, 5));
  EXPECT_EQ(sim.Status(v), CommandStatus::kCompleted);
  EXPECT_NEAR(sim.last_report[v].time, t0 + 2.0, 1e-9);
  EXPECT_GT(sim.D(1).position.x(), x0 + 0.3) << "it steered once control was back";
  // Taken back after the command ended: nothing resumes (motors stay at zero throttle).
  const CommandId late = sim.Send(1, cmd::MoveToPosition{sim.D(1).position + Vec3(10, 0, 0), 3.0, 30.0});
  sim.Tick();
  sim.Send(1, cmd::SetApiControl{false});
  const CommandId other = sim.Send(1, cmd::Hover{});  // replaces it (AirSim's SingleTaskCall): CANCELLED
  sim.Tick();
  EXPECT_EQ(sim.Status(late), CommandStatus::kCancelled);
  EXPECT_EQ(sim.Status(other), CommandStatus::kCompleted);
  sim.Send(1, cmd::SetApiControl{true});
  sim.Run(0.3);
  EXPECT_EQ(sim.Status(late), CommandStatus::kCancelled);
  EXPECT_EQ(sim.D(1).command.mode, CommandMode::kIdle);
}

TEST(air_world, ApiControlIsPartOfTheStateHash) {
  Sim a, b;
  a.Add(1);
  b.Add(1);
  a.Tick();
  b.Tick();
  ASSERT_EQ(StateHash(a.state), StateHash(b.state));
  b.Send(1, cmd::SetApiControl{false});
  a.Tick();
  b.Tick();
  EXPECT_NE(StateHash(a.state), StateHash(b.state));
}

}  // namespace
}  // namespace lockstep::air
