// CARLA 0.9.16's sensor.camera.rgb.wide_angle_lens: the scene through a lens model (a
// cube map of six faces resampled along each pixel's ray), not a pinhole image.
#include <gtest/gtest.h>

#include <cmath>

#include "lockstep/render/camera_config.h"
#include "lockstep/render/wide_angle_cube.h"
#include "render_fixture.h"

namespace lockstep::render {
namespace {

using namespace testing;

constexpr const char* kWide = "sensor.camera.rgb.wide_angle_lens";

// Centroid of the pixels labelled `tag` (offset from the image centre) and their count.
std::pair<Eigen::Vector2d, int> Centroid(const CameraFrame& f, std::uint8_t t) {
  Eigen::Vector2d sum = Eigen::Vector2d::Zero();
  int n = 0;
  for (int v = 0; v < f.height; ++v) {
    for (int u = 0; u < f.width; ++u) {
      if (f.Tag(u, v) != t) continue;
      sum += Eigen::Vector2d(u + 0.5 - f.width / 2.0, v + 0.5 - f.height / 2.0);
      ++n;
    }
  }
  return {n ? Eigen::Vector2d(sum / n) : sum, n};
}

Camera WideCam(const std::map<std::string, std::string>& attrs, int w, int h) {
  auto a = attrs;
  a["image_size_x"] = std::to_string(w);
  a["image_size_y"] = std::to_string(h);
  Camera c = ParseCamera(kWide, a).camera;
  c.pose = At(0, 0, 1.5);
  c.outputs = kOutColor | kOutLabels;
  return c;
}

TEST(WideAngleLens, ModelFunctionsAreCarlas) {
  const std::array<double, 4> k = {0.1, 0.02, 0.003, 0.0004};
  for (LensModel m : {LensModel::kPerspective, LensModel::kStereographic, LensModel::kEquidistant, LensModel::kEquisolid,
                      LensModel::kOrthographic, LensModel::kKannalaBrandt}) {
    for (double t : {0.1, 0.5, 1.0, 1.3}) EXPECT_NEAR(LensAngle(m, LensRadius(m, t, k), k), t, 1e-9);
  }
  EXPECT_DOUBLE_EQ(LensRadius(LensModel::kEquidistant, 0.7, k), 0.7);
  EXPECT_DOUBLE_EQ(LensRadius(LensModel::kStereographic, 0.7, k), 2 * std::tan(0.35));
  EXPECT_DOUBLE_EQ(LensRadius(LensModel::kEquisolid, 0.7, k), 2 * std::sin(0.35));
  EXPECT_DOUBLE_EQ(LensRadius(LensModel::kKannalaBrandt, 0.5, k), 0.5 * (1 + 0.1 * 0.25 + 0.02 * 0.0625 + 0.003 * std::pow(0.5, 6) + 0.0004 * std::pow(0.5, 8)));
  // CARLA's ComputeDistance: the vertical fov spans the height.
  EXPECT_DOUBLE_EQ(LensFocal(LensModel::kEquidistant, M_PI, 200, k), 100 / (M_PI / 2));
  EXPECT_DOUBLE_EQ(LensFocal(LensModel::kPerspective, M_PI / 2, 200, k), 100);
}

TEST(WideAngleLens, BlueprintHasCarlasAttributesAndRejectsBadOnes) {
  const auto s = ParseCamera(kWide, {});
  EXPECT_TRUE(s.camera.wide_angle.enabled);
  EXPECT_EQ(s.camera.wide_angle.model, LensModel::kPerspective);
  EXPECT_EQ(s.camera.fov_deg, 90);
  EXPECT_NEAR(s.camera.wide_angle.k[0], 0.08309221636708493, 1e-12);
  EXPECT_FALSE(ParseCamera("sensor.camera.rgb", {}).camera.wide_angle.enabled);
  EXPECT_EQ(ParseCamera(kWide, {{"fov", "220"}, {"camera_model", "equidistant"}}).camera.fov_deg, 220);
  EXPECT_EQ(s.camera.wide_angle.focal_length, 0);
  EXPECT_NEAR(WideAngleFocal(s.camera.wide_angle, 600, 90), 300, 1e-9);
  EXPECT_EQ(WideAngleFocal(ParseCamera(kWide, {{"focal_length", "123"}}).camera.wide_angle, 600, 90), 123);
  EXPECT_THROW(ParseCamera(kWide, {{"camera_model", "fisheye"}}), std::invalid_argument);
  EXPECT_THROW(ParseCamera(kWide, {{"k2", "abc"}}), std::invalid_argument);
}

// A car at angle theta from the optical axis lands at radius f theta in an equidistant
// image (and at 2 f tan(theta / 2) in a stereographic one): not where a pinhole puts it.
TEST(WideAngleLens, EquidistantPutsAPointAtAngleThetaAtRadiusFTheta) {
  Renderer& r = SharedRenderer();
  WorldView w;
  const Vec3 car(10, 17.32, 0.75);  // 60 degrees to the left of the camera's axis
  w.actors.push_back(Vehicle(r, 30, At(car.x(), car.y(), car.z(), 90)));
  const Vec3 d = (car - Vec3(0, 0, 1.5)).normalized();
  const double theta = std::acos(d.x());
  // Image direction of the car: left (-u) and a little down (+v).
  const Eigen::Vector2d dir = Eigen::Vector2d(-d.y(), -d.z()).normalized();
  for (const char* model : {"equidistant", "stereographic"}) {
    SCOPED_TRACE(model);
    const Camera cam = WideCam({{"camera_model", model}, {"fov", "180"}}, 201, 201);
    const auto frame = r.RenderFrames({cam}, w)[0];
    const auto [c, n] = Centroid(frame, tag::kCar);
    ASSERT_GT(n, 30);
    const LensModel m = std::string(model) == "equidistant" ? LensModel::kEquidistant : LensModel::kStereographic;
    const double f = LensFocal(m, M_PI, 201, {});
    EXPECT_NEAR(c.norm(), f * LensRadius(m, theta, {}), 2.5);
    EXPECT_GT(c.normalized().dot(dir), 0.995);
  }
  // A pinhole (the perspective flag re-projects to one) of 90 degrees does not see it.
  const auto pinhole = r.RenderFrames({WideCam({{"camera_model", "equidistant"}, {"fov", "90"}, {"perspective", "true"}}, 201, 201)}, w)[0];
  EXPECT_EQ(Centroid(pinhole, tag::kCar).second, 0);
}

// The depth, segmentation and normals wide-angle blueprints (manual_control_fisheye.py
// lists them) see through the same lens: labels agree with the colour camera's, depth of the
// road ahead is finite.
TEST(WideAngleLens, OtherKindsSeeThroughTheSameLens) {
  for (const char* bp : {"sensor.camera.depth.wide_angle_lens", "sensor.camera.semantic_segmentation.wide_angle_lens",
                         "sensor.camera.instance_segmentation.wide_angle_lens", "sensor.camera.normals.wide_angle_lens"}) {
    EXPECT_TRUE(IsCameraBlueprint(bp)) << bp;
    EXPECT_TRUE(ParseCamera(bp, {{"camera_model", "equisolid"}}).camera.wide_angle.enabled) << bp;
  }
  Renderer& r = SharedRenderer();
  WorldView w;
  const Vec3 car(10, 17.32, 0.75);
  w.actors.push_back(Vehicle(r, 30, At(car.x(), car.y(), car.z(), 90)));
  Camera cam = ParseCamera("sensor.camera.semantic_segmentation.wide_angle_lens",
                           {{"camera_model", "equidistant"}, {"fov", "180"}, {"image_size_x", "201"}, {"image_size_y", "201"}})
                   .camera;
  cam.pose = At(0, 0, 1.5);
  cam.outputs = kOutLabels | kOutDepth;
  const auto frame = r.RenderFrames({cam}, w)[0];
  const Vec3 d = (car - Vec3(0, 0, 1.5)).normalized();
  const double f = LensFocal(LensModel::kEquidistant, M_PI, 201, {});
  EXPECT_NEAR(Centroid(frame, tag::kCar).first.norm(), f * std::acos(d.x()), 2.5);
  ASSERT_EQ(frame.depth.size(), 201u * 201u);
  EXPECT_LT(frame.Depth(100, 150), 10.0f) << "the road below the axis";
}

// Every lens attribute changes the image.
TEST(WideAngleLens, EachAttributeChangesTheImage) {
  Renderer& r = SharedRenderer();
  WorldView w;
  w.actors.push_back(Vehicle(r, 30, At(12, 3, 0.75)));
  w.actors.push_back(Vehicle(r, 31, At(6, -5, 0.75, 90)));
  struct Case {
    std::map<std::string, std::string> base;
    std::string attr, value;
  };
  const std::vector<Case> cases = {
      {{}, "fov", "150"},
      {{}, "camera_model", "equidistant"},
      {{{"camera_model", "kannala_brandt"}, {"fov", "180"}}, "k0", "0.4"},
      {{{"camera_model", "kannala_brandt"}, {"fov", "180"}}, "k1", "0.2"},
      {{{"camera_model", "kannala_brandt"}, {"fov", "180"}}, "k2", "0.1"},
      {{{"camera_model", "kannala_brandt"}, {"fov", "180"}}, "k3", "0.05"},
      {{}, "equirectangular", "true"},
      {{{"camera_model", "equidistant"}, {"fov", "120"}}, "perspective", "true"},
      {{}, "fov_mask", "true"},
      {{{"fov_mask", "true"}, {"camera_model", "equidistant"}, {"fov", "150"}}, "fov_fade_size", "30"},
      {{{"equirectangular", "true"}}, "longitude_offset", "40"},
      {{{"camera_model", "equidistant"}}, "focal_length", "20"},
  };
  for (const auto& c : cases) {
    SCOPED_TRACE(c.attr);
    auto changed = c.base;
    changed[c.attr] = c.value;
    const auto frames = r.RenderFrames({WideCam(c.base, 96, 72), WideCam(changed, 96, 72)}, w);
    EXPECT_GT(MeanAbsDiff(frames[0].color, frames[1].color), 1.0);
  }
}

// The faces are CARLA's cube: forward, back, left, right, up, down, all 90 degrees.
TEST(WideAngleLens, FacesCoverTheSphere) {
  const Camera cam = WideCam({{"camera_model", "equidistant"}, {"fov", "360"}}, 64, 64);
  for (int f = 0; f < 6; ++f) {
    const Camera face = WideAngleFace(cam, f);
    EXPECT_EQ(face.fov_deg, 90);
    EXPECT_EQ(face.width, face.height);
    EXPECT_FALSE(face.wide_angle.enabled);
  }
  const Vec3 axes[6] = {Vec3::UnitX(), -Vec3::UnitX(), Vec3::UnitY(), -Vec3::UnitY(), Vec3::UnitZ(), -Vec3::UnitZ()};
  for (int f = 0; f < 6; ++f) {
    const Camera face = WideAngleFace(cam, f);
    const auto p = Project(face, cam.pose.position + axes[f]);
    ASSERT_TRUE(p.has_value());
    EXPECT_NEAR(p->x(), face.width / 2.0, 1e-9);
    EXPECT_NEAR(p->y(), face.height / 2.0, 1e-9);
  }
}

}  // namespace
}  // namespace lockstep::render
