// CARLA's Traffic Manager light stage (update_vehicle_lights): for each vehicle it drives
// with lights updates on, the position lights and low beams follow the sun, heavy rain and
// fog (fog lights too), and the brake lights a hard brake (brake > 0.5) of the TM's control.
// CARLA's thresholds (trafficmanager/Constants.h, VehicleLight); the blinkers, which CARLA
// sets from the route through the next junction, are left as they are.
#include <cmath>

#include "internal.h"

namespace lockstep::ground {
namespace {

// carla.VehicleLightState bits.
constexpr uint32_t kPosition = 0x1, kLowBeam = 0x2, kHighBeam = 0x4, kBrake = 0x8, kFog = 0x80;
constexpr double kSunBeforeDawn = 15.0, kSunAfterSunset = 165.0;      // deg: position and low beams
constexpr double kSunJustAfterDawn = 35.0, kSunJustBeforeSunset = 145.0;  // deg: position lights
constexpr double kHeavyPrecipitation = 80.0, kFogDensity = 20.0;

void SetBit(uint32_t* bits, uint32_t bit, bool on) { *bits = on ? (*bits | bit) : (*bits & ~bit); }

}  // namespace

uint32_t TmLightState(uint32_t current, const LightWeather& w, double brake) {
  bool position = false, low_beam = false, fog = false;
  if (w.sun_altitude_angle < kSunBeforeDawn || w.sun_altitude_angle > kSunAfterSunset) {
    position = low_beam = true;
  } else if (w.sun_altitude_angle < kSunJustAfterDawn || w.sun_altitude_angle > kSunJustBeforeSunset) {
    position = true;
  }
  if (w.precipitation > kHeavyPrecipitation) position = low_beam = true;
  if (w.fog_density > kFogDensity) position = low_beam = fog = true;
  uint32_t bits = current;
  SetBit(&bits, kBrake, brake > 0.5);
  SetBit(&bits, kPosition, position);
  SetBit(&bits, kLowBeam, low_beam);
  SetBit(&bits, kHighBeam, false);
  SetBit(&bits, kFog, fog);
  return bits;
}

void World::Impl::StepVehicleLights() {
  for (auto& [id, v] : vehicles) {
    // CARLA: the vehicles registered with the TM, physics on and not dormant.
    if (!v->autopilot || !v->tm.params.update_lights || !v->simulate_physics || v->kinematic) continue;
    v->light_state = TmLightState(v->light_state, weather, v->control.brake);
  }
}

void World::SetWeather(const LightWeather& w) { impl_->weather = w; }

std::string World::SetUpdateVehicleLights(uint32_t id, bool on) {
  VehicleActor* v = impl_->FindVehicle(id);
  if (!v) return "actor " + std::to_string(id) + " is not a vehicle of ground_sim";
  v->tm.params.update_lights = on;
  return {};
}

}  // namespace lockstep::ground
