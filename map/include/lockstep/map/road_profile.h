#pragma once
#include <vector>

#include <Eigen/Core>

#include "lockstep/map/opendrive.h"

// Evaluation of a road's cross-section: where each lane lies at a given s.
namespace lockstep::map {

double EvalPoly3Sequence(const std::vector<Poly3>& polys, double s, double fallback = 0.0);
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

// World position (ENU) of road coordinate (s, t) and the reference heading there.
Eigen::Vector3d RoadToWorld(const Road& road, double s, double t, double* heading = nullptr);

}  // namespace lockstep::map
