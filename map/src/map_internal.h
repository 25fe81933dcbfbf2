#pragma once
// Internals shared by the map's translation units; not installed.
#include <cstdint>
#include <memory>
#include <vector>

#include <Eigen/Core>

#include "lockstep/map/map.h"

namespace lockstep::map {

// A straight piece of one lane's centre line, between two samples.
struct LaneSegment {
  double ax, ay, bx, by;  // endpoints (m)
  double s0, s1;          // road s at a and b
  float half_width;       // max half lane width over the piece (m)
  int node;               // lane graph node
};

// Uniform grid over lane-centre segments. A segment is listed in every cell its
// bounding box (grown by its half width) touches, so a point inside a lane finds that
// lane in its own cell, and ring search finds the nearest centre line.
class SegmentIndex {
 public:
  std::vector<LaneSegment> segments;
  double x0 = 0, y0 = 0, cell = 8.0;
  int nx = 0, ny = 0;
  std::vector<std::uint32_t> cell_start;  // CSR offsets, nx*ny+1
  std::vector<std::uint32_t> items;       // segment ids
};

std::unique_ptr<SegmentIndex> BuildSegmentIndex(const Map& map, Eigen::Vector2d* bmin, Eigen::Vector2d* bmax);

// Road s nearest to (x, y) near `s_seed` (Newton on the reference line), clamped to [lo, hi].
double ProjectToReference(const Road& road, double x, double y, double s_seed, double lo, double hi);

// s samples covering [s0, s1]: geometry boundaries plus steps no longer than `max_step`
// on straight records and `curve_step` on curved ones.
std::vector<double> SampleStations(const Road& road, double s0, double s1, double max_step, double curve_step);

}  // namespace lockstep::map
