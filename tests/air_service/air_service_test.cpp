// The air_sim service behind the real coordinator on the in-process bus: drones are
// spawned and flown by client commands, AirState comes every frame stamped with it,
// bad commands are rejected with a reason, and two runs with one seed agree bit for bit.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <map>
#include <mutex>
#include <thread>

#include "air_service.h"
#include "lockstep/runtime/blueprint_builder.h"
#include "lockstep/runtime/command_builders.h"
#include "lockstep/coordinator/coordinator.h"
#include "lockstep/map/scene.h"
#include "missing_input.h"
#include "observer.h"
#include "stand_in_blueprints.h"

namespace lockstep {
namespace {

using namespace std::chrono_literals;

class AirServiceTest : public ::testing::Test {
 protected:
  void Start(bool sync) {
    LaunchConfig c;
    c.world = DefaultWorldSettings();
    c.world.synchronous_mode(sync);
    c.world.service_timeout(30);
    c.services.push_back({"air_sim", "air_sim", "", {}, true, false, "never"});
    bus_ = CreateInProcessBus();
    states_ = Reader<msg::AirState>(*bus_, topics::kAirState, [this](const msg::AirState& s, const SampleInfo&) {
      std::lock_guard<std::mutex> lock(mu_);
      air_[s.stamp().frame()] = s;
    });
    events_ = Reader<msg::SimEvent>(*bus_, topics::kEvent, [this](const msg::SimEvent& e, const SampleInfo&) {
      std::lock_guard<std::mutex> lock(mu_);
      event_log_.push_back(e.message().to_string());
    });
    observer_ = std::make_unique<testing::Observer>(*bus_);
    coordinator_ = std::make_unique<Coordinator>(*bus_, c);
    core_ = std::make_unique<AirService>(*bus_);
    runner_ = std::make_unique<ServiceRunner>(*bus_, ServiceOptions{"air_sim", "air_sim", false}, *core_);
    runner_thread_ = std::thread([this] { runner_->Run(stop_); });
    coordinator_thread_ = std::thread([this] { coordinator_->Run(stop_); });
  }
  void TearDown() override {
    stop_ = true;
    if (coordinator_thread_.joinable()) coordinator_thread_.join();
    if (runner_thread_.joinable()) runner_thread_.join();
  }
  msg::CommandReply Send(msg::CommandBody b) {
    auto r = observer_->WaitReply(observer_->Send(std::move(b)), 10s);
    EXPECT_TRUE(r.has_value());
    return r.value_or(msg::CommandReply{});
  }
  uint32_t SpawnDrone(double x, double y, const AttributeList& attrs = {}) {
    auto r = Send(SpawnBody("drone.generic_quad", MakePose(x, y, 0), attrs));
    EXPECT_TRUE(r.accepted()) << r.reason();
    return r.actor();
  }
  msg::CommandReply Drone(uint32_t actor, msg::DroneCommandKind kind, uint64_t id, std::function<void(msg::DroneCommand&)> fill = {}) {
    msg::DroneCommand d;
    d.actor(actor);
    d.kind(kind);
    d.command_id(id);
    d.velocity(3);
    if (fill) fill(d);
    msg::CommandBody b;
    b.drone(d);
    return Send(b);
  }
  void Tick(uint32_t n) {
    msg::TickRequest t;
    t.count(n);
    msg::CommandBody b;
    b.tick_request(t);
    auto r = Send(b);
    ASSERT_TRUE(r.accepted()) << r.reason();
    ASSERT_TRUE(observer_->WaitUntil([&] { return observer_->last_frame() >= r.frame(); }, 60s));
  }
  std::optional<msg::AirState> State(uint64_t frame) {
    std::lock_guard<std::mutex> lock(mu_);
    auto it = air_.find(frame);
    if (it == air_.end()) return std::nullopt;
    return it->second;
  }
  std::optional<msg::AirState> WaitState(uint64_t frame) {
    std::optional<msg::AirState> s;
    observer_->WaitUntil([&] { return (s = State(frame)).has_value(); }, 10s);
    return s;
  }

  std::unique_ptr<Bus> bus_;
  std::mutex mu_;
  std::map<uint64_t, msg::AirState> air_;
  std::vector<std::string> event_log_;
  Reader<msg::AirState> states_;
  Reader<msg::SimEvent> events_;
  std::unique_ptr<testing::Observer> observer_;
  std::unique_ptr<Coordinator> coordinator_;
  std::unique_ptr<AirService> core_;
  std::unique_ptr<ServiceRunner> runner_;
  std::thread runner_thread_, coordinator_thread_;
  std::atomic<bool> stop_{false};
};

TEST_F(AirServiceTest, TakesOffThroughTheWireAndReportsEveryFrame) {
  Start(true);
  ASSERT_TRUE(observer_->WaitUntil([&] { return observer_->status() && observer_->status()->state() == msg::RunState::RUN_READY; }, 10s));
  const uint32_t drone = SpawnDrone(10, -5);
  EXPECT_TRUE(Drone(drone, msg::DroneCommandKind::DRONE_ARM, 1).accepted());
  EXPECT_TRUE(Drone(drone, msg::DroneCommandKind::DRONE_TAKEOFF, 2).accepted());
  Tick(120);  // 6 s
  for (uint64_t f = 1; f <= 120; ++f) ASSERT_TRUE(WaitState(f)) << "no AirState for frame " << f;
  auto s = *State(120);
  ASSERT_EQ(s.drones().size(), 1u);
  const auto& d = s.drones()[0];
  EXPECT_EQ(d.actor(), drone);
  EXPECT_EQ(s.stamp().frame(), 120u);
  EXPECT_NEAR(s.stamp().sim_time(), 6.0, 1e-9);
  EXPECT_NEAR(d.transform().position().x(), 10, 0.2);
  EXPECT_NEAR(d.transform().position().z(), 2.0 + d.home_pose().position().z(), 0.15) << "take-off height 2 m";
  EXPECT_EQ(d.landed(), msg::LandedState::LANDED_FLYING);
  EXPECT_TRUE(d.armed());
  EXPECT_EQ(d.command_id(), 2u);
  EXPECT_EQ(d.command_status(), msg::DroneCommandStatus::DRONE_CMD_COMPLETED);
  EXPECT_EQ(d.rotors().size(), 4u);
}

// The calls a MultirotorClient user has, on the wire, and getMultirotorState's extra fields.
TEST_F(AirServiceTest, AirSimCallsOnTheWire) {
  Start(true);
  ASSERT_TRUE(observer_->WaitUntil([&] { return observer_->status() && observer_->status()->state() == msg::RunState::RUN_READY; }, 10s));
  const uint32_t drone = SpawnDrone(4, 2);
  using K = msg::DroneCommandKind;
  EXPECT_TRUE(Drone(drone, K::DRONE_ARM, 1).accepted());
  Tick(1);
  {
    auto s = WaitState(1);
    ASSERT_TRUE(s);
    const auto& d = s->drones()[0];
    EXPECT_TRUE(d.ready());
    EXPECT_TRUE(d.can_arm()) << "at rest on the ground";
    EXPECT_EQ(d.timestamp(), 50000000u);  // ns, frame 1 at 0.05 s
    EXPECT_EQ(d.collision().other_name().to_string(), "ground");
  }
  EXPECT_TRUE(Drone(drone, K::DRONE_TAKEOFF, 2).accepted());
  Tick(100);
  // moveToZ: 4 m up at 2 m/s, x, y kept.
  EXPECT_TRUE(Drone(drone, K::DRONE_MOVE_TO_Z, 3, [](msg::DroneCommand& d) {
                d.target().z(6.0);
                d.velocity(2);
              }).accepted());
  Tick(100);
  auto s = WaitState(201);
  ASSERT_TRUE(s);
  EXPECT_EQ(s->drones()[0].command_status(), msg::DroneCommandStatus::DRONE_CMD_COMPLETED);
  EXPECT_NEAR(s->drones()[0].transform().position().z(), 6.0, 0.2);
  EXPECT_NEAR(s->drones()[0].transform().position().x(), 4.0, 0.2);
  EXPECT_FALSE(s->drones()[0].can_arm()) << "flying";
  // moveToGPS through the geo-reference (no map here: lat_0 = lon_0 = 0): 3 m east.
  const map::GeoPoint goal = map::ToGeo(map::GeoReference{}, air::Vec3(7, 2, 6));
  EXPECT_TRUE(Drone(drone, K::DRONE_MOVE_TO_GPS, 12, [&](msg::DroneCommand& d) {
                d.values({goal.latitude, goal.longitude, goal.altitude});
                d.velocity(2);
              }).accepted());
  Tick(80);
  s = WaitState(281);
  ASSERT_TRUE(s);
  EXPECT_EQ(s->drones()[0].command_status(), msg::DroneCommandStatus::DRONE_CMD_COMPLETED);
  EXPECT_NEAR(s->drones()[0].transform().position().x(), 7.0, 0.25);
  EXPECT_NEAR(s->drones()[0].gps_location().longitude(), goal.longitude, 3e-6);
  // moveByRollPitchYawrateZ: yaw rate 0.5 rad/s at 6 m; rates-Z and rpy-rate-throttle accepted.
  EXPECT_TRUE(Drone(drone, K::DRONE_MOVE_BY_ROLL_PITCH_YAWRATE_Z, 4, [](msg::DroneCommand& d) {
                d.values({0, 0, 0.5, 6.0});
                d.duration(3);
              }).accepted());
  Tick(40);
  s = WaitState(321);
  ASSERT_TRUE(s);
  EXPECT_NEAR(s->drones()[0].angular_velocity().z(), 0.5, 0.1);
  EXPECT_EQ(s->drones()[0].command_status(), msg::DroneCommandStatus::DRONE_CMD_RUNNING);
  EXPECT_FALSE(Drone(drone, K::DRONE_MOVE_BY_ANGLE_RATES_Z, 5, [](msg::DroneCommand& d) { d.values({0, 0}); }).accepted());
  EXPECT_TRUE(Drone(drone, K::DRONE_MOVE_BY_ANGLE_RATES_Z, 6, [](msg::DroneCommand& d) {
                d.values({0, 0, 0, 6.0});
                d.duration(1);
              }).accepted());
  EXPECT_FALSE(Drone(drone, K::DRONE_MOVE_BY_ROLL_PITCH_YAWRATE_THROTTLE, 7, [](msg::DroneCommand& d) {
                 d.values({0, 0, 0, 1.5});
               }).accepted());
  // simSetWind: a 10 m/s wind towards +x pushes the hovering drone downwind until the position
  // loop leans it into the wind (a few degrees: the tilted bottom face, pi D^2 per rotor, also
  // meets the wind).
  s = WaitState(321);
  ASSERT_TRUE(s);
  const double x_before = s->drones()[0].transform().position().x();
  auto pitch_of = [](const msg::DroneState& d) {
    const auto& q = d.transform().orientation();
    return std::asin(std::clamp(2 * (q.w() * q.y() - q.z() * q.x()), -1.0, 1.0));
  };
  EXPECT_TRUE(Drone(drone, K::DRONE_SET_WIND, 8, [](msg::DroneCommand& d) { d.target().x(10); }).accepted());
  EXPECT_TRUE(Drone(drone, K::DRONE_HOVER, 9).accepted());
  Tick(100);
  s = WaitState(421);
  ASSERT_TRUE(s);
  const double hold_x = x_before;  // hover holds where it was (within the yaw manoeuvre's drift)
  EXPECT_LT(pitch_of(s->drones()[0]), -0.01) << "nose up into the wind (FLU pitch < 0)";
  EXPECT_GT(s->drones()[0].transform().position().x() - hold_x, 0.1) << "pushed downwind";
  // The weather's wind: wind_intensity 100 = 10 m/s towards +x with seeded gusts; simSetWind off.
  EXPECT_TRUE(Drone(drone, K::DRONE_SET_WIND, 11, [](msg::DroneCommand& d) { d.target().x(0); }).accepted());
  EXPECT_TRUE(Drone(drone, K::DRONE_HOVER, 13).accepted());
  Tick(20);
  msg::WeatherParameters weather;
  weather.wind_intensity(100);
  msg::CommandBody wb;
  wb.weather(weather);
  EXPECT_TRUE(Send(wb).accepted());
  Tick(100);
  s = WaitState(541);
  ASSERT_TRUE(s);
  EXPECT_LT(pitch_of(s->drones()[0]), -0.01) << "leaning into the weather's wind";
  // simSetKinematics: teleport with a velocity.
  EXPECT_TRUE(Drone(drone, K::DRONE_SET_KINEMATICS, 10, [](msg::DroneCommand& d) {
                d.target().x(20);
                d.target().y(20);
                d.target().z(10);
                d.values({1, 0, 0, 0, 2, 0, 0});
              }).accepted());
  Tick(1);
  s = WaitState(542);
  ASSERT_TRUE(s);
  EXPECT_NEAR(s->drones()[0].transform().position().x(), 20.0, 0.2);
  EXPECT_NEAR(s->drones()[0].transform().position().z(), 10.0, 0.2);
  // No map: the geo-reference is (0, 0); GPS follows the position.
  EXPECT_GT(s->drones()[0].gps_location().longitude(), 0.0);
  EXPECT_GT(s->drones()[0].gps_location().latitude(), 0.0);
  EXPECT_NEAR(s->drones()[0].gps_location().altitude(), s->drones()[0].transform().position().z(), 1e-9);
}

TEST_F(AirServiceTest, BadDroneCommandsAreRejectedAndTheServiceKeepsTicking) {
  Start(true);
  ASSERT_TRUE(observer_->WaitUntil([&] { return observer_->status() && observer_->status()->state() == msg::RunState::RUN_READY; }, 10s));
  const uint32_t drone = SpawnDrone(0, 0);
  auto nan = Drone(drone, msg::DroneCommandKind::DRONE_MOVE_TO_POSITION, 3, [](msg::DroneCommand& d) {
    d.target().x(std::numeric_limits<double>::quiet_NaN());
  });
  EXPECT_FALSE(nan.accepted());
  EXPECT_NE(nan.reason().to_string().find("NaN"), std::string::npos) << nan.reason();
  auto unknown = Drone(4242, msg::DroneCommandKind::DRONE_ARM, 4);
  EXPECT_FALSE(unknown.accepted());
  EXPECT_EQ(unknown.reason().to_string(), "unknown actor 4242");
  auto range = Drone(drone, msg::DroneCommandKind::DRONE_MOVE_BY_ROLL_PITCH_YAW_THROTTLE, 5,
                     [](msg::DroneCommand& d) { d.values({0, 0, 0, 3.0}); });
  EXPECT_FALSE(range.accepted());
  EXPECT_NE(range.reason().to_string().find("throttle"), std::string::npos);
  msg::SpawnActor bad;
  bad.blueprint("drone.generic_quad");
  bad.transform().orientation().w(1);
  msg::BlueprintAttribute mass;
  mass.key("mass");
  mass.value("0");
  bad.attributes({mass});
  msg::CommandBody b;
  b.spawn_actor(bad);
  auto spawn = Send(b);
  EXPECT_FALSE(spawn.accepted());
  EXPECT_NE(spawn.reason().to_string().find("mass"), std::string::npos) << spawn.reason();
  // A disarmed drone asked to move: accepted on the wire, rejected by the controller.
  EXPECT_TRUE(Drone(drone, msg::DroneCommandKind::DRONE_MOVE_TO_POSITION, 6, [](msg::DroneCommand& d) { d.target().x(5); }).accepted());
  Tick(10);
  auto s = WaitState(10);
  ASSERT_TRUE(s);
  EXPECT_EQ(s->drones()[0].command_id(), 6u);
  EXPECT_EQ(s->drones()[0].command_status(), msg::DroneCommandStatus::DRONE_CMD_REJECTED);
  std::lock_guard<std::mutex> lock(mu_);
  ASSERT_FALSE(event_log_.empty());
  bool found = false;
  for (const auto& e : event_log_) found = found || e.find("command 6 rejected") != std::string::npos;
  EXPECT_TRUE(found) << event_log_.back();
}

}  // namespace
}  // namespace lockstep

namespace lockstep {
namespace {

using namespace std::chrono_literals;

// The map travels over DDS: air_sim builds the town mesh from the coordinator's MapData
// (never from a file), and a drone flown at a building's wall collides with it.
TEST(AirServiceTown, DroneHitsABuildingOfTheMapPublishedOverDds) {
  const std::string xodr = std::string(LOCKSTEP_TEST_TOWN_DIR) + "/LockstepTown1.xodr";
  const map::Scene scene = map::LoadSceneFile(std::string(LOCKSTEP_TEST_TOWN_DIR) + "/LockstepTown1.scene.yaml");
  ASSERT_FALSE(scene.buildings.empty());
  const auto& b = scene.buildings.front();
  LaunchConfig c;
  c.world = DefaultWorldSettings();
  c.world.synchronous_mode(true);
  c.world.service_timeout(60);
  c.map = xodr;
  c.services.push_back({"air_sim", "air_sim", "", {}, true, false, "never"});
  auto bus = CreateInProcessBus();
  std::mutex mu;
  std::optional<msg::AirState> last;
  Reader<msg::AirState> states(*bus, topics::kAirState, [&](const msg::AirState& s, const SampleInfo&) {
    std::lock_guard<std::mutex> lock(mu);
    last = s;
  });
  // The drones' collisions for the sensors' collision sensor: one batch per frame.
  std::map<uint64_t, msg::PhysicsEvents> physics;
  Reader<msg::PhysicsEvents> physics_reader(*bus, topics::kPhysicsEvents, [&](const msg::PhysicsEvents& e, const SampleInfo&) {
    std::lock_guard<std::mutex> lock(mu);
    physics[e.stamp().frame()] = e;
  });
  testing::Observer obs(*bus);
  Coordinator coordinator(*bus, c);
  AirService core(*bus);
  ServiceRunner runner(*bus, ServiceOptions{"air_sim", "air_sim", false}, core);
  std::atomic<bool> stop{false};
  std::thread rt([&] { runner.Run(stop); });
  std::thread ct([&] { coordinator.Run(stop); });
  struct Join {
    std::atomic<bool>& stop;
    std::thread& a;
    std::thread& b;
    ~Join() {
      stop = true;
      a.join();
      b.join();
    }
  } join{stop, rt, ct};
  ASSERT_TRUE(obs.WaitUntil([&] { return obs.status() && obs.status()->state() == msg::RunState::RUN_READY; }, 60s));
  ASSERT_TRUE(core.model().statics.mesh) << "no town mesh";
  EXPECT_GT(core.model().statics.mesh->triangle_count(), 10000u);
  // Start 8 m from the building's centre along its local -y (the street side), at 3 m.
  const double ox = b.x + std::sin(b.yaw) * (b.depth / 2 + 6), oy = b.y - std::cos(b.yaw) * (b.depth / 2 + 6);
  msg::SpawnActor s;
  s.blueprint("drone.generic_quad");
  s.transform().position().x(ox);
  s.transform().position().y(oy);
  s.transform().position().z(b.z);
  s.transform().orientation().w(1);
  msg::CommandBody body;
  body.spawn_actor(s);
  auto spawn = obs.WaitReply(obs.Send(body), 10s);
  ASSERT_TRUE(spawn && spawn->accepted());
  auto send = [&](msg::DroneCommandKind kind, std::function<void(msg::DroneCommand&)> fill = {}) {
    msg::DroneCommand d;
    d.actor(spawn->actor());
    d.kind(kind);
    d.velocity(3);
    if (fill) fill(d);
    msg::CommandBody cb;
    cb.drone(d);
    auto r = obs.WaitReply(obs.Send(cb), 10s);
    ASSERT_TRUE(r && r->accepted()) << (r ? r->reason().to_string() : "no reply");
  };
  send(msg::DroneCommandKind::DRONE_ARM);
  send(msg::DroneCommandKind::DRONE_TAKEOFF);
  auto tick = [&](uint32_t n) {
    msg::TickRequest t;
    t.count(n);
    msg::CommandBody tb;
    tb.tick_request(t);
    auto r = obs.WaitReply(obs.Send(tb), 10s);
    ASSERT_TRUE(r && r->accepted());
    ASSERT_TRUE(obs.WaitUntil([&] { return obs.last_frame() >= r->frame(); }, 60s));
  };
  tick(100);
  // Fly through the building's centre at 3 m above its ground.
  send(msg::DroneCommandKind::DRONE_MOVE_TO_POSITION, [&](msg::DroneCommand& d) {
    d.target().x(b.x);
    d.target().y(b.y);
    d.target().z(b.z + 3);
  });
  tick(200);
  // AirState and PhysicsEvents of a frame are two writers: wait for both of frame 300.
  ASSERT_TRUE(obs.WaitUntil([&] { std::lock_guard<std::mutex> lock(mu); return last && last->stamp().frame() == 300 && physics.count(300); }, 10s));
  std::lock_guard<std::mutex> lock(mu);
  const auto& d = last->drones().at(0);
  EXPECT_TRUE(d.collision().has_collided());
  EXPECT_EQ(d.collision().other_kind(), msg::ObjectKind::OBJECT_STATIC);
  EXPECT_EQ(d.collision().other_name().to_string(), "static_1");
  EXPECT_EQ(d.collision().other_id(), 1);
  EXPECT_GE(d.collision().collision_count(), 1u);
  const double left = std::hypot(d.transform().position().x() - b.x, d.transform().position().y() - b.y);
  EXPECT_GT(left, std::min(b.width, b.depth) / 2 - 0.5) << "the drone must stay outside the walls";
  ASSERT_TRUE(physics.count(300)) << "a PhysicsEvents batch every frame";
  int hits = 0;
  for (uint64_t f = 1; f <= 300; ++f) {
    ASSERT_TRUE(physics.count(f)) << "no PhysicsEvents for frame " << f;
    EXPECT_EQ(physics[f].service().to_string(), "air_sim");
    for (const auto& col : physics[f].collisions()) {
      EXPECT_EQ(col.actor(), spawn->actor());
      hits += col.other_kind() == msg::ObjectKind::OBJECT_STATIC;
    }
  }
  EXPECT_GE(hits, 1) << "the building hit as a PhysicsEvents collision";
}

}  // namespace
}  // namespace lockstep

namespace lockstep {
namespace {

using namespace std::chrono_literals;

// Stands in for ground_sim: one car driving east at 5 m/s, published every frame.
class CarOnlyGround final : public ServiceCore {
 public:
  explicit CarOnlyGround(Bus& bus) : writer_(bus, topics::kGroundState) {}
  void BeginRun(const msg::WorldInfo&) override {}
  // It simulates vehicles: that (not its name) makes air_sim wait for its GroundState.
  std::vector<msg::BlueprintDeclaration> Blueprints() const override { return testing::StandInBlueprints(); }
  void Step(const msg::Tick& tick) override {
    msg::GroundState g;
    g.stamp().run(tick.run());
    g.stamp().frame(tick.frame());
    g.stamp().sim_time(tick.sim_time());
    msg::VehicleState v;
    v.actor(500);
    v.transform(MakePose(kSpeed * tick.sim_time(), 0, kHalfHeight));
    v.velocity().x(kSpeed);
    v.half_extents().x(2.4);
    v.half_extents().y(1.0);
    v.half_extents().z(kHalfHeight);
    g.vehicles({v});
    g.state_hash(tick.frame());
    writer_.Write(g);
  }
  static constexpr double kSpeed = 5.0;       // m/s
  static constexpr double kHalfHeight = 0.75; // m: the roof is at 1.5 m

 private:
  Writer<msg::GroundState> writer_;
};

// The Jacobi coupling through the wire: air_sim reads the car of frame k-1 from
// GroundState, and a client that only sees the published states lands a drone on the
// moving roof, which then carries it.
TEST(AirServiceGround, ClientLandsADroneOnACarDrivingAtFiveMetresPerSecond) {
  LaunchConfig c;
  c.world.synchronous_mode(true);
  c.world.service_timeout(30);
  c.services.push_back({"traffic", "car_only", "", {}, true, false, "never"});  // any name: found by its declarations
  c.services.push_back({"air_sim", "air_sim", "", {}, true, false, "never"});
  auto bus = CreateInProcessBus();
  std::mutex mu;
  std::map<uint64_t, msg::AirState> air;
  std::map<uint64_t, msg::GroundState> ground;
  Reader<msg::AirState> ar(*bus, topics::kAirState, [&](const msg::AirState& s, const SampleInfo&) {
    std::lock_guard<std::mutex> lock(mu);
    air[s.stamp().frame()] = s;
  });
  Reader<msg::GroundState> gr(*bus, topics::kGroundState, [&](const msg::GroundState& s, const SampleInfo&) {
    std::lock_guard<std::mutex> lock(mu);
    ground[s.stamp().frame()] = s;
  });
  testing::Observer obs(*bus);
  Coordinator coordinator(*bus, c);
  CarOnlyGround car(*bus);
  AirService drones(*bus);
  ServiceRunner rg(*bus, ServiceOptions{"traffic", "car_only", false}, car);
  ServiceRunner ra(*bus, ServiceOptions{"air_sim", "air_sim", false}, drones);
  std::atomic<bool> stop{false};
  std::thread tg([&] { rg.Run(stop); });
  std::thread ta([&] { ra.Run(stop); });
  std::thread tc([&] { coordinator.Run(stop); });
  struct Join {
    std::atomic<bool>& stop;
    std::vector<std::thread*> threads;
    ~Join() {
      stop = true;
      for (auto* t : threads) t->join();
    }
  } join{stop, {&tg, &ta, &tc}};
  ASSERT_TRUE(obs.WaitUntil([&] { return obs.status() && obs.status()->state() == msg::RunState::RUN_READY; }, 20s));

  auto send = [&](msg::CommandBody b) {
    auto r = obs.WaitReply(obs.Send(std::move(b)), 10s);
    EXPECT_TRUE(r && r->accepted()) << (r ? r->reason().to_string() : "no reply");
    return r.value_or(msg::CommandReply{});
  };
  auto drone = [&](uint32_t actor, msg::DroneCommandKind kind, std::function<void(msg::DroneCommand&)> fill = {}) {
    msg::DroneCommand d;
    d.actor(actor);
    d.kind(kind);
    d.yaw().is_rate(true);
    if (fill) fill(d);
    msg::CommandBody b;
    b.drone(d);
    send(b);
  };
  auto tick = [&](uint64_t* frame) {
    msg::TickRequest t;
    t.count(1);
    msg::CommandBody b;
    b.tick_request(t);
    const uint64_t want = send(b).frame();
    EXPECT_TRUE(obs.WaitUntil([&] {
      std::lock_guard<std::mutex> lock(mu);
      return air.count(want) && ground.count(want);
    }, 10s));
    *frame = want;
  };

  const uint32_t id = send(SpawnBody("drone.generic_quad", MakePose(-10, 4, 0))).actor();
  drone(id, msg::DroneCommandKind::DRONE_ARM);
  drone(id, msg::DroneCommandKind::DRONE_TAKEOFF, [](msg::DroneCommand& d) { d.values({3.0}); });
  uint64_t frame = 0;
  for (int i = 0; i < 160; ++i) tick(&frame);  // 8 s: up to 3 m at AirSim's 0.5 m/s

  // Follow the roof using only published states: target = car of this frame plus its
  // velocity (the service extrapolates it through the tick), first 1.5 m above the roof,
  // then onto it.
  bool touched = false;
  double touchdown_error = 1e9;
  for (int i = 0; i < 600 && !touched; ++i) {
    msg::GroundState g;
    msg::DroneState d;
    {
      std::lock_guard<std::mutex> lock(mu);
      g = ground.at(frame);
      d = air.at(frame).drones().at(0);
    }
    const auto& car_pos = g.vehicles().at(0).transform().position();
    const double dx = d.transform().position().x() - car_pos.x(), dy = d.transform().position().y() - car_pos.y();
    const bool above = std::hypot(dx, dy) < 0.25;

    if (d.collision().has_collided() && d.collision().other_kind() == msg::ObjectKind::OBJECT_VEHICLE) {
      touched = true;
      touchdown_error = std::hypot(dx, dy);
      break;
    }
    drone(id, msg::DroneCommandKind::DRONE_TRACK_TARGET, [&](msg::DroneCommand& c2) {
      c2.target().x(car_pos.x());
      c2.target().y(car_pos.y());
      c2.target().z(above ? 1.4 : 3.0);  // below the roof top: contact ends the descent
      c2.values({CarOnlyGround::kSpeed, 0.0, 0.0});
      c2.velocity(12);  // m/s, max closing speed
      c2.duration(0.05);
    });
    tick(&frame);
  }
  ASSERT_TRUE(touched) << "the drone never touched the car";
  EXPECT_LT(touchdown_error, 0.5) << "touchdown error (m)";
  std::cout << "touchdown at frame " << frame << ", error " << touchdown_error << " m\n";
  drone(id, msg::DroneCommandKind::DRONE_LAND);
  for (int i = 0; i < 60; ++i) tick(&frame);  // 3 s riding
  std::lock_guard<std::mutex> lock(mu);
  const auto& d = air.at(frame).drones().at(0);
  const auto& car_pos = ground.at(frame).vehicles().at(0).transform().position();
  EXPECT_EQ(d.landed(), msg::LandedState::LANDED_LANDED);
  EXPECT_NEAR(d.linear_velocity().x(), CarOnlyGround::kSpeed, 0.3) << "carried by the car";
  EXPECT_NEAR(d.transform().position().x(), car_pos.x(), 1.0) << "still on the roof";
  EXPECT_GT(d.transform().position().z(), 1.5) << "on top of the roof, not through it";
}

// The core alone on the in-process bus, fed by hand. A member that declares vehicles (not
// named "ground_sim") makes its GroundState of frame k-1 an input of frame k: a frame whose
// vehicles did not come faults the run (MissingInput out of Step) and leaves the state as it
// was, instead of stepping the drones without the cars (a state that would depend on when a
// sample arrived).
TEST(AirInputs, AFrameWithoutTheVehiclesOfTheFrameBeforeFaultsInsteadOfSteppingWithoutThem) {
  auto bus = CreateInProcessBus();
  Writer<msg::BlueprintSet> sets(*bus, topics::kBlueprints);
  Writer<msg::GroundState> ground(*bus, topics::kGroundState);
  msg::BlueprintSet cars;
  cars.service("cars");
  cars.blueprints({blueprint::Make("vehicle.lockstep.sedan", msg::ActorKind::ACTOR_VEHICLE, {blueprint::String("role_name", "")})});
  sets.Write(cars);
  AirService core(*bus);
  msg::WorldInfo world;
  world.run(1);
  world.seed(7);
  msg::WorldSettings settings = DefaultWorldSettings();
  settings.service_timeout(0.3);  // how long a step waits for an input
  world.settings(settings);
  world.required_services({msg::ServiceName("air_sim"), msg::ServiceName("cars")});
  core.BeginRun(world);
  EXPECT_FALSE(core.StepNeverWaits());
  auto tick = [](uint64_t frame) {
    msg::Tick t;
    t.run(1);
    t.frame(frame);
    t.dt(0.05);
    t.sim_time(0.05 * static_cast<double>(frame));
    return t;
  };
  msg::Tick first = tick(1);  // frame 1 reads no earlier frame
  msg::Command spawn;
  msg::CommandBody body = SpawnBody("drone.generic_quad", MakePose(3, 4, 0));
  body.spawn_actor().actor(40);
  body.spawn_actor().owner("air_sim");
  spawn.body(body);
  first.commands({spawn});
  core.Step(first);
  ASSERT_EQ(core.model().drones.size(), 1u);
  const uint64_t hash = core.StateHash();
  testing::ExpectMissingInput(core, tick(2), "no GroundState of frame 1");
  // With the input there, the frame steps.
  msg::GroundState g;
  g.stamp().run(1);
  g.stamp().frame(1);
  ground.Write(g);
  EXPECT_NO_THROW(core.Step(tick(2)));
  EXPECT_NE(core.StateHash(), hash);
}

}  // namespace
}  // namespace lockstep
