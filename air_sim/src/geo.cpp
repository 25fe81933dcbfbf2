#include "lockstep/air/geo.h"

#include <cmath>
#include <numbers>
#include <sstream>

namespace lockstep::air {
namespace {
constexpr double kEarthRadius = 6378137.0;  // m, equatorial (carla::geom::GeoLocation)
constexpr double kDeg = std::numbers::pi / 180.0;

// Mercator coordinates (m) of the reference, scaled at its latitude.
void ReferenceMercator(const GeoReference& ref, double* scale, double* mx, double* my) {
  *scale = std::cos(ref.latitude * kDeg);
  *mx = *scale * ref.longitude * kDeg * kEarthRadius;
  *my = *scale * kEarthRadius * std::log(std::tan((90.0 + ref.latitude) * std::numbers::pi / 360.0));
}
}  // namespace

GeoReference ParseGeoReference(const std::string& proj) {
  GeoReference r;
  std::istringstream in(proj);
  std::string token;
  while (in >> token) {
    const auto eq = token.find('=');
    if (eq == std::string::npos) continue;
    const std::string key = token.substr(0, eq);
    try {
      if (key == "+lat_0") r.latitude = std::stod(token.substr(eq + 1));
      if (key == "+lon_0") r.longitude = std::stod(token.substr(eq + 1));
    } catch (const std::exception&) {
      // CARLA leaves an unparsable value at its default too.
    }
  }
  return r;
}

GeoPoint ToGeo(const GeoReference& ref, const Vec3& enu) {
  double scale = 0, mx = 0, my = 0;
  ReferenceMercator(ref, &scale, &mx, &my);
  mx += enu.x();
  my += enu.y();
  GeoPoint p;
  p.longitude = mx * 180.0 / (std::numbers::pi * kEarthRadius * scale);
  p.latitude = 360.0 * std::atan(std::exp(my / (kEarthRadius * scale))) / std::numbers::pi - 90.0;
  p.altitude = ref.altitude + enu.z();
  return p;
}

Vec3 FromGeo(const GeoReference& ref, const GeoPoint& geo) {
  double scale = 0, mx0 = 0, my0 = 0;
  ReferenceMercator(ref, &scale, &mx0, &my0);
  const double mx = scale * geo.longitude * kDeg * kEarthRadius;
  const double my = scale * kEarthRadius * std::log(std::tan((90.0 + geo.latitude) * std::numbers::pi / 360.0));
  return Vec3(mx - mx0, my - my0, geo.altitude - ref.altitude);
}

}  // namespace lockstep::air
