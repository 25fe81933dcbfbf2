#pragma once
// The immutable part of a ground world: the road network, its static meshes (collision),
// the traffic lights with the lanes they govern, and spawn points. Shared by worlds.
#include <cstdint>
#include <map>
#include <memory>
#include <string>
#include <tuple>
#include <vector>

#include "lockstep/map/map.h"
#include "lockstep/map/mesh.h"
#include "lockstep/map/scene.h"
#include "lockstep/ground/walker_graph.h"

namespace lockstep::ground {

struct TownLight {
  map::TrafficLightInfo info;
  int group = 0;                      // lights of one junction cycle together
};

class Town {
 public:
  // meshes: the static collision (map::BuildWorldMeshes or hand-made for tests).
  Town(map::Map map, std::vector<map::Mesh> meshes);
  // The map's roads and a scene (buildings, poles, ...) as the other services build them.
  static std::shared_ptr<const Town> Build(map::Map map, const map::Scene& scene);
  static std::shared_ptr<const Town> Load(const std::string& xodr_path, uint64_t scene_seed);

  const map::Map& Map() const { return map_; }
  const std::vector<map::Mesh>& Meshes() const { return meshes_; }
  // In the coordinator's order: light i is actor i + 1.
  const std::vector<TownLight>& Lights() const { return lights_; }
  int GroupCount() const { return group_count_; }
  // Index of the light governing the lane (road, section, lane) at its exit, or -1.
  int LightOfLane(int road, int section, int lane) const;
  // Stop (type "206") and yield ("205") signs of the map with their stop lines.
  const std::vector<map::TrafficLightInfo>& Signs() const { return signs_; }
  // Index into Signs() of the sign governing the lane at its exit, or -1.
  int SignOfLane(int road, int section, int lane) const;
  // Speed (m/s) of the last speed-limit sign on the waypoint's road behind it in its
  // travel direction, NaN if none. Vehicles keep the last sign they passed (CARLA's
  // speed-limit trigger boxes set the vehicle's limit; 30 km/h until the first).
  double SignSpeedLimit(const map::Waypoint& wp) const;
  // Every crossing walkers use: the map's crosswalk objects, then those derived at
  // junction mouths (WalkerGraph::Crossings()).
  const std::vector<TownCrosswalk>& Crosswalks() const { return walker_graph_.Crossings(); }
  // The pedestrian navigation graph (sidewalks and crossings).
  const WalkerGraph& WalkerNav() const { return walker_graph_; }
  const std::vector<map::Transform>& SpawnPoints() const { return spawn_points_; }
  const std::vector<map::Transform>& WalkerSpawnPoints() const { return walker_spawn_points_; }
  uint64_t Hash() const { return hash_; }

 private:
  map::Map map_;
  std::vector<map::Mesh> meshes_;
  std::vector<TownLight> lights_;
  int group_count_ = 0;
  std::map<std::tuple<int, int, int>, int> lane_light_;
  std::vector<map::TrafficLightInfo> signs_;
  WalkerGraph walker_graph_;
  std::map<std::tuple<int, int, int>, int> lane_sign_;
  std::vector<map::Transform> spawn_points_;
  std::vector<map::Transform> walker_spawn_points_;
  uint64_t hash_ = 0;
};

}  // namespace lockstep::ground
