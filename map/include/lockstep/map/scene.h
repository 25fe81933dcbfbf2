#pragma once
#include <cstdint>
#include <string>
#include <vector>

namespace lockstep::map {

class Map;

// Static world content placed along a road network. Poses are ENU (m, rad).
struct BuildingInstance {
  int design = 0;              // 0 .. kBuildingDesignCount-1, see buildings.h
  double x = 0, y = 0;         // footprint centre (m)
  double z = 0;                // ground level (m)
  double yaw = 0;              // local +x runs along the street (rad)
  double width = 12, depth = 10;  // footprint extent along local x and y (m)
  int storeys = 2;
  double storey_height = 3.2;  // (m)
};

struct VegetationInstance {
  std::string kind = "tree";   // tree | conifer | bush
  double x = 0, y = 0, z = 0;  // base (m)
  double height = 6, radius = 2;  // (m)
};

// Poles, signs, fences and walls. Linear props (fence, wall) run `length` metres along yaw.
struct PropInstance {
  std::string kind;            // street_light | traffic_light | stop_sign | speed_sign | sign | fence | wall
  double x = 0, y = 0, z = 0, yaw = 0;
  double length = 0, height = 0;  // (m); 0 = kind default
  std::string ref;             // OpenDRIVE signal id for traffic lights and signs
};

struct SpawnPoint {
  double x = 0, y = 0, z = 0, yaw = 0;  // (m, rad)
};

struct Scene {
  std::string map;             // name of the road network it belongs to
  std::uint64_t seed = 0;
  std::vector<BuildingInstance> buildings;
  std::vector<VegetationInstance> vegetation;
  std::vector<PropInstance> props;
  std::vector<SpawnPoint> vehicle_spawn_points;
  std::vector<SpawnPoint> pedestrian_spawn_points;
};

// YAML with fixed number formatting: the same scene always gives the same bytes.
std::string SceneToYaml(const Scene& scene);
// Throws MapError naming the key and line on malformed input.
Scene SceneFromYaml(const std::string& text, const std::string& source = "<memory>");
Scene LoadSceneFile(const std::string& path);

struct SceneOptions {
  double building_density = 0.85;   // probability that a free lot gets a building
  double tree_spacing_m = 14.0;
  double street_light_spacing_m = 32.0;
  double road_end_margin_m = 6.0;   // keep lots this far from road ends (junction mouths)
  double vehicle_spawn_spacing_m = 25.0;
  double pedestrian_spawn_spacing_m = 20.0;
};

// Deterministic scene along the roads of any map: buildings on lots beside the
// outermost lanes, trees and street lights on the sidewalks, poles for every traffic
// light and sign, fences and walls on some lots, and spawn points. seeded mt19937_64 only.
Scene GenerateScene(const Map& map, std::uint64_t seed, const SceneOptions& options = {});

}  // namespace lockstep::map
