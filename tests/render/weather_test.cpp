// Weather and time of day change the colour image as they should; golden images.
#include <gtest/gtest.h>

#include <opencv2/imgcodecs.hpp>

#include "lockstep/render/images.h"
#include "lockstep/render/weather.h"
#include "render_fixture.h"

namespace lockstep::render {
namespace {

using namespace testing;

CameraFrame Shot(const Weather& weather, bool night_lights = false, double car_yaw = 0) {
  Renderer& r = SharedRenderer();
  WorldView w;
  w.weather = weather;
  w.actors.push_back(Vehicle(r, 10, At(20, -2, 0.75, car_yaw)));
  w.actors.back().light_state = night_lights ? light::kPosition | light::kLowBeam : 0u;
  w.actors.push_back(Walker(r, 11, At(15, 5.5, 1.05), 7));
  const Camera cam = Cam(96, 64, 90, At(0, 0, 2.0, 15, -5), kOutColor | kOutLabels);
  return r.RenderFrames({cam}, w)[0];
}

TEST(Weather, NoonIsBrighterThanSunsetAndSunsetBrighterThanNight) {
  const double noon = MeanLuma(Shot(WeatherPreset("ClearNoon")));
  const double sunset = MeanLuma(Shot(WeatherPreset("ClearSunset")));
  const double night = MeanLuma(Shot(WeatherPreset("ClearNight")));
  EXPECT_GT(noon, sunset + 10);
  EXPECT_GT(sunset, night + 10);
}

TEST(Weather, RainAndFogChangeTheImageButNotTheLabels) {
  const auto clear = Shot(WeatherPreset("ClearNoon"));
  Weather rain = WeatherPreset("ClearNoon");
  rain.precipitation = 80;
  rain.cloudiness = 80;
  Weather fog = WeatherPreset("ClearNoon");
  fog.fog_density = 60;
  fog.fog_distance = 0;
  const auto rainy = Shot(rain), foggy = Shot(fog);
  EXPECT_GT(MeanAbsDiff(clear.color, rainy.color), 5.0);
  EXPECT_GT(MeanAbsDiff(clear.color, foggy.color), 5.0);
  EXPECT_EQ(clear.labels, rainy.labels);
  EXPECT_EQ(clear.labels, foggy.labels);
}

TEST(Weather, EveryPresetIsKnownAndPresetsDiffer) {
  const auto names = WeatherPresetNames();
  EXPECT_EQ(names.size(), 22u);
  EXPECT_THROW(WeatherPreset("SunnyDay"), std::invalid_argument);
  const auto a = Shot(WeatherPreset("ClearNoon")), b = Shot(WeatherPreset("HardRainNoon")), c = Shot(WeatherPreset("WetCloudySunset"));
  EXPECT_GT(MeanAbsDiff(a.color, b.color), 5.0);
  EXPECT_GT(MeanAbsDiff(b.color, c.color), 5.0);
}

TEST(Weather, NightHasLitVehicleLights) {
  // The car faces the camera: its headlights and the road they light are in view.
  const auto off = Shot(WeatherPreset("ClearNight"), false, 180);
  const auto on = Shot(WeatherPreset("ClearNight"), true, 180);
  EXPECT_GT(MeanLuma(on), MeanLuma(off) + 1.0) << "headlights light the road ahead";
}

// Golden images: a fixed scene compared with stored PNGs. LOCKSTEP_UPDATE_GOLDEN=1 rewrites them.
void CompareGolden(const std::string& name, const std::vector<std::uint8_t>& bgra, int w, int h) {
  const std::string path = std::string(LOCKSTEP_RENDER_GOLDEN_DIR) + "/" + name + ".png";
  cv::Mat image(h, w, CV_8UC4, const_cast<std::uint8_t*>(bgra.data()));
  if (std::getenv("LOCKSTEP_UPDATE_GOLDEN")) {
    ASSERT_TRUE(cv::imwrite(path, image));
    return;
  }
  const cv::Mat golden = cv::imread(path, cv::IMREAD_UNCHANGED);
  ASSERT_FALSE(golden.empty()) << "no golden image " << path;
  ASSERT_EQ(golden.cols, w);
  ASSERT_EQ(golden.rows, h);
  ASSERT_EQ(golden.channels(), 4);
  double sum = 0;
  std::size_t off = 0;
  for (int i = 0; i < w * h * 4; ++i) {
    const int d = std::abs(int(golden.data[i]) - int(bgra[static_cast<std::size_t>(i)]));
    sum += d;
    off += d > 24;
  }
  EXPECT_LT(sum / (w * h * 4), 2.0) << name << ": mean difference";
  EXPECT_LT(off, static_cast<std::size_t>(w * h * 4 / 100)) << name << ": channels off by more than 24";
}

TEST(Golden, StreetAtNoonAndItsLabels) {
  const auto f = Shot(WeatherPreset("ClearNoon"));
  CompareGolden("street_noon", f.color, f.width, f.height);
  CompareGolden("street_semantic", SemanticToPalette(f.labels.data(), f.width, f.height), f.width, f.height);
}

TEST(Golden, StreetInHardRainAtSunset) {
  const auto f = Shot(WeatherPreset("HardRainSunset"));
  CompareGolden("street_rain_sunset", f.color, f.width, f.height);
}

}  // namespace
}  // namespace lockstep::render
