#pragma once
// Town01 with traffic for the render benchmark and the sample images.
#include <string>
#include <vector>

#include "lockstep/map/map.h"
#include "lockstep/map/scene.h"
#include "lockstep/render/renderer.h"

namespace lockstep::render::bench {

struct Town {
  map::Map map;
  map::Scene scene;
  WorldView world;
  Pose ego;    // the first vehicle
  Pose drone;  // a drone 25 m above the road ahead of the ego
  std::uint32_t drone_id = 0;
};

// Loads Town01 into `r` with `vehicles` cars and 30 pedestrians at the scene's spawn points.
Town LoadTown(Renderer& r, int vehicles);
// The ego's dash camera (CARLA's usual: 1.5 m forward, 2.4 m above the ground).
Pose DashCamera(const Town& t);

}  // namespace lockstep::render::bench
