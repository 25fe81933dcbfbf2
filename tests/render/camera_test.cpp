// Camera geometry as CARLA's: depth of a plane, pinhole projection, encodings.
#include <gtest/gtest.h>

#include <set>

#include "lockstep/render/camera.h"
#include "lockstep/render/images.h"
#include "render_fixture.h"

namespace lockstep::render {
namespace {

using namespace testing;

TEST(CarlaDepth, EncodesAndDecodesWithinAMillimetre) {
  for (float d : {0.1f, 1.0f, 12.345f, 99.9f, 512.25f, 999.0f}) {
    std::uint8_t px[4];
    EncodeCarlaDepth(d, px);
    EXPECT_NEAR(DecodeCarlaDepth(px), d, 1e-3) << d;
  }
  std::uint8_t px[4];
  EncodeCarlaDepth(1000.0f * 65536.0f / (256.0f * 256.0f * 256.0f - 1.0f), px);  // exactly B = 1
  EXPECT_EQ(px[0], 1);
  EXPECT_EQ(px[1], 0);
  EXPECT_EQ(px[2], 0);
}

TEST(CameraDepth, PlaneAtAKnownDistanceDecodesWithinOneCentimetre) {
  Renderer& r = SharedRenderer();
  // The building's front face is the plane y = 9; a camera on the road looking along +y.
  const double distance = 9.0 - 1.234;
  Camera cam = Cam(64, 48, 60, At(40, 1.234, 6, 90), kOutDepth);
  auto frames = r.RenderFrames({cam}, WorldView{});
  CameraImages im;
  im.width = 64;
  im.height = 48;
  im.depth = frames[0].depth.data();
  const auto carla = EncodeImage(ImageKind::kDepth, cam, im);
  for (int v = 0; v < 48; ++v) {
    for (int u = 0; u < 64; ++u) {
      const std::size_t i = static_cast<std::size_t>(v) * 64 + u;
      ASSERT_NEAR(DecodeCarlaDepth(&carla[i * 4]), distance, 0.01) << "pixel " << u << "," << v;
      ASSERT_NEAR(frames[0].depth[i], distance, 0.01);
    }
  }
}

TEST(CameraProjection, AKnownWorldPointProjectsToThePinholePixelWithinOnePixel) {
  Renderer& r = SharedRenderer();
  if (!r.HasModel("marker")) {
    Model m;
    map::Mesh cube;
    map::AddBox(cube, Vec3(0, 0, -0.15), 0.3, 0.3, 0.3, 0, true);
    AppendMesh(&m.vertices, cube, {255, 0, 0}, kMatPlain, tag::kStatic);
    m.half_extents = Vec3(0.15, 0.15, 0.15);
    r.AddModel("marker", m);
  }
  for (const auto& [cam_pose, point] : std::vector<std::pair<Pose, Vec3>>{
           {At(0, 0, 1.5, 0, 0), Vec3(20, 3, 1.5)},
           {At(0, 0, 1.5, 12, -6), Vec3(25, 7, 0.6)},
           {At(3, -2, 8, -20, -25), Vec3(22, -9, 1.0)}}) {
    WorldView w;
    ActorDraw a;
    a.id = 77;
    a.model = "marker";
    a.pose.position = point;
    w.actors.push_back(a);
    Camera cam = Cam(320, 240, 90, cam_pose, kOutLabels);
    auto f = r.RenderFrames({cam}, w)[0];
    double su = 0, sv = 0;
    int n = 0;
    for (int v = 0; v < 240; ++v) {
      for (int u = 0; u < 320; ++u) {
        if (f.Instance(u, v) == 77) {
          su += u + 0.5;
          sv += v + 0.5;
          ++n;
        }
      }
    }
    std::set<std::uint32_t> seen;
    for (int v = 0; v < 240; ++v) {
      for (int u = 0; u < 320; ++u) seen.insert(f.Instance(u, v));
    }
    std::string ids;
    for (auto id : seen) ids += std::to_string(id) + " ";
    ASSERT_GT(n, 0) << "marker not visible; ids: " << ids;
    const auto expected = Project(cam, point);
    ASSERT_TRUE(expected);
    EXPECT_NEAR(su / n, expected->x(), 1.0);
    EXPECT_NEAR(sv / n, expected->y(), 1.0);
  }
}

TEST(CameraProjection, IntrinsicsAreCarlas) {
  Camera c;
  c.width = 800;
  c.height = 600;
  c.fov_deg = 90;
  const auto k = Intrinsics(c);
  EXPECT_DOUBLE_EQ(k(0, 0), 400.0);  // w / (2 tan(fov / 2))
  EXPECT_DOUBLE_EQ(k(0, 2), 400.0);
  EXPECT_DOUBLE_EQ(k(1, 2), 300.0);
  const auto p = Project(c, Vec3(10, 0, 0));
  ASSERT_TRUE(p);
  EXPECT_DOUBLE_EQ(p->x(), 400.0);
  EXPECT_DOUBLE_EQ(p->y(), 300.0);
  EXPECT_FALSE(Project(c, Vec3(-1, 0, 0)));
  // A point to the left (body +y) and up projects left of and above the centre.
  const auto q = Project(c, Vec3(10, 1, 1));
  EXPECT_LT(q->x(), 400.0);
  EXPECT_LT(q->y(), 300.0);
}

TEST(Palette, MatchesCarlaAndThePaperMapping) {
  EXPECT_EQ(PaletteRgb(tag::kRoads), (std::array<std::uint8_t, 3>{128, 64, 128}));
  EXPECT_EQ(PaletteRgb(tag::kCar), (std::array<std::uint8_t, 3>{0, 0, 142}));
  EXPECT_EQ(PaletteRgb(28), (std::array<std::uint8_t, 3>{180, 165, 180}));
  EXPECT_EQ(ClassFromName("pedestrian"), tag::kPedestrian);
  EXPECT_EQ(ClassFromName("nope"), -1);
  EXPECT_EQ(ToPaperClass(tag::kRoads), 7);
  EXPECT_EQ(ToPaperClass(tag::kCar), 10);
  EXPECT_EQ(ToPaperClass(tag::kTruck), 10);
  EXPECT_EQ(ToPaperClass(tag::kPedestrian), 4);
  EXPECT_EQ(ToPaperClass(tag::kSky), 0);
}

}  // namespace
}  // namespace lockstep::render
