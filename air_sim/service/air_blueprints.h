#pragma once
// What air_sim declares on lockstep/blueprints (the drones it simulates) and its own check
// of a drone spawn: the parameters a declaration cannot express as a combination.
#include <string>
#include <vector>

#include "lockstep/air/params.h"
#include "lockstep/msg/blueprint.h"
#include "lockstep/msg/command.h"

namespace lockstep {

// drone.generic_quad, drone.quad_plus, drone.hexa_x: role_name and every multirotor
// parameter air::VisitParams names, each settable at spawn.
std::vector<msg::BlueprintDeclaration> AirBlueprints();

// The drone parameters of a spawn, as air_sim builds them (the blueprint picks the default
// frame). Throws std::invalid_argument naming the key on bad input.
air::MultirotorParams AirSpawnParams(const msg::SpawnActor& spawn);

// Empty if air_sim can fly the spawn, else why not ("drone parameters: mass: ...").
std::string CheckAirSpawn(const msg::SpawnActor& spawn);

}  // namespace lockstep
