// libFuzzer target: any bytes into the OpenDRIVE reader and the map built from it.
// Malformed input must end in MapError; anything else (crash, sanitizer report, other
// exception) is a bug.
#include <cstddef>
#include <cstdint>
#include <string>

#include "lockstep/map/error.h"
#include "lockstep/map/lane_invasion.h"
#include "lockstep/map/map.h"
#include "lockstep/map/map_info.h"
#include "lockstep/map/road_mesh.h"
#include "lockstep/map/route_planner.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string text(reinterpret_cast<const char*>(data), size);
  try {
    const lockstep::map::Map map = lockstep::map::Map::FromString(text, "fuzz.xodr");
    namespace lm = lockstep::map;
    const auto wps = map.GenerateWaypoints(5.0, lm::LaneType::Any);
    for (std::size_t i = 0; i < wps.size() && i < 16; ++i) {
      const lm::Waypoint& w = wps[i];
      map.Next(w, 7.5);
      map.Previous(w, 3.0);
      map.LeftLane(w);
      map.RightMarking(w);
      map.AllowedLaneChange(w);
      map.SpeedLimit(w);
      map.NearestWaypoint(w.transform.location + Eigen::Vector3d(1.3, -0.7, 0), true, lm::LaneType::Any);
      map.NearestWaypoint(w.transform.location, false, lm::LaneType::Any);
      lm::CrossedLaneMarkings(map, lm::MakeFootprint(w.transform.location.head<2>(), w.transform.yaw, 2, 1),
                              lm::MakeFootprint(w.transform.location.head<2>() + Eigen::Vector2d(0.5, 2), w.transform.yaw, 2, 1));
    }
    if (wps.size() >= 2) lm::PlanRoute(map, wps.front(), wps.back());
    map.Topology();
    map.TrafficLights();
    lm::ComputeStats(map);
    lm::BuildRoadMeshes(map);
  } catch (const lockstep::map::MapError&) {
    // Expected for malformed input.
  }
  return 0;
}
