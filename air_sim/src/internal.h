// Internal pieces shared by world.cpp and dynamics.cpp.
#pragma once

#include <vector>

#include "lockstep/air/world.h"

namespace lockstep::air::detail {

// One physics sub-step of one drone: rotors (lag), forces (thrust, torque, drag, gravity),
// integration, contacts, landed state, collision events, non-finite reset.
// t = sim time at the start of the sub-step; t_tick = time since the tick start (for vehicle
// extrapolation). Motor commands are in s->rotors[i].command.
void PhysicsSubstep(const World& model, const DroneModel& dm, DroneState* s, const Environment& env,
                    double t, double t_tick, double h, std::uint64_t frame,
                    std::vector<AirEvent>* events);

// Resets a drone to its spawn pose, disarmed, motors off (non-finite recovery).
void ResetToSpawn(const DroneModel& dm, DroneState* s);

std::uint64_t NextRandom(RandomState* r);
double NextGaussian(RandomState* r);
RandomState SeedRandom(std::uint64_t seed, std::uint64_t stream);

}  // namespace lockstep::air::detail
