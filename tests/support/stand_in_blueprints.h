#pragma once
// Blueprints for tests that spawn vehicles, walkers and sensors without the services that
// simulate them: a NoopCore declaring these stands in for ground_sim, render and sensors.
#include <vector>

#include "lockstep/msg/blueprint.h"

namespace lockstep::testing {

// vehicle.lockstep.{sedan,...}, walker.pedestrian.0001..0010 and CARLA's sensor.* set.
std::vector<msg::BlueprintDeclaration> StandInBlueprints();

}  // namespace lockstep::testing
