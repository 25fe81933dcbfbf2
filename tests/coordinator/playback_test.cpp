// Playback (CARLA's replay_file) as plain logic: a log in memory, a stand-in for the
// coordinator's command processor, and the commands each tick carries.
#include "playback.h"

#include <gtest/gtest.h>

#include <cmath>
#include <map>
#include <memory>
#include <set>

#include "lockstep/runtime/command_builders.h"
#include "lockstep/runtime/error.h"

namespace lockstep {
namespace {

using K = msg::CommandKind;

PlaybackActor Actor(uint32_t id, const std::string& bp, msg::ActorKind kind, uint32_t parent = 0, bool hero = false) {
  PlaybackActor a;
  a.id = id;
  a.kind = kind;
  a.spawn.blueprint(bp);
  a.spawn.transform(MakePose(id, 0, 0.5));
  a.spawn.parent(parent);
  a.spawn.actor(id);
  if (hero) a.spawn.attributes(MakeAttributes({{"role_name", "hero"}}));
  return a;
}

// A log of `n` frames 0.05 s apart: actor 10 (a car) drives along x at 1 m per frame; a
// walker 11 at y = 5; a drone 12 from frame 2; the car 13 (hero); a camera 14 on the car 10;
// the car 15 is destroyed by frame 4; traffic light 1 turns green at frame 3.
class MemoryLog : public PlaybackLog {
 public:
  explicit MemoryLog(size_t n, uint64_t map_hash = 7) : map_hash_(map_hash) {
    for (size_t i = 0; i < n; ++i) {
      PlaybackFrame f;
      f.time = 0.05 * static_cast<double>(i);
      if (i == 0) {
        f.spawned = {Actor(10, "vehicle.a", msg::ACTOR_VEHICLE), Actor(11, "walker.a", msg::ACTOR_WALKER),
                     Actor(13, "vehicle.b", msg::ACTOR_VEHICLE, 0, true), Actor(14, "sensor.camera.rgb", msg::ACTOR_SENSOR, 10),
                     Actor(15, "vehicle.c", msg::ACTOR_VEHICLE)};
      }
      if (i == 2) f.spawned = {Actor(12, "drone.a", msg::ACTOR_DRONE)};
      if (i == 4) f.destroyed = {15};
      f.poses.push_back({10, MakePose(100.0 + static_cast<double>(i), 0, 0.5, 0.01 * static_cast<double>(i))});
      f.poses.push_back({11, MakePose(0, 5, 1)});
      f.poses.push_back({13, MakePose(-50, 0, 0.5)});
      if (i >= 2) f.poses.push_back({12, MakePose(0, 0, 10.0 + static_cast<double>(i))});
      if (i < 4) f.poses.push_back({15, MakePose(30, 30, 0.5)});
      f.lights.push_back({1, i >= 3 ? msg::TrafficLightColor::LIGHT_GREEN : msg::TrafficLightColor::LIGHT_RED});
      f.vehicle_lights.push_back({10, i >= 5 ? 3u : 1u});  // the car's lights change at frame 5
      frames_.push_back(f);
    }
  }
  std::string Path() const override { return "/logs/test.log"; }
  std::string MapName() const override { return "Town01"; }
  uint64_t MapHash() const override { return map_hash_; }
  size_t Frames() const override { return frames_.size(); }
  double Time(size_t i) const override { return frames_.at(i).time; }
  PlaybackFrame Frame(size_t i) const override { return frames_.at(i); }
  std::vector<PlaybackActor> ActorsAt(size_t index) const override {
    std::map<uint32_t, PlaybackActor> alive;
    for (size_t i = 0; i <= index; ++i) {
      for (const auto& a : frames_[i].spawned) alive[a.id] = a;
      for (uint32_t d : frames_[i].destroyed) alive.erase(d);
    }
    std::vector<PlaybackActor> out;
    for (const auto& [id, a] : alive) out.push_back(a);
    return out;
  }

 private:
  std::vector<PlaybackFrame> frames_;
  uint64_t map_hash_;
};

// The coordinator's side: actors of the run, ids from 100, every command kept per tick.
struct World {
  std::map<uint32_t, std::string> actors{{1, "traffic.traffic_light"}, {2, "traffic.traffic_light"}};
  uint32_t next = 100;
  std::vector<msg::CommandBody> tick;
  std::set<std::string> refuse;  // blueprints whose spawn is refused
  msg::CommandReply Submit(const msg::CommandBody& b) {
    msg::CommandReply r;
    r.accepted(true);
    if (b._d() == K::CMD_SPAWN_ACTOR) {
      if (refuse.count(b.spawn_actor().blueprint().to_string())) {
        r.accepted(false);
        r.reason("occupied");
        return r;
      }
      actors[next] = b.spawn_actor().blueprint().to_string();
      r.actor(next++);
    } else if (b._d() == K::CMD_DESTROY_ACTOR) {
      if (!actors.erase(b.destroy_actor().actor())) r.accepted(false);
    }
    tick.push_back(b);
    return r;
  }
  std::vector<msg::CommandBody> Tick(Playback& p, double dt = 0.05) {
    tick.clear();
    p.Tick(
        dt, [this](const msg::CommandBody& b) { return Submit(b); },
        [this](uint32_t id) -> const std::string* {
          auto it = actors.find(id);
          return it == actors.end() ? nullptr : &it->second;
        });
    return tick;
  }
};

msg::RecorderCommand Replay(double start = 0, double duration = 0, bool sensors = false) {
  msg::RecorderCommand c;
  c.action(msg::RecorderAction::REPLAY_START);
  c.name("test.log");
  c.start(start);
  c.duration(duration);
  c.replay_sensors(sensors);
  return c;
}

msg::RecorderCommand Setting(msg::RecorderAction action, bool flag, double value = 0) {
  msg::RecorderCommand c;
  c.action(action);
  c.flag(flag);
  c.value(value);
  return c;
}

Playback Make(size_t frames = 8) {
  return Playback([frames](const std::string& name) -> std::unique_ptr<PlaybackLog> {
    if (name != "test.log") throw InputError("cannot open '" + name + "': No such file");
    return std::make_unique<MemoryLog>(frames);
  }, [](const std::string& name) { return "/logs/" + name; });
}

std::string Start(Playback& p, const msg::RecorderCommand& c) {
  std::string text;
  const std::string why = p.Prepare(c, "Town01", 7, &text);
  EXPECT_EQ(why, "");
  return p.Apply(c);
}

// The pose the tick's set_transform gives run actor `id`, if any.
const msg::Pose* PoseOf(const std::vector<msg::CommandBody>& tick, uint32_t id) {
  const msg::Pose* out = nullptr;
  for (const auto& b : tick) {
    if (b._d() == K::CMD_SET_TRANSFORM && b.set_transform().actor() == id) out = &b.set_transform().transform();
  }
  return out;
}

size_t Count(const std::vector<msg::CommandBody>& tick, K kind) {
  size_t n = 0;
  for (const auto& b : tick) {
    // set_light_state is counted on its own (LightStates)
    if (b._d() == K::CMD_ACTOR_PHYSICS && b.actor_physics().kind() == msg::ActorPhysicsKind::PHYSICS_SET_LIGHT_STATE) continue;
    n += b._d() == kind;
  }
  return n;
}

std::vector<uint32_t> LightStates(const std::vector<msg::CommandBody>& tick) {
  std::vector<uint32_t> out;
  for (const auto& b : tick) {
    if (b._d() == K::CMD_ACTOR_PHYSICS && b.actor_physics().kind() == msg::ActorPhysicsKind::PHYSICS_SET_LIGHT_STATE) {
      out.push_back(b.actor_physics().light_state());
    }
  }
  return out;
}

TEST(Playback, ReplyIsCarlasText) {
  Playback p = Make();
  EXPECT_EQ(Start(p, Replay()),
            "Replaying File: /logs/test.log\nTotal time recorded: 0.35\nReplaying from 0 s - 0.35 s (0.35 s) at 1.0x\n"
            "Ignoring Spectator camera\n");
  p.Apply(Setting(msg::RecorderAction::REPLAY_TIME_FACTOR, false, 2.5));
  p.Apply(Setting(msg::RecorderAction::REPLAY_IGNORE_HERO, true));
  p.Apply(Setting(msg::RecorderAction::REPLAY_IGNORE_SPECTATOR, false));
  EXPECT_EQ(Start(p, Replay(-0.1, 0.05)),
            "Replaying File: /logs/test.log\nTotal time recorded: 0.35\nReplaying from 0.25 s - 0.3 s (0.35 s) at 2.5x\n"
            "Ignoring Hero vehicle\n");
}

TEST(Playback, AMissingFileIsCarlasTextAndARefusal) {
  Playback p = Make();
  msg::RecorderCommand c = Replay();
  c.name("nope.log");
  std::string text;
  EXPECT_NE(p.Prepare(c, "Town01", 7, &text).find("No such file"), std::string::npos);
  EXPECT_EQ(text, "Replaying File: /logs/nope.log\nFile /logs/nope.log not found on server\n");
  EXPECT_FALSE(p.Busy());
}

TEST(Playback, ALogOfAnotherMapIsRefusedWithTheReason) {
  Playback p = Make();
  std::string text;
  const std::string why = p.Prepare(Replay(), "Town02", 8, &text);
  EXPECT_NE(why.find("recorded on map 'Town01'"), std::string::npos) << why;
  EXPECT_NE(why.find("'Town02'"), std::string::npos) << why;
}

TEST(Playback, EveryTickPutsEveryActorAtItsRecordedPose) {
  Playback p = Make();
  World w;
  Start(p, Replay());
  const MemoryLog log(8);
  std::map<uint32_t, uint32_t> ids;  // log -> run
  for (size_t frame = 0; frame < 8; ++frame) {
    const auto tick = w.Tick(p);
    if (frame == 0) {
      // Spawned high above (CARLA's way round a collision at spawn), physics off, then placed.
      ASSERT_EQ(Count(tick, K::CMD_SPAWN_ACTOR), 4u);  // not the camera (replay_sensors false)
      for (const auto& b : tick) {
        if (b._d() == K::CMD_SPAWN_ACTOR && b.spawn_actor().blueprint().to_string() == "vehicle.a") {
          EXPECT_DOUBLE_EQ(b.spawn_actor().transform().position().z(), 1000.5);
        }
      }
      EXPECT_EQ(Count(tick, K::CMD_ACTOR_PHYSICS), 3u);  // the three vehicles
      ids = p.mapped();
    }
    if (frame == 2) {
      ASSERT_EQ(Count(tick, K::CMD_SPAWN_ACTOR), 1u);  // the drone
      ids = p.mapped();
    }
    if (frame == 4) {
      EXPECT_EQ(Count(tick, K::CMD_DESTROY_ACTOR), 1u);
    }
    // The car's lights are set when they change.
    EXPECT_EQ(LightStates(tick), frame == 0 ? std::vector<uint32_t>{1} : frame == 5 ? std::vector<uint32_t>{3}
                                                                                    : std::vector<uint32_t>{})
        << frame;
    // Light 1 is set (frozen) when it changes, not every tick.
    EXPECT_EQ(Count(tick, K::CMD_TRAFFIC_LIGHT), frame == 0 || frame == 3 ? 1u : 0u) << frame;
    for (const auto& rec : log.Frame(frame).poses) {
      const msg::Pose* got = PoseOf(tick, ids.at(rec.id));
      ASSERT_NE(got, nullptr) << "actor " << rec.id << " frame " << frame;
      EXPECT_EQ(got->position().x(), rec.pose.position().x());
      EXPECT_EQ(got->position().y(), rec.pose.position().y());
      EXPECT_EQ(got->position().z(), rec.pose.position().z());
      EXPECT_EQ(got->orientation().w(), rec.pose.orientation().w());
      EXPECT_EQ(got->orientation().z(), rec.pose.orientation().z());
    }
  }
  EXPECT_TRUE(p.Busy());
  // The tick after the last frame: CARLA's end of a replay, physics on and autopilot, the lights free.
  const auto end = w.Tick(p);
  EXPECT_EQ(Count(end, K::CMD_SET_TRANSFORM), 0u);
  EXPECT_EQ(Count(end, K::CMD_ACTOR_PHYSICS), 2u);
  EXPECT_EQ(Count(end, K::CMD_TRAFFIC_MANAGER), 2u);
  ASSERT_EQ(Count(end, K::CMD_TRAFFIC_LIGHT), 1u);
  EXPECT_FALSE(p.Busy());
  EXPECT_TRUE(w.Tick(p).empty());
}

TEST(Playback, FromAnyTimeAtAnyFactor) {
  Playback p = Make();
  World w;
  p.Apply(Setting(msg::RecorderAction::REPLAY_TIME_FACTOR, false, 0.5));
  Start(p, Replay(0.1, 0.1));  // frames 2..4
  auto t = w.Tick(p);
  EXPECT_EQ(Count(t, K::CMD_SPAWN_ACTOR), 5u);  // everything alive at frame 2, the drone too
  const uint32_t car = p.mapped().at(10);
  EXPECT_DOUBLE_EQ(PoseOf(t, car)->position().x(), 102.0);
  t = w.Tick(p);  // half a frame later: between frames 2 and 3
  EXPECT_NEAR(PoseOf(t, car)->position().x(), 102.5, 1e-9);
  EXPECT_NEAR(std::atan2(2 * PoseOf(t, car)->orientation().w() * PoseOf(t, car)->orientation().z(),
                         1 - 2 * PoseOf(t, car)->orientation().z() * PoseOf(t, car)->orientation().z()),
              0.025, 1e-9);
  for (int i = 0; i < 3; ++i) t = w.Tick(p);
  EXPECT_DOUBLE_EQ(PoseOf(t, car)->position().x(), 104.0);  // the stop time's frame, shown
  EXPECT_EQ(Count(w.Tick(p), K::CMD_SET_TRANSFORM), 0u);
  EXPECT_FALSE(p.Busy());

  // Factor 2 and above: whole frames, skipped ones' events netted.
  Playback q = Make();
  World v;
  q.Apply(Setting(msg::RecorderAction::REPLAY_TIME_FACTOR, false, 3));
  Start(q, Replay());
  v.Tick(q);               // frame 0
  t = v.Tick(q);           // frame 3: the drone of frame 2 appears
  EXPECT_EQ(Count(t, K::CMD_SPAWN_ACTOR), 1u);
  EXPECT_DOUBLE_EQ(PoseOf(t, q.mapped().at(10))->position().x(), 103.0);
  t = v.Tick(q);           // frame 6: car 15 destroyed at 4
  EXPECT_EQ(Count(t, K::CMD_DESTROY_ACTOR), 1u);
  EXPECT_FALSE(q.mapped().count(15));
}

TEST(Playback, IgnoreHeroAndReplaySensors) {
  Playback p = Make();
  World w;
  p.Apply(Setting(msg::RecorderAction::REPLAY_IGNORE_HERO, true));
  Start(p, Replay(0, 0, true));
  const auto t = w.Tick(p);
  EXPECT_FALSE(p.mapped().count(13));  // the hero is not created
  ASSERT_TRUE(p.mapped().count(14));   // the camera, on its parent's new id
  for (const auto& b : t) {
    if (b._d() == K::CMD_SPAWN_ACTOR && b.spawn_actor().blueprint().to_string() == "sensor.camera.rgb") {
      EXPECT_EQ(b.spawn_actor().parent(), p.mapped().at(10));
    }
  }
  EXPECT_EQ(PoseOf(t, p.mapped().at(14)), nullptr);  // sensors ride on their parent
}

TEST(Playback, ReusesAnActorOfTheSameIdAndBlueprint) {
  Playback p = Make();
  World w;
  w.actors[10] = "vehicle.a";   // the recorded car still exists
  w.actors[11] = "vehicle.zz";  // another actor holds the walker's id
  Start(p, Replay());
  const auto t = w.Tick(p);
  EXPECT_EQ(p.mapped().at(10), 10u);
  EXPECT_NE(p.mapped().at(11), 11u);
  EXPECT_EQ(Count(t, K::CMD_TRAFFIC_MANAGER), 1u);  // its autopilot off (CARLA)
}

TEST(Playback, StopReplayerWithoutKeepingActorsAppliesTheLogsLaterEvents) {
  Playback p = Make();
  World w;
  Start(p, Replay());
  w.Tick(p);
  w.Tick(p);
  const uint32_t doomed = p.mapped().at(15);
  p.Apply(Setting(msg::RecorderAction::REPLAY_STOP, false));
  const auto t = w.Tick(p);
  EXPECT_FALSE(w.actors.count(doomed));       // destroyed at frame 4 of the log
  EXPECT_EQ(Count(t, K::CMD_SPAWN_ACTOR), 1u);  // the drone the log spawns at frame 2, where it spawned
  EXPECT_EQ(Count(t, K::CMD_TRAFFIC_MANAGER), 0u);  // no autopilot when the actors are not kept
  EXPECT_FALSE(p.Busy());
}

TEST(Playback, ASpawnRefusedIsSkippedAndTheRestGoesOn) {
  Playback p = Make();
  World w;
  w.refuse.insert("walker.a");
  Start(p, Replay());
  w.Tick(p);
  EXPECT_FALSE(p.mapped().count(11));
  EXPECT_TRUE(p.mapped().count(10));
  EXPECT_NE(PoseOf(w.Tick(p), p.mapped().at(10)), nullptr);
}

TEST(Playback, ChecksTheValues) {
  EXPECT_EQ(CheckReplayCommand(Setting(msg::RecorderAction::REPLAY_TIME_FACTOR, false, 0)), "");  // CARLA: frozen
  EXPECT_NE(CheckReplayCommand(Setting(msg::RecorderAction::REPLAY_TIME_FACTOR, false, -1)), "");
  EXPECT_NE(CheckReplayCommand(Setting(msg::RecorderAction::REPLAY_TIME_FACTOR, false, std::nan(""))), "");
  EXPECT_EQ(CheckReplayCommand(Setting(msg::RecorderAction::REPLAY_TIME_FACTOR, false, 0.5)), "");
  msg::RecorderCommand c = Replay(std::nan(""));
  EXPECT_NE(CheckReplayCommand(c), "");
  c = Replay();
  c.name("");
  EXPECT_NE(CheckReplayCommand(c), "");
}

}  // namespace
}  // namespace lockstep
