#include "lockstep/map/geo.h"

#include <cmath>
#include <numbers>
#include <sstream>

namespace lockstep::map {
namespace {
constexpr double kEarthRadius = 6378137.0;  // m, equatorial (carla::geom::GeoLocation)
constexpr double kDeg = std::numbers::pi / 180.0;

// CARLA's LatLonToMercator, scaled at the reference latitude.
double Scale(const GeoReference& ref) { return std::cos(ref.latitude * kDeg); }
double MercatorX(double scale, double longitude) { return scale * longitude * kDeg * kEarthRadius; }
double MercatorY(double scale, double latitude) {
  return scale * kEarthRadius * std::log(std::tan((90.0 + latitude) * std::numbers::pi / 360.0));
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

GeoPoint ToGeo(const GeoReference& ref, const Eigen::Vector3d& enu) {
  // CARLA: LatLonToMercator at the reference, add (x, -y_unreal) = (x, y_enu) metres, back.
  const double scale = Scale(ref);
  const double mx = MercatorX(scale, ref.longitude) + enu.x();
  const double my = MercatorY(scale, ref.latitude) + enu.y();
  GeoPoint p;
  p.longitude = mx * 180.0 / (std::numbers::pi * kEarthRadius * scale);
  p.latitude = 360.0 * std::atan(std::exp(my / (kEarthRadius * scale))) / std::numbers::pi - 90.0;
  p.altitude = ref.altitude + enu.z();
  return p;
}

Eigen::Vector3d FromGeo(const GeoReference& ref, const GeoPoint& geo) {
  const double scale = Scale(ref);
  return {MercatorX(scale, geo.longitude) - MercatorX(scale, ref.longitude),
          MercatorY(scale, geo.latitude) - MercatorY(scale, ref.latitude), geo.altitude - ref.altitude};
}

}  // namespace lockstep::map
