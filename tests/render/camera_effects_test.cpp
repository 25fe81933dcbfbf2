// CARLA's camera effects: motion blur from per-pixel motion, manual exposure (shutter,
// ISO, f-stop) and histogram auto exposure adapting over frames.
#include <gtest/gtest.h>

#include <cmath>

#include "lockstep/render/camera_config.h"
#include "lockstep/render/exposure.h"
#include "lockstep/render/weather.h"
#include "render_fixture.h"

namespace lockstep::render {
namespace {

using namespace testing;

// Sum of absolute differences between neighbours along x (horizontal) or y (vertical)
// over the pixels labelled `instance`.
double Gradient(const CameraFrame& f, std::uint32_t instance, bool along_x) {
  double s = 0;
  for (int v = 1; v < f.height - 1; ++v) {
    for (int u = 1; u < f.width - 1; ++u) {
      if (f.Instance(u, v) != instance) continue;
      const std::size_t a = (static_cast<std::size_t>(v) * f.width + u) * 4;
      const std::size_t b = along_x ? a + 4 : a + static_cast<std::size_t>(f.width) * 4;
      for (int c = 0; c < 3; ++c) s += std::abs(int(f.color[a + c]) - int(f.color[b + c]));
    }
  }
  return s;
}

// A still camera looks across the road at a car that moved 1.5 m since its previous
// image, along the road (x) or upwards (z).
CameraFrame CarShot(double blur, bool along_x, double min_size = 0.0, std::uint32_t extra = 0) {
  Renderer& r = SharedRenderer();
  WorldView w;
  w.weather = WeatherPreset("ClearNoon");
  w.actors.push_back(Vehicle(r, 30, At(10, 0, 0.75)));
  w.actors.back().previous_pose = w.actors.back().pose;
  (along_x ? w.actors.back().previous_pose->position.x() : w.actors.back().previous_pose->position.z()) -= 1.5;
  Camera cam = Cam(160, 120, 90, At(10, -10, 1.5, 90, 0), kOutColor | kOutLabels | extra);
  cam.previous_pose = cam.pose;
  cam.motion_blur_intensity = blur;
  cam.motion_blur_max_distortion = 20;  // % of the width: 32 px
  cam.motion_blur_min_object_screen_size = min_size;
  return r.RenderFrames({cam}, w)[0];
}

TEST(MotionBlur, AMovingCarSmearsAlongItsMotionWithBlurOnAndNotOff) {
  const CameraFrame sharp_x = CarShot(0, true), blurred_x = CarShot(1, true);
  const CameraFrame sharp_z = CarShot(0, false), blurred_z = CarShot(1, false);
  // Labels do not blur; the still background is untouched.
  EXPECT_EQ(sharp_x.labels, blurred_x.labels);
  int background_changed = 0, car_changed = 0;
  for (int v = 0; v < sharp_x.height; ++v) {
    for (int u = 0; u < sharp_x.width; ++u) {
      const std::size_t i = (static_cast<std::size_t>(v) * sharp_x.width + u) * 4;
      const bool differs = std::abs(int(sharp_x.color[i + 1]) - int(blurred_x.color[i + 1])) > 2;
      (sharp_x.Instance(u, v) == 30 ? car_changed : background_changed) += differs;
    }
  }
  EXPECT_EQ(background_changed, 0);
  EXPECT_GT(car_changed, 100);
  // Blur along x takes the car's detail along x, not along y; upward motion the reverse.
  const double hx = Gradient(blurred_x, 30, true) / Gradient(sharp_x, 30, true);
  const double vx = Gradient(blurred_x, 30, false) / Gradient(sharp_x, 30, false);
  const double hz = Gradient(blurred_z, 30, true) / Gradient(sharp_z, 30, true);
  const double vz = Gradient(blurred_z, 30, false) / Gradient(sharp_z, 30, false);
  EXPECT_LT(hx, 0.8 * vx) << "motion along x: horizontal detail " << hx << ", vertical " << vx;
  EXPECT_LT(vz, 0.8 * hz) << "motion along z: vertical detail " << vz << ", horizontal " << hz;
}

TEST(MotionBlur, ObjectsSmallerThanTheMinimumScreenSizeAreNotBlurred) {
  // The car is about a third of the image wide: under a minimum of 0.6 it keeps its edges.
  const CameraFrame sharp = CarShot(0, true), small_rule = CarShot(1, true, 0.6), blurred = CarShot(1, true, 0.1);
  EXPECT_EQ(sharp.color, small_rule.color);
  EXPECT_NE(sharp.color, blurred.color);
}

TEST(MotionBlur, TheFlowOutputIsOnlyGivenWhenAsked) {
  EXPECT_TRUE(CarShot(1, true).flow.empty());
  const CameraFrame with_flow = CarShot(1, true, 0.1, kOutFlow);
  ASSERT_FALSE(with_flow.flow.empty());
  EXPECT_EQ(with_flow.color, CarShot(1, true, 0.1).color);
  // The car moved 1.5 m to the camera's right at 9-11 m: 11-13.3 px (focal 80 px); the
  // still background does not move.
  int car = 0;
  for (int v = 0; v < with_flow.height; ++v) {
    for (int u = 0; u < with_flow.width; ++u) {
      const std::size_t i = static_cast<std::size_t>(v) * with_flow.width + u;
      const float px = with_flow.flow[i * 2] * with_flow.width / 2, py = with_flow.flow[i * 2 + 1] * with_flow.height / 2;
      if (with_flow.Instance(u, v) == 30) {
        ++car;
        EXPECT_NEAR(px, 12.2, 1.3) << u << "," << v;
        EXPECT_NEAR(py, 0.0, 0.3) << u << "," << v;
      } else {
        EXPECT_NEAR(px, 0.0, 1e-3) << u << "," << v;
        EXPECT_NEAR(py, 0.0, 1e-3) << u << "," << v;
      }
    }
  }
  EXPECT_GT(car, 200);
}

TEST(Exposure, ManualExposureFollowsTheExposureFormula) {
  ExposureSettings s;
  s.histogram = false;
  EXPECT_NEAR(ManualEv100(s), std::log2(1.4 * 1.4 * 200), 1e-12);  // CARLA's defaults: 8.61
  const double base = ExposureMultiplier(s, ManualEv100(s));
  EXPECT_NEAR(base, std::exp2(10 - std::log2(392.0)), 1e-12);
  ExposureSettings t = s;
  t.shutter_speed = 400;  // half the exposure time
  EXPECT_NEAR(ExposureMultiplier(t, ManualEv100(t)), base / 2, 1e-12);
  t = s;
  t.iso = 400;
  EXPECT_NEAR(ExposureMultiplier(t, ManualEv100(t)), base * 4, 1e-12);
  t = s;
  t.fstop = 2.8;
  EXPECT_NEAR(ExposureMultiplier(t, ManualEv100(t)), base / 4, 1e-12);
  // Images: the brightness read back from the pixels scales with the multiplier.
  Renderer& r = SharedRenderer();
  WorldView w;
  w.weather = WeatherPreset("CloudyNoon");
  Camera cam = Cam(96, 64, 90, At(0, 0, 2.0, 15, -5), kOutColor);
  cam.exposure = 0.25;
  const CameraFrame a = r.RenderFrames({cam}, w)[0];
  cam.exposure = 0.5;
  const CameraFrame b = r.RenderFrames({cam}, w)[0];
  const double la = MeasureLuminance(a.color.data(), a.width, a.height, 1.0, 2.2);
  const double lb = MeasureLuminance(b.color.data(), b.width, b.height, 1.0, 2.2);
  EXPECT_NEAR(lb / la, 2.0, 0.15);
  EXPECT_GT(MeanLuma(b), MeanLuma(a) + 5);
}

TEST(Exposure, MeasureLuminanceUndoesGammaToneMapAndExposure) {
  const double scene = 0.3, multiplier = 1.7;
  const double shown = std::pow(1 - std::exp(-scene * multiplier), 1 / 2.2);
  const auto byte = static_cast<std::uint8_t>(std::lround(shown * 255));
  std::vector<std::uint8_t> img(64 * 32 * 4, byte);
  EXPECT_NEAR(MeasureLuminance(img.data(), 64, 32, multiplier, 2.2), scene, scene * 0.02);
}

// Histogram exposure over a night: each image is rendered with the exposure adapted from
// the ones before it.
std::vector<double> NightSequence(ExposureSettings s, double dt, int frames, std::vector<double>* lumas) {
  Renderer& r = SharedRenderer();
  WorldView w;
  w.weather = WeatherPreset("ClearNight");
  AutoExposure e(s);
  std::vector<double> evs;
  Camera cam = Cam(96, 64, 90, At(0, 0, 2.0, 15, -5), kOutColor);
  for (int f = 0; f < frames; ++f) {
    cam.exposure = e.Multiplier();
    evs.push_back(e.ev100());
    const CameraFrame img = r.RenderFrames({cam}, w)[0];
    if (lumas) lumas->push_back(MeanLuma(img));
    e.Update(img.color.data(), img.width, img.height, cam.exposure, cam.gamma, f == 0 ? 0.0 : dt);
  }
  return evs;
}

TEST(Exposure, HistogramBrightensADarkSceneOverFramesAtItsSpeed) {
  ExposureSettings s;  // histogram, CARLA's speeds: 3 EV/s up, 1 EV/s down
  s.min_bright = -4;   // below CARLA's 10, so the night can be brightened
  std::vector<double> luma;
  const auto evs = NightSequence(s, 0.5, 8, &luma);
  EXPECT_DOUBLE_EQ(evs[0], 10.0);  // the first image: EV100 10
  EXPECT_DOUBLE_EQ(evs[1], 10.0);  // no time has passed at the first image: no adaptation yet
  for (std::size_t f = 2; f < evs.size(); ++f) {
    EXPECT_LT(evs[f], evs[f - 1]) << "frame " << f << ": the exposure opens up";
    EXPECT_GE(evs[f], evs[f - 1] - 0.5 * 1.0 - 1e-9) << "frame " << f << ": at most exposure_speed_down x dt per image";
  }
  EXPECT_GT(luma.back(), luma.front() + 20) << "the night got brighter";
  // Deterministic: a function of the frame history.
  EXPECT_EQ(NightSequence(s, 0.5, 8, nullptr), evs);
  // With CARLA's range [10, 12] the exposure cannot open beyond EV100 10: the night stays dark.
  const auto carla = NightSequence(ExposureSettings{}, 0.5, 4, nullptr);
  for (double ev : carla) EXPECT_DOUBLE_EQ(ev, 10.0);
  // Manual mode never adapts.
  ExposureSettings m = s;
  m.histogram = false;
  const auto manual = NightSequence(m, 0.5, 3, nullptr);
  EXPECT_EQ(manual[0], manual[2]);
}

TEST(Exposure, BlueprintAttributesParseWithCarlasDefaults) {
  const CameraSettings d = ParseCamera("sensor.camera.rgb", {});
  EXPECT_TRUE(d.exposure.histogram);
  EXPECT_DOUBLE_EQ(d.exposure.min_bright, 10);
  EXPECT_DOUBLE_EQ(d.exposure.max_bright, 12);
  EXPECT_DOUBLE_EQ(d.camera.exposure, 1.0);
  EXPECT_DOUBLE_EQ(d.camera.motion_blur_intensity, 0.45);
  EXPECT_DOUBLE_EQ(d.camera.motion_blur_max_distortion, 0.35);
  EXPECT_DOUBLE_EQ(d.camera.motion_blur_min_object_screen_size, 0.1);
  const CameraSettings m = ParseCamera("sensor.camera.rgb", {{"exposure_mode", "manual"}, {"shutter_speed", "100"}});
  EXPECT_FALSE(m.exposure.histogram);
  EXPECT_NEAR(m.camera.exposure, std::exp2(10 - std::log2(1.96 * 100)), 1e-9);
  try {
    ParseCamera("sensor.camera.rgb", {{"exposure_min_bright", "13"}});
    FAIL() << "min above max accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("exposure_min_bright"), std::string::npos);
  }
  EXPECT_THROW(ParseCamera("sensor.camera.rgb", {{"exposure_mode", "auto"}}), std::invalid_argument);
  EXPECT_THROW(ParseCamera("sensor.camera.rgb", {{"motion_blur_intensity", "2"}}), std::invalid_argument);
}

}  // namespace
}  // namespace lockstep::render
