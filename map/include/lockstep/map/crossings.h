#pragma once
// Pedestrian crossings at junction mouths. CARLA's towns have painted crosswalks where a
// road enters a junction, but Town01 and Town02's OpenDRIVE files carry no crosswalk
// objects: the walkers' graph (ground_sim) and the painted zebras (road meshes) both
// derive them here, so walkers cross where the cameras show a crossing.
#include <vector>

#include <Eigen/Core>

#include "lockstep/map/map.h"

namespace lockstep::map {

struct MouthCrossing {
  int road = -1;     // index into MapData::roads (not a junction's connecting road)
  int section = -1;  // the road's lane section at the junction end
  bool at_end = false;  // the road's end (successor) enters the junction, else its start
  std::vector<int> driving_lanes;  // lane ids crossed
  // Kerb to kerb: the centres of the innermost sidewalk lanes on both sides of the road
  // end (positive lane id side first), moved `setback` metres into the junction, or less
  // where that would stand on a driving lane.
  Eigen::Vector3d ends[2] = {Eigen::Vector3d::Zero(), Eigen::Vector3d::Zero()};
  Eigen::Vector3d into_junction = Eigen::Vector3d::UnitX();  // horizontal unit vector
};

// One per road end that enters a junction and has a sidewalk on both sides and no crosswalk
// object of the map within 10 m, in road order (start before end).
std::vector<MouthCrossing> JunctionMouthCrossings(const Map& m, double setback = 2.0);

// Whether the horizontal point stands on a driving lane of the map (junctions included).
bool OnDrivingLane(const Map& m, const Eigen::Vector3d& p);

}  // namespace lockstep::map
