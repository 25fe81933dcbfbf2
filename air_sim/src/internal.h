// Internal pieces shared by world.cpp and dynamics.cpp.
#pragma once

#include <vector>

#include "lockstep/air/world.h"

namespace lockstep::air::detail {

// One physics sub-step of one drone: rotors (lag), forces (thrust, torque, drag, gravity),
// integration, contacts, landed state, collision events, non-finite reset.
// t = sim time at the start of the sub-step; t_tick = time since the tick start (for vehicle
// extrapolation). Motor commands are in s->rotors[i].command.
// Other drones near this one during the tick (indices into model.drones / proximity arrays).
struct Neighbours {
  const WorldState::Proximity* proximity = nullptr;
  const std::uint32_t* begin = nullptr;
  const std::uint32_t* end = nullptr;
};

void PhysicsSubstep(const World& model, const DroneModel& dm, DroneState* s, const Environment& env,
                    const Neighbours& near, double t, double t_tick, double h, std::uint64_t frame,
                    std::vector<AirEvent>* events);

// Rebuilds state->proximity for a tick of dt (sweep and prune along x).
void BuildProximity(const World& model, WorldState* state, double dt);

// Resets a drone to its spawn pose, disarmed, motors off (non-finite recovery).
void ResetToSpawn(const DroneModel& dm, DroneState* s);

std::uint64_t NextRandom(RandomState* r);
double NextGaussian(RandomState* r);
RandomState SeedRandom(std::uint64_t seed, std::uint64_t stream);

}  // namespace lockstep::air::detail
