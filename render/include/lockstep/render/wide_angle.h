#pragma once
// CARLA 0.9.16's wide-angle lens cameras (sensor.camera.*.wide_angle_lens): the scene seen
// through a lens model from CARLA's CameraModelUtil. A pixel at distance r (px) from the
// image centre sees the ray at angle theta from the optical axis with r = f g(theta):
//   perspective   g = tan(theta)         stereographic g = 2 tan(theta / 2)
//   equidistant   g = theta              equisolid     g = 2 sin(theta / 2)
//   orthographic  g = sin(theta)         kannala_brandt g = theta (1 + k0 t^2 + k1 t^4 + k2 t^6 + k3 t^8)
// and f chosen so that the vertical field of view `fov` spans the image height:
// f = (H / 2) / g(fov / 2) (CARLA's ComputeDistance). The renderer draws six 90 degree
// faces of a cube map at the camera and samples them along each pixel's ray.
#include <array>
#include <optional>
#include <string>

#include <Eigen/Core>

namespace lockstep::render {

enum class LensModel { kPerspective, kStereographic, kEquidistant, kEquisolid, kOrthographic, kKannalaBrandt };

struct WideAngleLens {
  bool enabled = false;
  LensModel model = LensModel::kPerspective;
  std::array<double, 4> k = {0, 0, 0, 0};  // Kannala-Brandt k0..k3
  bool equirectangular = false;  // longitude/latitude image (angles proportional to pixels) instead
  bool perspective = false;      // re-project the lens image to a pinhole of the same vertical fov
  bool fov_mask = false;         // black outside the field of view
  double fov_fade_size = 0;      // deg: with fov_mask, fades to black over this band inside the edge
  double longitude_offset = 0;   // deg: equirectangular images turn by this about the up axis
  double focal_length = 0;       // px: > 0 replaces the focal length the fov gives (CARLA's focal_length)
  bool operator==(const WideAngleLens&) const = default;
};

// Parses CARLA's camera_model names (perspective, stereographic, equidistant, equisolid,
// orthographic, kannala_brandt; case-insensitive); nullopt for others.
std::optional<LensModel> LensModelFromName(const std::string& name);
// g(theta) above: image radius over focal length.
double LensRadius(LensModel model, double theta, const std::array<double, 4>& k);
// Its inverse: the angle from the axis of a pixel at radius r = distance x f (Newton's
// method for Kannala-Brandt, as CARLA's solver). NaN where the model has no ray.
double LensAngle(LensModel model, double distance, const std::array<double, 4>& k);
// f in pixels for vertical field of view fov_rad over an image `height` px high.
double LensFocal(LensModel model, double fov_rad, int height, const std::array<double, 4>& k);

// The ray of image point (u, v) (continuous, pixel centres at +0.5) of a width x height
// wide-angle camera with vertical field of view fov_deg, in the camera frame (x right,
// y down, z forward), unit length; and its weight (1 inside, 0 masked, between in the fade).
// nullopt where the lens sees nothing (black).
struct LensRay {
  Eigen::Vector3d direction;
  double weight = 1;
};
// The lens's focal length in px: focal_length where > 0, else LensFocal of the fov.
double WideAngleFocal(const WideAngleLens& lens, int height, double fov_deg);
std::optional<LensRay> WideAngleRay(const WideAngleLens& lens, int width, int height, double fov_deg, double u, double v);

}  // namespace lockstep::render
