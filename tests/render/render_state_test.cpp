// The render service's state (render::RenderState): its hash is equal for equal states
// and changes with every part that changes future images (weather, spawns, each camera's
// mount, attributes, parent, schedule, last pose, world pose, auto-exposure and DVS state,
// the actors' last poses, debug shapes); a snapshot restores the same state; the rig
// detaches a camera from a destroyed parent where it was.
#include <gtest/gtest.h>

#include <functional>
#include <string>
#include <vector>

#include "lockstep/render/render_state.h"

namespace lockstep::render {
namespace {

Pose At(double x, double y, double z) { return Pose{Vec3(x, y, z), Quat::Identity()}; }

SpawnedActor Actor(const std::string& bp, std::map<std::string, std::string> attrs = {}, uint32_t parent = 0, Pose at = At(0, 0, 0)) {
  return SpawnedActor{bp, std::move(attrs), parent, at};
}

constexpr uint64_t kSeed = 42;

// A car (1), an RGB camera on it (2), a DVS camera in the world (3), a debug line,
// and one rendered frame's actor poses.
RenderState Sample() {
  RenderState s;
  s.weather.fog_density = 10;
  s.Spawn(1, Actor("vehicle.tesla.model3", {{"color", "10,20,30"}}), true, kSeed);
  s.Spawn(2, Actor("sensor.camera.rgb", {{"image_size_x", "8"}, {"image_size_y", "6"}}, 1, At(1.5, 0, 2.4)), true, kSeed);
  // (Manual exposure: its state is the DVS sensor's alone.)
  s.Spawn(3, Actor("sensor.camera.dvs", {{"image_size_x", "8"}, {"image_size_y", "6"}, {"exposure_mode", "manual"}}, 0, At(5, 0, 2)), true,
          kSeed);
  s.previous_poses[1] = At(10, 0, 0.7);
  s.debug.AddLine(DebugLine{Vec3(0, 0, 0), Vec3(1, 0, 0), 0.1, {255, 0, 0}}, 3, 0.1, 2.0);
  return s;
}

// A frame: every camera due, the car's mount at x.
std::vector<CameraPass> Frame(RenderState& s, uint64_t k, double x) { return s.Plan(k, 0.05 * static_cast<double>(k), {{1, At(x, 0, 0)}}, kSeed); }

// Every member of every pass takes a grey image of level `grey`.
void Take(RenderState& s, const std::vector<CameraPass>& passes, uint8_t grey, double t) {
  for (const auto& pass : passes) {
    std::vector<uint8_t> bgra(static_cast<std::size_t>(pass.camera.width) * pass.camera.height * 4, grey);
    CameraImages im;
    im.width = pass.camera.width;
    im.height = pass.camera.height;
    im.color = bgra.data();
    for (std::size_t i = 0; i < pass.members.size(); ++i) s.Take(pass, i, im, t);
  }
}

TEST(RenderState, EqualStatesHashEqualAndTheHashIsTheSnapshots) {
  RenderState a = Sample(), b = Sample();
  EXPECT_EQ(a.Hash(), b.Hash());
  Take(a, Frame(a, 1, 10), 100, 0.05);
  Take(b, Frame(b, 1, 10), 100, 0.05);
  EXPECT_EQ(a.Hash(), b.Hash()) << "the same frames give the same state";
  RenderState copy = a;
  EXPECT_EQ(copy.Hash(), a.Hash());
  EXPECT_NE(a.Hash(), RenderState{}.Hash());
}

// Each change of a part that changes future images changes the hash.
TEST(RenderState, TheHashChangesWithEveryPart) {
  RenderState base = Sample();
  Take(base, Frame(base, 1, 10), 100, 0.05);  // primes exposure, DVS, schedule and last poses
  const uint64_t h = base.Hash();
  const std::vector<std::pair<std::string, std::function<void(RenderState&)>>> changes{
      {"weather", [](RenderState& s) { s.weather.sun_altitude_angle += 1; }},
      {"a spawned actor", [](RenderState& s) { s.Spawn(9, Actor("walker.pedestrian.0001"), true, kSeed); }},
      {"an actor's attributes", [](RenderState& s) { s.spawned[1].attributes["color"] = "10,20,31"; }},
      {"an actor's transform", [](RenderState& s) { s.SetTransform(1, At(0, 0, 0.01)); }},
      {"a camera's mount", [](RenderState& s) { s.SetTransform(2, At(1.5, 0, 2.5)); }},
      {"a camera's attributes",
       [](RenderState& s) {
         auto a = s.cameras.at(2).attributes;
         a["fov"] = "60";
         s.cameras.erase(2);
         s.Spawn(2, Actor("sensor.camera.rgb", a, 1, At(1.5, 0, 2.4)), true, kSeed);
       }},
      {"a camera's parent", [](RenderState& s) { s.cameras.at(2).parent = 0; }},
      {"a camera's last capture", [](RenderState& s) { s.cameras.at(2).last_capture += 0.05; }},
      {"a camera's last pose", [](RenderState& s) { s.cameras.at(2).last_pose->position.x() += 0.01; }},
      {"a camera's world pose", [](RenderState& s) { s.cameras.at(2).world_pose.reset(); }},
      {"auto-exposure", [](RenderState& s) { Take(s, {CameraPass{s.cameras.at(2).settings.camera, {2}, {0.05}}}, 250, 0.1); }},
      {"the DVS state", [](RenderState& s) { Take(s, {CameraPass{s.cameras.at(3).settings.camera, {3}, {0.05}}}, 30, 0.1); }},
      {"the actors' last poses", [](RenderState& s) { s.previous_poses[1].position.y() += 0.01; }},
      {"debug shapes", [](RenderState& s) { s.debug.AddPoint(DebugPoint{Vec3(0, 0, 1), 0.1, {0, 255, 0}}, 4, 0.15, 0); }},
      {"a debug shape's life", [](RenderState& s) {
         s.debug.Clear();
         s.debug.AddLine(DebugLine{Vec3(0, 0, 0), Vec3(1, 0, 0), 0.1, {255, 0, 0}}, 3, 0.1, 2.5);
       }},
  };
  for (const auto& [what, change] : changes) {
    RenderState s = base;
    ASSERT_EQ(s.Hash(), h);
    change(s);
    EXPECT_NE(s.Hash(), h) << what << " is not in the state hash";
  }
}

// The exposure adaptation and the DVS reference image change with the images: a camera's
// second image changes its state, the first one primes it.
TEST(RenderState, ImagesChangeExposureAndDvsState) {
  RenderState s = Sample();
  EXPECT_TRUE(s.cameras.at(2).ImagesChangeState());  // RGB, histogram exposure (CARLA's default)
  EXPECT_TRUE(s.cameras.at(3).ImagesChangeState());  // DVS
  s.Spawn(4, Actor("sensor.camera.depth", {{"image_size_x", "8"}, {"image_size_y", "6"}}), true, kSeed);
  s.Spawn(5, Actor("sensor.camera.rgb", {{"exposure_mode", "manual"}}), true, kSeed);
  EXPECT_FALSE(s.cameras.at(4).ImagesChangeState());
  EXPECT_FALSE(s.cameras.at(5).ImagesChangeState());
  const double ev = s.cameras.at(2).exposure.ev100();
  Take(s, Frame(s, 1, 10), 100, 0.05);
  auto passes = Frame(s, 2, 10);
  std::vector<DvsEvent> events;
  for (const auto& pass : passes) {
    std::vector<uint8_t> bright(static_cast<std::size_t>(pass.camera.width) * pass.camera.height * 4, 250);
    CameraImages im;
    im.width = pass.camera.width;
    im.height = pass.camera.height;
    im.color = bright.data();
    for (std::size_t i = 0; i < pass.members.size(); ++i) {
      auto e = s.Take(pass, i, im, 0.1);
      if (pass.members[i] == 3) events = e;
    }
  }
  EXPECT_GT(s.cameras.at(2).exposure.ev100(), ev) << "a brighter image raises EV100";
  // Grey 100 -> 250: log intensity up by ln((250/255 + 0.001) / (100/255 + 0.001)) = 0.91, so
  // three events of threshold 0.3 at every one of the 48 pixels.
  EXPECT_EQ(events.size(), 3u * 48u) << "every pixel of the DVS camera got brighter";
}

TEST(RenderState, ASnapshotRestoresTheState) {
  RenderState a = Sample();
  Take(a, Frame(a, 1, 10), 100, 0.05);
  Take(a, Frame(a, 2, 10.5), 180, 0.1);
  const std::vector<uint8_t> bytes = a.Save();
  RenderState b;
  b.Restore(bytes);
  EXPECT_EQ(b.Hash(), a.Hash());
  EXPECT_EQ(b.Save(), bytes);
  EXPECT_EQ(b.cameras.at(2).settings.camera.width, 8) << "the settings follow from the attributes";
  // The same next frame from both gives the same state and the same DVS events.
  auto pa = Frame(a, 3, 11), pb = Frame(b, 3, 11);
  Take(a, pa, 60, 0.15);
  Take(b, pb, 60, 0.15);
  EXPECT_EQ(b.Hash(), a.Hash());
}

TEST(RenderState, ABadSnapshotIsRefusedAndLeavesTheStateAlone) {
  RenderState a = Sample();
  Take(a, Frame(a, 1, 10), 100, 0.05);
  std::vector<uint8_t> bytes = a.Save();
  RenderState b = Sample();
  const uint64_t h = b.Hash();
  auto refused = [&](std::vector<uint8_t> bad, const std::string& why) {
    try {
      b.Restore(bad);
      ADD_FAILURE() << "accepted: " << why;
    } catch (const std::invalid_argument& e) {
      EXPECT_NE(std::string(e.what()).find(why), std::string::npos) << e.what();
    }
    EXPECT_EQ(b.Hash(), h);
  };
  refused(std::vector<uint8_t>(bytes.begin(), bytes.end() - 3), "truncated");
  auto longer = bytes;
  longer.push_back(0);
  refused(longer, "trailing bytes");
  auto version = bytes;
  version[0] ^= 0x7f;
  refused(version, "version");
  refused({}, "truncated");
}

// CARLA destroys only the actor: its cameras stay where they were, in the world.
TEST(RenderState, ACameraStaysWhereItWasWhenItsParentIsDestroyed) {
  RenderState s = Sample();
  Frame(s, 1, 10);
  ASSERT_TRUE(s.cameras.at(2).world_pose);
  s.Destroy(1);
  EXPECT_EQ(s.spawned.count(1), 0u);
  EXPECT_EQ(s.cameras.at(2).parent, 0u);
  EXPECT_NEAR(s.cameras.at(2).relative.position.x(), 11.5, 1e-12);
  EXPECT_NEAR(s.cameras.at(2).relative.position.z(), 2.4, 1e-12);
  EXPECT_EQ(s.spawned.at(2).parent, 0u);
  auto passes = Frame(s, 2, 20);  // the old parent's mount no longer moves it
  for (const auto& p : passes) {
    if (p.members.front() == 2) {
      EXPECT_NEAR(p.camera.pose.position.x(), 11.5, 1e-12);
    }
  }
}

// A camera with a sensor_tick is planned only when due; cameras with one pose and lens
// share a pass.
TEST(RenderState, ThePlanFollowsSensorTicksAndSharesPasses) {
  RenderState s;
  s.Spawn(1, Actor("sensor.camera.rgb", {{"image_size_x", "8"}, {"image_size_y", "6"}, {"sensor_tick", "0.1"}}, 0, At(0, 0, 2)), true, kSeed);
  s.Spawn(2, Actor("sensor.camera.depth", {{"image_size_x", "8"}, {"image_size_y", "6"}}, 0, At(0, 0, 2)), true, kSeed);
  s.Spawn(3, Actor("sensor.camera.rgb", {{"image_size_x", "8"}, {"image_size_y", "6"}}, 0, At(0, 0, 2)), false, kSeed);
  EXPECT_EQ(s.cameras.count(3), 0u) << "not this process's camera";
  EXPECT_EQ(s.spawned.count(3), 1u);
  auto p1 = s.Plan(1, 0.05, {}, kSeed);
  ASSERT_EQ(p1.size(), 1u);
  EXPECT_EQ(p1[0].members, (std::vector<uint32_t>{1, 2}));
  auto p2 = s.Plan(2, 0.10, {}, kSeed);
  ASSERT_EQ(p2.size(), 1u);
  EXPECT_EQ(p2[0].members, (std::vector<uint32_t>{2})) << "camera 1 is due every 0.1 s";
  auto p3 = s.Plan(3, 0.15, {}, kSeed);
  ASSERT_EQ(p3.size(), 1u);
  EXPECT_EQ(p3[0].members, (std::vector<uint32_t>{1, 2}));
  EXPECT_NEAR(p3[0].exposure_dt[0], 0.1, 1e-12);
}

TEST(RenderState, ABadCameraIsRecordedWithoutACamera) {
  RenderState s;
  EXPECT_THROW(s.Spawn(1, Actor("sensor.camera.rgb", {{"fov", "500"}}), true, kSeed), std::invalid_argument);
  EXPECT_EQ(s.cameras.count(1), 0u);
  EXPECT_EQ(s.spawned.count(1), 1u);
}

}  // namespace
}  // namespace lockstep::render
