#pragma once
#include <string>

#include "lockstep/map/map.h"

namespace lockstep::map {

// Summary of a road network, for `lockstep map info <file> [--json]`.
struct MapStats {
  std::string name;
  int roads = 0;                      // all roads, junction connectors included
  int junction_roads = 0;             // connectors (roads inside junctions)
  int junctions = 0;
  int lane_sections = 0;
  int driving_lanes = 0;              // lane graph nodes of type driving
  double road_length_m = 0;           // sum of reference-line lengths, connectors included
  double junction_road_length_m = 0;  // connectors only
  double driving_lane_length_m = 0;   // sum over driving lanes of their length
  double sidewalk_length_m = 0;
  int traffic_lights = 0;             // dynamic signals
  int stop_signs = 0;                 // signal type 206
  int speed_limit_signs = 0;          // signal type 274, or RoadRunner "Speed_*" objects
  int crosswalks = 0;                 // objects of type crosswalk
  int spawn_points = 0;               // Map::SpawnPoints() with the default spacing
  int pedestrian_spawn_points = 0;
  double min_x = 0, min_y = 0, max_x = 0, max_y = 0;  // bounds (m, ENU)
};

MapStats ComputeStats(const Map& map);
std::string StatsToJson(const MapStats& stats);  // one JSON object, one line
std::string StatsToText(const MapStats& stats);  // aligned "key: value" lines

}  // namespace lockstep::map
