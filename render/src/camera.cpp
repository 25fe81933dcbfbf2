#include "lockstep/render/camera.h"

#include <algorithm>
#include <cctype>
#include <cmath>

namespace lockstep::render {
namespace {

struct PaletteEntry {
  const char* name;
  std::uint8_t r, g, b;
};
// ../shared/reference/carla_constants.json, semantic_palette_0_9_14_plus.
constexpr PaletteEntry kPalette[] = {
    {"Unlabeled", 0, 0, 0},       {"Roads", 128, 64, 128},      {"SideWalks", 244, 35, 232},
    {"Building", 70, 70, 70},     {"Wall", 102, 102, 156},      {"Fence", 190, 153, 153},
    {"Pole", 153, 153, 153},      {"TrafficLight", 250, 170, 30}, {"TrafficSign", 220, 220, 0},
    {"Vegetation", 107, 142, 35}, {"Terrain", 152, 251, 152},   {"Sky", 70, 130, 180},
    {"Pedestrian", 220, 20, 60},  {"Rider", 255, 0, 0},         {"Car", 0, 0, 142},
    {"Truck", 0, 0, 70},          {"Bus", 0, 60, 100},          {"Train", 0, 80, 100},
    {"Motorcycle", 0, 0, 230},    {"Bicycle", 119, 11, 32},     {"Static", 110, 190, 160},
    {"Dynamic", 170, 120, 50},    {"Other", 55, 90, 80},        {"Water", 45, 60, 150},
    {"RoadLine", 157, 234, 50},   {"Ground", 81, 0, 81},        {"Bridge", 150, 100, 100},
    {"RailTrack", 230, 150, 140}, {"GuardRail", 180, 165, 180}};
constexpr int kClassCount = sizeof(kPalette) / sizeof(kPalette[0]);

// Body (x forward, y left, z up) to OpenGL eye (x right, y up, z backwards).
Eigen::Matrix3d BodyToEye() {
  Eigen::Matrix3d m;
  m << 0, -1, 0, 0, 0, 1, -1, 0, 0;
  return m;
}

}  // namespace

double Camera::Focal() const { return width / (2.0 * std::tan(fov_deg * M_PI / 360.0)); }

Eigen::Matrix3d Intrinsics(const Camera& cam) {
  Eigen::Matrix3d k = Eigen::Matrix3d::Identity();
  k(0, 0) = k(1, 1) = cam.Focal();
  k(0, 2) = cam.width / 2.0;
  k(1, 2) = cam.height / 2.0;
  return k;
}

std::optional<Eigen::Vector2d> Project(const Camera& cam, const Vec3& world, double* depth) {
  const Vec3 b = cam.pose.orientation.conjugate() * (world - cam.pose.position);
  if (b.x() <= 1e-9) return std::nullopt;
  if (depth) *depth = b.x();
  // Standard camera frame (x right, y down, z forward) as in CARLA's projection examples.
  const Eigen::Vector3d p = Intrinsics(cam) * Eigen::Vector3d(-b.y(), -b.z(), b.x());
  return Eigen::Vector2d(p.x() / p.z(), p.y() / p.z());
}

Eigen::Matrix4f ViewMatrix(const Pose& pose) {
  const Eigen::Matrix3d r = BodyToEye() * pose.orientation.toRotationMatrix().transpose();
  Eigen::Matrix4d v = Eigen::Matrix4d::Identity();
  v.topLeftCorner<3, 3>() = r;
  v.topRightCorner<3, 1>() = -r * pose.position;
  return v.cast<float>();
}

Eigen::Matrix4f ProjectionMatrix(const Camera& cam) {
  const double f = cam.Focal(), n = kNearPlane, fa = kFarPlane;
  Eigen::Matrix4d p = Eigen::Matrix4d::Zero();
  p(0, 0) = 2 * f / cam.width;
  p(1, 1) = -2 * f / cam.height;  // row 0 of the read-back image is the top row
  p(2, 2) = -(fa + n) / (fa - n);
  p(2, 3) = -2 * fa * n / (fa - n);
  p(3, 2) = -1;
  return p.cast<float>();
}

bool Camera::HasLensDistortion() const { return lens_circle_multiplier > 0 && (lens_k != 0 || lens_kcube != 0); }

bool Camera::HasMotionBlur() const {
  return (outputs & kOutColor) && motion_blur_intensity > 0 && motion_blur_max_distortion > 0;
}

bool SameLens(const Camera& a, const Camera& b) {
  const bool geometry = a.width == b.width && a.height == b.height && a.fov_deg == b.fov_deg &&
                        a.lens_circle_multiplier == b.lens_circle_multiplier && a.lens_circle_falloff == b.lens_circle_falloff &&
                        a.lens_k == b.lens_k && a.lens_kcube == b.lens_kcube && a.lens_x_size == b.lens_x_size &&
                        a.lens_y_size == b.lens_y_size && a.lines_only == b.lines_only &&
                        a.wide_angle == b.wide_angle;
  // The colour settings matter only where both have a colour output (the pass takes them
  // from the one that has: TakeColourSettings).
  if (!geometry || !(a.outputs & kOutColor) || !(b.outputs & kOutColor)) return geometry;
  return a.gamma == b.gamma && a.exposure == b.exposure && a.exposure_compensation == b.exposure_compensation &&
         a.post_process == b.post_process && a.motion_blur_intensity == b.motion_blur_intensity &&
         a.motion_blur_max_distortion == b.motion_blur_max_distortion &&
         a.motion_blur_min_object_screen_size == b.motion_blur_min_object_screen_size;
}

void TakeColourSettings(Camera& dst, const Camera& src) {
  dst.gamma = src.gamma;
  dst.exposure = src.exposure;
  dst.exposure_compensation = src.exposure_compensation;
  dst.post_process = src.post_process;
  dst.motion_blur_intensity = src.motion_blur_intensity;
  dst.motion_blur_max_distortion = src.motion_blur_max_distortion;
  dst.motion_blur_min_object_screen_size = src.motion_blur_min_object_screen_size;
}

Eigen::Vector2d DistortedSource(const Camera& cam, double u, double v) {
  const double half = cam.width / 2.0;
  const double x = (u - half) / half, y = (v - cam.height / 2.0) / half;
  const double xs = x * cam.lens_x_size, ys = y * cam.lens_y_size;
  const double r2 = xs * xs + ys * ys;
  const double f = 1 + cam.lens_circle_multiplier * r2 * (cam.lens_k + cam.lens_kcube * std::sqrt(r2));
  return {half + x * f * half, cam.height / 2.0 + y * f * half};
}

double DecodeCarlaDepth(const std::uint8_t* bgra) {
  const double v = bgra[2] + bgra[1] * 256.0 + bgra[0] * 65536.0;
  return kFarPlane * v / (256.0 * 256.0 * 256.0 - 1.0);
}

std::array<std::uint8_t, 3> PaletteRgb(std::uint8_t tag) {
  if (tag >= kClassCount) return {0, 0, 0};
  return {kPalette[tag].r, kPalette[tag].g, kPalette[tag].b};
}

const char* ClassName(std::uint8_t tag) { return tag < kClassCount ? kPalette[tag].name : "Unknown"; }

int ClassFromName(const std::string& name) {
  auto lower = [](std::string s) {
    std::transform(s.begin(), s.end(), s.begin(), [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
    return s;
  };
  const std::string n = lower(name);
  for (int i = 0; i < kClassCount; ++i) {
    if (lower(kPalette[i].name) == n) return i;
  }
  return -1;
}

std::uint8_t ToPaperClass(std::uint8_t t) {
  switch (t) {
    case tag::kBuilding: return 1;
    case tag::kFence: return 2;
    case tag::kPedestrian:
    case tag::kRider: return 4;
    case tag::kPole:
    case tag::kTrafficLight: return 5;
    case tag::kRoadLine: return 6;
    case tag::kRoads: return 7;
    case tag::kSideWalks: return 8;
    case tag::kVegetation: return 9;
    case tag::kCar:
    case tag::kTruck:
    case tag::kBus:
    case tag::kMotorcycle:
    case tag::kBicycle:
    case 17: return 10;
    case tag::kWall: return 11;
    case tag::kTrafficSign: return 12;
    case tag::kUnlabeled:
    case tag::kSky: return 0;
    default: return 3;  // Other: terrain, static, dynamic, water, ground, ...
  }
}

}  // namespace lockstep::render
