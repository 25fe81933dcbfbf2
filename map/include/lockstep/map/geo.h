#pragma once
// The map's geo reference and CARLA's local-to-geodetic projection
// (carla::geom::GeoLocation::Transform, 0.9.x): a Mercator projection scaled at the
// reference latitude. One copy for every user: the sensors' GNSS and V2X, and air_sim's
// GPS calls (getMultirotorState.gps_location, moveToGPS).
#include <string>

#include <Eigen/Core>

namespace lockstep::map {

struct GeoReference {
  double latitude = 0;   // deg
  double longitude = 0;  // deg
  double altitude = 0;   // m at world z = 0
};

struct GeoPoint {
  double latitude = 0;   // deg
  double longitude = 0;  // deg
  double altitude = 0;   // m
};

// +lat_0 / +lon_0 of an OpenDRIVE header's PROJ string (CARLA reads only these two);
// missing or unparsable values are 0, as in CARLA.
GeoReference ParseGeoReference(const std::string& proj);
// Map point (ENU, m) to latitude / longitude / altitude as CARLA computes it.
GeoPoint ToGeo(const GeoReference& ref, const Eigen::Vector3d& enu);
// The inverse of ToGeo (exact up to rounding).
Eigen::Vector3d FromGeo(const GeoReference& ref, const GeoPoint& geo);

}  // namespace lockstep::map
