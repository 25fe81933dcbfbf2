#pragma once
#include <cstdint>
#include <string>

namespace lockstep::map {

// Town1: like the 2017 CARLA paper's training town (a 5 x 4 grid of streets, >= 2.9 km
// of drivable road, signalised junctions). Town2: like its test town (4 x 3, ~1.4 km).
enum class TownKind { Town1, Town2 };
TownKind ParseTownKind(const std::string& text);  // "town1" | "town2"; throws MapError otherwise

struct GeneratedTown {
  std::string name;        // LockstepTown1 / LockstepTown2
  std::string xodr;        // OpenDRIVE 1.4 text
  std::string scene_yaml;  // scene file (scene.h)
  // What the generator wrote, to check a reader against.
  int roads = 0, junctions = 0, traffic_lights = 0;
  double road_length_m = 0;           // all reference lines, junction connectors included
  double junction_road_length_m = 0;  // connectors only
  double driving_lane_length_m = 0;
};

// Deterministic: the same kind and seed give byte-identical files (seeded mt19937_64,
// fixed number formatting, no clock).
GeneratedTown GenerateTown(TownKind kind, std::uint64_t seed);
// Writes <dir>/<name>.xodr and <dir>/<name>.scene.yaml (creates dir).
void WriteTownFiles(const GeneratedTown& town, const std::string& dir);

}  // namespace lockstep::map
