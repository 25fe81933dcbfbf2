// AirSim's simFlushPersistentMarkers through the render service's DebugDraw handling
// (AddDebugDraw): Unreal's FlushPersistentDebugLines empties the persistent line batcher,
// which holds both the persistent shapes and the timed ones, before the batch's own shapes
// are drawn; what is drawn after the flush stays.
#include <gtest/gtest.h>

#include "lockstep/render/debug_draw.h"
#include "render_fixture.h"
#include "render_service.h"

namespace lockstep {
namespace {

using namespace render::testing;
using Rgb = std::array<int, 3>;

constexpr double kDt = 0.05;

msg::DebugShape Point(double x, double y, double z, Rgb c, double life_time) {
  msg::DebugShape s;
  s.kind(msg::DebugShapeKind::DEBUG_POINT);
  s.begin().x(x);
  s.begin().y(y);
  s.begin().z(z);
  s.size(0.1);  // 10 px
  s.r(static_cast<std::uint8_t>(c[0]));
  s.g(static_cast<std::uint8_t>(c[1]));
  s.b(static_cast<std::uint8_t>(c[2]));
  s.a(255);
  s.life_time(life_time);
  return s;
}

msg::DebugShape Line(double x, double y0, double y1, double z, Rgb c, double life_time) {
  msg::DebugShape s = Point(x, y0, z, c, life_time);
  s.kind(msg::DebugShapeKind::DEBUG_LINE);
  s.end().x(x);
  s.end().y(y1);
  s.end().z(z);
  return s;
}

msg::DebugDraw Draw(std::vector<msg::DebugShape> shapes, bool flush = false) {
  msg::DebugDraw d;
  d.shapes(std::move(shapes));
  d.flush_persistent(flush);
  return d;
}

const Rgb kRed{255, 0, 0}, kGreen{0, 255, 0}, kBlue{0, 0, 255}, kYellow{255, 255, 0}, kMagenta{255, 0, 255};

// Pixels of exactly colour c in the frame the shapes of `debug` show at `frame`.
class DebugFlush : public ::testing::Test {
 protected:
  std::map<Rgb, int> Count(std::uint64_t frame) {
    render::Renderer& r = SharedRenderer();
    const render::Camera cam = Cam(160, 120, 90, At(0, 0, 2.0), render::kOutColor);
    render::WorldView w;
    w.weather.sun_altitude_angle = 60;
    w.debug = debug.Visible(frame, static_cast<double>(frame) * kDt);
    const render::CameraFrame f = r.RenderFrames({cam}, w)[0];
    std::map<Rgb, int> n;
    for (std::size_t i = 0; i + 3 < f.color.size(); i += 4) {
      const Rgb px{f.color[i + 2], f.color[i + 1], f.color[i]};
      for (const Rgb& c : {kRed, kGreen, kBlue, kYellow, kMagenta}) n[c] += px == c;
    }
    return n;
  }
  // The commands of the tick of `frame`, in their order (issued at the frame before).
  void Tick(std::uint64_t frame, const std::vector<msg::DebugDraw>& commands) {
    for (const auto& d : commands) AddDebugDraw(debug, d, frame, static_cast<double>(frame - 1) * kDt);
  }
  render::DebugShapes debug;
};

TEST_F(DebugFlush, AFlushErasesThePersistentAndTimedShapesAndKeepsWhatIsDrawnAfterIt) {
  // Frame 21: a persistent point (life <= 0) and line (AirSim's is_persistent), a point timed for 100 s.
  Tick(21, {Draw({Point(15, 3, 2, kRed, 0.0), Line(20, -6, 6, 4.0, kMagenta, -1.0), Point(15, -3, 2, kGreen, 100.0)})});
  auto n = Count(21);
  ASSERT_GE(n[kRed], 80) << "a 10 px point";
  ASSERT_GE(n[kGreen], 80);
  ASSERT_GT(n[kMagenta], 10);
  EXPECT_EQ(n[kBlue], 0);
  n = Count(22);
  ASSERT_GE(n[kRed], 80) << "they last";
  ASSERT_GE(n[kGreen], 80);
  // Frame 23: simFlushPersistentMarkers, then a new persistent point drawn after it in the same tick.
  Tick(23, {Draw({}, true), Draw({Point(15, 0, 2, kBlue, 0.0)})});
  n = Count(23);
  EXPECT_EQ(n[kRed], 0) << "the persistent point is flushed";
  EXPECT_EQ(n[kMagenta], 0) << "the persistent line is flushed";
  EXPECT_EQ(n[kGreen], 0) << "a timed shape is in Unreal's persistent line batcher too";
  EXPECT_GE(n[kBlue], 80) << "a shape drawn after the flush stays";
  // A flush carrying shapes draws them after erasing; a shape drawn earlier in the same tick is erased.
  Tick(24, {Draw({Point(15, 3, 2, kRed, 0.0)}), Draw({Point(15, -3, 2, kYellow, 10.0)}, true)});
  n = Count(24);
  EXPECT_EQ(n[kRed], 0);
  EXPECT_EQ(n[kBlue], 0);
  EXPECT_GE(n[kYellow], 80);
  // Without the flag nothing is erased.
  Tick(25, {Draw({Point(15, 3, 2, kRed, 0.0)})});
  n = Count(25);
  EXPECT_GE(n[kRed], 80);
  EXPECT_GE(n[kYellow], 80);
}

}  // namespace
}  // namespace lockstep
