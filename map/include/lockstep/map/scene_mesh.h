#pragma once
#include <vector>

#include "lockstep/map/map.h"
#include "lockstep/map/mesh.h"
#include "lockstep/map/road_mesh.h"
#include "lockstep/map/scene.h"

namespace lockstep::map {

// One mesh per scene object (instance ids from `first_instance_id` upward), with the
// semantic tag of its class; traffic lights and signs are two meshes (Pole + head).
std::vector<Mesh> BuildSceneMeshes(const Scene& scene, std::uint32_t first_instance_id = 1);

// Everything static in a world: a ground plane (Terrain) under the map, road meshes,
// then scene meshes, with unique instance ids.
std::vector<Mesh> BuildWorldMeshes(const Map& map, const Scene& scene, const RoadMeshOptions& options = {});

}  // namespace lockstep::map
