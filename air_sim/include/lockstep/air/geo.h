// The map's geo-reference for AirSim's GPS calls (getMultirotorState.gps_location, moveToGPS):
// the OpenDRIVE header's PROJ string (+lat_0, +lon_0) with CARLA's projection (a Mercator
// scaled at the reference latitude, as carla::geom::GeoLocation and the sensors' GNSS do).
#pragma once

#include <string>

#include "lockstep/air/types.h"

namespace lockstep::air {

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

// Reads +lat_0 / +lon_0 from a PROJ string; missing or unparsable values stay 0 (CARLA).
GeoReference ParseGeoReference(const std::string& proj);
// World ENU (m) -> geodetic, and back (exact inverse up to rounding).
GeoPoint ToGeo(const GeoReference& ref, const Vec3& enu);
Vec3 FromGeo(const GeoReference& ref, const GeoPoint& geo);

}  // namespace lockstep::air
