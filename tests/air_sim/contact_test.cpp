// Contact with the ground, a static mesh and moving vehicles.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>

#include "sim_fixture.h"

namespace lockstep::air {
namespace {
using testing::NoDrag;
using testing::Sim;

// Axis-aligned box as a triangle mesh (12 triangles), like the map layer hands over.
std::shared_ptr<const StaticMesh> BoxMesh(const Vec3& lo, const Vec3& hi, std::uint32_t id = 7) {
  std::vector<float> v;
  for (int i = 0; i < 8; ++i) {
    v.push_back(static_cast<float>((i & 1) ? hi.x() : lo.x()));
    v.push_back(static_cast<float>((i & 2) ? hi.y() : lo.y()));
    v.push_back(static_cast<float>((i & 4) ? hi.z() : lo.z()));
  }
  const std::vector<std::uint32_t> idx = {0, 2, 1, 1, 2, 3, 4, 5, 6, 5, 7, 6, 0, 1, 4, 1, 5, 4,
                                          2, 6, 3, 3, 6, 7, 0, 4, 2, 2, 4, 6, 1, 3, 5, 3, 7, 5};
  return StaticMesh::Build(v, idx, 2.0, id);
}

TEST(air_contact, RestsOnGroundAndIsLanded) {
  Sim sim;
  sim.Add(1);
  const double z0 = sim.D(1).position.z();
  sim.Run(2.0);
  EXPECT_NEAR(sim.D(1).position.z(), z0, 0.003);
  EXPECT_LT(sim.D(1).velocity.norm(), 1e-3);
  EXPECT_EQ(sim.D(1).landed, LandedState::kLanded);
  EXPECT_TRUE(sim.D(1).collision.has_collided);
  EXPECT_EQ(sim.D(1).collision.kind, ObjectKind::kGround);
}

TEST(air_contact, BounceRestitution) {
  // landing_model: impulse (AirSim's ground lock off): a level drop bounces with restitution.
  Sim sim;
  sim.dt = 0.001;
  MultirotorParams p = NoDrag();
  p.landing_model = LandingModel::kImpulse;
  sim.Add(1, p);
  sim.D(1).position.z() += 1.0;
  double v_in = 0, v_out = 0;
  bool hit = false;
  for (int i = 0; i < 1000; ++i) {
    const double vz_before = sim.D(1).velocity.z();
    sim.Tick();
    if (!hit && sim.D(1).velocity.z() > 0) {
      hit = true;
      v_in = -vz_before;
      v_out = sim.D(1).velocity.z();
      break;
    }
  }
  ASSERT_TRUE(hit);
  EXPECT_NEAR(v_in, std::sqrt(2 * sim.model.gravity * 1.0), 0.05);
  std::printf("bounce: in %.3f m/s out %.3f m/s ratio %.3f\n", v_in, v_out, v_out / v_in);
  EXPECT_NEAR(v_out / v_in, 0.55, 0.03);
  const AirEvent* first = nullptr;
  for (const AirEvent& ev : sim.all_events) {
    if (ev.kind == EventKind::kCollision && first == nullptr) first = &ev;
  }
  ASSERT_NE(first, nullptr);
  const AirEvent& e = *first;
  EXPECT_EQ(e.object_kind, ObjectKind::kGround);
  EXPECT_NEAR(e.impact_speed, v_in, 0.05);
  EXPECT_TRUE(e.normal.isApprox(Vec3::UnitZ()));
}

TEST(air_contact, FrictionStopsASlidingDrone) {
  // Sliding on the ground at 2 m/s, motors off: Coulomb friction decelerates at mu g, so it
  // stops after v^2 / (2 mu g).
  Sim sim;
  sim.dt = 0.01;
  MultirotorParams p = NoDrag();
  p.landing_model = LandingModel::kImpulse;  // ground lock would stop it at once
  sim.Add(1, p);
  sim.Tick();
  sim.D(1).velocity = Vec3(2, 0, 0);
  const double x0 = sim.D(1).position.x();
  sim.Run(1.5);
  const double expect = 4.0 / (2 * 0.5 * sim.model.gravity);
  EXPECT_NEAR(sim.D(1).position.x() - x0, expect, 0.05 * expect);
  EXPECT_LT(sim.D(1).velocity.norm(), 1e-3);
}

TEST(air_contact, StaticMeshRoofAndWall) {
  Sim sim;
  sim.model.statics.mesh = BoxMesh(Vec3(0, -5, 0), Vec3(10, 5, 5));
  sim.Add(1, {}, Vec3(-3, 0, 0));
  // Fly east into the building's wall (x = 0) at 2 m above ground.
  sim.TakeOff(1);
  const CommandId v = sim.Send(1, cmd::MoveByVelocity{Vec3(2, 0, 0), 4.0});
  sim.Run(4.0);
  EXPECT_EQ(sim.Status(v), CommandStatus::kCompleted);
  const DroneState& d = sim.D(1);
  EXPECT_LT(d.position.x(), 0.0);     // did not pass through
  EXPECT_GT(d.position.x(), -0.40);   // pressed against it (arm + contact radius)
  EXPECT_EQ(d.collision.kind, ObjectKind::kStatic);
  EXPECT_EQ(d.collision.object_id, 7u);
  EXPECT_NEAR(d.collision.normal.x(), -1.0, 1e-6);
  bool saw = false;
  for (const AirEvent& e : sim.all_events) saw |= e.kind == EventKind::kCollision && e.object_kind == ObjectKind::kStatic;
  EXPECT_TRUE(saw);
  // Up and over, then land on the roof (z = 5).
  sim.Send(1, cmd::MoveToPosition{Vec3(-1, 0, 7), 3.0});
  sim.Run(4.0);
  sim.Send(1, cmd::MoveToPosition{Vec3(5, 0, 7), 3.0});
  sim.Run(5.0);
  const CommandId l = sim.Send(1, cmd::Land{});
  ASSERT_TRUE(sim.RunUntil([&] { return sim.Done(l); }, 20));
  EXPECT_EQ(sim.Status(l), CommandStatus::kCompleted);
  EXPECT_NEAR(d.position.z(), 5.0 + RestHeight(sim.model.drones[0].derived), 0.01);
  EXPECT_EQ(d.landed, LandedState::kLanded);
  EXPECT_EQ(d.collision.kind, ObjectKind::kStatic);
  EXPECT_GT(sim.model.statics.mesh->HeightBelow(Vec3(5, 0, 6), 10), 0.99);
}

TEST(air_contact, MeshBuildRejectsBadInput) {
  const std::vector<float> v = {0, 0, 0, 1, 0, 0, 0, 1, 0};
  EXPECT_THROW(StaticMesh::Build(v, std::vector<std::uint32_t>{0, 1, 3}), std::invalid_argument);
  EXPECT_THROW(StaticMesh::Build(v, std::vector<std::uint32_t>{0, 1}), std::invalid_argument);
  const std::vector<float> bad = {0, 0, NAN, 1, 0, 0, 0, 1, 0};
  EXPECT_THROW(StaticMesh::Build(bad, std::vector<std::uint32_t>{0, 1, 2}), std::invalid_argument);
  auto ok = StaticMesh::Build(v, std::vector<std::uint32_t>{0, 1, 2});
  EXPECT_EQ(ok->triangle_count(), 1u);
  ContactPoint cp[4];
  EXPECT_EQ(ok->QuerySphere(Vec3(0.2, 0.2, 0.05), 0.1, cp, 4), 1);
  EXPECT_NEAR(cp[0].depth, 0.05, 1e-6);
  EXPECT_EQ(ok->QuerySphere(Vec3(0.2, 0.2, 0.15), 0.1, cp, 4), 0);
}

TEST(air_contact, SphereBoxContactGeometry) {
  Pose box;
  box.position = Vec3(1, 2, 0.75);
  box.orientation = FromEuler(0, 0, 0.5);
  ContactPoint cp;
  const Vec3 half(2, 1, 0.75);
  ASSERT_TRUE(SphereBoxContact(Vec3(1, 2, 1.55), 0.1, box, half, &cp));
  EXPECT_NEAR(cp.depth, 0.05, 1e-12);
  EXPECT_TRUE(cp.normal.isApprox(Vec3::UnitZ(), 1e-12));
  EXPECT_FALSE(SphereBoxContact(Vec3(1, 2, 1.65), 0.1, box, half, &cp));
  VehicleBox vb;
  vb.pose = box;
  vb.velocity = Vec3(5, 0, 0);
  vb.angular_velocity = Vec3(0, 0, 0.2);
  const Pose p = ExtrapolateVehicle(vb, 0.5);
  EXPECT_TRUE(p.position.isApprox(Vec3(3.5, 2, 0.75)));
  EXPECT_NEAR(YawOf(p.orientation), 0.6, 1e-12);
}

// The CARLA-Air workload: land on a car driving at 5 m/s, then ride on it.
TEST(air_contact, LandsOnMovingCarAndIsCarried) {
  Sim sim;
  sim.Add(1);
  VehicleBox car;
  car.id = 42;
  car.half_extents = Vec3(2.4, 1.0, 0.75);
  car.pose.position = Vec3(-40, 0, 0.75);
  car.velocity = Vec3(5, 0, 0);
  sim.env.vehicles = {car};
  auto advance_car = [&](double accel) {
    VehicleBox& c = sim.env.vehicles[0];
    c.pose.position += c.velocity * sim.dt + 0.5 * Vec3(accel, 0, 0) * sim.dt * sim.dt;
    c.velocity += Vec3(accel, 0, 0) * sim.dt;
  };
  auto tick = [&](double accel) {
    sim.Tick();          // air sim steps k -> k+1 with the car of frame k (Jacobi)
    advance_car(accel);  // ground sim's car at k+1
  };
  // Climb to 12 m.
  sim.Send(1, cmd::Arm{});
  const CommandId up = sim.Send(1, cmd::MoveToPosition{Vec3(0, 0, 12), 4.0});
  for (int i = 0; i < 200 && !sim.Done(up); ++i) tick(0);
  ASSERT_EQ(sim.Status(up), CommandStatus::kCompleted);
  // The client: track a point above the roof centre, descend once aligned, cut motors on touch.
  const double roof = 2 * car.half_extents.z();
  double alt = 12.0 - roof;  // planned height above the roof
  Vec3 touchdown_err = Vec3::Constant(1e9);
  bool touched = false;
  for (int i = 0; i < 800 && !touched; ++i) {
    const VehicleBox& c = sim.env.vehicles[0];
    const Vec3 roof_centre = c.pose.position + Vec3(0, 0, c.half_extents.z());
    const double horiz = (sim.D(1).position - roof_centre).head<2>().norm();
    if (horiz < 0.5) alt = std::max(-0.3, alt - 1.0 * sim.dt);  // descend 1 m/s, press at the end
    cmd::TrackTarget t;
    t.position = roof_centre + Vec3(0, 0, alt);
    t.velocity = c.velocity;
    t.max_speed = 9.0;
    t.duration = 0.2;
    sim.Send(1, t);
    tick(0);
    const DroneState& d = sim.D(1);
    if (d.landed == LandedState::kLanded && d.collision.kind == ObjectKind::kVehicle) {
      touched = true;
      const VehicleBox& cn = sim.env.vehicles[0];  // car at the same instant as the drone
      touchdown_err = (d.position - cn.pose.position);
    }
  }
  ASSERT_TRUE(touched) << "never landed on the car";
  std::printf("touchdown error %.3f m at t = %.2f s\n", touchdown_err.head<2>().norm(), sim.state.time);
  EXPECT_LT(touchdown_err.head<2>().norm(), 0.5) << touchdown_err.transpose();
  EXPECT_GT(sim.state.time, 5.0);
  EXPECT_EQ(sim.D(1).collision.object_id, 42u);
  // Motors off; the car keeps going and then accelerates at 1 m/s^2: friction carries the drone.
  sim.Send(1, cmd::Disarm{});
  tick(0);
  const Vec3 rel0 = sim.D(1).position - sim.env.vehicles[0].pose.position;
  for (int i = 0; i < 40; ++i) tick(0);
  for (int i = 0; i < 40; ++i) tick(1.0);
  const Vec3 rel1 = sim.D(1).position - sim.env.vehicles[0].pose.position;
  std::printf("slip on the roof while carried: %.3f m\n", (rel1 - rel0).head<2>().norm());
  EXPECT_LT((rel1 - rel0).head<2>().norm(), 0.3) << (rel1 - rel0).transpose();
  EXPECT_NEAR(rel1.z(), car.half_extents.z() + RestHeight(sim.model.drones[0].derived), 0.02);
  EXPECT_NEAR(sim.D(1).velocity.x(), sim.env.vehicles[0].velocity.x(), 0.2);
  EXPECT_EQ(sim.D(1).landed, LandedState::kLanded);
  EXPECT_GT(sim.env.vehicles[0].pose.position.x(), 20.0);  // it really drove on
}

TEST(air_contact, CarHitsHoveringDrone) {
  Sim sim;
  sim.Add(1);
  sim.TakeOff(1);
  VehicleBox car;
  car.id = 9;
  car.pose.position = Vec3(-6, 0, 1.5);  // tall van
  car.half_extents = Vec3(2.4, 1.0, 1.5);
  car.velocity = Vec3(8, 0, 0);
  sim.env.vehicles = {car};
  bool hit = false;
  for (int i = 0; i < 40 && !hit; ++i) {
    sim.Tick();
    sim.env.vehicles[0].pose.position += sim.env.vehicles[0].velocity * sim.dt;
    for (const AirEvent& e : sim.state.events) hit |= e.kind == EventKind::kCollision && e.object_id == 9;
  }
  ASSERT_TRUE(hit);
  EXPECT_GT(sim.D(1).velocity.x(), 2.0);  // knocked forward by the van
  EXPECT_EQ(sim.D(1).collision.kind, ObjectKind::kVehicle);
  EXPECT_GT(sim.D(1).collision.collision_count, 0u);
}

}  // namespace
}  // namespace lockstep::air

namespace lockstep::air {
namespace {

TEST(air_contact, RidesATurningCar) {
  // Drone placed on the roof (motors off) of a car that accelerates and then turns at
  // 0.25 rad/s at 4 m/s (1 m/s^2 lateral, below mu g): friction keeps it on its spot.
  Sim sim;
  sim.Add(1);
  VehicleBox car;
  car.id = 5;
  car.half_extents = Vec3(2.4, 1.0, 0.75);
  car.pose.position = Vec3(0, 0, 0.75);
  sim.env.vehicles = {car};
  const double rest = RestHeight(sim.model.drones[0].derived);
  Pose on_roof;
  on_roof.position = Vec3(0.5, 0.2, 1.5 + rest);
  sim.Send(1, cmd::SetPose{on_roof});
  sim.Tick();
  double yaw = 0, speed = 0;
  auto car_frame = [&] {
    const VehicleBox& c = sim.env.vehicles[0];
    return Vec3(c.pose.orientation.conjugate() * (sim.D(1).position - c.pose.position));
  };
  const Vec3 start = car_frame();
  for (int i = 0; i < 200; ++i) {
    const double accel = i < 80 ? 1.0 : 0.0;  // m/s^2, for 4 s
    const double yaw_rate = i >= 80 ? 0.25 : 0.0;
    VehicleBox& c = sim.env.vehicles[0];
    c.velocity = speed * Vec3(std::cos(yaw), std::sin(yaw), 0);
    c.angular_velocity = Vec3(0, 0, yaw_rate);
    sim.Tick();
    c.pose.position += c.velocity * sim.dt;
    yaw += yaw_rate * sim.dt;
    c.pose.orientation = FromEuler(0, 0, yaw);
    speed += accel * sim.dt;
  }
  const Vec3 end = car_frame();
  std::printf("turning car: speed %.2f m/s, yaw %.2f rad, slip %.3f m\n", speed, yaw, (end - start).head<2>().norm());
  EXPECT_GT(speed, 3.9);
  EXPECT_GT(yaw, 1.4);
  EXPECT_LT((end - start).head<2>().norm(), 0.3) << (end - start).transpose();
  EXPECT_NEAR(end.z(), 0.75 + rest, 0.02);
  EXPECT_EQ(sim.D(1).landed, LandedState::kLanded);
  EXPECT_EQ(sim.D(1).collision.kind, ObjectKind::kVehicle);
}

}  // namespace
}  // namespace lockstep::air
