#include "lockstep/render/weather.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <utility>

namespace lockstep::render {
namespace {

struct Preset {
  const char* name;
  Weather w;
};
// CARLA's presets, from ../shared/reference/carla_constants.json (fields in WeatherParameters order).
const Preset kPresets[] = {
    {"ClearNoon", {5.0f, 0.0f, 0.0f, 10.0f, -1.0f, 45.0f, 2.0f, 0.75f, 0.1f, 0.0f, 1.0f, 0.03f, 0.0331f, 0.0f}},
    {"CloudyNoon", {60.0f, 0.0f, 0.0f, 10.0f, -1.0f, 45.0f, 3.0f, 0.75f, 0.1f, 0.0f, 1.0f, 0.03f, 0.0331f, 0.0f}},
    {"WetNoon", {5.0f, 0.0f, 50.0f, 10.0f, -1.0f, 45.0f, 3.0f, 0.75f, 0.1f, 0.0f, 1.0f, 0.03f, 0.0331f, 0.0f}},
    {"WetCloudyNoon", {60.0f, 0.0f, 50.0f, 10.0f, -1.0f, 45.0f, 3.0f, 0.75f, 0.1f, 0.0f, 1.0f, 0.03f, 0.0331f, 0.0f}},
    {"MidRainyNoon", {60.0f, 60.0f, 60.0f, 60.0f, -1.0f, 45.0f, 3.0f, 0.75f, 0.1f, 0.0f, 1.0f, 0.03f, 0.0331f, 0.0f}},
    {"HardRainNoon", {100.0f, 100.0f, 90.0f, 100.0f, -1.0f, 45.0f, 7.0f, 0.75f, 0.1f, 0.0f, 1.0f, 0.03f, 0.0331f, 0.0f}},
    {"SoftRainNoon", {20.0f, 30.0f, 50.0f, 30.0f, -1.0f, 45.0f, 3.0f, 0.75f, 0.1f, 0.0f, 1.0f, 0.03f, 0.0331f, 0.0f}},
    {"ClearSunset", {5.0f, 0.0f, 0.0f, 10.0f, -1.0f, 15.0f, 2.0f, 0.75f, 0.1f, 0.0f, 1.0f, 0.03f, 0.0331f, 0.0f}},
    {"CloudySunset", {60.0f, 0.0f, 0.0f, 10.0f, -1.0f, 15.0f, 3.0f, 0.75f, 0.1f, 0.0f, 1.0f, 0.03f, 0.0331f, 0.0f}},
    {"WetSunset", {5.0f, 0.0f, 50.0f, 10.0f, -1.0f, 15.0f, 2.0f, 0.75f, 0.1f, 0.0f, 1.0f, 0.03f, 0.0331f, 0.0f}},
    {"WetCloudySunset", {60.0f, 0.0f, 50.0f, 10.0f, -1.0f, 15.0f, 2.0f, 0.75f, 0.1f, 0.0f, 1.0f, 0.03f, 0.0331f, 0.0f}},
    {"MidRainSunset", {60.0f, 60.0f, 60.0f, 60.0f, -1.0f, 15.0f, 3.0f, 0.75f, 0.1f, 0.0f, 1.0f, 0.03f, 0.0331f, 0.0f}},
    {"HardRainSunset", {100.0f, 100.0f, 90.0f, 100.0f, -1.0f, 15.0f, 7.0f, 0.75f, 0.1f, 0.0f, 1.0f, 0.03f, 0.0331f, 0.0f}},
    {"SoftRainSunset", {20.0f, 30.0f, 50.0f, 30.0f, -1.0f, 15.0f, 2.0f, 0.75f, 0.1f, 0.0f, 1.0f, 0.03f, 0.0331f, 0.0f}},
    {"ClearNight", {5.0f, 0.0f, 0.0f, 10.0f, -1.0f, -90.0f, 60.0f, 75.0f, 1.0f, 0.0f, 1.0f, 0.03f, 0.0331f, 0.0f}},
    {"CloudyNight", {60.0f, 0.0f, 0.0f, 10.0f, -1.0f, -90.0f, 60.0f, 0.75f, 0.1f, 0.0f, 1.0f, 0.03f, 0.0331f, 0.0f}},
    {"WetNight", {5.0f, 0.0f, 50.0f, 10.0f, -1.0f, -90.0f, 60.0f, 75.0f, 1.0f, 60.0f, 1.0f, 0.03f, 0.0331f, 0.0f}},
    {"WetCloudyNight", {60.0f, 0.0f, 50.0f, 10.0f, -1.0f, -90.0f, 60.0f, 0.75f, 0.1f, 60.0f, 1.0f, 0.03f, 0.0331f, 0.0f}},
    {"SoftRainNight", {60.0f, 30.0f, 50.0f, 30.0f, -1.0f, -90.0f, 60.0f, 0.75f, 0.1f, 60.0f, 1.0f, 0.03f, 0.0331f, 0.0f}},
    {"MidRainyNight", {80.0f, 60.0f, 60.0f, 60.0f, -1.0f, -90.0f, 60.0f, 0.75f, 0.1f, 80.0f, 1.0f, 0.03f, 0.0331f, 0.0f}},
    {"HardRainNight", {100.0f, 100.0f, 90.0f, 100.0f, -1.0f, -90.0f, 100.0f, 0.75f, 0.1f, 100.0f, 1.0f, 0.03f, 0.0331f, 0.0f}},
    {"DustStorm", {100.0f, 0.0f, 0.0f, 100.0f, -1.0f, 45.0f, 2.0f, 0.75f, 0.1f, 0.0f, 1.0f, 0.03f, 0.0331f, 100.0f}},
};

float Smooth(float e0, float e1, float x) {
  const float t = std::clamp((x - e0) / (e1 - e0), 0.0f, 1.0f);
  return t * t * (3 - 2 * t);
}
Eigen::Vector3f Mix(const Eigen::Vector3f& a, const Eigen::Vector3f& b, float t) { return a + (b - a) * t; }

}  // namespace

Weather WeatherPreset(const std::string& name) {
  for (const auto& p : kPresets) {
    if (name == p.name) return p.w;
  }
  std::string known;
  for (const auto& p : kPresets) known += std::string(known.empty() ? "" : ", ") + p.name;
  throw std::invalid_argument("unknown weather preset '" + name + "' (known: " + known + ")");
}

std::vector<std::string> WeatherPresetNames() {
  std::vector<std::string> out;
  for (const auto& p : kPresets) out.emplace_back(p.name);
  return out;
}

Lighting ComputeLighting(const Weather& w) {
  Lighting l;
  const float deg = static_cast<float>(M_PI) / 180.0f;
  const float alt = std::clamp(w.sun_altitude_angle, -90.0f, 90.0f);
  const float az = w.sun_azimuth_angle < 0 ? 0.0f : w.sun_azimuth_angle;  // CARLA's -1: unset
  // CARLA turns the azimuth about its (left-handed) z axis; in ENU that is clockwise.
  l.sun_direction = Eigen::Vector3f(std::cos(alt * deg) * std::cos(az * deg), -std::cos(alt * deg) * std::sin(az * deg),
                                    std::sin(alt * deg))
                        .normalized();
  const float clouds = std::clamp(w.cloudiness / 100.0f, 0.0f, 1.0f);
  const float rain = std::clamp(w.precipitation / 100.0f, 0.0f, 1.0f);
  const float dust = std::clamp(w.dust_storm / 100.0f, 0.0f, 1.0f);
  l.clouds = std::max(clouds, rain);
  const float day = Smooth(-6.0f, 8.0f, alt);            // 0 at night, 1 in daylight
  const float low_sun = 1.0f - Smooth(4.0f, 35.0f, alt);  // warm light near the horizon
  const float overcast = 1.0f - 0.85f * l.clouds;
  const float strength = Smooth(-1.0f, 6.0f, alt) * (0.35f + 0.65f * std::sqrt(std::max(0.0f, std::sin(alt * deg)))) * overcast *
                         (1.0f - 0.7f * dust);
  const Eigen::Vector3f white(1.0f, 0.96f, 0.9f), warm(1.0f, 0.5f, 0.22f);
  l.sun_color = Mix(white, warm, low_sun) * (2.2f * strength);
  const Eigen::Vector3f day_ambient(0.30f, 0.36f, 0.46f), grey_ambient(0.42f, 0.43f, 0.45f), night_ambient(0.012f, 0.016f, 0.03f);
  const Eigen::Vector3f dusk_ambient(0.32f, 0.22f, 0.2f);
  Eigen::Vector3f amb = Mix(Mix(day_ambient, dusk_ambient, low_sun * 0.8f), grey_ambient, l.clouds * 0.6f) *
                        (0.45f + 0.55f * Smooth(0.0f, 50.0f, alt)) * (1.0f - 0.35f * rain);
  l.ambient = Mix(night_ambient, amb, day);
  const Eigen::Vector3f zenith_day(0.16f, 0.33f, 0.72f), horizon_day(0.62f, 0.74f, 0.9f);
  const Eigen::Vector3f zenith_dusk(0.2f, 0.22f, 0.42f), horizon_dusk(0.95f, 0.5f, 0.25f);
  const Eigen::Vector3f grey(0.55f, 0.57f, 0.6f), night_sky(0.004f, 0.006f, 0.016f);
  Eigen::Vector3f zen = Mix(Mix(zenith_day, zenith_dusk, low_sun), grey * (0.5f + 0.5f * day), l.clouds * 0.85f);
  Eigen::Vector3f hor = Mix(Mix(horizon_day, horizon_dusk, low_sun), grey * 1.1f, l.clouds * 0.85f);
  l.sky_zenith = Mix(night_sky, zen * (1.0f - 0.4f * rain), day);
  l.sky_horizon = Mix(night_sky * 2.0f, hor * (1.0f - 0.4f * rain), day);
  const Eigen::Vector3f dust_color(0.55f, 0.42f, 0.28f);
  l.sky_zenith = Mix(l.sky_zenith, dust_color * (0.2f + 0.8f * day), dust);
  l.sky_horizon = Mix(l.sky_horizon, dust_color * (0.2f + 0.8f * day), dust);
  l.fog_color = l.sky_horizon;
  l.fog_extinction = std::max(0.0f, w.fog_density) * 4e-4f + dust * 0.04f + rain * 0.006f;
  l.fog_start = std::max(0.0f, w.fog_distance);
  l.fog_height_falloff = std::max(0.0f, w.fog_falloff) * 0.2f;
  l.rain = rain;
  l.rain_slant = std::clamp(w.wind_intensity / 100.0f, 0.0f, 1.0f) * 0.5f;
  l.wetness = std::clamp(std::max(w.wetness, w.precipitation) / 100.0f, 0.0f, 1.0f);
  l.puddles = std::clamp(w.precipitation_deposits / 100.0f, 0.0f, 1.0f);
  l.night = alt < 0.0f;
  return l;
}

}  // namespace lockstep::render
