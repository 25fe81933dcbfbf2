// The C++ client against the real coordinator, air_sim and a stand-in sensors service on
// the in-process bus: ticks, spawns and their errors, drones with futures, batches, and
// the no-lost-frames guarantee of listen() in synchronous mode.
#include <gtest/gtest.h>

#include <atomic>
#include <cmath>
#include <condition_variable>
#include <limits>
#include <map>
#include <optional>
#include <mutex>
#include <thread>

#include "air_service.h"
#include "fake_sensors.h"
#include "lockstep/client/client.h"
#include "lockstep/client/multirotor.h"
#include "lockstep/coordinator/coordinator.h"
#include "lockstep/runtime/actor_list.h"

namespace lockstep::client {
namespace {

class ClientTest : public ::testing::Test {
 protected:
  void Start(bool sync, uint64_t skip_frame = 0, double sensor_timeout = 10) {
    LaunchConfig c;
    c.world = DefaultWorldSettings();
    c.world.synchronous_mode(sync);
    c.world.service_timeout(30);
    c.services.push_back({"air_sim", "air_sim", "", {}, true, false, "never"});
    c.services.push_back({"sensors", "fake_sensors", "", {}, true, true, "never"});
    bus_ = CreateInProcessBus();
    coordinator_ = std::make_unique<Coordinator>(*bus_, c);
    air_ = std::make_unique<AirService>(*bus_);
    sensors_ = std::make_unique<testing::FakeSensors>(*bus_, "sensors", skip_frame);
    air_runner_ = std::make_unique<ServiceRunner>(*bus_, ServiceOptions{"air_sim", "air_sim", false}, *air_);
    sensor_runner_ = std::make_unique<ServiceRunner>(*bus_, ServiceOptions{"sensors", "fake_sensors", true}, *sensors_);
    threads_.emplace_back([this] { air_runner_->Run(stop_); });
    threads_.emplace_back([this] { sensor_runner_->Run(stop_); });
    threads_.emplace_back([this] { coordinator_->Run(stop_); });
    ClientOptions o;
    o.bus = bus_.get();
    o.name = "client-test";
    o.sensor_timeout_s = sensor_timeout;
    client_ = std::make_unique<Client>(o);
    ASSERT_TRUE(client_->wait_ready(30)) << "services did not join";
  }
  void TearDown() override {
    if (sensors_) sensors_->Hold(false);
    client_.reset();
    stop_ = true;
    for (auto& t : threads_) t.join();
  }

  std::unique_ptr<Bus> bus_;
  std::unique_ptr<Coordinator> coordinator_;
  std::unique_ptr<AirService> air_;
  std::unique_ptr<testing::FakeSensors> sensors_;
  std::unique_ptr<ServiceRunner> air_runner_, sensor_runner_;
  std::vector<std::thread> threads_;
  std::atomic<bool> stop_{false};
  std::unique_ptr<Client> client_;
  // What listen callbacks record: members, so they outlive the client even when an
  // assertion ends a test early.
  std::mutex mu_;
  std::map<uint32_t, std::vector<uint64_t>> frames_;
};

TEST(ClientConnect, NoSimulationGivesAClearError) {
  auto bus = CreateInProcessBus();
  ClientOptions o;
  o.bus = bus.get();
  o.timeout_s = 0.2;
  try {
    Client c(o);
    FAIL() << "connected to nothing";
  } catch (const ClientError& e) {
    EXPECT_NE(std::string(e.what()).find("no Lockstep simulation on DDS domain"), std::string::npos) << e.what();
  }
}

TEST_F(ClientTest, TickReturnsConsecutiveFramesAndTheirState) {
  Start(true);
  const uint32_t drone = client_->spawn("drone.generic_quad", MakePose(47.75, 1.75, 0));
  uint64_t last = client_->frame();
  for (int i = 0; i < 20; ++i) {
    const uint64_t k = client_->tick();
    EXPECT_EQ(k, last + 1);
    last = k;
    const Snapshot s = client_->snapshot();
    EXPECT_EQ(s.frame, k);
    ASSERT_TRUE(s.air.has_value());
    EXPECT_EQ(s.air->stamp().frame(), k);  // tick() waited for the frame's air state
    EXPECT_NE(s.Drone(drone), nullptr);
  }
  auto info = client_->actor(drone);
  ASSERT_TRUE(info.has_value());
  EXPECT_EQ(info->blueprint, "drone.generic_quad");
  EXPECT_EQ(info->kind, msg::ActorKind::ACTOR_DRONE);
}

// lockstep/actors: a reader that joins after the spawns gets every live actor's spawn
// (attributes included), without the destroyed ones, from the coordinator's latest list.
TEST_F(ClientTest, ALateReaderOfTheActorListGetsEveryLiveActorsSpawn) {
  Start(true);
  const uint32_t hero = client_->spawn("drone.generic_quad", MakePose(47.75, 1.75, 0), {{"role_name", "hero"}});
  const uint32_t gone = client_->spawn("drone.generic_quad", MakePose(43.25, 1.75, 0), {{"role_name", "gone"}});
  client_->tick();
  client_->destroy(gone);
  const uint64_t k = client_->tick();
  std::mutex mu;
  std::condition_variable cv;
  std::optional<msg::ActorList> latest;
  Reader<msg::ActorList> late(*bus_, topics::kActors, [&](const msg::ActorList& l, const SampleInfo&) {
    std::lock_guard<std::mutex> lock(mu);
    latest = l;
    cv.notify_all();
  });
  std::unique_lock<std::mutex> lock(mu);
  ASSERT_TRUE(cv.wait_for(lock, std::chrono::seconds(10), [&] { return latest.has_value(); })) << "no actor list";
  EXPECT_EQ(latest->run(), client_->run());
  EXPECT_EQ(latest->frame(), k);
  ASSERT_EQ(latest->actors().size(), 1u);
  const auto& a = latest->actors()[0];
  EXPECT_EQ(a.spawn().actor(), hero);
  EXPECT_EQ(a.spawn().blueprint().to_string(), "drone.generic_quad");
  EXPECT_EQ(a.spawn().owner().to_string(), "air_sim");
  std::string role;
  for (const auto& at : a.spawn().attributes()) {
    if (at.key().to_string() == "role_name") role = at.value().to_string();
  }
  EXPECT_EQ(role, "hero");
  EXPECT_EQ(a.frame(), k - 1);
}

// A watched command the coordinator accepts but the owning service refuses when it
// applies it: the tick that applies it throws the service's reason, naming the call;
// watched commands the service applies throw nothing.
TEST_F(ClientTest, AWatchedCommandTheServiceRefusesIsThrownByTheTickThatAppliesIt) {
  Start(true);
  const uint32_t drone = client_->spawn("drone.generic_quad", MakePose(43.25, -1.75, 3.0));
  client_->tick();
  client_->tick();  // falling by now
  auto body = [&](msg::DroneCommandKind kind, uint64_t id) {
    msg::DroneCommand c;
    c.actor(drone);
    c.kind(kind);
    c.command_id(id);
    msg::CommandBody b;
    b.drone(c);
    return b;
  };
  client_->SubmitWatched(body(msg::DroneCommandKind::DRONE_ARM, 1), "armDisarm");
  for (int i = 0; i < 3; ++i) EXPECT_NO_THROW(client_->tick());
  client_->SubmitWatched(body(msg::DroneCommandKind::DRONE_TAKEOFF, 2), "takeoffAsync");
  std::string what, reason;
  // The applying tick, or a later one: the refusal event and FrameDone come from different writers,
  // so under load the event can arrive a tick or two after the frame is done (it failed 2 in 6 loaded
  // runs with a single tick of slack). It must come, and only once.
  for (int i = 0; i < 10 && what.empty(); ++i) {
    try {
      client_->tick();
    } catch (const CommandRejected& e) {
      what = e.what();
      reason = e.reason();
    }
  }
  EXPECT_NE(reason.find("cannot take off while moving"), std::string::npos) << what;
  EXPECT_NE(what.find("takeoffAsync (actor " + std::to_string(drone)), std::string::npos) << what;
  EXPECT_NE(what.find("air_sim"), std::string::npos) << what;
  EXPECT_NO_THROW(client_->check_failures());  // thrown once
}

TEST_F(ClientTest, TickInFreeRunningModeRaisesTheCoordinatorsReason) {
  Start(false);
  try {
    client_->tick();
    FAIL() << "tick accepted in free-running mode";
  } catch (const CommandRejected& e) {
    EXPECT_NE(e.reason().find("synchronous_mode"), std::string::npos) << e.reason();
  }
  EXPECT_GT(client_->wait_for_tick(10), 0u);
}

TEST_F(ClientTest, BadCallsRaiseWithTheServicesReason) {
  Start(true);
  auto reason = [&](auto&& f) -> std::string {
    try {
      f();
    } catch (const CommandRejected& e) {
      return e.reason();
    }
    return "(accepted)";
  };
  EXPECT_NE(reason([&] { client_->spawn("vehicle.does.not_exist", MakePose(0, 0, 0)); }).find("unknown blueprint"),
            std::string::npos);
  EXPECT_NE(reason([&] { client_->spawn("drone.generic_quad", MakePose(0, 0, 0), {{"no_such_attribute", "1"}}); })
                .find("no_such_attribute"),
            std::string::npos);
  const uint32_t drone = client_->spawn("drone.generic_quad", MakePose(47.75, 1.75, 0));
  client_->tick();
  client_->destroy(drone);
  EXPECT_NE(reason([&] { client_->destroy(drone); }).find("unknown actor"), std::string::npos);
  const uint32_t other = client_->spawn("drone.generic_quad", MakePose(43.25, -1.75, 0));
  msg::DroneCommand nan;
  nan.actor(other);
  nan.kind(msg::DroneCommandKind::DRONE_MOVE_TO_POSITION);
  nan.velocity(2);
  nan.target().x(std::numeric_limits<double>::quiet_NaN());
  EXPECT_NE(reason([&] { client_->send_drone(nan); }).find("NaN"), std::string::npos);
  std::string why;
  EXPECT_FALSE(client_->try_spawn("nothing.here", MakePose(0, 0, 0), {}, 0, &why).has_value());
  EXPECT_NE(why.find("unknown blueprint"), std::string::npos) << why;
}

TEST_F(ClientTest, BatchGivesOneReplyPerCommandInOrder) {
  Start(true);
  std::vector<msg::CommandBody> batch{SpawnBody("drone.generic_quad", MakePose(47.75, 1.75, 0)),
                                      SpawnBody("no.such.blueprint", MakePose(0, 0, 0)),
                                      SpawnBody("drone.hexa_x", MakePose(43.25, -1.75, 0))};
  const auto replies = client_->SubmitBatch(batch);
  ASSERT_EQ(replies.size(), 3u);
  EXPECT_TRUE(replies[0].accepted());
  EXPECT_FALSE(replies[1].accepted());
  EXPECT_NE(replies[1].reason().to_string().find("unknown blueprint"), std::string::npos);
  EXPECT_TRUE(replies[2].accepted());
  EXPECT_NE(replies[0].actor(), replies[2].actor());
}

TEST_F(ClientTest, DroneFuturesCompleteWhenAirSimReportsCompletion) {
  Start(true);
  MultirotorClient mc(*client_);
  const uint32_t id = client_->spawn("drone.generic_quad", MakePose(47.75, 1.75, 0), {{"role_name", "hero"}});
  client_->tick();
  EXPECT_EQ(mc.Resolve("hero"), id);
  EXPECT_TRUE(mc.isApiControlEnabled("hero"));  // a drone spawned without the attribute off starts under control
  mc.enableApiControl(false, "hero");
  EXPECT_FALSE(mc.isApiControlEnabled("hero"));
  mc.enableApiControl(true, "hero");
  EXPECT_TRUE(mc.isApiControlEnabled("hero"));
  ASSERT_TRUE(mc.armDisarm(true, "hero"));
  CommandFuture takeoff = mc.takeoffAsync(20, "hero");
  EXPECT_TRUE(takeoff.join(60));
  const auto state = mc.getMultirotorState("hero");
  EXPECT_NEAR(state.kinematics.position.z, -2.0, 0.3);  // NED: 2 m up from home
  EXPECT_FALSE(state.landed);
  ASSERT_TRUE(mc.moveToPositionAsync(4, 3, -6, 3, 60, NedDrivetrain::kMaxDegreeOfFreedom, {}, -1, "hero").join(120));
  const auto p = mc.simGetVehiclePose("hero").first;
  EXPECT_NEAR(p.x, 4, 0.5);   // north
  EXPECT_NEAR(p.y, 3, 0.5);   // east
  EXPECT_NEAR(p.z, -6, 0.5);  // up is negative
  const msg::Vector3 enu = client_->snapshot().Drone(id)->transform().position();
  EXPECT_NEAR(enu.x(), 47.75 + 3, 0.5);
  EXPECT_NEAR(enu.y(), 1.75 + 4, 0.5);
}

TEST_F(ClientTest, SixSensorsDeliverEveryFrameOnceAndInOrderBeforeTickReturns) {
  Start(true);
  auto& mu = mu_;
  auto& frames = frames_;
  std::vector<uint32_t> ids;
  for (int i = 0; i < 6; ++i) {
    const std::string bp = i % 2 ? "sensor.camera.rgb" : "sensor.other.imu";
    ids.push_back(client_->spawn(bp, MakePose(i, 0, 1)));
  }
  client_->tick();  // the spawn frame: frames after it are guaranteed
  for (uint32_t id : ids) {
    client_->listen(id, [&, id](const SensorSample& s) {
      if (s.type == SensorType::kImu) {
        EXPECT_EQ(s.As<msg::Imu>().accelerometer().z(), static_cast<double>(s.stamp.frame()));
      }
      if (s.type == SensorType::kImage) {
        EXPECT_EQ(s.ByteCount(), 128u);
      }
      std::lock_guard<std::mutex> lock(mu);
      frames[id].push_back(s.stamp.frame());
    });
  }
  uint64_t first = 0, k = 0;
  for (int t = 0; t < 500; ++t) {
    k = client_->tick();
    if (!first) first = k;
    std::lock_guard<std::mutex> lock(mu);
    for (uint32_t id : ids) {
      ASSERT_FALSE(frames[id].empty()) << "sensor " << id << " at frame " << k;
      ASSERT_EQ(frames[id].back(), k) << "sensor " << id << ": frame " << k << " not delivered before tick() returned";
    }
  }
  std::lock_guard<std::mutex> lock(mu);
  for (uint32_t id : ids) {
    const auto& f = frames[id];
    // Each frame exactly once, in order.
    ASSERT_EQ(f.size(), 500u) << "sensor " << id;
    for (size_t i = 0; i < f.size(); ++i) EXPECT_EQ(f[i], first + i);
    EXPECT_EQ(client_->delivered(id), f.size());
  }
}

// The shared sensor topics are VOLATILE: a reader made only by the first listen() could be
// matched after the service wrote the frame the next tick() waits for (SensorLate under load).
TEST_F(ClientTest, TheSharedSensorTopicsAreReadFromConnectNotFromTheFirstListen) {
  Start(true);
  EXPECT_GE(sensors_->ImuReaders(), 1) << "no client reader on the IMU topic before any listen()";
  const uint32_t imu = client_->spawn("sensor.other.imu", MakePose(0, 0, 1));
  client_->listen(imu, [](const SensorSample&) {});
  EXPECT_EQ(client_->delivered(imu), 0u);
  const uint64_t k = client_->tick();
  EXPECT_EQ(client_->delivered(imu), 1u) << "frame " << k;
}

// CARLA's world.tick(seconds): the frame's wait is bounded by the call's own time-out.
TEST_F(ClientTest, TickGivesUpAfterItsOwnTimeoutAndTheNextTickGoesOn) {
  Start(true);
  client_->tick();
  sensors_->Hold(true);
  try {
    client_->tick(0.25);
    ADD_FAILURE() << "tick(0.25) returned with a service holding the frame";
  } catch (const ClientError& e) {
    EXPECT_NE(std::string(e.what()).find("did not complete within 0.25 s"), std::string::npos) << e.what();
  }
  sensors_->Hold(false);
  const uint64_t k = client_->tick();
  EXPECT_GT(k, 0u);
}

TEST_F(ClientTest, ALateSensorIsNamedAndItsDataStillArrivesOnce) {
  Start(true, /*skip_frame=*/5, /*sensor_timeout=*/0.5);
  const uint32_t good = client_->spawn("sensor.other.imu", MakePose(0, 0, 1));
  const uint32_t late = client_->spawn("sensor.other.imu", MakePose(0, 0, 1), {{"role_name", "late"}});
  std::atomic<int> count{0};
  client_->listen(good, [&](const SensorSample&) { ++count; });
  client_->listen(late, [&](const SensorSample&) {});
  bool named = false;
  while (client_->frame() < 8) {
    try {
      client_->tick();
    } catch (const SensorLate& e) {
      EXPECT_EQ(e.frame(), 5u);
      ASSERT_EQ(e.sensors().size(), 1u);
      EXPECT_EQ(e.sensors()[0], late);
      EXPECT_NE(std::string(e.what()).find(std::to_string(late)), std::string::npos);
      named = true;
    }
  }
  EXPECT_TRUE(named);
  client_->stop(good);
  EXPECT_FALSE(client_->is_listening(good));
}

// CARLA destroys only the actor; Unreal detaches what was attached to it keeping its world
// transform: the IMU stays, unattached where the drone carried it, and is still listened to.
TEST_F(ClientTest, ASensorOfADestroyedParentStaysDetachedWhereItWas) {
  Start(true, /*skip_frame=*/0, /*sensor_timeout=*/0.5);
  const uint32_t drone = client_->spawn("drone.generic_quad", MakePose(47.75, 1.75, 0));
  const uint32_t imu = client_->spawn("sensor.other.imu", MakePose(0, 0, 0.2), {}, drone);
  std::atomic<int> count{0};
  client_->listen(imu, [&](const SensorSample&) { ++count; });
  for (int i = 0; i < 3; ++i) client_->tick();
  EXPECT_GE(count.load(), 2);
  const auto carrier = client_->snapshot().Find(drone);
  ASSERT_TRUE(carrier.has_value());
  client_->destroy(drone);
  EXPECT_TRUE(client_->is_listening(imu));
  const auto info = client_->actor(imu);
  ASSERT_TRUE(info.has_value());
  EXPECT_EQ(info->parent, 0u);
  // Its world pose: the drone's last pose (its centre is its mount) times the mount transform.
  const auto& p = info->spawn_pose.position();
  const auto& d = carrier->transform.position();
  const auto& q = carrier->transform.orientation();
  const double up_x = 2 * (q.x() * q.z() + q.w() * q.y()), up_y = 2 * (q.y() * q.z() - q.w() * q.x()),
               up_z = 1 - 2 * (q.x() * q.x() + q.y() * q.y());  // the drone's z axis in the world
  EXPECT_NEAR(p.x(), d.x() + 0.2 * up_x, 1e-9);
  EXPECT_NEAR(p.y(), d.y() + 0.2 * up_y, 1e-9);
  EXPECT_NEAR(p.z(), d.z() + 0.2 * up_z, 1e-9);
  const int before = count.load();
  for (int i = 0; i < 3; ++i) EXPECT_NO_THROW(client_->tick());
  EXPECT_GE(count.load(), before + 2);  // it samples on
}

TEST_F(ClientTest, ASensorOfAnEarlierRunIsNoLongerAwaitedByTick) {
  Start(true, /*skip_frame=*/0, /*sensor_timeout=*/0.5);
  const uint32_t imu = client_->spawn("sensor.other.imu", MakePose(0, 0, 1));
  std::atomic<int> count{0};
  client_->listen(imu, [&](const SensorSample&) { ++count; });
  for (int i = 0; i < 3; ++i) client_->tick();
  EXPECT_GE(count.load(), 2);
  client_->reset(7);  // a new run: the IMU is gone
  for (int i = 0; i < 3; ++i) EXPECT_NO_THROW(client_->tick());
}

}  // namespace
}  // namespace lockstep::client
