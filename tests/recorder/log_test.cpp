// The Lockstep log on its own (no DDS): what the writer puts in, the reader gives back
// (quantised poses, the tick bit for bit, events, hashes), seeking through keyframes, a
// truncated file read to its last whole frame, and CARLA's recorder text formats.
#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <cstdlib>
#include <ctime>
#include <filesystem>
#include <fstream>

#include "lockstep/recorder/carla_text.h"
#include "lockstep/recorder/log_reader.h"
#include "lockstep/recorder/log_writer.h"

namespace lockstep::recorder {
namespace {

msg::Pose Pose(double x, double y, double z, double yaw) {
  msg::Pose p;
  p.position().x(x);
  p.position().y(y);
  p.position().z(z);
  p.orientation().w(std::cos(yaw / 2));
  p.orientation().z(std::sin(yaw / 2));
  return p;
}

msg::Tick MakeTick(uint64_t frame, double dt) {
  msg::Tick t;
  t.run(1);
  t.frame(frame);
  t.dt(dt);
  t.sim_time(static_cast<double>(frame) * dt);
  t.seed(42);
  return t;
}

std::string TempPath(const std::string& name) {
  return (std::filesystem::temp_directory_path() / ("lockstep-log-test-" + std::to_string(getpid()) + "-" + name)).string();
}

LogHeader Header(const std::string& map = "TestTown") {
  LogHeader h;
  h.map_name = map;
  h.map_digest = 0x1234;
  h.seed = 42;
  h.run = 1;
  h.first_frame = 1;
  h.start_unix_time = 1700000000;  // 2023-11-14 22:13:20 UTC
  return h;
}

// A moving world: car 1 drives east at 10 m/s and turns, car 2 stands, car 3 lives for
// frames 100..299, two walkers, a light that turns green at 150, a climbing drone.
struct World {
  msg::GroundState ground;
  msg::AirState air;
  msg::PhysicsEvents events;
  msg::Tick tick;

  void Build(uint64_t k) {
    const double t = static_cast<double>(k) * 0.05;
    tick = MakeTick(k, 0.05);
    if (k == 100) {
      msg::Command c;
      c.client("test");
      c.sequence_number(k);
      msg::SpawnActor s;
      s.blueprint("vehicle.audi.tt");
      s.actor(3);
      s.transform(Pose(0, 50, 0.7, 0));
      msg::BlueprintAttribute a;
      a.key("color");
      a.value("0,0,255");
      s.attributes().push_back(a);
      c.body().spawn_actor(s);
      tick.commands().push_back(c);
    }
    ground = msg::GroundState();
    ground.stamp().frame(k);
    auto vehicle = [&](uint32_t id, const msg::Pose& p, float throttle) {
      msg::VehicleState v;
      v.actor(id);
      v.blueprint("vehicle.tesla.model3");
      v.transform(p);
      v.half_extents().x(2.4);
      v.half_extents().y(1.0);
      v.half_extents().z(0.75);
      v.control().throttle(throttle);
      v.red_light_infractions(k >= 200 ? 1 : 0);
      ground.vehicles().push_back(v);
    };
    vehicle(1, Pose(10 * t, 0.123456, 0.75, 0.1 * t), k < 300 ? 0.5f : 0.0f);
    vehicle(2, Pose(30, 3.5, 0.75, 1.0), 0);
    if (k >= 100 && k < 300) vehicle(3, Pose(0, 50 + t, 0.7, 0), 0.3f);
    for (uint32_t id : {4u, 5u}) {
      msg::WalkerState w;
      w.actor(id);
      w.blueprint("walker.pedestrian.0001");
      w.transform(Pose(id == 4 ? 1.4 * t : 7, -5, 0.9, 0));
      w.control().speed(id == 4 ? 1.4f : 0.0f);
      ground.walkers().push_back(w);
    }
    msg::TrafficLightState l;
    l.actor(6);
    l.transform(Pose(20, 10, 0, 0));
    l.state(k < 150 ? msg::TrafficLightColor::LIGHT_RED : msg::TrafficLightColor::LIGHT_GREEN);
    l.elapsed(k < 150 ? t : t - 7.5);
    l.green_time(10);
    l.yellow_time(3);
    l.red_time(12);
    ground.traffic_lights().push_back(l);
    air = msg::AirState();
    air.stamp().frame(k);
    msg::DroneState d;
    d.actor(7);
    d.blueprint("drone.generic_quad");
    d.transform(Pose(-3, -4, 0.5 + 0.3 * t, 0.5));
    d.armed(k >= 10);
    d.landed(k < 20 ? msg::LandedState::LANDED_LANDED : msg::LandedState::LANDED_FLYING);
    air.drones().push_back(d);
    events = msg::PhysicsEvents();
    events.stamp().frame(k);
    if (k == 50) {
      msg::ActorCollision c;
      c.actor(1);
      c.other_actor(2);
      c.normal_impulse().x(100);
      events.collisions().push_back(c);
    }
  }
};

std::string WriteWorldLog(const std::string& name, uint64_t frames) {
  const std::string path = TempPath(name);
  LogWriter w(path, Header());
  World world;
  for (uint64_t k = 1; k <= frames; ++k) {
    world.Build(k);
    FrameInputs in;
    in.tick = &world.tick;
    in.state_frame = k;
    in.ground = {&world.ground};
    in.air = {&world.air};
    in.events = {&world.events};
    if (k > 1) in.hashes.push_back({k - 1, FrameHashes{0xabc0 + (k - 1), false, {{"ground_sim", k - 1}, {"recorder", 0}}}});
    w.WriteFrame(in);
  }
  w.Close("stopped", {{frames, FrameHashes{0xabc0 + frames, false, {}}}});
  return path;
}

TEST(LockstepLog, WhatTheWriterPutsInTheReaderGivesBack) {
  const std::string path = WriteWorldLog("roundtrip", 450);
  LogReader log(path);
  EXPECT_FALSE(log.truncated());
  EXPECT_EQ(log.stop_reason(), "stopped");
  EXPECT_EQ(log.first_frame(), 1u);
  EXPECT_EQ(log.last_frame(), 450u);
  EXPECT_NEAR(log.duration(), 449 * 0.05, 1e-9);
  EXPECT_EQ(log.header().map_name, "TestTown");
  ASSERT_EQ(log.actors().size(), 7u);
  EXPECT_EQ(log.actors().at(3).blueprint, "vehicle.tesla.model3");  // described from its state (no describe())
  EXPECT_EQ(log.actors().at(3).first_frame, 100u);
  EXPECT_EQ(log.actors().at(3).last_frame, 299u);
  EXPECT_EQ(log.actors().at(6).kind, msg::ActorKind::ACTOR_TRAFFIC_LIGHT);
  World world;
  uint64_t seen = 0;
  log.ForEach([&](const LogFrame& f) -> bool {
    world.Build(f.frame);
    ++seen;
    EXPECT_EQ(f.keyframe, (f.frame - 1) % 200 == 0) << f.frame;
    EXPECT_EQ(ToCdr(f.tick), ToCdr(world.tick)) << "the tick comes back bit for bit, frame " << f.frame;
    EXPECT_EQ(f.actors.size(), f.frame >= 100 && f.frame < 300 ? 7u : 6u) << f.frame;
    for (const auto& v : world.ground.vehicles()) {
      const ActorState* s = f.Find(v.actor());
      if (!s) {
        ADD_FAILURE() << "no vehicle " << v.actor() << " in frame " << f.frame;
        continue;
      }
      EXPECT_NEAR(s->x, v.transform().position().x(), 0.00051);
      EXPECT_NEAR(s->y, v.transform().position().y(), 0.00051);
      EXPECT_NEAR(s->z, v.transform().position().z(), 0.00051);
      EXPECT_NEAR(s->yaw, 2 * std::atan2(v.transform().orientation().z(), v.transform().orientation().w()), 0.000051);
      EXPECT_FLOAT_EQ(s->throttle, v.control().throttle());
    }
    const ActorState* light = f.Find(6);
    if (light == nullptr) {
      ADD_FAILURE() << "no light in frame " << f.frame;
      return false;
    }
    EXPECT_EQ(light->light, world.ground.traffic_lights()[0].state()) << f.frame;
    EXPECT_NEAR(light->elapsed, world.ground.traffic_lights()[0].elapsed(), 1e-9) << f.frame;
    const ActorState* drone = f.Find(7);
    if (drone == nullptr) {
      ADD_FAILURE() << "no drone in frame " << f.frame;
      return false;
    }
    EXPECT_EQ(drone->armed, f.frame >= 10);
    EXPECT_NEAR(drone->z, world.air.drones()[0].transform().position().z(), 0.0005);
    if (f.frame > 1) {
      EXPECT_NEAR(drone->vz, 0.3, 0.03) << "velocity from the pose change, frame " << f.frame;
    }
    EXPECT_EQ(f.collisions.size(), f.frame == 50 ? 1u : 0u);
    EXPECT_EQ(f.infractions.size(), f.frame == 200 ? 3u : 0u) << "each car's red light";
    EXPECT_EQ(f.spawned.size(), f.frame == 1 ? 6u : (f.frame == 100 ? 1u : 0u));
    EXPECT_EQ(f.destroyed.size(), f.frame == 300 ? 1u : 0u);
    EXPECT_TRUE(f.hashes.has_value()) << f.frame;
    if (f.hashes) {
      EXPECT_EQ(f.hashes->world_hash, 0xabc0 + f.frame);
    }
    return true;
  });
  EXPECT_EQ(seen, 450u);
  // Seeking: a frame read on its own equals the same frame read in sequence.
  const LogFrame a = log.Read(437);
  uint64_t checked = 0;
  log.ForEach(430, 440, [&](const LogFrame& f) -> bool {
    if (f.frame == 437) {
      if (f.actors.size() != a.actors.size()) {
        ADD_FAILURE() << f.actors.size() << " actors vs " << a.actors.size();
        return false;
      }
      for (size_t i = 0; i < f.actors.size(); ++i) {
        EXPECT_EQ(f.actors[i].x, a.actors[i].x);
        EXPECT_EQ(f.actors[i].vx, a.actors[i].vx);
      }
      ++checked;
    }
    return true;
  });
  EXPECT_EQ(checked, 1u);
  EXPECT_EQ(log.FrameAtElapsed(1.0), 21u);
  EXPECT_THROW(log.Read(451), LogError);
  std::filesystem::remove(path);
}

TEST(LockstepLog, CompactEnoughForAnHourOfTraffic) {
  // 450 frames of 7 actors: keyframes and deltas keep a frame small.
  const std::string path = WriteWorldLog("size", 450);
  const auto bytes = std::filesystem::file_size(path);
  EXPECT_LT(static_cast<double>(bytes) / 450, 300.0) << bytes << " bytes";
  std::filesystem::remove(path);
}

TEST(LockstepLog, ATruncatedLogReadsToItsLastWholeFrame) {
  const std::string path = WriteWorldLog("whole", 300);
  const std::string cut = TempPath("cut");
  std::ifstream in(path, std::ios::binary);
  std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  // Find where frame 250's record ends: the smallest cut that still reads 250 whole frames
  // (binary search: more bytes never read fewer frames).
  LogReader full(path);
  auto frames_in = [&](size_t size) -> uint64_t {
    std::ofstream(cut, std::ios::binary | std::ios::trunc).write(bytes.data(), static_cast<std::streamsize>(size));
    try {
      LogReader part(cut);
      EXPECT_TRUE(part.truncated());
      return part.last_frame();
    } catch (const LogError&) {
      return 0;  // cut inside the header: not a log yet
    }
  };
  size_t lo = 8, hi = bytes.size() - 17;  // frames_in(hi) >= 250: only the footer is cut
  while (lo < hi) {
    const size_t mid = (lo + hi) / 2;
    if (frames_in(mid) >= 250) {
      hi = mid;
    } else {
      lo = mid + 1;
    }
  }
  const size_t cut_at = lo;
  const uint64_t frames_at_cut = frames_in(cut_at);
  ASSERT_EQ(frames_at_cut, 250u);
  // Cut a few bytes further: still inside frame 251, so still 250 whole frames.
  std::ofstream(cut, std::ios::binary | std::ios::trunc).write(bytes.data(), static_cast<std::streamsize>(cut_at + 3));
  LogReader part(cut);
  EXPECT_TRUE(part.truncated());
  EXPECT_EQ(part.last_frame(), 250u);
  EXPECT_EQ(part.actors().at(3).last_frame, 250u);
  const LogFrame a = part.Read(250);
  const LogFrame b = full.Read(250);
  ASSERT_EQ(a.actors.size(), b.actors.size());
  for (size_t i = 0; i < a.actors.size(); ++i) EXPECT_EQ(a.actors[i].x, b.actors[i].x);
  // The last whole frame's hashes would ride on frame 251: not there.
  EXPECT_FALSE(a.hashes.has_value());
  EXPECT_TRUE(part.Read(249).hashes.has_value());
  std::filesystem::remove(path);
  std::filesystem::remove(cut);
}

TEST(LockstepLog, NotALogIsRefusedNamingTheFile) {
  const std::string path = TempPath("notalog.txt");
  std::ofstream(path) << "frame,sim_time\n1,0.05\n";
  try {
    LogReader log(path);
    ADD_FAILURE() << "opened a CSV file as a log";
  } catch (const LogError& e) {
    EXPECT_NE(std::string(e.what()).find(path), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("not a Lockstep log"), std::string::npos) << e.what();
  }
  std::filesystem::remove(path);
  EXPECT_THROW(LogReader(TempPath("missing")), LogError);
}

// A small log for CARLA's text formats: dt 1 s, 8 frames. Hero car 10 drives 1 m per frame
// and is destroyed at frame 4; walker 11 stands still; light 3; car 10 hits the walker in
// frames 2 and 3 (both report it) and a wall in frame 3.
std::string WriteCarlaLog() {
  const std::string path = TempPath("carla.lslog");
  LogWriter w(path, Header());
  for (uint64_t k = 1; k <= 8; ++k) {
    msg::Tick tick = MakeTick(k, 1.0);
    msg::GroundState g;
    if (k < 4) {
      msg::VehicleState v;
      v.actor(10);
      v.blueprint("vehicle.tesla.model3");
      v.transform(Pose(1.0 + static_cast<double>(k - 1), 2, 0.75, 0));
      v.half_extents().z(0.75);
      v.control().steer(-0.25f);
      v.control().throttle(0.5f);
      g.vehicles().push_back(v);
    }
    msg::WalkerState wk;
    wk.actor(11);
    wk.blueprint("walker.pedestrian.0001");
    wk.transform(Pose(5, -3, 0.9, 0));
    g.walkers().push_back(wk);
    msg::TrafficLightState l;
    l.actor(3);
    l.transform(Pose(20, 10, 0, 0));
    l.state(msg::TrafficLightColor::LIGHT_RED);
    g.traffic_lights().push_back(l);
    msg::PhysicsEvents e;
    auto hit = [&](uint32_t a, uint32_t b) {
      msg::ActorCollision c;
      c.actor(a);
      c.other_actor(b);
      e.collisions().push_back(c);
    };
    if (k == 2 || k == 3) {
      hit(10, 11);
      hit(11, 10);
    }
    if (k == 3) hit(10, 0);
    FrameInputs in;
    in.tick = &tick;
    in.state_frame = k;
    in.ground = {&g};
    in.events = {&e};
    in.describe = [](uint32_t id) -> std::optional<ActorInfo> {
      if (id != 10) return std::nullopt;
      ActorInfo a;
      a.id = 10;
      a.blueprint = "vehicle.tesla.model3";
      a.kind = msg::ActorKind::ACTOR_VEHICLE;
      a.attributes = {{"role_name", "hero"}, {"color", "255,0,0"}};
      a.half_extents[2] = 0.75;
      return a;
    };
    w.WriteFrame(in);
  }
  w.Close("stopped");
  return path;
}

class CarlaText : public ::testing::Test {
 protected:
  void SetUp() override {
    setenv("TZ", "UTC", 1);
    tzset();
    path_ = WriteCarlaLog();
  }
  void TearDown() override { std::filesystem::remove(path_); }
  std::string path_;
};

TEST_F(CarlaText, FileInfo) {
  EXPECT_EQ(ShowRecorderFileInfo(path_, false),
            "Version: 1\n"
            "Map: TestTown\n"
            "Date: 11/14/23 22:13:20\n"
            "\n"
            "Frame 1 at 0 seconds\n"
            " Create 3: traffic.traffic_light (3) at (2000, -1000, 0)\n"
            " Create 10: vehicle.tesla.model3 (1) at (100, -200, 0)\n"
            "  role_name = hero\n"
            "  color = 255,0,0\n"
            " Create 11: walker.pedestrian.0001 (2) at (500, 300, 90)\n"
            "Frame 2 at 1 seconds\n"
            " Collision id 1 between 10 (hero)  with 11\n"
            "Frame 3 at 2 seconds\n"
            " Collision id 2 between 10 (hero)  with 11\n"
            " Collision id 3 between 10 (hero)  with 4294967295\n"
            "Frame 4 at 3 seconds\n"
            " Destroy 10\n"
            "\n"
            "Frames: 8\n"
            "Duration: 7 seconds\n");
}

TEST_F(CarlaText, FileInfoShowAll) {
  const std::string all = ShowRecorderFileInfo(path_, true);
  EXPECT_NE(all.find("Frame 2 at 1 seconds\n Collision id 1 between 10 (hero)  with 11\n Positions: 2\n"
                     "  Id: 10 Location: (200, -200, 0) Rotation: (0, 0, 0)\n  Id: 11 Location: (500, 300, 90) Rotation: (0, 0, 0)\n"
                     " State traffic lights: 1\n  Id: 3 state: 0 frozen: 0 elapsedTime: 0\n"
                     " Vehicle animations: 1\n  Id: 10 Steering: -0.25 Throttle: 0.5 Brake: 0 Handbrake: 0 Gear: 0\n"
                     " Walker animations: 1\n  Id: 11 speed: 0\n Vehicle light animations: 0\n"),
            std::string::npos)
      << all;
  EXPECT_NE(all.find("Frame 8 at 7 seconds\n Positions: 1\n"), std::string::npos) << all;
}

TEST_F(CarlaText, Collisions) {
  const std::string header =
      "Version: 1\nMap: TestTown\nDate: 11/14/23 22:13:20\n\n"
      "    Time  Types     Id Actor 1                                 Id Actor 2                            \n";
  EXPECT_EQ(ShowRecorderCollisions(path_, 'v', 'a'),
            header +
                "       1   v w      10 vehicle.tesla.model3                    11 walker.pedestrian.0001             \n"
                "       2   v o      10 vehicle.tesla.model3                4294967295                                    \n"
                "\nFrames: 8\nDuration: 7 seconds\n");
  EXPECT_EQ(ShowRecorderCollisions(path_, 'h', 'w'),
            header + "       1   v w      10 vehicle.tesla.model3                    11 walker.pedestrian.0001             \n"
                     "\nFrames: 8\nDuration: 7 seconds\n");
  // No match: the stream was never switched to fixed, so the duration prints as CARLA's does.
  EXPECT_EQ(ShowRecorderCollisions(path_, 't', 't'), header + "\nFrames: 8\nDuration: 7 seconds\n");
}

TEST_F(CarlaText, ActorsBlocked) {
  EXPECT_EQ(ShowRecorderActorsBlocked(path_, 1, 10),
            "Version: 1\nMap: TestTown\nDate: 11/14/23 22:13:20\n\n"
            "    Time     Id Actor                                 Duration\n"
            "       1     11 walker.pedestrian.0001                       5\n"
            "\nFrames: 8\nDuration: 7 seconds\n");
  // CARLA counts the last frame as -1 s: 6 s blocked show as 5.
  EXPECT_EQ(ShowRecorderActorsBlocked(path_, 6, 10).find("walker"), std::string::npos);
}

TEST_F(CarlaText, AMissingFileIsCarlasMessage) {
  const std::string missing = TempPath("nothere.log");
  EXPECT_EQ(ShowRecorderFileInfo(missing, false), "File " + missing + " not found on server\n");
  setenv("LOCKSTEP_RECORDINGS_DIR", "/tmp/lockstep-recordings-test", 1);
  EXPECT_EQ(ShowRecorderCollisions("x.log", 'a', 'a'), "File /tmp/lockstep-recordings-test/x.log not found on server\n");
  unsetenv("LOCKSTEP_RECORDINGS_DIR");
}

}  // namespace
}  // namespace lockstep::recorder
