#pragma once
// Exposure of colour cameras, with CARLA's attributes (Unreal Engine's physical camera and
// eye adaptation). The renderer scales the scene's linear colour by Camera::exposure
// before its tone map (colour' = 1 - exp(-colour * exposure)). Exposure is in EV100:
// the renderer's linear unit is kSceneLuminance cd/m^2, chosen so that EV100 10 (the
// lower end of CARLA's default auto-exposure range) gives exposure 1.
//   multiplier(EV100) = 2^(10 - EV100); the renderer applies exposure_compensation on top (2^EV)
// manual:    EV100 = log2(fstop^2 * shutter_speed * 100 / iso)   (exposure time 1/shutter_speed s)
// histogram: the scene's EV100 = log2(L * kSceneLuminance * 100 / calibration_constant), L
//            the mean luminance (geometric, of the pixels between the 10th and 90th
//            percentile) of the camera's previous image, clamped to [exposure_min_bright,
//            exposure_max_bright]; the camera's EV100 moves towards it by at most
//            exposure_speed_up (scene brighter) or exposure_speed_down (darker) EV per
//            second of simulated time between its images. A function of the frame
//            history only: no wall clock.
#include <cstdint>
#include <string>

#include "lockstep/render/state_io.h"

namespace lockstep::render {

inline constexpr double kSceneLuminance = 1.2 * 1024.0;  // cd/m^2 per linear unit (UE: EV100 -> 1.2 * 2^EV100)

struct ExposureSettings {
  bool histogram = true;              // exposure_mode: "histogram" (CARLA's default) or "manual"
  double min_bright = 10, max_bright = 12;  // exposure_min_bright, exposure_max_bright, EV100
  double speed_up = 3, speed_down = 1;      // exposure_speed_up, exposure_speed_down, EV per second
  double calibration_constant = 16;
  double shutter_speed = 200;         // 1/s
  double iso = 100;
  double fstop = 1.4;
};

// EV100 of the manual camera.
double ManualEv100(const ExposureSettings& s);
// The multiplier the renderer applies for an EV100 (Camera::exposure).
double ExposureMultiplier(const ExposureSettings& s, double ev100);

// One camera's exposure over its images.
class AutoExposure {
 public:
  explicit AutoExposure(const ExposureSettings& s = {});
  // The multiplier for the next image.
  double Multiplier() const;
  double ev100() const { return ev_; }
  // After an image: bgra is the camera's colour output (8 bits, row-major), rendered with
  // `multiplier` (all of it: Camera::exposure times 2^exposure_compensation) and `gamma`; dt the simulated time since its previous image (0 for the
  // first). Manual cameras ignore it.
  void Update(const std::uint8_t* bgra, int width, int height, double multiplier, double gamma, double dt);
  // The mean scene luminance (linear units) the last Update measured.
  double measured() const { return measured_; }
  // The adaptation state (the settings come from the spawn).
  void Save(StateOut& out) const { out.Put(ev_).Put(measured_); }
  void Restore(StateIn& in) { in.Get(ev_).Get(measured_); }

 private:
  ExposureSettings s_;
  double ev_;
  double measured_ = 0;
};

// The geometric mean linear luminance (scene units, before exposure) of the pixels between
// the 10th and 90th percentile of an image rendered with `multiplier` and `gamma`.
double MeasureLuminance(const std::uint8_t* bgra, int width, int height, double multiplier, double gamma);

}  // namespace lockstep::render
