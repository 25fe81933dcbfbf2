#pragma once
// The weather a run starts with when nobody set one: CARLA's default preset, ClearNoon
// (carla.WeatherParameters.ClearNoon), as every service reads it from WorldInfo.
#include "lockstep/runtime/messages.h"

namespace lockstep {

msg::WeatherParameters DefaultWeather();

}  // namespace lockstep
