// Encodings of the outputs, camera blueprints' attributes, DVS events.
#include <gtest/gtest.h>

#include "lockstep/render/camera_config.h"
#include "lockstep/render/dvs.h"
#include "lockstep/render/images.h"
#include "render_fixture.h"

namespace lockstep::render {
namespace {

using namespace testing;

TEST(CameraConfig, DefaultsAreCarlasAndBadValuesNameTheAttribute) {
  const auto rgb = ParseCamera("sensor.camera.rgb", {});
  EXPECT_EQ(rgb.camera.width, 800);
  EXPECT_EQ(rgb.camera.height, 600);
  EXPECT_EQ(rgb.camera.fov_deg, 90);
  EXPECT_EQ(rgb.camera.outputs, kOutColor);
  const auto depth = ParseCamera("sensor.camera.depth", {{"image_size_x", "320"}, {"encoding", "float"}});
  EXPECT_EQ(depth.kind, ImageKind::kDepthFloat);
  EXPECT_EQ(depth.camera.width, 320);
  EXPECT_EQ(ParseCamera("sensor.camera.airsim", {{"image_type", "DepthPerspective"}}).kind, ImageKind::kAirSimDepthPerspective);
  auto message = [](const std::string& bp, const std::map<std::string, std::string>& a) {
    try {
      ParseCamera(bp, a);
    } catch (const std::invalid_argument& e) {
      return std::string(e.what());
    }
    return std::string();
  };
  EXPECT_NE(message("sensor.camera.rgb", {{"fov", "abc"}}).find("fov"), std::string::npos);
  EXPECT_NE(message("sensor.camera.rgb", {{"image_size_x", "0"}}).find("image_size_x"), std::string::npos);
  // Over Image's bound goes as a LargeImage, up to 8K; a DVS camera's events stay within the bound.
  EXPECT_EQ(message("sensor.camera.rgb", {{"image_size_x", "3840"}, {"image_size_y", "2160"}}), "");
  EXPECT_NE(message("sensor.camera.rgb", {{"image_size_x", "7680"}, {"image_size_y", "7680"}}).find("7680x4320"), std::string::npos);
  EXPECT_NE(message("sensor.camera.dvs", {{"image_size_x", "3840"}, {"image_size_y", "2160"}}).find("1920x1080"), std::string::npos);
  EXPECT_NE(message("sensor.camera.airsim", {{"image_type", "Thermal"}}).find("image_type"), std::string::npos);
  EXPECT_NE(message("sensor.camera.rgb", {{"exposure_mode", "auto"}}).find("exposure_mode"), std::string::npos);
  EXPECT_NE(message("sensor.camera.lidar", {}).find("not a camera"), std::string::npos);
  EXPECT_GE(CameraBlueprints().size(), 8u);
}

TEST(Images, AirSimTypesComeFromTheSamePass) {
  Renderer& r = SharedRenderer();
  WorldView w;
  w.actors.push_back(Vehicle(r, 9, At(12, 0, 0.75)));
  Camera cam = Cam(64, 48, 90, At(0, 0, 1.5), kOutColor | kOutDepth | kOutLabels | kOutNormals | kOutFlow);
  r.Render({cam}, w, [&](std::size_t, const CameraImages& im) {
    for (ImageKind k : {ImageKind::kAirSimScene, ImageKind::kAirSimDepthPlanar, ImageKind::kAirSimDepthPerspective,
                        ImageKind::kAirSimDepthVis, ImageKind::kAirSimDisparityNormalized, ImageKind::kAirSimSegmentation,
                        ImageKind::kAirSimSurfaceNormals, ImageKind::kAirSimInfrared, ImageKind::kSemantic, ImageKind::kInstance}) {
      const auto out = EncodeImage(k, cam, im);
      EXPECT_EQ(out.size(), 64u * 48u * BytesPerPixel(k)) << ImageKindName(k);
    }
    const auto planar = EncodeImage(ImageKind::kAirSimDepthPlanar, cam, im);
    const auto persp = EncodeImage(ImageKind::kAirSimDepthPerspective, cam, im);
    const float* p = reinterpret_cast<const float*>(planar.data());
    const float* q = reinterpret_cast<const float*>(persp.data());
    EXPECT_NEAR(q[24 * 64 + 32], p[24 * 64 + 32], 0.01 * p[24 * 64 + 32]) << "centre: the same";
    EXPECT_GT(q[0], p[0] * 1.3) << "corner: longer along the ray";
    const auto inst = EncodeImage(ImageKind::kInstance, cam, im);
    const std::size_t c = (24 * 64 + 32) * 4;
    EXPECT_EQ(inst[c + 2], tag::kCar);  // R = class
    EXPECT_EQ(inst[c + 1], 9);          // G = instance low byte
    EXPECT_EQ(inst[c + 0], 0);          // B = instance high byte
    // Normals: the car's back faces the camera: +z in camera frame -> B (stored first) ~ 255.
    EXPECT_GT(im.normals[c + 0], 200) << "z towards the camera";
    EXPECT_NEAR(im.normals[c + 2], 128, 3) << "x: none";
  });
}

TEST(Images, OpticalFlowFollowsAMovingCamera) {
  Renderer& r = SharedRenderer();
  Camera cam = Cam(64, 48, 90, At(0, 0, 1.5), kOutFlow);
  cam.previous_pose = At(0, 0, 1.5, 2.0);  // the camera turned right by 2 degrees since
  const auto f = r.RenderFrames({cam}, WorldView{})[0];
  const std::size_t c = (24 * 64 + 32) * 2;
  // Turning right moves the scene left in the image: negative x flow.
  EXPECT_LT(f.flow[c], -0.01);
  EXPECT_NEAR(f.flow[c] * 32, -32 * std::tan(2 * M_PI / 180), 0.3) << "in pixels";
}

TEST(Dvs, BrighteningGivesPositiveEventsAtThresholdCrossings) {
  DvsParams p;
  DvsSensor s(p, 2, 1, 42);
  std::vector<std::uint8_t> img = {50, 50, 50, 255, 50, 50, 50, 255};
  EXPECT_TRUE(s.Update(img.data(), 0).empty());
  img[0] = img[1] = img[2] = 200;  // pixel 0 much brighter: log(200/50) = 1.386 -> 4 events of 0.3
  img[4] = img[5] = img[6] = 40;   // pixel 1 slightly darker: log(40/50) = -0.22 -> none
  const auto ev = s.Update(img.data(), 50'000'000);
  ASSERT_EQ(ev.size(), 4u);
  for (const auto& e : ev) {
    EXPECT_EQ(e.x, 0);
    EXPECT_TRUE(e.pol);
    EXPECT_GT(e.t, 0);
    EXPECT_LE(e.t, 50'000'000);
  }
  EXPECT_LT(ev.front().t, ev.back().t);
  EXPECT_EQ(DvsSensor::Pack(ev).size(), 64u);
}

}  // namespace
}  // namespace lockstep::render
