// CARLA's lens distortion attributes (undistorted by default; once lens_circle_multiplier
// is set, lens_k < 0 stretches the edges outwards, lens_k > 0 draws them in) and the
// shadows of drone rotors.
#include <gtest/gtest.h>

#include "lockstep/render/camera_config.h"
#include "lockstep/render/weather.h"
#include "render_fixture.h"

namespace lockstep::render {
namespace {

using namespace testing;

// Mean column distance of the car's pixels from the image centre, and their count.
std::pair<double, int> CarSpread(const CameraFrame& f) {
  double sum = 0;
  int n = 0;
  for (int v = 0; v < f.height; ++v) {
    for (int u = 0; u < f.width; ++u) {
      if (f.Tag(u, v) != tag::kCar) continue;
      sum += std::abs(u + 0.5 - f.width / 2.0);
      ++n;
    }
  }
  return {n ? sum / n : 0, n};
}

TEST(Lens, CarlasDefaultsAreUndistortedAndKBendsTheEdges) {
  const auto settings = ParseCamera("sensor.camera.rgb", {});
  EXPECT_EQ(settings.camera.lens_k, -1.0);
  EXPECT_EQ(settings.camera.lens_kcube, 0.0);
  EXPECT_EQ(settings.camera.lens_x_size, 0.08);
  EXPECT_EQ(settings.camera.lens_y_size, 0.08);
  EXPECT_FALSE(settings.camera.HasLensDistortion()) << "CARLA's defaults give undistorted images";

  Renderer& r = SharedRenderer();
  WorldView w;
  w.actors.push_back(Vehicle(r, 30, At(12, 6, 0.75)));  // near the right edge of the image
  Camera cam = Cam(160, 120, 90, At(0, 0, 1.5, 0, 0), kOutLabels | kOutDepth | kOutColor);
  const auto plain = r.RenderFrames({cam}, w)[0];
  cam.lens_circle_multiplier = 2;
  cam.lens_x_size = cam.lens_y_size = 0.5;
  ASSERT_TRUE(cam.HasLensDistortion());
  const auto stretched = r.RenderFrames({cam}, w)[0];
  const auto [plain_spread, plain_n] = CarSpread(plain);
  const auto [stretched_spread, stretched_n] = CarSpread(stretched);
  ASSERT_GT(plain_n, 20);
  EXPECT_GT(stretched_spread, plain_spread + 3) << "lens_k < 0 pushes what is near the edges outwards";
  EXPECT_GT(stretched_n, plain_n) << "and enlarges it";
  // The centre does not move; the source of a pixel follows DistortedSource.
  EXPECT_EQ(stretched.Tag(80, 60), plain.Tag(80, 60));
  EXPECT_FLOAT_EQ(stretched.Depth(80, 60), plain.Depth(80, 60));
  const Eigen::Vector2d s = DistortedSource(cam, 150.5, 100.5);
  EXPECT_LT(s.x(), 150.5);
  EXPECT_LT(s.y(), 100.5);
  EXPECT_EQ(stretched.Tag(150, 100), plain.Tag(static_cast<int>(s.x()), static_cast<int>(s.y())));
  // lens_k > 0 draws the edges in (barrel): the corners read beyond the image and are zero.
  cam.lens_k = 2;
  const auto barrel = r.RenderFrames({cam}, w)[0];
  EXPECT_LT(CarSpread(barrel).first, plain_spread - 3);
  EXPECT_EQ(barrel.Tag(0, 0), 0);
  EXPECT_EQ(barrel.Depth(0, 0), 0.0f);
}

TEST(Lens, BadLensAttributesNameTheAttribute) {
  try {
    ParseCamera("sensor.camera.rgb", {{"lens_x_size", "2"}});
    FAIL() << "lens_x_size 2 is out of CARLA's range [0, 1]";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("lens_x_size"), std::string::npos) << e.what();
  }
}

TEST(Rotors, BladesCastShadowsThatTurnWithThem) {
  Renderer& r = SharedRenderer();
  WorldView w;
  w.weather = WeatherPreset("ClearNoon");
  w.weather.sun_altitude_angle = 85;  // the shadow right under the drone
  ActorDraw drone = Drone(r, 40, At(10, 0, 1.2));
  w.actors.push_back(drone);
  // Looking down at the road beside the drone, from the side and above.
  const Camera cam = Cam(160, 120, 60, At(10, -6, 5, 90, -45), kOutColor | kOutLabels);
  const auto a = r.RenderFrames({cam}, w)[0];
  for (double& angle : w.actors[0].rotor_angles) angle += 0.6;
  const auto b = r.RenderFrames({cam}, w)[0];
  int road_changed = 0;
  for (int v = 0; v < a.height; ++v) {
    for (int u = 0; u < a.width; ++u) {
      if (a.Tag(u, v) != tag::kRoads || b.Tag(u, v) != tag::kRoads) continue;  // not the drone itself
      const std::size_t i = (static_cast<std::size_t>(v) * a.width + u) * 4;
      road_changed += std::abs(int(a.color[i + 1]) - int(b.color[i + 1])) > 8;
    }
  }
  EXPECT_GT(road_changed, 5) << "the blades' shadows on the road moved with the blades";
}

}  // namespace
}  // namespace lockstep::render
