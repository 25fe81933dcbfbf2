// CARLA's world.debug shapes in the colour output: a drawn box changes the pixels where it
// projects and nowhere else, a point is a 100 x size px square of its colour, the scene
// hides what is behind it, labels and depth stay the scene's; and the shapes' life time.
#include <gtest/gtest.h>

#include "lockstep/render/camera_config.h"
#include "lockstep/render/debug_draw.h"
#include "render_fixture.h"

namespace lockstep::render {
namespace {

using namespace testing;

// Looking along +x over the road from 2 m up, level.
Camera Eye(std::uint32_t outputs = kOutColor | kOutLabels | kOutDepth) { return Cam(160, 120, 90, At(0, 0, 2.0), outputs); }

WorldView Noon() {
  WorldView w;
  w.weather.sun_altitude_angle = 60;
  return w;
}

std::array<int, 3> Rgb(const CameraFrame& f, int u, int v) {
  const std::uint8_t* p = &f.color[(static_cast<std::size_t>(v) * f.width + u) * 4];
  return {p[2], p[1], p[0]};
}

TEST(DebugDraw, ABoxChangesThePixelsOfItsEdgesOnly) {
  Renderer& r = SharedRenderer();
  const Camera cam = Eye();
  WorldView w = Noon();
  const CameraFrame before = r.RenderFrames({cam}, w)[0];
  // A 2 m cube 20 m ahead, on the road, green edges 0.1 m thick.
  const Pose box = At(20, 0, 1.0);
  w.debug.AddBox(box, Vec3(1, 1, 1), 0.1, {0, 255, 0});
  ASSERT_EQ(w.debug.lines.size(), 12u);
  const CameraFrame after = r.RenderFrames({cam}, w)[0];
  // Where its edges project, the image is the box's green; far from the box, unchanged.
  int green = 0, changed_far = 0;
  double depth = 0;
  const auto top_left = Project(cam, box.Apply(Vec3(-1, 1, 1)), &depth);
  const auto bottom_right = Project(cam, box.Apply(Vec3(-1, -1, -1)), &depth);
  ASSERT_TRUE(top_left && bottom_right);
  for (int v = 0; v < cam.height; ++v) {
    for (int u = 0; u < cam.width; ++u) {
      const auto a = Rgb(before, u, v), b = Rgb(after, u, v);
      const bool near_box = u >= top_left->x() - 6 && u <= bottom_right->x() + 6 && v >= top_left->y() - 6 && v <= bottom_right->y() + 6;
      if (!near_box && a != b) ++changed_far;
      if (near_box && b == std::array<int, 3>{0, 255, 0} && a != b) ++green;
    }
  }
  EXPECT_GT(green, 40) << "the box's edges are drawn in its colour";
  EXPECT_EQ(changed_far, 0) << "nothing changes away from the box";
  // The front top edge, in the middle (about 0.4 px thick there: drawn one pixel wide): green.
  const auto mid_top = Project(cam, box.Apply(Vec3(-1, 0, 1)));
  ASSERT_TRUE(mid_top);
  bool edge = false;
  for (int dv = -1; dv <= 1; ++dv) {
    edge |= Rgb(after, static_cast<int>(mid_top->x()), static_cast<int>(mid_top->y()) + dv) == std::array<int, 3>{0, 255, 0};
  }
  EXPECT_TRUE(edge);
  EXPECT_EQ(before.labels, after.labels) << "shapes are not in the segmentation";
  EXPECT_EQ(before.depth, after.depth) << "nor in the depth";
}

TEST(DebugDraw, APointIsASquareOfAHundredTimesItsSizeInPixelsAndTheSceneHidesWhatIsBehindIt) {
  Renderer& r = SharedRenderer();
  const Camera cam = Eye(kOutColor);
  WorldView w = Noon();
  // 0.1 -> 10 px, wherever it is (CARLA's point size is in screen pixels).
  const Vec3 near_point(15, 0, 2.0), far_point(60, -20, 2.0);
  w.debug.points.push_back({near_point, 0.1, {255, 0, 255}});
  w.debug.points.push_back({far_point, 0.1, {255, 0, 255}});
  // Behind the building (x 40..80 from y 14 on): hidden.
  const Vec3 hidden(60, 20, 3.0);
  w.debug.points.push_back({hidden, 0.1, {255, 0, 255}});
  const CameraFrame f = r.RenderFrames({cam}, w)[0];
  for (const Vec3& p : {near_point, far_point}) {
    const auto px = Project(cam, p);
    ASSERT_TRUE(px);
    int magenta_cols = 0;
    const int v = static_cast<int>(px->y());
    for (int u = static_cast<int>(px->x()) - 12; u <= static_cast<int>(px->x()) + 12; ++u) {
      magenta_cols += Rgb(f, u, v) == std::array<int, 3>{255, 0, 255};
    }
    EXPECT_EQ(magenta_cols, 10) << "at " << p.transpose();
  }
  const auto h = Project(cam, hidden);
  ASSERT_TRUE(h);
  EXPECT_NE(Rgb(f, static_cast<int>(h->x()), static_cast<int>(h->y())), (std::array<int, 3>{255, 0, 255}));
}

TEST(DebugDraw, AnArrowIsItsLineAndFourStrokesToTheTip) {
  DebugDrawList l;
  l.AddArrow(Vec3(0, 0, 0), Vec3(10, 0, 0), 0.1, 0.5, {255, 0, 0});
  ASSERT_EQ(l.lines.size(), 5u);
  for (std::size_t i = 1; i < 5; ++i) {
    EXPECT_EQ(l.lines[i].end, Vec3(10, 0, 0));
    EXPECT_NEAR(l.lines[i].begin.x(), 9.5, 1e-12);
    EXPECT_NEAR(std::abs(l.lines[i].begin.y()), 0.5, 1e-12);
    EXPECT_NEAR(std::abs(l.lines[i].begin.z()), 0.5, 1e-12);
  }
}

// CARLA's persistent line batcher: a shape drawn between frames k-1 and k (sim time t) shows
// from frame k while the frame's time is before t + life_time; life_time <= 0 keeps it.
TEST(DebugDraw, ShapesLiveForTheirLifeTimeInSimulationSeconds) {
  const double dt = 0.05;
  DebugShapes s;
  DebugLine line;
  // Issued at t = 1.0 (frame 20), carried by the tick of frame 21.
  s.AddLine(line, 21, 1.0, 0.06);   // manual_control's radar points: one frame
  s.AddLine(line, 21, 1.0, 1.0);    // the agents' arrows: 19 frames
  s.AddLine(line, 21, 1.0, -1.0);   // CARLA's default: until the world is reloaded
  s.AddLine(line, 21, 1.0, dt);     // a life of one step ends before the frame is drawn
  EXPECT_EQ(s.Visible(20, 20 * dt).lines.size(), 0u) << "not before the frame of its tick";
  EXPECT_EQ(s.Visible(21, 21 * dt).lines.size(), 3u);
  EXPECT_EQ(s.Visible(22, 22 * dt).lines.size(), 2u);
  EXPECT_EQ(s.Visible(39, 39 * dt).lines.size(), 2u);
  EXPECT_EQ(s.Visible(40, 40 * dt).lines.size(), 1u);
  EXPECT_EQ(s.Visible(10000, 10000 * dt).lines.size(), 1u);
  EXPECT_EQ(s.size(), 1u) << "ended shapes are forgotten";
  s.Clear();
  EXPECT_EQ(s.Visible(10001, 10001 * dt).lines.size(), 0u);
}

}  // namespace
}  // namespace lockstep::render

namespace lockstep::render {
namespace {

using namespace testing;

// CARLA 0.9.16's sensor.camera.cosmos_visualization: no scene, only the lines on black.
TEST(CosmosVisualization, ShowsOnlyItsLinesOnBlack) {
  const CameraSettings s = ParseCamera("sensor.camera.cosmos_visualization", {{"image_size_x", "160"}, {"image_size_y", "120"}});
  ASSERT_TRUE(s.camera.lines_only);
  EXPECT_TRUE(IsCameraBlueprint("sensor.camera.cosmos_visualization"));
  Renderer& r = SharedRenderer();
  Camera cam = s.camera;
  cam.pose = At(0, 0, 2.0);
  WorldView w;
  w.weather.sun_altitude_angle = 60;
  w.actors.push_back(Vehicle(r, 10, At(20, 0, 0.75)));  // the scene: not drawn
  const CameraFrame empty = r.RenderFrames({cam}, w)[0];
  for (std::size_t i = 0; i < empty.color.size(); i += 4) {
    ASSERT_EQ(empty.color[i] | empty.color[i + 1] | empty.color[i + 2], 0) << "black without lines";
  }
  w.cosmos.AddBox(At(20, 0, 0.75), Vec3(2.3, 1.0, 0.75), 0.1, {255, 0, 0});
  w.debug.points.push_back({Vec3(15, 3, 2), 0.1, {0, 0, 255}});
  const CameraFrame f = r.RenderFrames({cam}, w)[0];
  int red = 0, blue = 0, other = 0;
  for (std::size_t i = 0; i < f.color.size(); i += 4) {
    const int b = f.color[i], g = f.color[i + 1], rr = f.color[i + 2];
    if (rr == 255 && g == 0 && b == 0) ++red;
    else if (b == 255 && g == 0 && rr == 0) ++blue;
    else if (b | g | rr) ++other;
  }
  EXPECT_GT(red, 40) << "the box's edges";
  EXPECT_EQ(blue, 100) << "the world's debug point, 10 x 10 px";
  EXPECT_EQ(other, 0) << "nothing of the scene";
}

}  // namespace
}  // namespace lockstep::render
