#pragma once
// CARLA's WeatherParameters (same fields, same ranges) and the lighting the renderer
// derives from them: sun direction and colour, sky, ambient, fog, rain, wetness, dust.
#include <string>
#include <vector>

#include "lockstep/render/types.h"

namespace lockstep::render {

struct Weather {
  float cloudiness = 5;              // 0..100
  float precipitation = 0;           // 0..100
  float precipitation_deposits = 0;  // 0..100: puddles
  float wind_intensity = 10;         // 0..100: slants the rain
  float sun_azimuth_angle = 0;       // deg; CARLA's -1 (unset) reads as 0
  float sun_altitude_angle = 45;     // deg, -90..90
  float fog_density = 2;             // 0..100
  float fog_distance = 0.75f;        // m, fog starts here
  float fog_falloff = 0.1f;          // >= 0: higher keeps the fog lower
  float wetness = 0;                 // 0..100
  float scattering_intensity = 1;
  float mie_scattering_scale = 0.03f;
  float rayleigh_scattering_scale = 0.0331f;
  float dust_storm = 0;              // 0..100
};

// CARLA's presets (carla_constants.json) by name, e.g. "ClearNoon", "HardRainSunset", "ClearNight".
// Throws std::invalid_argument naming the preset if unknown.
Weather WeatherPreset(const std::string& name);
std::vector<std::string> WeatherPresetNames();

// What the shaders need, in linear RGB.
struct Lighting {
  Eigen::Vector3f sun_direction;   // unit, world, towards the sun
  Eigen::Vector3f sun_color;       // direct light (0 at night)
  Eigen::Vector3f ambient;         // sky light on an upward surface
  Eigen::Vector3f sky_zenith, sky_horizon;
  Eigen::Vector3f fog_color;
  float fog_extinction = 0;        // 1/m at ground level
  float fog_start = 0;             // m
  float fog_height_falloff = 0;    // 1/m
  float rain = 0;                  // 0..1 streak density
  float rain_slant = 0;            // streak slant from the wind
  float wetness = 0;               // 0..1: darker, glossier surfaces
  float puddles = 0;               // 0..1: share of the road under water
  float clouds = 0;                // 0..1
  bool night = false;              // street lamps and vehicle lights on
};

Lighting ComputeLighting(const Weather& w);

}  // namespace lockstep::render
