// The renderer's speed-ups (RenderTuning) leave every output as it was: the same frames
// rendered with each speed-up off, and with all off, match the frames with all on.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

#include "lockstep/render/weather.h"
#include "render_fixture.h"

namespace lockstep::render {
namespace {

using namespace testing;

// Three frames of a street at noon (sun shadows) with a car driving past a walker and a
// drone, seen by a camera that moves too: every output requested, then the same view
// without flow and without colour and flow (passes that clear to the sky instead of drawing it).
std::vector<CameraFrame> Sequence(Renderer& r, const RenderTuning& tuning) {
  r.SetTuning(tuning);
  std::vector<CameraFrame> out;
  WorldView w;
  w.weather = WeatherPreset("ClearNoon");
  w.weather.sun_altitude_angle = 35;
  w.weather.sun_azimuth_angle = 60;
  w.actors.push_back(Vehicle(r, 10, At(14, -1.5, 0.75)));
  w.actors.push_back(Walker(r, 11, At(16, 5.5, 0.15 + 0.9)));
  w.actors.push_back(Drone(r, 12, At(20, 1, 4)));
  Camera cam = Cam(160, 120, 90, At(0, 0, 2.0, 5, -8), kOutColor | kOutLabels | kOutDepth | kOutNormals | kOutFlow);
  for (int f = 0; f < 3; ++f) {
    Camera no_flow = cam, no_colour = cam;
    no_flow.outputs &= ~static_cast<std::uint32_t>(kOutFlow);
    no_colour.outputs = kOutLabels | kOutDepth | kOutNormals;
    no_colour.pose.position.y() += 0.5;  // not the same pose: a pass of its own
    for (const CameraFrame& c : r.RenderFrames({cam, no_flow, no_colour}, w)) out.push_back(c);
    cam.previous_pose = cam.pose;
    cam.pose.position.x() += 5;  // the shadow box moves (8 m steps) between frames 0 and 1
    for (auto& a : w.actors) {
      a.previous_pose = a.pose;
      a.pose.position.x() += 1.5;
    }
  }
  r.SetTuning(RenderTuning{});
  return out;
}

void ExpectSame(const CameraFrame& a, const CameraFrame& b, const std::string& what) {
  ASSERT_EQ(a.color.size(), b.color.size());
  int colour_off = 0;
  for (std::size_t i = 0; i < a.color.size(); ++i) colour_off += std::abs(int(a.color[i]) - int(b.color[i])) > 2;
  EXPECT_EQ(colour_off, 0) << what << ": colour channels that differ by more than 2";
  EXPECT_EQ(a.labels, b.labels) << what << ": labels";
  EXPECT_EQ(a.normals, b.normals) << what << ": normals";
  float depth = 0, flow = 0;
  for (std::size_t i = 0; i < a.depth.size(); ++i) depth = std::max(depth, std::abs(a.depth[i] - b.depth[i]));
  for (std::size_t i = 0; i < a.flow.size(); ++i) flow = std::max(flow, std::abs(a.flow[i] - b.flow[i]));
  EXPECT_LT(depth, 1e-4f) << what << ": depth";
  EXPECT_LT(flow, 1e-5f) << what << ": flow";
}

TEST(Tuning, SpeedUpsDoNotChangeWhatACameraSees) {
  Renderer& r = SharedRenderer();
  const auto fast = Sequence(r, RenderTuning{});
  RenderTuning none{false, false, false, false, false};
  const auto slow = Sequence(r, none);
  for (std::size_t f = 0; f < fast.size(); ++f) ExpectSame(slow[f], fast[f], "all speed-ups off, frame " + std::to_string(f));
  const char* names[] = {"output_variants", "depth_prepass", "front_to_back", "static_shadow_cache", "sky_by_clear"};
  for (int k = 0; k < 5; ++k) {
    RenderTuning t;
    bool* flags[] = {&t.output_variants, &t.depth_prepass, &t.front_to_back, &t.static_shadow_cache, &t.sky_by_clear};
    *flags[k] = false;
    const auto one_off = Sequence(r, t);
    for (std::size_t f = 0; f < fast.size(); ++f) ExpectSame(one_off[f], fast[f], std::string(names[k]) + " off, frame " + std::to_string(f));
  }
}

TEST(Tuning, MovingActorsMoveTheirShadowsWithTheTownsShadowsKept) {
  Renderer& r = SharedRenderer();
  // A tall truck beside the road, the sun low on its side: its shadow falls across the road.
  WorldView w;
  w.weather = WeatherPreset("ClearNoon");
  w.weather.sun_altitude_angle = 30;
  w.weather.sun_azimuth_angle = 90;  // the sun towards -y: shadows towards +y
  w.actors.push_back(Vehicle(r, 20, At(15, -6, 1.6), "truck", Vec3(4, 1.2, 1.6)));
  const Camera cam = Cam(160, 120, 90, At(0, 0, 6.0, 0, -25), kOutColor);
  const auto road_luma = [&](const CameraFrame& f, double x) {
    const auto uv = Project(cam, Vec3(x, -2, 0));
    EXPECT_TRUE(uv);
    const std::uint8_t* p = &f.color[(static_cast<std::size_t>(uv->y()) * f.width + static_cast<std::size_t>(uv->x())) * 4];
    return 0.114 * p[0] + 0.587 * p[1] + 0.299 * p[2];
  };
  const auto before = r.RenderFrames({cam}, w)[0];
  w.actors[0].pose.position.x() += 10;
  const auto after = r.RenderFrames({cam}, w)[0];
  // The truck's shadow left x = 15 for x = 25: that road got darker, this one lighter.
  EXPECT_GT(road_luma(after, 15), road_luma(before, 15) + 10);
  EXPECT_LT(road_luma(after, 25) + 10, road_luma(before, 25));
}

}  // namespace
}  // namespace lockstep::render
