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

// 600 m road along +x from x = -100: lanes -1 (y = -1.75) and -2 (y = -5.25) eastbound
// with a broken line between them, lane 1 westbound behind a solid centre line.
inline std::shared_ptr<const Town> TwoLaneTown() {
  static std::shared_ptr<const Town> town = [] {
    const std::string width = "<width sOffset=\"0\" a=\"3.5\" b=\"0\" c=\"0\" d=\"0\"/>";
    const std::string xodr = R"(<?xml version="1.0"?>
<OpenDRIVE><header revMajor="1" revMinor="4" name="twolane"/>
<road name="r" length="600" id="1" junction="-1">
 <planView><geometry s="0" x="-100" y="0" hdg="0" length="600"><line/></geometry></planView>
 <lanes><laneSection s="0">
  <left><lane id="1" type="driving" level="false">)" + width + R"(<roadMark sOffset="0" type="solid" color="standard" width="0.15"/></lane></left>
  <center><lane id="0" type="none" level="false"><roadMark sOffset="0" type="solid" color="yellow" width="0.15"/></lane></center>
  <right><lane id="-1" type="driving" level="false">)" + width + R"(<roadMark sOffset="0" type="broken" color="standard" width="0.15"/></lane>
   <lane id="-2" type="driving" level="false">)" + width + R"(<roadMark sOffset="0" type="solid" color="standard" width="0.15"/></lane></right>
 </laneSection></lanes>
</road></OpenDRIVE>)";
    map::Map m = map::Map::FromString(xodr, "twolane");
    std::vector<map::Mesh> meshes = map::BuildRoadMeshes(m);
    return std::make_shared<const Town>(std::move(m), std::move(meshes));
  }();
  return town;
}

// Road "in" (x 0..100, lanes 1 and -1) ends in junction "J"; its connecting road "c"
// carries lane -1 on to x 160. A stop sign at s 95 on the right of "in" governs lane -1.
inline std::string StopSignXodr() {
  const std::string width = "<width sOffset=\"0\" a=\"3.5\" b=\"0\" c=\"0\" d=\"0\"/>";
  return R"(<?xml version="1.0"?>
<OpenDRIVE><header revMajor="1" revMinor="4" name="stop"/>
<road name="in" length="100" id="in" junction="-1"><link><successor elementType="junction" elementId="J"/></link>
 <planView><geometry s="0" x="0" y="0" hdg="0" length="100"><line/></geometry></planView>
 <lanes><laneSection s="0">
  <left><lane id="1" type="driving" level="false">)" + width + R"(</lane></left>
  <center><lane id="0" type="none" level="false"/></center>
  <right><lane id="-1" type="driving" level="false">)" + width + R"(</lane></right>
 </laneSection></lanes>
 <signals><signal id="stop1" name="Stop" s="95" t="-4" zOffset="0" orientation="+" dynamic="no" country="DE" type="206"
   subtype="-1" value="-1" height="2" width="0.6"/></signals>
</road>
<road name="c" length="60" id="c" junction="J"><link><predecessor elementType="road" elementId="in" contactPoint="end"/></link>
 <planView><geometry s="0" x="100" y="0" hdg="0" length="60"><line/></geometry></planView>
 <lanes><laneSection s="0"><center><lane id="0" type="none" level="false"/></center>
  <right><lane id="-1" type="driving" level="false"><link><predecessor id="-1"/></link>)" + width + R"(</lane></right>
 </laneSection></lanes>
</road>
<junction id="J" name="J"><connection id="0" incomingRoad="in" connectingRoad="c" contactPoint="start">
 <laneLink from="-1" to="-1"/></connection></junction>
</OpenDRIVE>)";
}

inline std::shared_ptr<const Town> StopSignTown() {
  map::Map m = map::Map::FromString(StopSignXodr(), "stop");
  std::vector<map::Mesh> meshes = map::BuildRoadMeshes(m);
  return std::make_shared<Town>(std::move(m), std::move(meshes));
}

// 300 m road along +x from x = -100 (lanes 1 and -1), a crosswalk across it at x = 100
// (3 m wide along the road, 7 m across).
inline std::shared_ptr<const Town> CrosswalkTown() {
  static std::shared_ptr<const Town> town = [] {
    std::string xodr = StraightRoadXodr();
    const std::string cw = R"(<objects><object id="cw" type="crosswalk" s="200" t="0" zOffset="0" hdg="0" length="3" width="7">
  <outline><cornerLocal u="-1.5" v="-3.5" z="0"/><cornerLocal u="1.5" v="-3.5" z="0"/><cornerLocal u="1.5" v="3.5" z="0"/>
  <cornerLocal u="-1.5" v="3.5" z="0"/></outline></object></objects>
</road>)";
    xodr.replace(xodr.find("</road>"), 7, cw);
    map::Map m = map::Map::FromString(xodr, "crosswalk");
    std::vector<map::Mesh> meshes = map::BuildRoadMeshes(m);
    return std::make_shared<const Town>(std::move(m), std::move(meshes));
  }();
  return town;
}

// 5 km road along +x from x = -100 (lanes 1 and -1, as StraightTown without a wall): longer
// than CARLA's actor_active_distance (2 km), so a hero at one end leaves the other dormant.
inline std::shared_ptr<const Town> LongRoadTown() {
  static std::shared_ptr<const Town> town = [] {
    std::string xodr = StraightRoadXodr();
    for (size_t at = xodr.find("length=\"600\""); at != std::string::npos; at = xodr.find("length=\"600\"", at))
      xodr.replace(at, 12, "length=\"5000\"");
    map::Map m = map::Map::FromString(xodr, "long");
    std::vector<map::Mesh> meshes = map::BuildRoadMeshes(m);
    return std::make_shared<const Town>(std::move(m), std::move(meshes));
  }();
  return town;
}

inline std::shared_ptr<const Town> Town01() {
  static std::shared_ptr<const Town> town = Town::Load(std::string(LOCKSTEP_CARLA_MAPS_DIR) + "/Town01.xodr", 42);
  return town;
}

}  // namespace lockstep::ground::testing
