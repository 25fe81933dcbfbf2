#pragma once
// Camera model as CARLA's: a pinhole from the horizontal field of view, principal point
// at the image centre; the camera looks along its body +x with body +z up. Pixel (u, v)
// covers [u, u+1) x [v, v+1), v grows downwards, row 0 is the top row.
#include <algorithm>
#include <array>
#include <cstdint>
#include <optional>
#include <string>

#include "lockstep/render/types.h"
#include "lockstep/render/wide_angle.h"

namespace lockstep::render {

inline constexpr double kFarPlane = 1000.0;  // m: CARLA's depth range; the sky is at this depth
inline constexpr double kNearPlane = 0.1;    // m

struct Camera {
  int width = 800;
  int height = 600;
  double fov_deg = 90.0;           // horizontal
  Pose pose;                       // world pose of the camera body
  std::optional<Pose> previous_pose;  // pose of the previous rendered frame (optical flow)
  std::uint32_t outputs = kOutColor;
  // Exposure and lens (CARLA attributes of the same names).
  double exposure = 1.0;               // linear colour multiplier before the tone map (see exposure.h)
  double exposure_compensation = 0.0;  // EV: colour scaled by 2^ev on top of `exposure`
  double gamma = 2.2;
  double lens_circle_falloff = 5.0;
  double lens_circle_multiplier = 0.0;  // 0: no vignetting and no distortion (CARLA's default)
  // Lens distortion (CARLA's attributes and defaults), a cubic model scaled by
  // lens_circle_multiplier: CARLA's defaults give undistorted images. See DistortedSource.
  double lens_k = -1.0;
  double lens_kcube = 0.0;
  double lens_x_size = 0.08;
  double lens_y_size = 0.08;
  bool post_process = true;             // weather effects on the colour (rain streaks)
  // Motion blur of the colour output (CARLA's attributes; 0 intensity: none, the default
  // here, 0.45 from a blueprint as in CARLA): each pixel averages the image along
  // intensity x its motion since the previous image (the optical flow), at most
  // max_distortion % of the image width long; actors narrower on screen than
  // min_object_screen_size x the width blur by the camera's motion only.
  double motion_blur_intensity = 0.0;
  double motion_blur_max_distortion = 0.35;
  double motion_blur_min_object_screen_size = 0.1;
  std::uint64_t noise_seed = 0;         // seeds rain streaks: run seed ^ sensor id
  // CARLA 0.9.16's sensor.camera.cosmos_visualization: no scene, only lines on black (the
  // world's debug shapes and WorldView::cosmos), unlit.
  bool lines_only = false;
  // CARLA 0.9.16's sensor.camera.rgb.wide_angle_lens: a lens model instead of the pinhole;
  // fov_deg is then the vertical field of view (wide_angle.h). The renderer draws a cube map.
  WideAngleLens wide_angle;

  double Focal() const;  // px
  bool HasLensDistortion() const;  // lens_circle_multiplier > 0 and lens_k or lens_kcube not 0
  bool HasMotionBlur() const;      // colour output, motion_blur_intensity and max_distortion > 0
};

// True if two cameras at one pose give the same images from one pass: same size, field of
// view and lens, and where both output colour, the same colour settings (gamma, exposure,
// post-processing, motion blur).
bool SameLens(const Camera& a, const Camera& b);
// Copies the colour settings of `src` (a camera with colour joining the pass of `dst`).
void TakeColourSettings(Camera& dst, const Camera& src);

// Lens distortion: the output pixel (u, v) (continuous, pixel centres at +0.5) shows what
// the pinhole image shows at the returned position. With x = (u - W/2) / (W/2) and
// y = (v - H/2) / (W/2), r^2 = (x lens_x_size)^2 + (y lens_y_size)^2 and
// f = 1 + lens_circle_multiplier r^2 (lens_k + lens_kcube r), the source is (x f, y f)
// (the cubic model of Syntheyes that CARLA's lens shader follows): lens_k < 0 stretches
// the edges outwards, lens_k > 0 draws them in and the corners read outside the image.
Eigen::Vector2d DistortedSource(const Camera& cam, double u, double v);

// Pixel position (continuous) of a world point; nullopt behind the camera. depth: planar m.
std::optional<Eigen::Vector2d> Project(const Camera& cam, const Vec3& world, double* depth = nullptr);
// The 3x3 intrinsic matrix K as CARLA's examples build it.
Eigen::Matrix3d Intrinsics(const Camera& cam);
// World to camera view (OpenGL eye space: x right, y up, looking down -z).
Eigen::Matrix4f ViewMatrix(const Pose& pose);
// Projection to clip space with image rows top first (y flipped: row 0 = top).
Eigen::Matrix4f ProjectionMatrix(const Camera& cam);

// CARLA's depth encoding: normalized = (R + G*256 + B*65536) / (256^3 - 1), metres = 1000 * normalized.
// Inline: the depth image encodes every pixel with it.
inline void EncodeCarlaDepth(float metres, std::uint8_t* bgra) {
  const double normalized = std::clamp(static_cast<double>(metres) / kFarPlane, 0.0, 1.0);
  // Rounds half up, as std::lround does for these non-negative values, without its call.
  const auto v = static_cast<std::uint32_t>(normalized * (256.0 * 256.0 * 256.0 - 1.0) + 0.5);
  bgra[2] = static_cast<std::uint8_t>(v & 0xff);          // R
  bgra[1] = static_cast<std::uint8_t>((v >> 8) & 0xff);   // G
  bgra[0] = static_cast<std::uint8_t>((v >> 16) & 0xff);  // B
  bgra[3] = 255;
}
double DecodeCarlaDepth(const std::uint8_t* bgra);

// CARLA 0.9.14+ palette (29 classes, ids 0..28); unknown ids are black.
std::array<std::uint8_t, 3> PaletteRgb(std::uint8_t tag);
const char* ClassName(std::uint8_t tag);
int ClassFromName(const std::string& name);  // -1 if unknown; case-insensitive
// The 2017 CARLA paper's 12 classes (0 None, 1 Buildings, 2 Fences, 3 Other, 4 Pedestrians,
// 5 Poles, 6 RoadLines, 7 Roads, 8 Sidewalks, 9 Vegetation, 10 Vehicles, 11 Walls, 12 TrafficSigns).
std::uint8_t ToPaperClass(std::uint8_t tag);

// CARLA semantic tags used by the renderer.
namespace tag {
inline constexpr std::uint8_t kUnlabeled = 0, kRoads = 1, kSideWalks = 2, kBuilding = 3, kWall = 4, kFence = 5,
                              kPole = 6, kTrafficLight = 7, kTrafficSign = 8, kVegetation = 9, kTerrain = 10,
                              kSky = 11, kPedestrian = 12, kRider = 13, kCar = 14, kTruck = 15, kBus = 16,
                              kMotorcycle = 18, kBicycle = 19, kStatic = 20, kDynamic = 21, kOther = 22,
                              kRoadLine = 24, kGround = 25;
}

}  // namespace lockstep::render
