#pragma once
#include <vector>

#include <Eigen/Core>

#include "lockstep/map/opendrive.h"

// Evaluation of a road's cross-section: where each lane lies at a given s.
namespace lockstep::map {

double EvalPoly3Sequence(const std::vector<Poly3>& polys, double s, double fallback = 0.0);
// d/ds of EvalPoly3Sequence (0 before the first record and for an empty sequence).
double EvalPoly3SequenceSlope(const std::vector<Poly3>& polys, double s);
// Both at once, from one record lookup (fallback 0).
void EvalPoly3SequenceWithSlope(const std::vector<Poly3>& polys, double s, double* value, double* slope);
double RoadElevation(const Road& road, double s);
double RoadSlope(const Road& road, double s);  // dz/ds
double RoadLaneOffset(const Road& road, double s);
std::size_t FindSection(const Road& road, double s);
double LaneWidth(const Lane& lane, double ds_in_section);
const RoadMark* MarkAt(const Lane& lane, double ds_in_section);

// Lateral extent of one lane at s: t_inner is the border nearer the centre lane.
struct LaneSpan {
  int id = 0;
  double t_inner = 0, t_outer = 0;  // (m), t positive to the left of the reference line
  double Center() const { return 0.5 * (t_inner + t_outer); }
  double Width() const { return t_outer > t_inner ? t_outer - t_inner : t_inner - t_outer; }
};
// Spans of all lanes of a section at road coordinate s, in section.lanes order
// (the centre lane gets a zero-width span at the lane offset).
void LaneSpans(const Road& road, std::size_t section, double s, std::vector<LaneSpan>* out);
// Span of one lane (zero-width span if the id does not exist).
LaneSpan LaneSpanOf(const Road& road, std::size_t section, int lane_id, double s);
// One lane's centre line at road coordinate s, in one pass over the cross-section.
struct LaneCentre {
  double t = 0;      // lateral position of the centre (m, positive left)
  double width = 0;  // lane width (m)
  double dt = 0;     // dt/ds of the centre (the slope of the lateral offset)
};
LaneCentre LaneCentreOf(const Road& road, std::size_t section, int lane_id, double s);
// dt/ds of the lane centre's t at road coordinate s: the laneOffset slope plus the
// width slopes of the lanes inside it and half its own (0 if the id does not exist).
double LaneCenterSlope(const Road& road, std::size_t section, int lane_id, double s);

// World position (ENU) of road coordinate (s, t) and the reference heading there.
Eigen::Vector3d RoadToWorld(const Road& road, double s, double t, double* heading = nullptr);

}  // namespace lockstep::map
