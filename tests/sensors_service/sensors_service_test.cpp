// The sensors service behind the real coordinator with air_sim, on the in-process bus:
// sensors spawned by a client attach to a drone or stand in the world, every sample is
// stamped with the frame it shows (k in strict mode, k-1 in pipelined) and matches the
// AirState of that frame, two sensors services each simulate the spawns they own, and a
// bad attribute is reported with its reason.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <condition_variable>
#include <map>
#include <mutex>
#include <thread>

#include <Eigen/Geometry>

#include "air_service.h"
#include "lockstep/coordinator/coordinator.h"
#include "lockstep/runtime/blueprint_builder.h"
#include "lockstep/runtime/command_builders.h"
#include "missing_input.h"
#include "observer.h"
#include "sensors_service.h"

namespace lockstep {
namespace {

using namespace std::chrono_literals;

class SensorsServiceTest : public ::testing::Test {
 protected:
  void Start(msg::PerceptionMode mode) {
    LaunchConfig c;
    c.world = DefaultWorldSettings();
    c.world.synchronous_mode(true);
    c.world.perception_mode(mode);
    c.world.service_timeout(30);
    c.services.push_back({"air_sim", "air_sim", "", {}, true, false, "never"});
    c.services.push_back({"sensors_a", "sensors", "", {}, true, true, "never"});
    c.services.push_back({"sensors_b", "sensors", "", {}, true, true, "never"});
    bus_ = CreateInProcessBus();
    air_reader_ = Reader<msg::AirState>(*bus_, topics::kAirState, [this](const msg::AirState& s, const SampleInfo&) {
      {
        std::lock_guard<std::mutex> lock(mu_);
        air_[s.stamp().frame()] = s;
      }
      cv_.notify_all();
    });
    cloud_reader_ = Reader<msg::PointCloud>(*bus_, topics::kPointCloud, [this](const msg::PointCloud& p, const SampleInfo&) {
      {
        std::lock_guard<std::mutex> lock(mu_);
        clouds_[p.sensor()].push_back(p);
      }
      cv_.notify_all();
    });
    imu_reader_ = Reader<msg::Imu>(*bus_, topics::kImu, [this](const msg::Imu& m, const SampleInfo&) {
      {
        std::lock_guard<std::mutex> lock(mu_);
        imus_[m.sensor()].push_back(m);
      }
      cv_.notify_all();
    });
    event_reader_ = Reader<msg::SimEvent>(*bus_, topics::kEvent, [this](const msg::SimEvent& e, const SampleInfo&) {
      std::lock_guard<std::mutex> lock(mu_);
      events_.push_back(e.service().to_string() + ": " + e.message().to_string());
    });
    observer_ = std::make_unique<testing::Observer>(*bus_);
    coordinator_ = std::make_unique<Coordinator>(*bus_, c);
    air_service_ = std::make_unique<AirService>(*bus_);
    sensors_a_ = std::make_unique<SensorsService>(*bus_, "sensors_a");
    sensors_b_ = std::make_unique<SensorsService>(*bus_, "sensors_b");
    runners_.push_back(std::make_unique<ServiceRunner>(*bus_, ServiceOptions{"air_sim", "air_sim", false}, *air_service_));
    runners_.push_back(std::make_unique<ServiceRunner>(*bus_, ServiceOptions{"sensors_a", "sensors", true}, *sensors_a_));
    runners_.push_back(std::make_unique<ServiceRunner>(*bus_, ServiceOptions{"sensors_b", "sensors", true}, *sensors_b_));
    for (auto& r : runners_) threads_.emplace_back([this, &r] { r->Run(stop_); });
    threads_.emplace_back([this] { coordinator_->Run(stop_); });
  }
  void TearDown() override {
    stop_ = true;
    for (auto& t : threads_) t.join();
  }
  msg::CommandReply Send(msg::CommandBody b) {
    auto r = observer_->WaitReply(observer_->Send(std::move(b)), 10s);
    EXPECT_TRUE(r.has_value());
    return r.value_or(msg::CommandReply{});
  }
  uint32_t Spawn(const std::string& bp, const msg::Pose& pose, const AttributeList& attrs, uint32_t parent, const std::string& owner) {
    msg::CommandBody b = SpawnBody(bp, pose, attrs, parent);
    b.spawn_actor().owner(owner);
    auto r = Send(b);
    EXPECT_TRUE(r.accepted()) << r.reason();
    return r.actor();
  }
  void Drone(uint32_t actor, msg::DroneCommandKind kind, uint64_t id, const msg::Vector3& target = {}) {
    msg::DroneCommand d;
    d.actor(actor);
    d.kind(kind);
    d.command_id(id);
    d.velocity(4);
    d.target(target);
    msg::CommandBody b;
    b.drone(d);
    ASSERT_TRUE(Send(b).accepted());
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

  // Spawns a drone with a LiDAR and an IMU on it (owned by sensors_a) and a semantic
  // LiDAR standing in the world looking at it (owned by sensors_b), then flies it.
  void Scenario() {
    ASSERT_TRUE(observer_->WaitUntil([&] { auto s = observer_->status(); return s && s->state() == msg::RunState::RUN_READY; }, 30s));
    drone_ = Spawn("drone.generic_quad", MakePose(0, 0, 0), {}, 0, "");
    ASSERT_NE(drone_, 0u);
    lidar_ = Spawn("sensor.lidar.ray_cast", MakePose(0, 0, -0.2), {{"range", "30"}, {"noise_seed", "3"}}, drone_, "sensors_a");
    imu_ = Spawn("sensor.other.imu", MakePose(0, 0, 0), {}, drone_, "sensors_a");
    watcher_ = Spawn("sensor.lidar.ray_cast_semantic", MakePose(-6, 0, 1),
                     {{"range", "40"}, {"upper_fov", "60"}, {"lower_fov", "-10"}, {"channels", "64"}, {"points_per_second", "400000"}}, 0,
                     "sensors_b");
    Tick(1);
    Drone(drone_, msg::DroneCommandKind::DRONE_ARM, 1);
    Tick(1);
    Drone(drone_, msg::DroneCommandKind::DRONE_TAKEOFF, 2);
    Tick(40);
    msg::Vector3 target;
    target.x(3);
    target.y(0);
    target.z(4);
    Drone(drone_, msg::DroneCommandKind::DRONE_MOVE_TO_POSITION, 3, target);
    Tick(40);
  }

  void CheckAlignment(msg::PerceptionMode mode) {
    const uint64_t last = observer_->last_frame();
    ASSERT_GE(last, 80u);
    const uint64_t shift = mode == msg::PerceptionMode::PERCEPTION_PIPELINED ? 1 : 0;
    std::unique_lock<std::mutex> lock(mu_);
    // Samples (and this test's copy of the AirState, one writer: in frame order) may be
    // delivered after the FrameDone the observer saw: wait for them (or more).
    cv_.wait_for(lock, 10s, [&] {
      return air_.count(last) > 0 && clouds_[lidar_].size() >= last - shift && clouds_[watcher_].size() >= last - shift && imus_[imu_].size() >= last - shift;
    });
    // One sample per sensor per frame, stamped with the frame it shows: k (strict) or k-1.
    for (uint32_t sensor : {lidar_, watcher_}) {
      const auto& list = clouds_[sensor];
      ASSERT_EQ(list.size(), last - shift) << "sensor " << sensor;
      for (size_t i = 0; i < list.size(); ++i) EXPECT_EQ(list[i].stamp().frame(), i + 1) << "sensor " << sensor;
    }
    ASSERT_EQ(imus_[imu_].size(), last - shift);
    // The drone LiDAR's pose is the drone's pose of the stamped frame, lowered 0.2 m.
    size_t moving = 0;
    for (const auto& pc : clouds_[lidar_]) {
      const auto& state = air_.at(pc.stamp().frame());
      ASSERT_EQ(state.drones().size(), 1u);
      const auto& p = state.drones()[0].transform().position();
      const auto& q = state.drones()[0].transform().orientation();
      const Eigen::Vector3d expected =
          Eigen::Vector3d(p.x(), p.y(), p.z()) + Eigen::Quaterniond(q.w(), q.x(), q.y(), q.z()).normalized() * Eigen::Vector3d(0, 0, -0.2);
      EXPECT_NEAR(pc.sensor_pose().position().x(), expected.x(), 1e-9);
      EXPECT_NEAR(pc.sensor_pose().position().y(), expected.y(), 1e-9);
      EXPECT_NEAR(pc.sensor_pose().position().z(), expected.z(), 1e-9);
      EXPECT_DOUBLE_EQ(pc.stamp().sim_time(), state.stamp().sim_time());
      if (pc.stamp().frame() > 1 && std::abs(p.z() - air_.at(pc.stamp().frame() - 1).drones()[0].transform().position().z()) > 1e-3) ++moving;
      EXPECT_EQ(pc.format(), msg::PointFormat::POINTS_XYZI);
      EXPECT_EQ(pc.points_per_channel().size(), 32u);
    }
    EXPECT_GT(moving, 30u) << "the drone climbs and flies: a one-frame shift would show";
    // The IMU's orientation is the drone's of the stamped frame.
    for (const auto& m : imus_[imu_]) {
      const auto& q = air_.at(m.stamp().frame()).drones()[0].transform().orientation();
      EXPECT_NEAR(std::abs(m.orientation().w() * q.w() + m.orientation().x() * q.x() + m.orientation().y() * q.y() +
                           m.orientation().z() * q.z()),
                  1.0, 1e-9);
    }
    // The world LiDAR sees the drone once it is in the air.
    size_t drone_points = 0;
    for (const auto& pc : clouds_[watcher_]) {
      ASSERT_EQ(pc.format(), msg::PointFormat::POINTS_SEMANTIC);
      ASSERT_EQ(pc.point_step(), 24u);
      for (uint32_t i = 0; i < pc.point_count(); ++i) {
        uint32_t object = 0;
        std::memcpy(&object, pc.data().data() + i * 24 + 16, 4);
        if (object == drone_) ++drone_points;
      }
    }
    EXPECT_GT(drone_points, 50u);
  }

  std::unique_ptr<Bus> bus_;
  std::mutex mu_;
  std::condition_variable cv_;
  std::map<uint64_t, msg::AirState> air_;
  std::map<uint32_t, std::vector<msg::PointCloud>> clouds_;
  std::map<uint32_t, std::vector<msg::Imu>> imus_;
  std::vector<std::string> events_;
  Reader<msg::AirState> air_reader_;
  Reader<msg::PointCloud> cloud_reader_;
  Reader<msg::Imu> imu_reader_;
  Reader<msg::SimEvent> event_reader_;
  std::unique_ptr<testing::Observer> observer_;
  std::unique_ptr<Coordinator> coordinator_;
  std::unique_ptr<AirService> air_service_;
  std::unique_ptr<SensorsService> sensors_a_, sensors_b_;
  std::vector<std::unique_ptr<ServiceRunner>> runners_;
  std::vector<std::thread> threads_;
  std::atomic<bool> stop_{false};
  uint32_t drone_ = 0, lidar_ = 0, imu_ = 0, watcher_ = 0;
};

TEST_F(SensorsServiceTest, StrictSamplesShowTheTicksFrame) {
  Start(msg::PerceptionMode::PERCEPTION_STRICT);
  Scenario();
  CheckAlignment(msg::PerceptionMode::PERCEPTION_STRICT);
  // Each service simulates what it owns.
  EXPECT_TRUE(sensors_a_->world()->Has(lidar_));
  EXPECT_TRUE(sensors_a_->world()->Has(imu_));
  EXPECT_FALSE(sensors_a_->world()->Has(watcher_));
  EXPECT_TRUE(sensors_b_->world()->Has(watcher_));
  EXPECT_FALSE(sensors_b_->world()->Has(lidar_));
  // No owner named: the coordinator picks one of the two, and only that one simulates it.
  for (int i = 0; i < 4; ++i) {
    const uint32_t gnss = Spawn("sensor.other.gnss", MakePose(0, 0, 0), {}, drone_, "");
    Tick(1);
    EXPECT_NE(sensors_a_->world()->Has(gnss), sensors_b_->world()->Has(gnss)) << "gnss " << gnss;
  }
}

TEST_F(SensorsServiceTest, ABadAttributeIsRejectedWithItsReason) {
  Start(msg::PerceptionMode::PERCEPTION_STRICT);
  ASSERT_TRUE(observer_->WaitUntil([&] { auto s = observer_->status(); return s && s->state() == msg::RunState::RUN_READY; }, 30s));
  msg::CommandBody b = SpawnBody("sensor.lidar.ray_cast", MakePose(0, 0, 2), {{"upper_fov", "-40"}});
  b.spawn_actor().owner("sensors_a");
  auto r = Send(b);
  EXPECT_FALSE(r.accepted());
  EXPECT_NE(r.reason().to_string().find("upper_fov (-40) is below lower_fov (-30)"), std::string::npos) << r.reason();
  b = SpawnBody("sensor.lidar.ray_cast", MakePose(0, 0, 2), {{"channels", "1000"}});
  r = Send(b);
  EXPECT_FALSE(r.accepted());
  EXPECT_NE(r.reason().to_string().find("channels"), std::string::npos) << r.reason();
}

TEST_F(SensorsServiceTest, PipelinedSamplesShowThePreviousFrame) {
  Start(msg::PerceptionMode::PERCEPTION_PIPELINED);
  Scenario();
  CheckAlignment(msg::PerceptionMode::PERCEPTION_PIPELINED);
}

TEST_F(SensorsServiceTest, DeclaresCarlasSensorBlueprintsAndChecksSpawns) {
  SensorsService s(*CreateInProcessBus(), "sensors");
  const auto decl = s.Blueprints();
  bool lidar = false;
  for (const auto& bp : decl) {
    EXPECT_EQ(bp.kind(), msg::ActorKind::ACTOR_SENSOR);
    if (bp.id().to_string() != "sensor.lidar.ray_cast") continue;
    lidar = true;
    std::map<std::string, std::string> defaults;
    for (const auto& a : bp.attributes()) defaults[a.id().to_string()] = a.default_value().to_string();
    EXPECT_EQ(defaults["channels"], "32");
    EXPECT_EQ(defaults["points_per_second"], "56000");
    EXPECT_EQ(defaults["atmosphere_attenuation_rate"], "0.004");
    EXPECT_EQ(defaults["sensor_tick"], "0");
  }
  EXPECT_TRUE(lidar);
  msg::SpawnActor sp;
  sp.blueprint("sensor.lidar.ray_cast");
  sp.attributes(MakeAttributes({{"upper_fov", "-50"}}));
  EXPECT_NE(s.CheckSpawn(sp).find("upper_fov"), std::string::npos);
  sp.attributes(MakeAttributes({{"channels", "8"}}));
  EXPECT_EQ(s.CheckSpawn(sp), "");
  sp.owner("other_sensors");
  EXPECT_FALSE(s.Owns(sp));
  sp.owner("sensors");
  EXPECT_TRUE(s.Owns(sp));
  sp.owner("");
  EXPECT_TRUE(s.Owns(sp)) << "no owner named: a sensor blueprint of ours";
  sp.blueprint("sensor.camera.rgb");
  EXPECT_FALSE(s.Owns(sp));
}

// The event sensors without a coordinator: a stand-in "ground_sim" declares vehicles and
// publishes GroundState and PhysicsEvents; the collision and lane-invasion sensors on car 5
// deliver car 5's events of the frame, stamped with it, and nothing else.
TEST(SensorsEvents, CollisionAndLaneInvasionStreamsFromPhysicsEvents) {
  auto bus = CreateInProcessBus();
  std::mutex mu;
  std::vector<msg::CollisionEvent> collisions;
  std::vector<msg::LaneInvasionEvent> invasions;
  std::condition_variable cv;
  Reader<msg::CollisionEvent> cr(*bus, topics::kCollision, [&](const msg::CollisionEvent& e, const SampleInfo&) {
    {
      std::lock_guard<std::mutex> lock(mu);
      collisions.push_back(e);
    }
    cv.notify_all();
  });
  Reader<msg::LaneInvasionEvent> lr(*bus, topics::kLaneInvasion, [&](const msg::LaneInvasionEvent& e, const SampleInfo&) {
    {
      std::lock_guard<std::mutex> lock(mu);
      invasions.push_back(e);
    }
    cv.notify_all();
  });
  Writer<msg::BlueprintSet> sets(*bus, topics::kBlueprints);
  Writer<msg::GroundState> ground(*bus, topics::kGroundState);
  Writer<msg::PhysicsEvents> physics(*bus, topics::kPhysicsEvents);
  msg::BlueprintSet set;
  set.service("ground_sim");
  msg::BlueprintDeclaration car;
  car.id("vehicle.lockstep.sedan");
  car.kind(msg::ActorKind::ACTOR_VEHICLE);
  set.blueprints({car});
  sets.Write(set);

  SensorsService service(*bus, "sensors");
  msg::WorldInfo world;
  world.run(1);
  world.seed(3);
  world.settings(DefaultWorldSettings());
  world.required_services({msg::ServiceName("ground_sim"), msg::ServiceName("sensors")});
  msg::BlueprintSet own;
  own.service("sensors");
  own.blueprints(service.Blueprints());
  sets.Write(own);
  service.BeginRun(world);

  for (uint64_t k = 1; k <= 3; ++k) {
    msg::FrameStamp stamp;
    stamp.run(1);
    stamp.frame(k);
    stamp.sim_time(0.05 * k);
    msg::GroundState g;
    g.stamp(stamp);
    msg::VehicleState v;
    v.actor(5);
    v.blueprint("vehicle.lockstep.sedan");
    v.transform(MakePose(10, 0, 0.75));
    g.vehicles({v});
    ground.Write(g);
    msg::PhysicsEvents ev;
    ev.stamp(stamp);
    ev.service("ground_sim");
    if (k == 2) {
      msg::ActorCollision hit, other;
      hit.actor(5);
      hit.other_actor(9);
      hit.other_kind(msg::ObjectKind::OBJECT_VEHICLE);
      hit.normal_impulse().x(250);
      other.actor(9);
      other.other_actor(5);
      ev.collisions({hit, other});
      msg::ActorLaneInvasion inv;
      inv.actor(5);
      msg::LaneMarking m;
      m.type(msg::LaneMarkingType::MARKING_SOLID);
      m.color("white");
      inv.crossed({m});
      ev.lane_invasions({inv});
    }
    physics.Write(ev);
    msg::Tick tick;
    tick.run(1);
    tick.frame(k);
    tick.sim_time(0.05 * k);
    tick.dt(0.05);
    if (k == 1) {
      std::vector<msg::Command> cmds;
      uint32_t id = 100;
      for (const char* bp : {"sensor.other.collision", "sensor.other.lane_invasion"}) {
        msg::CommandBody b = SpawnBody(bp, MakePose(0, 0, 0), {}, 5);
        b.spawn_actor().actor(id++);
        b.spawn_actor().owner("sensors");
        msg::Command c;
        c.body(b);
        cmds.push_back(c);
      }
      tick.commands(cmds);
    }
    service.Step(tick);
  }
  std::unique_lock<std::mutex> lock(mu);
  // Delivery to this test's readers may lag the Step that wrote them.
  cv.wait_for(lock, 10s, [&] { return !collisions.empty() && !invasions.empty(); });
  ASSERT_EQ(collisions.size(), 1u);
  EXPECT_EQ(collisions[0].sensor(), 100u);
  EXPECT_EQ(collisions[0].stamp().frame(), 2u);
  EXPECT_EQ(collisions[0].actor(), 5u);
  EXPECT_EQ(collisions[0].other_actor(), 9u);
  EXPECT_EQ(collisions[0].other_kind(), msg::ObjectKind::OBJECT_VEHICLE);
  EXPECT_DOUBLE_EQ(collisions[0].normal_impulse().x(), 250);
  ASSERT_EQ(invasions.size(), 1u);
  EXPECT_EQ(invasions[0].sensor(), 101u);
  EXPECT_EQ(invasions[0].stamp().frame(), 2u);
  ASSERT_EQ(invasions[0].crossed().size(), 1u);
  EXPECT_EQ(invasions[0].crossed()[0].color().to_string(), "white");
}


// The core alone on the in-process bus, fed by hand. Members that declare vehicles and
// drones (not named ground_sim or air_sim) make their GroundState and AirState of the frame
// inputs of the sensors' step: a frame whose input did not come faults the run (MissingInput
// out of Step) and leaves the state as it was, instead of sensing a world without those
// actors (samples that would depend on when a state arrived).
TEST(SensorsInputs, AFrameWithoutItsGroundOrAirStateFaultsInsteadOfSensingWithoutThem) {
  auto bus = CreateInProcessBus();
  Writer<msg::BlueprintSet> sets(*bus, topics::kBlueprints);
  Writer<msg::GroundState> ground(*bus, topics::kGroundState);
  Writer<msg::AirState> air(*bus, topics::kAirState);
  auto declare = [&](const std::string& service, msg::ActorKind kind, const std::string& bp) {
    msg::BlueprintSet set;
    set.service(service);
    set.blueprints({blueprint::Make(bp, kind, {blueprint::String("role_name", "")})});
    sets.Write(set);
  };
  declare("cars", msg::ActorKind::ACTOR_VEHICLE, "vehicle.lockstep.sedan");
  declare("flyers", msg::ActorKind::ACTOR_DRONE, "drone.flyer");
  SensorsOptions options;
  options.input_timeout_s = 0.3;  // how long a step waits for an input
  SensorsService service(*bus, "sensors", options);
  msg::BlueprintSet own;
  own.service("sensors");
  own.blueprints(service.Blueprints());
  sets.Write(own);
  msg::WorldInfo world;
  world.run(1);
  world.seed(3);
  msg::WorldSettings settings = DefaultWorldSettings();
  settings.perception_mode(msg::PerceptionMode::PERCEPTION_STRICT);
  settings.service_timeout(0.3);
  world.settings(settings);
  world.required_services({msg::ServiceName("cars"), msg::ServiceName("flyers"), msg::ServiceName("sensors")});
  service.BeginRun(world);
  auto stamp = [](uint64_t k) {
    msg::FrameStamp s;
    s.run(1);
    s.frame(k);
    s.sim_time(0.05 * static_cast<double>(k));
    return s;
  };
  auto publish_ground = [&](uint64_t k) {
    msg::GroundState g;
    g.stamp(stamp(k));
    msg::VehicleState v;
    v.actor(5);
    v.blueprint("vehicle.lockstep.sedan");
    v.transform(MakePose(10, 0, 0.75));
    g.vehicles({v});
    ground.Write(g);
  };
  auto publish_air = [&](uint64_t k) {
    msg::AirState a;
    a.stamp(stamp(k));
    msg::DroneState d;
    d.actor(6);
    d.blueprint("drone.flyer");
    d.transform(MakePose(0, 10, 5));
    a.drones({d});
    air.Write(a);
  };
  auto tick = [](uint64_t k) {
    msg::Tick t;
    t.run(1);
    t.frame(k);
    t.sim_time(0.05 * static_cast<double>(k));
    t.dt(0.05);
    return t;
  };
  msg::Tick first = tick(1);
  msg::CommandBody b = SpawnBody("sensor.other.imu", MakePose(0, 0, 1));
  b.spawn_actor().actor(100);
  b.spawn_actor().owner("sensors");
  msg::Command c;
  c.body(b);
  first.commands({c});
  publish_ground(1);
  publish_air(1);
  service.Step(first);
  ASSERT_EQ(service.world()->size(), 1u);
  testing::ExpectMissingInput(service, tick(2), "no GroundState of frame 2");
  publish_ground(2);
  testing::ExpectMissingInput(service, tick(2), "no AirState of frame 2");
  // With both inputs there, the frame steps.
  publish_air(2);
  EXPECT_NO_THROW(service.Step(tick(2)));
}

// A custom prop (an asset the render service imported and declared as custom.<name> with
// its bounding box and class) is seen by the ray sensors: a semantic LiDAR's rays hit its
// box and the points carry the prop's actor id and class; once destroyed it is gone.
TEST(SensorsCustomProps, ALidarHitsTheDeclaredBoxWithItsClass) {
  auto bus = CreateInProcessBus();
  std::mutex mu;
  std::condition_variable cv;
  std::map<uint64_t, msg::PointCloud> clouds;
  Reader<msg::PointCloud> reader(*bus, topics::kPointCloud, [&](const msg::PointCloud& p, const SampleInfo&) {
    {
      std::lock_guard<std::mutex> lock(mu);
      clouds[p.stamp().frame()] = p;
    }
    cv.notify_all();
  });
  Writer<msg::BlueprintSet> sets(*bus, topics::kBlueprints);
  msg::BlueprintSet render;
  render.service("render");
  msg::BlueprintDeclaration crate;
  crate.id("custom.crate");
  crate.tags("custom,crate,TrafficSign");  // as render/service declares an imported asset
  crate.kind(msg::ActorKind::ACTOR_PROP);
  crate.half_extents().x(1.0);
  crate.half_extents().y(0.5);
  crate.half_extents().z(0.75);
  render.blueprints({crate});
  sets.Write(render);

  SensorsService service(*bus, "sensors");
  msg::WorldInfo world;
  world.run(1);
  world.seed(3);
  world.settings(DefaultWorldSettings());
  world.required_services({msg::ServiceName("sensors")});
  msg::BlueprintSet own;
  own.service("sensors");
  own.blueprints(service.Blueprints());
  sets.Write(own);
  service.BeginRun(world);

  const uint32_t kProp = 50, kLidar = 100;
  for (uint64_t k = 1; k <= 3; ++k) {
    msg::Tick tick;
    tick.run(1);
    tick.frame(k);
    tick.sim_time(0.05 * k);
    tick.dt(0.05);
    std::vector<msg::Command> cmds;
    if (k == 1) {
      msg::CommandBody prop = SpawnBody("custom.crate", MakePose(10, 2, 0.75, M_PI / 2), {}, 0);
      prop.spawn_actor().actor(kProp);
      prop.spawn_actor().owner("render");
      msg::CommandBody lidar = SpawnBody("sensor.lidar.ray_cast_semantic", MakePose(0, 0, 0.75),
                                         {{"channels", "1"}, {"upper_fov", "0"}, {"lower_fov", "0"}, {"range", "50"},
                                          {"rotation_frequency", "20"}, {"points_per_second", "72000"}},
                                         0);
      lidar.spawn_actor().actor(kLidar);
      lidar.spawn_actor().owner("sensors");
      for (const auto& b : {prop, lidar}) {
        msg::Command c;
        c.body(b);
        cmds.push_back(c);
      }
    }
    if (k == 3) {
      msg::DestroyActor d;
      d.actor(kProp);
      msg::CommandBody gone;
      gone.destroy_actor(d);
      msg::Command c;
      c.body(gone);
      cmds.push_back(c);
    }
    tick.commands(cmds);
    service.Step(tick);
  }
  std::unique_lock<std::mutex> lock(mu);
  ASSERT_TRUE(cv.wait_for(lock, 10s, [&] { return clouds.size() >= 3; }));
  // A full turn per frame (20 Hz at dt 0.05): the crate, turned 90 degrees, spans y in
  // [1, 3] at x in [9.5, 10.5].
  auto prop_points = [&](uint64_t frame) {
    const msg::PointCloud& pc = clouds.at(frame);
    EXPECT_EQ(pc.format(), msg::PointFormat::POINTS_SEMANTIC);
    int n = 0;
    for (uint32_t i = 0; i < pc.point_count(); ++i) {
      float xyz[3];
      uint32_t object = 0, tag = 0;
      std::memcpy(xyz, pc.data().data() + i * 24, 12);
      std::memcpy(&object, pc.data().data() + i * 24 + 16, 4);
      std::memcpy(&tag, pc.data().data() + i * 24 + 20, 4);
      if (object != kProp) continue;
      ++n;
      EXPECT_EQ(tag, 8u) << "TrafficSign";
      // On the declared box (sensor frame = world frame here: FLU at the origin facing +x).
      EXPECT_GE(xyz[0], 9.5 - 1e-3);
      EXPECT_LE(xyz[0], 10.5 + 1e-3);
      EXPECT_GE(xyz[1], 1.0 - 1e-3);
      EXPECT_LE(xyz[1], 3.0 + 1e-3);
    }
    return n;
  };
  EXPECT_GT(prop_points(1), 10);
  EXPECT_GT(prop_points(2), 10);
  EXPECT_EQ(prop_points(3), 0) << "destroyed at frame 3";
}

// The custom-prop placement the service and the client's ray queries share (frame_actors.h):
// the declared box and class, on the parent's mount; none without its parent in the frame.
TEST(FrameActors, CustomPropsSitOnTheirParentsMountWithTheirDeclaredClass) {
  msg::BlueprintDeclaration crate;
  crate.id("custom.crate");
  crate.tags("custom,crate,TrafficSign");
  crate.half_extents().x(1.0);
  crate.half_extents().y(0.5);
  crate.half_extents().z(0.25);
  msg::BlueprintDeclaration plain = crate;
  plain.tags("custom,plain");
  std::vector<sensors::Actor> actors;
  msg::GroundState g;
  msg::VehicleState v;
  v.actor(7);
  v.transform(MakePose(10, 0, 0.75, M_PI / 2));
  v.half_extents().x(2.0);
  v.half_extents().y(1.0);
  v.half_extents().z(0.75);
  g.vehicles({v});
  sensors::AppendActors(g, &actors);
  const std::vector<sensors::CustomProp> props{sensors::MakeCustomProp(crate, 50, 7, MakePose(1, 0, 0.25)),
                                               sensors::MakeCustomProp(plain, 51, 0, MakePose(3, 4, 5)),
                                               sensors::MakeCustomProp(crate, 52, 99, MakePose(0, 0, 0))};
  sensors::AppendProps(props, &actors);
  ASSERT_EQ(actors.size(), 3u) << "the prop on the absent actor 99 is not placed";
  const sensors::Actor& on_car = actors[1];
  EXPECT_EQ(on_car.id, 50u);
  EXPECT_EQ(on_car.tag, 8);  // TrafficSign
  EXPECT_EQ(on_car.kind, sensors::ActorKind::kOther);
  EXPECT_NEAR((on_car.half_extents - sensors::Vec3(1.0, 0.5, 0.25)).norm(), 0.0, 1e-12);
  // 1 m ahead of the car facing north, on the bottom of its box (z 0), 0.25 m up.
  EXPECT_NEAR((on_car.pose.position - sensors::Vec3(10, 1, 0.25)).norm(), 0.0, 1e-9);
  EXPECT_EQ(actors[2].tag, 20) << "Static without a class";
  EXPECT_NEAR((actors[2].pose.position - sensors::Vec3(3, 4, 5)).norm(), 0.0, 1e-12);
}

}  // namespace
}  // namespace lockstep
