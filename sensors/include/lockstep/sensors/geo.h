#pragma once
// Geo reference and CARLA's local-to-geodetic conversion (carla::geom::GeoLocation::
// Transform, 0.9.x): a Mercator projection scaled at the reference latitude. Also the
// standard atmosphere and dipole magnetic field of AirSim's EarthUtils.
#include <string>

#include "lockstep/sensors/types.h"

namespace lockstep::sensors {

struct GeoReference {
  double latitude = 0;   // deg
  double longitude = 0;  // deg
  double altitude = 0;   // m
};

struct GeoPoint {
  double latitude = 0;   // deg
  double longitude = 0;  // deg
  double altitude = 0;   // m
};

// +lat_0 / +lon_0 of an OpenDRIVE header's PROJ string (CARLA reads only these two);
// missing ones are 0, as in CARLA.
GeoReference ParseGeoReference(const std::string& proj);
// Map point (ENU, m) to latitude / longitude / altitude as CARLA computes it.
GeoPoint ToGeo(const GeoReference& ref, const Vec3& enu);

// AirSim's standard atmosphere: pressure (Pa) at a geometric altitude (m), and the
// pressure altitude (m) its barometer reports for a pressure.
double StandardPressure(double altitude_m);
double PressureAltitude(double pressure_pa);

// AirSim's tilted-dipole Earth field at a geo point, gauss, in ENU.
Vec3 MagneticFieldEnu(const GeoPoint& p);

}  // namespace lockstep::sensors
