#pragma once
#include <array>
#include <vector>

#include <Eigen/Core>

#include "lockstep/map/map.h"

namespace lockstep::map {

// A vehicle footprint: the four bounding-box corners on the ground (ENU, m), in order
// around the box (front-left, front-right, rear-right, rear-left).
using Footprint = std::array<Eigen::Vector2d, 4>;
Footprint MakeFootprint(const Eigen::Vector2d& centre, double yaw, double half_length, double half_width);

struct CrossedMarking {
  int road = -1;        // road index
  int between_a = 0;    // lane ids on either side of the border
  int between_b = 0;
  LaneMarking marking;
};

// Lane markings crossed by any corner between the previous and the current frame
// (CARLA's lane invasion sensor). Borders whose marking type is None are not reported.
std::vector<CrossedMarking> CrossedLaneMarkings(const Map& map, const Footprint& previous, const Footprint& current);

// Share of the footprint on a driving lane of the opposite direction and off the
// drivable road (sidewalk or no lane): CARLA 2017 benchmark's intersection_otherlane
// and intersection_offroad. Sampled on a grid of `samples` x `samples` points.
struct FootprintOverlap {
  double opposite_lane = 0;  // fraction in [0, 1]
  double offroad = 0;        // fraction in [0, 1] (sidewalk + outside any lane)
  double sidewalk = 0;       // fraction in [0, 1]
};
FootprintOverlap ComputeFootprintOverlap(const Map& map, const Footprint& footprint, double yaw, int samples = 8);

}  // namespace lockstep::map
