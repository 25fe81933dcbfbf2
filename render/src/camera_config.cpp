#include "lockstep/render/camera_config.h"

#include <charconv>
#include <cmath>
#include <stdexcept>

namespace lockstep::render {
namespace {

AttributeSpec F(const std::string& id, double def, double min, double max) {
  char buf[64];
  std::snprintf(buf, sizeof buf, "%g", def);
  return AttributeSpec{id, AttributeType::kFloat, buf, min, max, {}};
}
AttributeSpec I(const std::string& id, int def, double min, double max) { return AttributeSpec{id, AttributeType::kInt, std::to_string(def), min, max, {}}; }
AttributeSpec B(const std::string& id, bool def) { return AttributeSpec{id, AttributeType::kBool, def ? "true" : "false", 0, 1, {}}; }
AttributeSpec S(const std::string& id, const std::string& def, std::vector<std::string> choices) {
  return AttributeSpec{id, AttributeType::kString, def, 0, 0, std::move(choices)};
}

std::vector<AttributeSpec> Basic() {
  return {S("role_name", "", {}), I("image_size_x", 800, 1, 7680), I("image_size_y", 600, 1, 7680), F("fov", 90, 1, 170),
          F("sensor_tick", 0, 0, 3600), F("lens_circle_falloff", 5, 0, 10), F("lens_circle_multiplier", 0, 0, 10),
          F("lens_k", -1, -100, 100), F("lens_kcube", 0, -100, 100), F("lens_x_size", 0.08, 0, 1), F("lens_y_size", 0.08, 0, 1)};
}
std::vector<AttributeSpec> Rgb() {
  auto v = Basic();
  v.push_back(F("gamma", 2.2, 0.5, 5));
  // Exposure and motion blur: CARLA's attributes and defaults (exposure.h, Camera).
  v.push_back(S("exposure_mode", "histogram", {"manual", "histogram"}));
  v.push_back(F("exposure_compensation", 0, -10, 10));
  v.push_back(F("exposure_min_bright", 10, -10, 20));
  v.push_back(F("exposure_max_bright", 12, -10, 20));
  v.push_back(F("exposure_speed_up", 3, 0, 100));
  v.push_back(F("exposure_speed_down", 1, 0, 100));
  v.push_back(F("calibration_constant", 16, 0.01, 1000));
  v.push_back(F("shutter_speed", 200, 0.001, 1e6));
  v.push_back(F("iso", 100, 1, 1e6));
  v.push_back(F("fstop", 1.4, 0.1, 64));
  v.push_back(F("motion_blur_intensity", 0.45, 0, 1));
  v.push_back(F("motion_blur_max_distortion", 0.35, 0, 100));
  v.push_back(F("motion_blur_min_object_screen_size", 0.1, 0, 1));
  v.push_back(B("enable_postprocess_effects", true));
  // CARLA's other post-process attributes and defaults (bloom, lens flare, depth of field,
  // tone mapper, white balance, chromatic aberration): declared, so scripts can set them;
  // the renderer does not simulate these effects (docs/render.md).
  v.push_back(F("bloom_intensity", 0.675, 0, 100));
  v.push_back(F("lens_flare_intensity", 0.1, 0, 100));
  v.push_back(F("min_fstop", 1.2, 0.1, 64));
  v.push_back(I("blade_count", 5, 4, 16));
  v.push_back(F("focal_distance", 1000, 0, 1e8));
  v.push_back(F("blur_amount", 1, 0, 100));
  v.push_back(F("blur_radius", 0, 0, 100));
  v.push_back(F("slope", 0.88, 0, 1));
  v.push_back(F("toe", 0.55, 0, 1));
  v.push_back(F("shoulder", 0.26, 0, 1));
  v.push_back(F("black_clip", 0, 0, 1));
  v.push_back(F("white_clip", 0.04, 0, 1));
  v.push_back(F("temp", 6500, 1500, 15000));
  v.push_back(F("tint", 0, -1, 1));
  v.push_back(F("chromatic_aberration_intensity", 0, 0, 1e4));
  v.push_back(F("chromatic_aberration_offset", 0, 0, 1));
  return v;
}
// CARLA 0.9.16's wide-angle lens cameras: fov is vertical and may pass 180 degrees; the lens
// model and its parameters (SceneCaptureSensor_WideAngleLens defaults: perspective, 90
// degrees, its Kannala-Brandt coefficients).
std::vector<AttributeSpec> WideAngle(std::vector<AttributeSpec> v) {
  for (auto& a : v) {
    if (a.id == "fov") a = F("fov", 90, 1, 360);
  }
  v.push_back(S("camera_model", "perspective",
                {"perspective", "stereographic", "equidistant", "equisolid", "orthographic", "kannala_brandt"}));
  v.push_back(AttributeSpec{"k0", AttributeType::kFloat, "0.08309221636708493", -100, 100, {}});
  v.push_back(AttributeSpec{"k1", AttributeType::kFloat, "0.01112126630599195", -100, 100, {}});
  v.push_back(AttributeSpec{"k2", AttributeType::kFloat, "0.008587261043925865", -100, 100, {}});
  v.push_back(AttributeSpec{"k3", AttributeType::kFloat, "0.0008542188930970716", -100, 100, {}});
  v.push_back(F("focal_length", 0, 0, 1e6));
  v.push_back(B("equirectangular", false));
  v.push_back(B("perspective", false));
  v.push_back(B("fov_mask", false));
  v.push_back(F("fov_fade_size", 0, 0, 360));
  v.push_back(F("longitude_offset", 0, -360, 360));
  return v;
}
std::vector<AttributeSpec> With(std::vector<AttributeSpec> v, const std::vector<AttributeSpec>& more) {
  v.insert(v.end(), more.begin(), more.end());
  return v;
}

const AttributeSpec* Find(const CameraBlueprintSpec& bp, const std::string& id) {
  for (const auto& a : bp.attributes) {
    if (a.id == id) return &a;
  }
  return nullptr;
}

}  // namespace

const std::vector<CameraBlueprintSpec>& CameraBlueprints() {
  static const std::vector<CameraBlueprintSpec> list = {
      {"sensor.camera.rgb", ImageKind::kRgb, Rgb()},
      {"sensor.camera.depth", ImageKind::kDepth, With(Basic(), {S("encoding", "carla", {"carla", "float"})})},
      {"sensor.camera.semantic_segmentation", ImageKind::kSemantic, With(Basic(), {S("classes", "carla", {"carla", "paper"})})},
      {"sensor.camera.instance_segmentation", ImageKind::kInstance, Basic()},
      {"sensor.camera.normals", ImageKind::kNormals, Basic()},
      {"sensor.camera.optical_flow", ImageKind::kFlow, Basic()},
      {"sensor.camera.dvs", ImageKind::kDvs,
       With(Rgb(), {F("positive_threshold", 0.3, 0.001, 10), F("negative_threshold", 0.3, 0.001, 10),
                    F("sigma_positive_threshold", 0, 0, 10), F("sigma_negative_threshold", 0, 0, 10),
                    I("refractory_period_ns", 0, 0, 1e12), B("use_log", true), F("log_eps", 0.001, 1e-9, 1)})},
      // CARLA 0.9.16's Cosmos control visualization: the scene's boxes and lines on black.
      {"sensor.camera.cosmos_visualization", ImageKind::kRgb, Basic()},
      {"sensor.camera.rgb.wide_angle_lens", ImageKind::kRgb, WideAngle(Rgb())},
      {"sensor.camera.depth.wide_angle_lens", ImageKind::kDepth, WideAngle(Basic())},
      {"sensor.camera.semantic_segmentation.wide_angle_lens", ImageKind::kSemantic, WideAngle(Basic())},
      {"sensor.camera.instance_segmentation.wide_angle_lens", ImageKind::kInstance, WideAngle(Basic())},
      {"sensor.camera.normals.wide_angle_lens", ImageKind::kNormals, WideAngle(Basic())},
      {"sensor.camera.airsim", ImageKind::kAirSimScene,
       With(Rgb(), {S("image_type", "Scene",
                      {"Scene", "DepthPlanar", "DepthPerspective", "DepthVis", "DisparityNormalized", "Segmentation",
                       "SurfaceNormals", "Infrared"})})},
  };
  return list;
}

bool IsCameraBlueprint(const std::string& id) {
  for (const auto& b : CameraBlueprints()) {
    if (b.id == id) return true;
  }
  return false;
}

CameraSettings ParseCamera(const std::string& blueprint, const std::map<std::string, std::string>& attrs) {
  const CameraBlueprintSpec* bp = nullptr;
  for (const auto& b : CameraBlueprints()) {
    if (b.id == blueprint) bp = &b;
  }
  if (!bp) throw std::invalid_argument("'" + blueprint + "' is not a camera blueprint");
  auto text = [&](const std::string& id) {
    auto it = attrs.find(id);
    if (it != attrs.end()) return it->second;
    const AttributeSpec* a = Find(*bp, id);
    return a ? a->def : std::string();
  };
  auto number = [&](const std::string& id) {
    const AttributeSpec* a = Find(*bp, id);
    const std::string s = text(id);
    double v = 0;
    auto [p, ec] = std::from_chars(s.data(), s.data() + s.size(), v);
    if (ec != std::errc() || p != s.data() + s.size() || !std::isfinite(v)) {
      throw std::invalid_argument(blueprint + ": attribute " + id + " = '" + s + "' is not a number");
    }
    if (a && a->type == AttributeType::kInt && v != std::floor(v)) throw std::invalid_argument(blueprint + ": attribute " + id + " = '" + s + "' is not an integer");
    if (a && (v < a->min || v > a->max)) {
      throw std::invalid_argument(blueprint + ": attribute " + id + " = " + s + " is outside [" + std::to_string(a->min) + ", " +
                                  std::to_string(a->max) + "]");
    }
    return v;
  };
  auto boolean = [&](const std::string& id) {
    const std::string s = text(id);
    if (s == "true" || s == "True" || s == "1") return true;
    if (s == "false" || s == "False" || s == "0") return false;
    throw std::invalid_argument(blueprint + ": attribute " + id + " = '" + s + "' is not true or false");
  };
  auto choice = [&](const std::string& id) {
    const AttributeSpec* a = Find(*bp, id);
    const std::string s = text(id);
    bool ok = a->choices.empty();
    for (const auto& c : a->choices) ok = ok || c == s;
    if (!ok) throw std::invalid_argument(blueprint + ": attribute " + id + " = '" + s + "' is not one of the allowed values");
    return s;
  };
  CameraSettings s;
  s.blueprint = blueprint;
  s.kind = bp->kind;
  s.camera.width = static_cast<int>(number("image_size_x"));
  s.camera.height = static_cast<int>(number("image_size_y"));
  s.camera.fov_deg = number("fov");
  s.sensor_tick = number("sensor_tick");
  s.camera.lens_circle_falloff = number("lens_circle_falloff");
  s.camera.lens_circle_multiplier = number("lens_circle_multiplier");
  s.camera.lens_k = number("lens_k");
  s.camera.lens_kcube = number("lens_kcube");
  s.camera.lens_x_size = number("lens_x_size");
  s.camera.lens_y_size = number("lens_y_size");
  if (Find(*bp, "gamma")) {
    s.camera.gamma = number("gamma");
    s.exposure.histogram = choice("exposure_mode") == "histogram";
    s.camera.exposure_compensation = number("exposure_compensation");
    s.exposure.min_bright = number("exposure_min_bright");
    s.exposure.max_bright = number("exposure_max_bright");
    if (s.exposure.min_bright > s.exposure.max_bright) {
      throw std::invalid_argument(blueprint + ": attribute exposure_min_bright = " + text("exposure_min_bright") +
                                  " is above exposure_max_bright = " + text("exposure_max_bright"));
    }
    s.exposure.speed_up = number("exposure_speed_up");
    s.exposure.speed_down = number("exposure_speed_down");
    s.exposure.calibration_constant = number("calibration_constant");
    s.exposure.shutter_speed = number("shutter_speed");
    s.exposure.iso = number("iso");
    s.exposure.fstop = number("fstop");
    s.camera.exposure = AutoExposure(s.exposure).Multiplier();
    s.camera.motion_blur_intensity = number("motion_blur_intensity");
    s.camera.motion_blur_max_distortion = number("motion_blur_max_distortion");
    s.camera.motion_blur_min_object_screen_size = number("motion_blur_min_object_screen_size");
    s.camera.post_process = boolean("enable_postprocess_effects");
  }
  if (blueprint == "sensor.camera.depth" && choice("encoding") == "float") s.kind = ImageKind::kDepthFloat;
  if (blueprint == "sensor.camera.semantic_segmentation") s.paper_classes = choice("classes") == "paper";
  if (blueprint == "sensor.camera.airsim") s.kind = AirSimImageKind(choice("image_type"));
  s.camera.lines_only = blueprint == "sensor.camera.cosmos_visualization";
  if (Find(*bp, "camera_model")) {
    auto& lens = s.camera.wide_angle;
    lens.enabled = true;
    lens.model = *LensModelFromName(choice("camera_model"));
    static const char* const kNames[4] = {"k0", "k1", "k2", "k3"};
    for (std::size_t i = 0; i < 4; ++i) lens.k[i] = number(kNames[i]);
    lens.equirectangular = boolean("equirectangular");
    lens.perspective = boolean("perspective");
    lens.fov_mask = boolean("fov_mask");
    lens.fov_fade_size = number("fov_fade_size");
    lens.longitude_offset = number("longitude_offset");
    lens.focal_length = number("focal_length");
  }
  if (s.kind == ImageKind::kDvs) {
    s.dvs.positive_threshold = number("positive_threshold");
    s.dvs.negative_threshold = number("negative_threshold");
    s.dvs.sigma_positive_threshold = number("sigma_positive_threshold");
    s.dvs.sigma_negative_threshold = number("sigma_negative_threshold");
    s.dvs.refractory_period_ns = static_cast<std::int64_t>(number("refractory_period_ns"));
    s.dvs.use_log = boolean("use_log");
    s.dvs.log_eps = number("log_eps");
  }
  // DVS events travel in one Image (its bound); other images over the bound as a LargeImage, up to 8K.
  const std::size_t pixels = static_cast<std::size_t>(s.camera.width) * s.camera.height;
  if (s.kind == ImageKind::kDvs && pixels * 4 > kMaxImageBytes) {
    throw std::invalid_argument(blueprint + ": image_size_x x image_size_y = " + std::to_string(s.camera.width) + "x" +
                                std::to_string(s.camera.height) + " gives more than " + std::to_string(kMaxImageBytes) +
                                " bytes per image (1920x1080 at most for a DVS camera)");
  }
  if (pixels > kMaxCameraPixels) {
    throw std::invalid_argument(blueprint + ": image_size_x x image_size_y = " + std::to_string(s.camera.width) + "x" +
                                std::to_string(s.camera.height) + " is more than 7680x4320 (8K) pixels");
  }
  s.camera.outputs = OutputsFor(s.kind);
  return s;
}

}  // namespace lockstep::render
