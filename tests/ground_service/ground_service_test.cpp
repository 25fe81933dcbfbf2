// The ground_sim service behind the real coordinator on the in-process bus, in CARLA's
// Town01: vehicles spawned by CARLA ids, GroundState and PhysicsEvents every frame,
// controls applied, bad commands rejected with a reason, the Traffic Manager driving.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <map>
#include <mutex>
#include <sstream>
#include <thread>

#include "ground_service.h"
#include "lockstep/coordinator/coordinator.h"
#include "lockstep/map/map.h"
#include "lockstep/runtime/blueprint_builder.h"
#include "lockstep/runtime/command_builders.h"
#include "lockstep/runtime/error.h"
#include "lockstep/runtime/hash.h"
#include "missing_input.h"
#include "observer.h"

namespace lockstep {
namespace {

using namespace std::chrono_literals;

const std::string kTown01 = std::string(LOCKSTEP_CARLA_MAPS_DIR) + "/Town01.xodr";

class GroundServiceTest : public ::testing::Test {
 protected:
  void SetUp() override {
    LaunchConfig c;
    c.world = DefaultWorldSettings();
    c.world.synchronous_mode(true);
    c.world.service_timeout(30);
    c.map = kTown01;
    c.services.push_back({"ground_sim", "ground_sim", "", {}, true, false, "never"});
    bus_ = CreateInProcessBus();
    states_ = Reader<msg::GroundState>(*bus_, topics::kGroundState, [this](const msg::GroundState& s, const SampleInfo&) {
      std::lock_guard<std::mutex> lock(mu_);
      ground_[s.stamp().frame()] = s;
    });
    physics_ = Reader<msg::PhysicsEvents>(*bus_, topics::kPhysicsEvents, [this](const msg::PhysicsEvents& e, const SampleInfo&) {
      std::lock_guard<std::mutex> lock(mu_);
      physics_events_[e.stamp().frame()] = e;
    });
    events_ = Reader<msg::SimEvent>(*bus_, topics::kEvent, [this](const msg::SimEvent& e, const SampleInfo&) {
      std::lock_guard<std::mutex> lock(mu_);
      failures_.push_back(e);
    });
    observer_ = std::make_unique<testing::Observer>(*bus_);
    coordinator_ = std::make_unique<Coordinator>(*bus_, c);
    std::filesystem::remove_all(out_dir_);
    core_ = std::make_unique<GroundService>(*bus_, "ground_sim", out_dir_);
    runner_ = std::make_unique<ServiceRunner>(*bus_, ServiceOptions{"ground_sim", "ground_sim", false}, *core_);
    runner_thread_ = std::thread([this] { runner_->Run(stop_); });
    coordinator_thread_ = std::thread([this] { coordinator_->Run(stop_); });
    ASSERT_TRUE(observer_->WaitUntil([&] { return observer_->status() && observer_->status()->state() == msg::RunState::RUN_READY; }, 60s));
  }
  void TearDown() override {
    stop_ = true;
    if (coordinator_thread_.joinable()) coordinator_thread_.join();
    if (runner_thread_.joinable()) runner_thread_.join();
    std::filesystem::remove_all(out_dir_);
  }
  msg::CommandReply Send(msg::CommandBody b) {
    auto r = observer_->WaitReply(observer_->Send(std::move(b)), 20s);
    EXPECT_TRUE(r.has_value());
    return r.value_or(msg::CommandReply{});
  }
  // A Town01 spawn point, as a vehicle pose (the box centre half its height above the road).
  msg::Pose SpawnPose(size_t index, double half_z = 0.745) {
    static const map::Map town = map::Map::Load(kTown01);
    const auto sp = town.SpawnPoints().at(index);
    return MakePose(sp.location.x(), sp.location.y(), sp.location.z() - 0.5 + half_z + 0.02, sp.yaw);
  }
  uint32_t Spawn(const std::string& bp, const msg::Pose& pose, const AttributeList& attrs = {}) {
    auto r = Send(SpawnBody(bp, pose, attrs));
    EXPECT_TRUE(r.accepted()) << r.reason();
    return r.actor();
  }
  void Tick(uint32_t n) {
    msg::TickRequest t;
    t.count(n);
    msg::CommandBody b;
    b.tick_request(t);
    auto r = Send(b);
    ASSERT_TRUE(r.accepted()) << r.reason();
    ASSERT_TRUE(observer_->WaitUntil([&] { return observer_->last_frame() >= r.frame(); }, 60s));
    ASSERT_TRUE(observer_->WaitUntil([&] { return State(r.frame()).has_value(); }, 10s));
  }
  std::optional<msg::GroundState> State(uint64_t frame) {
    std::lock_guard<std::mutex> lock(mu_);
    auto it = ground_.find(frame);
    if (it == ground_.end()) return std::nullopt;
    return it->second;
  }
  std::optional<msg::VehicleState> Vehicle(uint64_t frame, uint32_t id) {
    auto s = State(frame);
    if (!s) return std::nullopt;
    for (const auto& v : s->vehicles()) {
      if (v.actor() == id) return v;
    }
    return std::nullopt;
  }
  bool WaitFailure(const std::string& needle) {
    return observer_->WaitUntil([&] {
      std::lock_guard<std::mutex> lock(mu_);
      for (const auto& e : failures_) {
        if (e.kind() == msg::EventKind::EVENT_COMMAND_FAILED && e.message().to_string().find(needle) != std::string::npos) return true;
      }
      return false;
    }, 10s);
  }

  std::unique_ptr<Bus> bus_;
  std::mutex mu_;
  std::map<uint64_t, msg::GroundState> ground_;
  std::map<uint64_t, msg::PhysicsEvents> physics_events_;
  std::vector<msg::SimEvent> failures_;
  Reader<msg::GroundState> states_;
  Reader<msg::PhysicsEvents> physics_;
  Reader<msg::SimEvent> events_;
  std::unique_ptr<testing::Observer> observer_;
  std::unique_ptr<Coordinator> coordinator_;
  std::unique_ptr<GroundService> core_;
  std::unique_ptr<ServiceRunner> runner_;
  std::thread runner_thread_, coordinator_thread_;
  std::atomic<bool> stop_{false};
  const std::string out_dir_ = ::testing::TempDir() + "ground_service_out_" + std::to_string(::getpid());
};

TEST_F(GroundServiceTest, DrivesACarlaBlueprintAndPublishesEveryFrame) {
  const uint32_t car = Spawn("vehicle.tesla.model3", SpawnPose(0), {{"role_name", "hero"}});
  msg::VehicleControl c;
  c.actor(car);
  c.throttle(0.6);
  msg::CommandBody b;
  b.vehicle_control(c);
  ASSERT_TRUE(Send(b).accepted());
  Tick(40);
  const uint64_t last = observer_->last_frame();
  ASSERT_TRUE(observer_->WaitUntil([&] {
    std::lock_guard<std::mutex> lock(mu_);
    return physics_events_.count(last) > 0;
  }, 10s));
  std::lock_guard<std::mutex> lock(mu_);
  for (uint64_t f = 1; f <= last; ++f) {
    ASSERT_TRUE(ground_.count(f)) << "no GroundState for frame " << f;
    ASSERT_TRUE(physics_events_.count(f)) << "no PhysicsEvents for frame " << f;
    EXPECT_EQ(physics_events_.at(f).service().to_string(), "ground_sim");
    EXPECT_NE(ground_.at(f).state_hash(), 0u);
  }
  const auto& s = ground_.at(last);
  ASSERT_EQ(s.vehicles().size(), 1u);
  const auto& v = s.vehicles()[0];
  EXPECT_EQ(v.blueprint().to_string(), "vehicle.tesla.model3");
  EXPECT_EQ(v.role_name().to_string(), "hero");
  EXPECT_GT(std::hypot(v.velocity().x(), v.velocity().y()), 3.0);
  EXPECT_GT(v.physics().mass(), 1000);
  // Town01's lights are the coordinator's actors 1..n, grouped by junction.
  ASSERT_FALSE(s.traffic_lights().empty());
  for (size_t i = 0; i < s.traffic_lights().size(); ++i) EXPECT_EQ(s.traffic_lights()[i].actor(), i + 1);
  // The run's files: the vehicle log (rows of this car) and the infraction summary.
  const std::string dir = out_dir_ + "/run" + std::to_string(s.stamp().run()) + "/ground";
  std::ifstream csv(dir + "/vehicles.csv");
  std::string header, row;
  ASSERT_TRUE(std::getline(csv, header)) << dir;
  EXPECT_EQ(header.rfind("frame,sim_time_s,id,blueprint", 0), 0u);
  ASSERT_TRUE(std::getline(csv, row));
  EXPECT_NE(row.find("," + std::to_string(car) + ",vehicle.tesla.model3,hero,"), std::string::npos) << row;
  EXPECT_TRUE(std::filesystem::exists(dir + "/infractions.json"));
}

TEST_F(GroundServiceTest, RejectsWhatItCannotApplyWithAReason) {
  const uint32_t car = Spawn("vehicle.audi.tt", SpawnPose(1, 0.693));
  // The coordinator: a walker command to a vehicle; a bad colour attribute.
  msg::WalkerControl w;
  w.actor(car);
  w.speed(1);
  msg::CommandBody wb;
  wb.walker_control(w);
  auto r = Send(wb);
  EXPECT_FALSE(r.accepted());
  EXPECT_NE(r.reason().to_string().find("vehicle"), std::string::npos) << r.reason();
  auto bad = Send(SpawnBody("vehicle.audi.tt", SpawnPose(2, 0.693), {{"color", "300,0,0"}}));
  EXPECT_FALSE(bad.accepted());
  EXPECT_NE(bad.reason().to_string().find("color"), std::string::npos) << bad.reason();
  // ground_sim: manual control of a car the Traffic Manager drives; a spawn on top of a car.
  msg::TrafficManagerCommand tm;
  tm.parameter(msg::TrafficManagerParameter::TM_AUTOPILOT);
  tm.actor(car);
  tm.value(1);
  msg::CommandBody tb;
  tb.traffic_manager(tm);
  ASSERT_TRUE(Send(tb).accepted());
  msg::VehicleControl c;
  c.actor(car);
  c.throttle(1);
  msg::CommandBody cb;
  cb.vehicle_control(c);
  ASSERT_TRUE(Send(cb).accepted());
  Tick(2);
  EXPECT_TRUE(WaitFailure("autopilot"));
}

// CARLA refuses a spawn whose box overlaps an actor ("Spawn failed because of collision at
// spawn position"): the reply says so and no actor id is handed out, whether the other
// actor is in the state already or only spawned for the next tick (a batch, or two
// try_spawn_actor calls before a tick).
TEST_F(GroundServiceTest, ASpawnOnAnOccupiedSpawnPointIsRefusedBeforeItGetsAnId) {
  const uint32_t car = Spawn("vehicle.audi.tt", SpawnPose(1, 0.693));
  auto twin = Send(SpawnBody("vehicle.audi.tt", SpawnPose(1, 0.693)));
  EXPECT_FALSE(twin.accepted()) << "the first car is not in any state yet: only its spawn is pending";
  EXPECT_NE(twin.reason().to_string().find("Spawn failed because of collision at spawn position"), std::string::npos) << twin.reason();
  EXPECT_EQ(twin.actor(), 0u);
  auto walker = Send(SpawnBody("walker.pedestrian.0001", SpawnPose(1, 0.9)));
  EXPECT_FALSE(walker.accepted()) << "a walker inside the car";
  Tick(2);
  const uint64_t frame = observer_->last_frame();
  ASSERT_TRUE(Vehicle(frame, car).has_value());
  EXPECT_EQ(State(frame)->vehicles().size(), 1u) << "no ghost: exactly the accepted car";
  twin = Send(SpawnBody("vehicle.audi.tt", SpawnPose(1, 0.693)));
  EXPECT_FALSE(twin.accepted()) << "the car is in the state now";
  EXPECT_NE(twin.reason().to_string().find("collision at spawn position"), std::string::npos) << twin.reason();
  // Another spawn point is free; and the spot is free again once the car is gone.
  EXPECT_TRUE(Send(SpawnBody("vehicle.audi.tt", SpawnPose(2, 0.693))).accepted());
  msg::DestroyActor d;
  d.actor(car);
  msg::CommandBody db;
  db.destroy_actor(d);
  ASSERT_TRUE(Send(db).accepted());
  Tick(1);
  EXPECT_TRUE(Send(SpawnBody("vehicle.audi.tt", SpawnPose(1, 0.693))).accepted());
}

// TrafficManager.update_vehicle_lights: CARLA's light stage sets the lights of a TM car
// from the weather (night: position and low beams; fog: fog lights too) and its brake; a
// car without it keeps its lights off.
TEST_F(GroundServiceTest, TheTrafficManagerDrivesTheLightsOfTheCarsItWasAskedTo) {
  const uint32_t lit = Spawn("vehicle.lincoln.mkz_2020", SpawnPose(5, 0.757));
  const uint32_t dark = Spawn("vehicle.lincoln.mkz_2020", SpawnPose(20, 0.757));
  auto tm = [&](msg::TrafficManagerParameter p, uint32_t actor, double value) {
    msg::TrafficManagerCommand c;
    c.parameter(p);
    c.actor(actor);
    c.value(value);
    msg::CommandBody b;
    b.traffic_manager(c);
    ASSERT_TRUE(Send(b).accepted());
  };
  tm(msg::TrafficManagerParameter::TM_AUTOPILOT, lit, 1);
  tm(msg::TrafficManagerParameter::TM_AUTOPILOT, dark, 1);
  tm(msg::TrafficManagerParameter::TM_UPDATE_VEHICLE_LIGHTS, lit, 1);
  auto weather = [&](float sun, float fog) {
    msg::WeatherParameters w;
    w.sun_altitude_angle(sun);
    w.fog_density(fog);
    w.fog_distance(0);
    msg::CommandBody b;
    b.weather(w);
    ASSERT_TRUE(Send(b).accepted());
  };
  constexpr uint32_t kPosition = 0x1, kLowBeam = 0x2, kFog = 0x80;
  weather(60, 0);  // noon
  Tick(3);
  EXPECT_EQ(Vehicle(observer_->last_frame(), lit)->light_state() & (kPosition | kLowBeam), 0u);
  weather(-30, 0);  // night
  Tick(3);
  EXPECT_EQ(Vehicle(observer_->last_frame(), lit)->light_state() & (kPosition | kLowBeam | kFog), kPosition | kLowBeam);
  EXPECT_EQ(Vehicle(observer_->last_frame(), dark)->light_state(), 0u) << "not asked: CARLA leaves them off";
  weather(60, 50);  // fog by day
  Tick(3);
  EXPECT_EQ(Vehicle(observer_->last_frame(), lit)->light_state() & (kPosition | kLowBeam | kFog), kPosition | kLowBeam | kFog);
  tm(msg::TrafficManagerParameter::TM_UPDATE_VEHICLE_LIGHTS, lit, 0);
  weather(-30, 0);
  Tick(3);
  EXPECT_EQ(Vehicle(observer_->last_frame(), lit)->light_state() & kFog, kFog) << "turned off: the lights stay as the TM left them";
}

TEST_F(GroundServiceTest, TheTrafficManagerDrivesAHandedOverCarAndGivesItBack) {
  const uint32_t car = Spawn("vehicle.lincoln.mkz_2020", SpawnPose(5, 0.757));
  msg::TrafficManagerCommand tm;
  tm.parameter(msg::TrafficManagerParameter::TM_AUTOPILOT);
  tm.actor(car);
  tm.value(1);
  msg::CommandBody tb;
  tb.traffic_manager(tm);
  ASSERT_TRUE(Send(tb).accepted());
  Tick(200);
  auto v = Vehicle(observer_->last_frame(), car);
  ASSERT_TRUE(v);
  EXPECT_TRUE(v->autopilot());
  const auto start = SpawnPose(5).position();
  EXPECT_GT(std::hypot(v->transform().position().x() - start.x(), v->transform().position().y() - start.y()), 20.0);
  tm.value(0);
  tb.traffic_manager(tm);
  ASSERT_TRUE(Send(tb).accepted());
  Tick(1);
  v = Vehicle(observer_->last_frame(), car);
  ASSERT_TRUE(v);
  EXPECT_FALSE(v->autopilot());
}

// The core alone on the in-process bus, fed by hand: the run's map, the members' declarations
// and (or not) the drones' AirState of the frame before. Whose AirState ground_sim waits for
// follows from what the required members declare, never from a service name; a frame whose
// drones did not come faults the run (MissingInput out of Step) instead of stepping without
// them after a wall-clock wait (a state that would depend on when a sample arrived).
class GroundInputs : public ::testing::Test {
 protected:
  void Declare(const std::string& service, msg::ActorKind kind, const std::string& blueprint) {
    msg::BlueprintSet set;
    set.service(service);
    set.blueprints({blueprint::Make(blueprint, kind, {blueprint::String("role_name", "")})});
    sets_.Write(set);
  }
  msg::WorldInfo World(const std::vector<std::string>& required) {
    std::ifstream in(kTown01);
    std::stringstream xodr;
    xodr << in.rdbuf();
    msg::MapData m;
    m.run(1);
    m.name("Town01");
    m.opendrive(xodr.str());
    m.content_hash(Fnv1a64().Add(std::string_view(m.opendrive())).Add(std::string_view(m.scene())).value());
    map_.Write(m);
    msg::WorldInfo w;
    w.run(1);
    w.map_name("Town01");
    w.map_hash(m.content_hash());
    w.seed(7);
    msg::WorldSettings settings = DefaultWorldSettings();
    settings.service_timeout(0.3);  // how long a step waits for an input
    w.settings(settings);
    std::vector<msg::ServiceName> names(required.begin(), required.end());
    w.required_services(names);
    return w;
  }
  static msg::Tick TickOf(uint64_t frame) {
    msg::Tick t;
    t.run(1);
    t.frame(frame);
    t.dt(0.05);
    t.sim_time(0.05 * static_cast<double>(frame));
    return t;
  }
  void PublishDrones(uint64_t frame) {
    msg::AirState a;
    a.stamp().run(1);
    a.stamp().frame(frame);
    msg::DroneState d;
    d.actor(99);
    d.blueprint("drone.flyer");
    d.transform(MakePose(150, 2, 3, 0));
    a.drones({d});
    air_.Write(a);
  }

  std::unique_ptr<Bus> bus_ = CreateInProcessBus();
  Writer<msg::BlueprintSet> sets_{*bus_, topics::kBlueprints};
  Writer<msg::MapData> map_{*bus_, topics::kMap};
  Writer<msg::AirState> air_{*bus_, topics::kAirState};
  GroundService core_{*bus_};
};

TEST_F(GroundInputs, AFrameWithoutTheDronesOfTheFrameBeforeFaultsInsteadOfSteppingWithoutThem) {
  // A drone simulator that is not called "air_sim": it declares drones, so its AirState is an input.
  Declare("flyers", msg::ActorKind::ACTOR_DRONE, "drone.flyer");
  core_.BeginRun(World({"ground_sim", "flyers"}));
  EXPECT_EQ(core_.drone_sources(), std::vector<std::string>{"flyers"});
  EXPECT_FALSE(core_.StepNeverWaits());
  core_.Step(TickOf(1));  // frame 1 reads no earlier frame
  testing::ExpectMissingInput(core_, TickOf(2), "no AirState of frame 1 (from flyers)");
  // With the input there, the frame steps.
  PublishDrones(1);
  EXPECT_NO_THROW(core_.Step(TickOf(2)));
}

TEST_F(GroundInputs, AMemberNamedAirSimThatDeclaresNoDronesIsNotWaitedFor) {
  Declare("air_sim", msg::ActorKind::ACTOR_PROP, "static.prop.crate");
  core_.BeginRun(World({"ground_sim", "air_sim"}));
  EXPECT_TRUE(core_.drone_sources().empty());
  EXPECT_TRUE(core_.StepNeverWaits());
  core_.Step(TickOf(1));
  EXPECT_NO_THROW(core_.Step(TickOf(2)));
}

}  // namespace
}  // namespace lockstep
