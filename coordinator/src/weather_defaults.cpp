#include "weather_defaults.h"

namespace lockstep {

msg::WeatherParameters DefaultWeather() {
  // CARLA's ClearNoon.
  msg::WeatherParameters w;
  w.cloudiness(5);
  w.precipitation(0);
  w.precipitation_deposits(0);
  w.wind_intensity(10);
  w.sun_azimuth_angle(-1);
  w.sun_altitude_angle(45);
  w.fog_density(2);
  w.fog_distance(0.75f);
  w.fog_falloff(0.1f);
  w.wetness(0);
  w.scattering_intensity(1);
  w.mie_scattering_scale(0.03f);
  w.rayleigh_scattering_scale(0.0331f);
  w.dust_storm(0);
  return w;
}

}  // namespace lockstep
