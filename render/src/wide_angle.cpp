#include "lockstep/render/wide_angle.h"
#include "lockstep/render/wide_angle_cube.h"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <limits>

namespace lockstep::render {

std::optional<LensModel> LensModelFromName(const std::string& name) {
  std::string n;
  for (char c : name) n += static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  if (n == "perspective") return LensModel::kPerspective;
  if (n == "stereographic") return LensModel::kStereographic;
  if (n == "equidistant") return LensModel::kEquidistant;
  if (n == "equisolid") return LensModel::kEquisolid;
  if (n == "orthographic") return LensModel::kOrthographic;
  if (n == "kannala_brandt" || n == "kannalabrandt") return LensModel::kKannalaBrandt;
  return std::nullopt;
}

namespace {
double KbPolynomial(double t, const std::array<double, 4>& k) {
  const double t2 = t * t;
  double tn = 1, r = 1;
  for (double c : k) {
    tn *= t2;
    r += c * tn;
  }
  return r * t;
}
double KbDerivative(double t, const std::array<double, 4>& k) {
  const double t2 = t * t;
  double tn = t2, r = 1, a = 3;
  for (double c : k) {
    r += a * c * tn;
    a += 2;
    tn *= t2;
  }
  return r;
}
}  // namespace

double LensRadius(LensModel model, double theta, const std::array<double, 4>& k) {
  switch (model) {
    case LensModel::kPerspective: return std::tan(theta);
    case LensModel::kStereographic: return 2 * std::tan(theta / 2);
    case LensModel::kEquidistant: return theta;
    case LensModel::kEquisolid: return 2 * std::sin(theta / 2);
    case LensModel::kOrthographic: return std::sin(theta);
    case LensModel::kKannalaBrandt: return KbPolynomial(theta, k);
  }
  return theta;
}

double LensAngle(LensModel model, double d, const std::array<double, 4>& k) {
  const double nan = std::numeric_limits<double>::quiet_NaN();
  switch (model) {
    case LensModel::kPerspective: return std::atan(d);
    case LensModel::kStereographic: return 2 * std::atan(d / 2);
    case LensModel::kEquidistant: return d;
    case LensModel::kEquisolid: return d / 2 <= 1 ? 2 * std::asin(d / 2) : nan;
    case LensModel::kOrthographic: return d <= 1 ? std::asin(d) : nan;
    case LensModel::kKannalaBrandt: {
      double t = d;
      for (int i = 0; i < 32; ++i) {
        const double der = KbDerivative(t, k);
        if (der == 0 || !std::isfinite(der)) return nan;
        t -= (KbPolynomial(t, k) - d) / der;
      }
      return std::abs(KbPolynomial(t, k) - d) < 1e-6 * std::max(1.0, d) ? t : nan;
    }
  }
  return d;
}

double LensFocal(LensModel model, double fov_rad, int height, const std::array<double, 4>& k) {
  return height * 0.5 / LensRadius(model, fov_rad * 0.5, k);
}

double WideAngleFocal(const WideAngleLens& lens, int height, double fov_deg) {
  if (lens.focal_length > 0) return lens.focal_length;
  return LensFocal(lens.model, fov_deg * M_PI / 180.0, height, lens.k);
}

std::optional<LensRay> WideAngleRay(const WideAngleLens& lens, int width, int height, double fov_deg, double u, double v) {
  const double half_fov = fov_deg * M_PI / 360.0;
  const double x = u - width * 0.5, y = v - height * 0.5;
  LensRay ray;
  if (lens.equirectangular) {
    // Angles proportional to pixels: vertical fov over the height, the same scale across.
    const double per_px = 2 * half_fov / height;
    const double lon = x * per_px + lens.longitude_offset * M_PI / 180.0, lat = -y * per_px;
    if (std::abs(lat) > M_PI / 2) return std::nullopt;
    ray.direction = Eigen::Vector3d(std::cos(lat) * std::sin(lon), -std::sin(lat), std::cos(lat) * std::cos(lon));
    return ray;
  }
  const double r = std::hypot(x, y);
  double theta;
  if (lens.perspective) {
    // CARLA re-projects the lens image to a pinhole of the same vertical field of view.
    theta = std::atan(r / LensFocal(LensModel::kPerspective, 2 * half_fov, height, lens.k));
  } else {
    theta = LensAngle(lens.model, r / WideAngleFocal(lens, height, fov_deg), lens.k);
  }
  if (!std::isfinite(theta) || theta > M_PI || theta < 0) return std::nullopt;
  if (lens.fov_mask) {
    if (theta > half_fov) return std::nullopt;
    const double fade = lens.fov_fade_size * M_PI / 180.0;
    if (fade > 0) ray.weight = std::clamp((half_fov - theta) / fade, 0.0, 1.0);
  }
  const double s = r > 0 ? std::sin(theta) / r : 0;
  ray.direction = Eigen::Vector3d(x * s, y * s, std::cos(theta));
  return ray;
}

}  // namespace lockstep::render

// ---- cube map faces and composition (wide_angle_cube.h) ----

namespace lockstep::render {
namespace {
Quat FaceRotation(int f) {
  switch (f) {
    case 0: return Quat::Identity();
    case 1: return Quat(Eigen::AngleAxisd(M_PI, Vec3::UnitZ()));
    case 2: return Quat(Eigen::AngleAxisd(M_PI / 2, Vec3::UnitZ()));
    case 3: return Quat(Eigen::AngleAxisd(-M_PI / 2, Vec3::UnitZ()));
    case 4: return Quat(Eigen::AngleAxisd(-M_PI / 2, Vec3::UnitY()));
    default: return Quat(Eigen::AngleAxisd(M_PI / 2, Vec3::UnitY()));
  }
}
int FaceOf(const Vec3& b) {
  const Vec3 a = b.cwiseAbs();
  if (a.x() >= a.y() && a.x() >= a.z()) return b.x() >= 0 ? 0 : 1;
  if (a.y() >= a.z()) return b.y() >= 0 ? 2 : 3;
  return b.z() >= 0 ? 4 : 5;
}
// Pixels per radian at the image centre.
double CentreResolution(const Camera& cam) {
  const auto& l = cam.wide_angle;
  const double fov = cam.fov_deg * M_PI / 180.0;
  if (l.equirectangular) return cam.height / fov;
  if (l.perspective) return LensFocal(LensModel::kPerspective, fov, cam.height, l.k);
  return WideAngleFocal(l, cam.height, cam.fov_deg);
}
}  // namespace

Camera WideAngleFace(const Camera& cam, int face) {
  Camera c = cam;
  c.wide_angle = WideAngleLens{};
  c.fov_deg = 90;
  const double n = std::ceil(2 * CentreResolution(cam));
  c.width = c.height = static_cast<int>(std::clamp(std::isfinite(n) ? n : 16.0, 16.0, 2048.0));
  c.pose.orientation = (cam.pose.orientation * FaceRotation(face)).normalized();
  c.previous_pose.reset();
  c.outputs = cam.outputs & (kOutColor | kOutLabels | kOutDepth | kOutNormals);
  if (!c.outputs) c.outputs = kOutColor;
  c.motion_blur_intensity = 0;
  c.lens_circle_multiplier = 0;
  return c;
}

CameraFrame ComposeWideAngle(const Camera& cam, const std::array<CameraFrame, 6>& faces) {
  std::array<Camera, 6> face_cams;
  for (int f = 0; f < 6; ++f) face_cams[f] = WideAngleFace(cam, f);
  CameraFrame out;
  out.width = cam.width;
  out.height = cam.height;
  const std::size_t n = static_cast<std::size_t>(cam.width) * cam.height;
  const bool colour = !faces[0].color.empty(), labels = !faces[0].labels.empty();
  const bool depth = !faces[0].depth.empty(), normals = !faces[0].normals.empty();
  if (colour) out.color.assign(n * 4, 0);
  if (labels) out.labels.assign(n * 4, 0);
  if (depth) out.depth.assign(n, static_cast<float>(kFarPlane));
  if (normals) out.normals.assign(n * 4, 0);
  for (std::size_t p = 0; p < n && colour; ++p) out.color[p * 4 + 3] = 255;
  for (int v = 0; v < cam.height; ++v) {
    for (int u = 0; u < cam.width; ++u) {
      const auto ray = WideAngleRay(cam.wide_angle, cam.width, cam.height, cam.fov_deg, u + 0.5, v + 0.5);
      if (!ray || ray->weight <= 0) continue;
      const Eigen::Vector3d& d = ray->direction;  // x right, y down, z forward
      const Vec3 body(d.z(), -d.x(), -d.y());
      const int f = FaceOf(body);
      const Camera& fc = face_cams[f];
      const auto px = Project(fc, cam.pose.position + cam.pose.orientation * body);
      if (!px) continue;
      const int su = std::clamp(static_cast<int>(std::floor(px->x())), 0, fc.width - 1);
      const int sv = std::clamp(static_cast<int>(std::floor(px->y())), 0, fc.height - 1);
      const std::size_t s = static_cast<std::size_t>(sv) * fc.width + su, o = static_cast<std::size_t>(v) * cam.width + u;
      const CameraFrame& src = faces[f];
      if (colour && src.color.size() >= (s + 1) * 4) {
        for (int c = 0; c < 3; ++c) {
          out.color[o * 4 + c] = static_cast<std::uint8_t>(std::lround(src.color[s * 4 + c] * ray->weight));
        }
      }
      if (labels && src.labels.size() >= (s + 1) * 4) std::copy_n(&src.labels[s * 4], 4, &out.labels[o * 4]);
      // Depth and normals as the face drew them (planar to that face, its camera frame).
      if (depth && src.depth.size() > s) out.depth[o] = src.depth[s];
      if (normals && src.normals.size() >= (s + 1) * 4) std::copy_n(&src.normals[s * 4], 4, &out.normals[o * 4]);
    }
  }
  return out;
}

}  // namespace lockstep::render
