// air_sim and ground_sim as real processes behind the real coordinator, over Fast DDS, in
// CARLA's Town01 (issue 10, item 10): a drone lands on a Traffic-Manager car while it
// drives and rides on its roof; a drone flown into a car gives a collision event from
// each simulator, each naming the other actor.
#include <gtest/gtest.h>

#include <cmath>
#include <functional>
#include <iostream>
#include <map>
#include <mutex>

#include "lockstep/map/map.h"
#include "lockstep/runtime/command_builders.h"
#include "lockstep/runtime/messages.h"
#include "observer.h"
#include "process.h"

namespace lockstep::testing {
namespace {

using namespace std::chrono_literals;

constexpr double kDt = 0.05;  // the world's fixed_delta_seconds (default)
const char* kProfile = "lockstep.participant.loopback";
const std::string kTown01 = std::string(LOCKSTEP_CARLA_MAPS_DIR) + "/Town01.xodr";

// The Town01 spawn point with the longest drive ahead before a junction (a straight for the
// landing), as a vehicle pose: its box centre `half_z` above the road.
msg::Pose LongestStraight(double half_z, double* straight, double* yaw) {
  const map::Map town = map::Map::Load(kTown01);
  double best = -1;
  map::Transform pick;
  for (const auto& sp : town.SpawnPoints()) {
    auto wp = town.NearestWaypoint(sp.location);
    if (!wp || wp->IsJunction()) continue;
    double ahead = 0;
    while (ahead < 400) {
      auto next = town.Next(*wp, 2.0);
      if (next.empty() || next.front().IsJunction() ||
          std::abs(std::remainder(next.front().transform.yaw - sp.yaw, 2 * M_PI)) > 0.05)
        break;
      wp = next.front();
      ahead += 2.0;
    }
    if (ahead > best) {
      best = ahead;
      pick = sp;
    }
  }
  *straight = best;
  *yaw = pick.yaw;
  return MakePose(pick.location.x(), pick.location.y(), pick.location.z() - 0.5 + half_z + 0.02, pick.yaw);
}

class DroneCarTest : public ::testing::Test {
 protected:
  void SetUp() override {
    const std::string config = WriteTempFile(
        "drone-car.yaml", "domain_id: " + std::to_string(TestDomain()) + "\nparticipant_profile: " + kProfile +
                              "\nseed: 2017\nmap: " + kTown01 +
                              "\nworld:\n  synchronous_mode: true\n  service_timeout: 30\n"
                              "services:\n  - {name: ground_sim, kind: ground_sim}\n  - {name: air_sim, kind: air_sim}\n");
    coordinator_ = std::make_unique<Process>(std::vector<std::string>{Bin("lockstep_coordinator"), config});
    ground_ = std::make_unique<Process>(std::vector<std::string>{Bin("lockstep_ground_sim"), "--name", "ground_sim", "--config", config});
    air_ = std::make_unique<Process>(std::vector<std::string>{Bin("lockstep_air_sim"), "--name", "air_sim", "--config", config});
    bus_ = CreateDdsBus({TestDomain(), "", kProfile, "drone-car-test"});
    ground_reader_ = Reader<msg::GroundState>(*bus_, topics::kGroundState, [this](const msg::GroundState& s, const SampleInfo&) {
      std::lock_guard<std::mutex> lock(mu_);
      ground_states_[s.stamp().frame()] = s;
    });
    air_reader_ = Reader<msg::AirState>(*bus_, topics::kAirState, [this](const msg::AirState& s, const SampleInfo&) {
      std::lock_guard<std::mutex> lock(mu_);
      air_states_[s.stamp().frame()] = s;
    });
    events_reader_ = Reader<msg::PhysicsEvents>(*bus_, topics::kPhysicsEvents, [this](const msg::PhysicsEvents& e, const SampleInfo&) {
      std::lock_guard<std::mutex> lock(mu_);
      events_[e.service().to_string()][e.stamp().frame()] = e;
    });
    observer_ = std::make_unique<Observer>(*bus_);
    ASSERT_TRUE(observer_->WaitUntil([&] { return observer_->status() && observer_->status()->state() == msg::RunState::RUN_READY; }, 60s))
        << "the run never became ready";
  }
  void TearDown() override {
    if (HasFailure()) {
      std::cerr << "coordinator:\n" << coordinator_->Output() << "\nground_sim:\n" << ground_->Output() << "\nair_sim:\n" << air_->Output();
    }
    observer_.reset();
    bus_.reset();
  }

  msg::CommandReply Send(msg::CommandBody b) {
    auto r = observer_->WaitReply(observer_->Send(std::move(b)), 20s);
    EXPECT_TRUE(r && r->accepted()) << (r ? r->reason().to_string() : "no reply");
    return r.value_or(msg::CommandReply{});
  }
  void Drone(uint32_t actor, msg::DroneCommandKind kind, const std::function<void(msg::DroneCommand&)>& fill = {}) {
    msg::DroneCommand d;
    d.actor(actor);
    d.kind(kind);
    d.command_id(++command_id_);
    d.yaw().is_rate(true);
    if (fill) fill(d);
    msg::CommandBody b;
    b.drone(d);
    Send(b);
  }
  void Autopilot(uint32_t car) {
    msg::TrafficManagerCommand tm;
    tm.parameter(msg::TrafficManagerParameter::TM_AUTOPILOT);
    tm.actor(car);
    tm.value(1);
    msg::CommandBody b;
    b.traffic_manager(tm);
    Send(b);
  }
  // One tick; waits until both simulators published it (and their events).
  uint64_t Tick() {
    msg::TickRequest t;
    t.count(1);
    msg::CommandBody b;
    b.tick_request(t);
    const uint64_t want = Send(b).frame();
    EXPECT_TRUE(observer_->WaitUntil([&] {
      std::lock_guard<std::mutex> lock(mu_);
      return ground_states_.count(want) && air_states_.count(want) && events_["ground_sim"].count(want) &&
             events_["air_sim"].count(want);
    }, 30s)) << "frame " << want << " not published by both simulators";
    return want;
  }
  msg::VehicleState Car(uint64_t frame, uint32_t id) {
    std::lock_guard<std::mutex> lock(mu_);
    for (const auto& v : ground_states_.at(frame).vehicles()) {
      if (v.actor() == id) return v;
    }
    ADD_FAILURE() << "vehicle " << id << " missing from frame " << frame;
    return {};
  }
  msg::DroneState DroneAt(uint64_t frame) {
    std::lock_guard<std::mutex> lock(mu_);
    return air_states_.at(frame).drones().at(0);
  }
  std::vector<msg::ActorCollision> Collisions(const std::string& service, uint64_t frame) {
    std::lock_guard<std::mutex> lock(mu_);
    return events_.at(service).at(frame).collisions();
  }

  std::unique_ptr<Process> coordinator_, ground_, air_;
  std::unique_ptr<Bus> bus_;
  std::mutex mu_;
  std::map<uint64_t, msg::GroundState> ground_states_;
  std::map<uint64_t, msg::AirState> air_states_;
  std::map<std::string, std::map<uint64_t, msg::PhysicsEvents>> events_;
  Reader<msg::GroundState> ground_reader_;
  Reader<msg::AirState> air_reader_;
  Reader<msg::PhysicsEvents> events_reader_;
  std::unique_ptr<Observer> observer_;
  uint64_t command_id_ = 0;
};

double Horizontal(const msg::Vector3& a, const msg::Vector3& b) { return std::hypot(a.x() - b.x(), a.y() - b.y()); }

// The drone takes off beside a parked Tesla, the car is handed to the Traffic Manager, and a
// client that sees only the published states flies the drone over the roof (AirSim's
// moveToPosition-style tracking with the car's velocity as feed-forward), descends onto it
// and lands. The drone must come to rest on the moving roof within 0.5 m of its centre and
// stay there while the car drives on.
TEST_F(DroneCarTest, DroneLandsOnATrafficManagerCarDrivingThroughTown01) {
  double straight = 0, yaw = 0;
  const msg::Pose car_pose = LongestStraight(0.745, &straight, &yaw);
  ASSERT_GT(straight, 100.0) << "no long straight in Town01";
  const uint32_t car = Send(SpawnBody("vehicle.tesla.model3", car_pose)).actor();
  // The drone on the road 6 m behind the car (CARLA yaw: the spawn point's heading).
  const double dx = -6 * std::cos(yaw), dy = -6 * std::sin(yaw);
  const uint32_t drone = Send(SpawnBody("drone.generic_quad", MakePose(car_pose.position().x() + dx,
                                                                        car_pose.position().y() + dy, 0))).actor();
  Drone(drone, msg::DroneCommandKind::DRONE_ARM);
  Drone(drone, msg::DroneCommandKind::DRONE_TAKEOFF, [](msg::DroneCommand& d) { d.values({3.0}); });
  uint64_t frame = 0;
  for (int i = 0; i < 160; ++i) frame = Tick();  // 8 s: up to 3 m
  ASSERT_GT(DroneAt(frame).transform().position().z(), 2.0) << "the drone did not take off";

  Autopilot(car);
  // Track the roof; once over it with the car under way, descend below the roof top (the
  // contact ends the descent) and keep tracking until the drone has been at rest on the roof
  // (AirSim's LANDED state) for 10 ticks.
  uint64_t touchdown = 0;
  double touchdown_speed = 0, rest_error = 1e9;
  int at_rest = 0;
  for (int i = 0; i < 1200 && at_rest < 10; ++i) {
    const msg::VehicleState v = Car(frame, car);
    const msg::DroneState d = DroneAt(frame);
    const double error = Horizontal(d.transform().position(), v.transform().position());
    const double roof = v.transform().position().z() + v.half_extents().z();
    const double speed = std::hypot(v.velocity().x(), v.velocity().y());
    if (touchdown == 0 && d.collision().has_collided() && d.collision().other_actor() == car) {
      touchdown = frame;
      touchdown_speed = speed;
    }
    const bool on_roof = d.landed() == msg::LandedState::LANDED_LANDED && d.transform().position().z() < roof + 0.3 &&
                         d.transform().position().z() > roof - 0.05;
    at_rest = touchdown != 0 && on_roof ? at_rest + 1 : 0;
    rest_error = error;
    if (at_rest >= 10) break;
    const bool descend = touchdown != 0 || (error < 0.25 && speed > 3.0);
    // The target: where the car will be at the end of the tick the command acts in.
    Drone(drone, msg::DroneCommandKind::DRONE_TRACK_TARGET, [&](msg::DroneCommand& c) {
      c.target().x(v.transform().position().x() + v.velocity().x() * kDt);
      c.target().y(v.transform().position().y() + v.velocity().y() * kDt);
      c.target().z(descend ? roof - 0.1 : roof + 1.5);
      c.values({v.velocity().x(), v.velocity().y(), 0.0});
      c.velocity(12);  // m/s, max closing speed
      c.duration(0.05);
    });
    frame = Tick();
  }
  ASSERT_NE(touchdown, 0u) << "the drone never touched the car";
  ASSERT_GE(at_rest, 10) << "the drone never came to rest on the roof";
  std::cout << "touchdown at frame " << touchdown << " (car at " << touchdown_speed << " m/s), at rest on the roof at frame "
            << frame << ", " << rest_error << " m from the roof centre\n";
  EXPECT_GT(touchdown_speed, 3.0) << "the car was not under way";
  EXPECT_GT(std::hypot(Car(frame, car).velocity().x(), Car(frame, car).velocity().y()), 3.0) << "the car was not under way";
  EXPECT_LT(rest_error, 0.5) << "landing error (m)";

  Drone(drone, msg::DroneCommandKind::DRONE_LAND);
  double worst = 0, min_speed = 1e9, min_ride_height = 1e9;
  int landed_ticks = 0;
  for (int i = 0; i < 400; ++i) {  // 20 s riding
    frame = Tick();
    const msg::VehicleState v = Car(frame, car);
    const msg::DroneState d = DroneAt(frame);
    worst = std::max(worst, Horizontal(d.transform().position(), v.transform().position()));
    min_speed = std::min(min_speed, std::hypot(v.velocity().x(), v.velocity().y()));
    const double roof = v.transform().position().z() + v.half_extents().z();
    EXPECT_GT(d.transform().position().z(), roof - 0.05) << "frame " << frame << ": not on top of the roof";
    EXPECT_LT(d.transform().position().z(), roof + 0.5) << "frame " << frame << ": off the roof";
    if (d.landed() == msg::LandedState::LANDED_LANDED) ++landed_ticks;
    // The drone's weight, not an immovable body, on the roof (ground_sim sees it as a 1 kg box).
    min_ride_height = std::min(min_ride_height, v.transform().position().z());
  }
  const msg::VehicleState v = Car(frame, car);
  const msg::DroneState d = DroneAt(frame);
  std::cout << "riding 20 s: worst distance from the roof centre " << worst << " m, car speed >= " << min_speed << " m/s\n";
  EXPECT_EQ(d.landed(), msg::LandedState::LANDED_LANDED);
  EXPECT_GT(landed_ticks, 380) << "at rest on the roof for most of the ride";
  EXPECT_GT(min_speed, 2.0) << "the car kept driving";
  EXPECT_LT(worst, 0.5) << "the drone slid on the roof";
  EXPECT_GT(min_ride_height, v.half_extents().z() - 0.03) << "the drone pressed the car down";
  EXPECT_NEAR(d.linear_velocity().x(), v.velocity().x(), 0.3) << "carried by the car";
  EXPECT_NEAR(d.linear_velocity().y(), v.velocity().y(), 0.3) << "carried by the car";
}

// A drone flown into the back of a parked car: air_sim reports the contact for the drone
// (PhysicsEvents, and AirState's collision naming "vehicle_<id>"), ground_sim for the car
// (PhysicsEvents, other = the drone), each naming the other, within a frame of each other
// (Jacobi coupling: each sees the other's body of the previous frame).
TEST_F(DroneCarTest, ADroneHittingACarIsACollisionOnBothSides) {
  double straight = 0, yaw = 0;
  const msg::Pose car_pose = LongestStraight(0.745, &straight, &yaw);
  const uint32_t car = Send(SpawnBody("vehicle.tesla.model3", car_pose)).actor();
  // 8 m behind the car on its lane; (lx, ly) points from the car to the drone.
  const double lx = -std::cos(yaw), ly = -std::sin(yaw);
  const double x0 = car_pose.position().x(), y0 = car_pose.position().y();
  const uint32_t drone = Send(SpawnBody("drone.generic_quad", MakePose(x0 + 8 * lx, y0 + 8 * ly, 0))).actor();
  Drone(drone, msg::DroneCommandKind::DRONE_ARM);
  Drone(drone, msg::DroneCommandKind::DRONE_TAKEOFF, [](msg::DroneCommand& d) { d.values({1.0}); });
  uint64_t frame = 0;
  for (int i = 0; i < 160; ++i) frame = Tick();
  ASSERT_GT(DroneAt(frame).transform().position().z(), 0.8) << "the drone did not take off";
  // Through the car at 1 m (its box reaches 1.49 m), at 4 m/s.
  Drone(drone, msg::DroneCommandKind::DRONE_MOVE_TO_POSITION, [&](msg::DroneCommand& d) {
    d.target().x(x0 - 8 * lx);
    d.target().y(y0 - 8 * ly);
    d.target().z(1.0);
    d.velocity(4);
  });
  uint64_t air_frame = 0, ground_frame = 0;
  msg::ActorCollision air_event, ground_event;
  for (int i = 0; i < 200 && (air_frame == 0 || ground_frame == 0); ++i) {
    frame = Tick();
    for (const auto& c : Collisions("air_sim", frame)) {
      if (air_frame == 0 && c.actor() == drone && c.other_kind() == msg::ObjectKind::OBJECT_VEHICLE) {
        air_frame = frame;
        air_event = c;
      }
    }
    for (const auto& c : Collisions("ground_sim", frame)) {
      if (ground_frame == 0 && c.actor() == car && c.other_kind() == msg::ObjectKind::OBJECT_DRONE) {
        ground_frame = frame;
        ground_event = c;
      }
    }
  }
  ASSERT_NE(air_frame, 0u) << "air_sim reported no collision of the drone with a vehicle";
  ASSERT_NE(ground_frame, 0u) << "ground_sim reported no collision of the car with a drone";
  std::cout << "air_sim: drone " << drone << " hit vehicle " << air_event.other_actor() << " at frame " << air_frame
            << "; ground_sim: car " << car << " hit drone " << ground_event.other_actor() << " at frame " << ground_frame << "\n";
  EXPECT_EQ(air_event.other_actor(), car) << "air_sim names the car";
  EXPECT_EQ(ground_event.other_actor(), drone) << "ground_sim names the drone";
  EXPECT_LE(std::max(air_frame, ground_frame) - std::min(air_frame, ground_frame), 1u) << "one contact, seen from both sides";
  const msg::DroneState d = DroneAt(air_frame);
  EXPECT_EQ(d.collision().other_actor(), car);
  EXPECT_EQ(d.collision().other_kind(), msg::ObjectKind::OBJECT_VEHICLE);
  EXPECT_EQ(d.collision().other_name().to_string(), "vehicle_" + std::to_string(car));
  // The impulses: on the drone away from the car, on the car away from the drone.
  const double air_push = air_event.normal_impulse().x() * lx + air_event.normal_impulse().y() * ly;
  const double ground_push = ground_event.normal_impulse().x() * lx + ground_event.normal_impulse().y() * ly;
  EXPECT_GT(air_push, 0.0) << "the drone is pushed back towards where it came from";
  EXPECT_LT(ground_push, 0.0) << "the car is pushed away from the drone";
}

}  // namespace
}  // namespace lockstep::testing
