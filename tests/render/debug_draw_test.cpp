// CARLA's world.debug shapes in the colour output: a drawn box changes the pixels where it
// projects and nowhere else, a point is a 100 x size px square of its colour, the scene
// hides what is behind it, labels and depth stay the scene's; and the shapes' life time.
#include <gtest/gtest.h>

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
