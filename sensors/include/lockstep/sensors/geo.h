#pragma once
// The geo reference and CARLA's local-to-geodetic conversion (lockstep/map/geo.h, one copy
// for the sensors and air_sim), and the standard atmosphere and dipole magnetic field of
// AirSim's EarthUtils.
#include "lockstep/map/geo.h"
#include "lockstep/sensors/types.h"

namespace lockstep::sensors {

// The map's geo reference and CARLA's projection (lockstep/map/geo.h).
using map::GeoPoint;
using map::GeoReference;
using map::ParseGeoReference;
using map::ToGeo;

// AirSim's standard atmosphere: pressure (Pa) at a geometric altitude (m), and the
// pressure altitude (m) its barometer reports for a pressure.
double StandardPressure(double altitude_m);
double PressureAltitude(double pressure_pa);

// AirSim's tilted-dipole Earth field at a geo point, gauss, in ENU.
Vec3 MagneticFieldEnu(const GeoPoint& p);

}  // namespace lockstep::sensors
