#pragma once
#include <vector>

#include "lockstep/map/map.h"
#include "lockstep/map/mesh.h"

namespace lockstep::map {

struct RoadMeshOptions {
  double straight_step_m = 10.0;  // sample spacing on straight, constant-width stretches
  double curve_step_m = 2.0;      // on curves and where widths change
  double curb_height_m = 0.15;    // sidewalks are raised by this much, with curb faces
  double marking_lift_m = 0.02;   // paint sits this far above the road surface
  double dash_length_m = 3.0;     // broken lines: dash and gap
  double dash_gap_m = 6.0;
  // Zebra crossings where a road with sidewalks enters a junction (crossings.h): where
  // ground_sim's walkers cross; CARLA's towns have them painted, their OpenDRIVE files not.
  bool junction_crosswalks = true;
  double junction_crosswalk_width_m = 3.0;  // along the road
};

// Per road: "road_<id>" (Roads: driving, shoulder, parking, ...), "sidewalk_<id>"
// (SideWalks, raised with curbs), "verge_<id>" (Terrain: borders, medians) and
// "markings_<id>" (RoadLine). Empty meshes are left out. Instance ids start at
// `first_instance_id` and increase by one per mesh.
std::vector<Mesh> BuildRoadMeshes(const Map& map, const RoadMeshOptions& options = {},
                                  std::uint32_t first_instance_id = 1);

}  // namespace lockstep::map
