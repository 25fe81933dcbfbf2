#pragma once
// Towns for the ground core tests: a straight two-lane road (optionally a wall across it)
// and CARLA's Town01, each built once per test process.
#include <memory>
#include <string>

#include "lockstep/ground/town.h"
#include "lockstep/map/road_mesh.h"

namespace lockstep::ground::testing {

// 600 m road along +x from x = -100, lanes -1 (eastbound, y = -1.75) and 1, a solid centre line.
inline std::string StraightRoadXodr() {
  return R"(<?xml version="1.0"?>
<OpenDRIVE><header revMajor="1" revMinor="4" name="straight"/>
<road name="r" length="600" id="1" junction="-1">
 <planView><geometry s="0" x="-100" y="0" hdg="0" length="600"><line/></geometry></planView>
 <lanes><laneSection s="0">
  <left><lane id="1" type="driving" level="false"><width sOffset="0" a="3.5" b="0" c="0" d="0"/>
    <roadMark sOffset="0" type="solid" color="standard" width="0.15"/></lane></left>
  <center><lane id="0" type="none" level="false"><roadMark sOffset="0" type="solid" color="yellow" width="0.15"/></lane></center>
  <right><lane id="-1" type="driving" level="false"><width sOffset="0" a="3.5" b="0" c="0" d="0"/>
    <roadMark sOffset="0" type="solid" color="standard" width="0.15"/></lane></right>
 </laneSection></lanes>
</road></OpenDRIVE>)";
}

// wall_x: a 20 m wide, 3 m high wall across the road at this x (none if NaN).
inline std::shared_ptr<const Town> StraightTown(double wall_x = std::nan("")) {
  map::Map m = map::Map::FromString(StraightRoadXodr(), "straight");
  std::vector<map::Mesh> meshes = map::BuildRoadMeshes(m);
  if (!std::isnan(wall_x)) {
    map::Mesh wall;
    wall.name = "wall";
    wall.semantic_tag = map::semantic::kWall;
    map::AddBox(wall, Eigen::Vector3d(wall_x, 0, 0), 0.5, 20, 3, 0);
    meshes.push_back(std::move(wall));
  }
  return std::make_shared<Town>(std::move(m), std::move(meshes));
}

inline std::shared_ptr<const Town> Town01() {
  static std::shared_ptr<const Town> town = Town::Load(std::string(LOCKSTEP_CARLA_MAPS_DIR) + "/Town01.xodr", 42);
  return town;
}

}  // namespace lockstep::ground::testing
