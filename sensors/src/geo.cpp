#include "lockstep/sensors/geo.h"

#include <cmath>

namespace lockstep::sensors {

namespace {
constexpr double kDeg = M_PI / 180.0;

double Geopotential(double altitude_km) {
  constexpr double kRadiusKm = 6356.766;
  return kRadiusKm * altitude_km / (kRadiusKm + altitude_km);
}
double StandardTemperature(double h) {  // K at geopotential height h (km)
  if (h <= 11) return 288.15 - 6.5 * h;
  if (h <= 20) return 216.65;
  if (h <= 32) return 196.65 + h;
  if (h <= 47) return 228.65 + 2.8 * (h - 32);
  return 270.65;
}
}  // namespace

double StandardPressure(double altitude_m) {
  if (altitude_m < 0) altitude_m = 0;  // AirSim clamps below sea level
  const double h = Geopotential(altitude_m / 1000.0);
  const double t = StandardTemperature(h);
  if (h <= 11) return 101325.0 * std::pow(288.15 / t, -5.255877);
  if (h <= 20) return 22632.06 * std::exp(-0.1577 * (h - 11));
  if (h <= 32) return 5474.889 * std::pow(216.65 / t, 34.16319);
  if (h <= 47) return 868.0187 * std::pow(228.65 / t, 12.2011);
  return 110.9063 * std::exp(-0.1262 * (h - 47));
}

double PressureAltitude(double pressure_pa) { return (1.0 - std::pow(pressure_pa / 101325.0, 0.190284)) * 145366.45 * 0.3048; }

Vec3 MagneticFieldEnu(const GeoPoint& g) {
  constexpr double kMagPoleLat = 80.31 * kDeg;
  constexpr double kMagPoleLon = -72.62 * kDeg;
  constexpr double kMeanField = 3.12e-5;  // T
  constexpr double kEarthRadius = 6378137.0;
  const double lat = g.latitude * kDeg;  // AirSim treats it as the colatitude: kept as is
  const double lon = g.longitude * kDeg;
  const double radius = g.altitude + kEarthRadius;
  const double mag_clat = std::acos(std::cos(lat) * std::cos(kMagPoleLat) + std::sin(lat) * std::sin(kMagPoleLat) * std::cos(lon - kMagPoleLon));
  const double cos_mag_clat = std::cos(mag_clat);
  const double field = kMeanField * std::pow(kEarthRadius / radius, 3) * std::sqrt(1 + 3 * cos_mag_clat * cos_mag_clat);
  const double lat_test = std::sin(kMagPoleLat) * std::sin(lat);
  const double dec_factor = std::cos(kMagPoleLat) / std::sin(mag_clat);
  const double declination = cos_mag_clat > lat_test ? std::asin(std::sin(lon - kMagPoleLon) * dec_factor)
                                                     : std::asin(std::cos(lon - kMagPoleLon) * dec_factor);
  const double inclination = std::atan(2.0 / std::tan(mag_clat));
  const double horizontal = field * std::cos(inclination);
  // AirSim's result is NED (north, east, down) in tesla; ENU in gauss here.
  const double north = horizontal * std::cos(declination), east = horizontal * std::sin(declination);
  const double down = field * std::sin(inclination);
  return Vec3(east, north, -down) * 1e4;
}

}  // namespace lockstep::sensors
