#include "lockstep/render/exposure.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <vector>

namespace lockstep::render {

double ManualEv100(const ExposureSettings& s) { return std::log2(s.fstop * s.fstop * s.shutter_speed * 100.0 / s.iso); }

double ExposureMultiplier(const ExposureSettings& s, double ev100) { (void)s;
  return std::exp2(10.0 - ev100); }

AutoExposure::AutoExposure(const ExposureSettings& s)
    : s_(s), ev_(s.histogram ? std::clamp(10.0, s.min_bright, std::max(s.min_bright, s.max_bright)) : ManualEv100(s)) {}

double AutoExposure::Multiplier() const { return ExposureMultiplier(s_, ev_); }

double MeasureLuminance(const std::uint8_t* bgra, int width, int height, double multiplier, double gamma) {
  // Byte -> linear scene value: undo the gamma, the tone map 1 - exp(-x) and the exposure.
  std::array<double, 256> lin{};
  for (int b = 0; b < 256; ++b) {
    const double t = std::min(std::pow(b / 255.0, gamma), 1.0 - 1.0 / 512);
    lin[static_cast<std::size_t>(b)] = -std::log1p(-t) / multiplier;
  }
  // Every 4th pixel of every 4th row (Unreal meters a downsampled image too).
  constexpr int kStep = 4;
  constexpr double kLowest = 1e-6;  // black pixels count as this
  std::vector<double> logs;
  logs.reserve(static_cast<std::size_t>((width / kStep + 1) * (height / kStep + 1)));
  for (int v = kStep / 2; v < height; v += kStep) {
    const std::uint8_t* row = bgra + static_cast<std::size_t>(v) * width * 4;
    for (int u = kStep / 2; u < width; u += kStep) {
      const std::uint8_t* p = row + static_cast<std::size_t>(u) * 4;
      const double l = 0.0722 * lin[p[0]] + 0.7152 * lin[p[1]] + 0.2126 * lin[p[2]];
      logs.push_back(std::log2(std::max(l, kLowest)));
    }
  }
  if (logs.empty()) return kLowest;
  std::sort(logs.begin(), logs.end());
  const std::size_t lo = logs.size() / 10, hi = std::max(lo + 1, logs.size() * 9 / 10);
  double sum = 0;
  for (std::size_t i = lo; i < hi; ++i) sum += logs[i];
  return std::exp2(sum / static_cast<double>(hi - lo));
}

void AutoExposure::Update(const std::uint8_t* bgra, int width, int height, double multiplier, double gamma, double dt) {
  if (!s_.histogram) return;
  measured_ = MeasureLuminance(bgra, width, height, multiplier, gamma);
  const double target =
      std::clamp(std::log2(measured_ * kSceneLuminance * 100.0 / s_.calibration_constant), s_.min_bright, std::max(s_.min_bright, s_.max_bright));
  // A brighter scene needs a higher EV100 (less exposure): exposure_speed_up; darker: down.
  if (target > ev_) ev_ = std::min(target, ev_ + s_.speed_up * std::max(dt, 0.0));
  else ev_ = std::max(target, ev_ - s_.speed_down * std::max(dt, 0.0));
}

}  // namespace lockstep::render
