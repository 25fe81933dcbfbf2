#include "lockstep/map/road_profile.h"

#include <algorithm>
#include <cmath>

namespace lockstep::map {

double EvalPoly3Sequence(const std::vector<Poly3>& polys, double s, double fallback) {
  if (polys.empty()) return fallback;
  auto it = std::upper_bound(polys.begin(), polys.end(), s, [](double v, const Poly3& p) { return v < p.s; });
  if (it == polys.begin()) return polys.front().Eval(0.0);
  --it;
  return it->Eval(s - it->s);
}

double EvalPoly3SequenceSlope(const std::vector<Poly3>& polys, double s) {
  auto it = std::upper_bound(polys.begin(), polys.end(), s, [](double v, const Poly3& p) { return v < p.s; });
  if (it == polys.begin()) return 0.0;
  --it;
  return it->Slope(s - it->s);
}

double RoadElevation(const Road& road, double s) { return EvalPoly3Sequence(road.elevation, s); }
double RoadSlope(const Road& road, double s) {
  const auto& e = road.elevation;
  auto it = std::upper_bound(e.begin(), e.end(), s, [](double v, const Poly3& p) { return v < p.s; });
  if (it == e.begin()) return 0.0;
  --it;
  return it->Slope(s - it->s);
}
double RoadLaneOffset(const Road& road, double s) { return EvalPoly3Sequence(road.lane_offset, s); }

std::size_t FindSection(const Road& road, double s) {
  const auto& secs = road.sections;
  auto it = std::upper_bound(secs.begin(), secs.end(), s, [](double v, const LaneSection& sec) { return v < sec.s; });
  return it == secs.begin() ? 0 : static_cast<std::size_t>(it - secs.begin() - 1);
}

double LaneWidth(const Lane& lane, double ds) {
  // Negative widths (bad data) would fold lanes over each other; clamp to zero.
  return std::max(0.0, EvalPoly3Sequence(lane.widths, ds));
}

const RoadMark* MarkAt(const Lane& lane, double ds) {
  if (lane.marks.empty()) return nullptr;
  auto it = std::upper_bound(lane.marks.begin(), lane.marks.end(), ds,
                             [](double v, const RoadMark& m) { return v < m.s_offset; });
  if (it == lane.marks.begin()) return &lane.marks.front();
  return &*(it - 1);
}

void LaneSpans(const Road& road, std::size_t section, double s, std::vector<LaneSpan>* out) {
  out->clear();
  if (section >= road.sections.size()) return;
  const LaneSection& sec = road.sections[section];
  const double ds = s - sec.s;
  const double offset = RoadLaneOffset(road, s);
  out->resize(sec.lanes.size());
  const int centre = sec.left_count;
  (*out)[static_cast<std::size_t>(centre)] = LaneSpan{0, offset, offset};
  double t = offset;
  for (int i = centre - 1; i >= 0; --i) {  // left lanes 1..n, outward
    const Lane& l = sec.lanes[static_cast<std::size_t>(i)];
    const double w = LaneWidth(l, ds);
    (*out)[static_cast<std::size_t>(i)] = LaneSpan{l.id, t, t + w};
    t += w;
  }
  t = offset;
  for (std::size_t i = static_cast<std::size_t>(centre) + 1; i < sec.lanes.size(); ++i) {  // right lanes -1..-m
    const Lane& l = sec.lanes[i];
    const double w = LaneWidth(l, ds);
    (*out)[i] = LaneSpan{l.id, t, t - w};
    t -= w;
  }
}

LaneSpan LaneSpanOf(const Road& road, std::size_t section, int lane_id, double s) {
  if (section >= road.sections.size()) return {};
  const LaneSection& sec = road.sections[section];
  const double ds = s - sec.s;
  double t = RoadLaneOffset(road, s);
  if (lane_id == 0 || !sec.Find(lane_id)) return LaneSpan{lane_id, t, t};
  const int step = lane_id > 0 ? 1 : -1;
  for (int id = step;; id += step) {
    const double w = LaneWidth(*sec.Find(id), ds);
    if (id == lane_id) return LaneSpan{id, t, t + step * w};
    t += step * w;
  }
}

void EvalPoly3SequenceWithSlope(const std::vector<Poly3>& polys, double s, double* value, double* slope) {
  if (polys.empty()) {
    *value = 0;
    *slope = 0;
    return;
  }
  auto it = std::upper_bound(polys.begin(), polys.end(), s, [](double v, const Poly3& p) { return v < p.s; });
  if (it == polys.begin()) {
    *value = polys.front().Eval(0.0);
    *slope = 0;
    return;
  }
  --it;
  *value = it->Eval(s - it->s);
  *slope = it->Slope(s - it->s);
}

LaneCentre LaneCentreOf(const Road& road, std::size_t section, int lane_id, double s) {
  LaneCentre out;
  if (section >= road.sections.size()) return out;
  const LaneSection& sec = road.sections[section];
  const double ds = s - sec.s;
  double t, dt;
  EvalPoly3SequenceWithSlope(road.lane_offset, s, &t, &dt);
  out.t = t;
  out.dt = dt;
  if (lane_id == 0 || !sec.Find(lane_id)) return out;
  const int step = lane_id > 0 ? 1 : -1;
  for (int id = step;; id += step) {
    double w, w_slope;
    EvalPoly3SequenceWithSlope(sec.Find(id)->widths, ds, &w, &w_slope);
    if (!(w > 0)) w = w_slope = 0;  // negative widths are clamped to zero (LaneWidth)
    if (id == lane_id) {
      out.t = t + step * 0.5 * w;
      out.dt = dt + step * 0.5 * w_slope;
      out.width = w;
      return out;
    }
    t += step * w;
    dt += step * w_slope;
  }
}

double LaneCenterSlope(const Road& road, std::size_t section, int lane_id, double s) {
  if (section >= road.sections.size()) return 0.0;
  const LaneSection& sec = road.sections[section];
  const double ds = s - sec.s;
  double slope = EvalPoly3SequenceSlope(road.lane_offset, s);
  if (lane_id == 0 || !sec.Find(lane_id)) return slope;
  const int step = lane_id > 0 ? 1 : -1;
  for (int id = step;; id += step) {
    const Lane& l = *sec.Find(id);
    // LaneWidth clamps negative widths to zero; a clamped width does not change.
    const double w_slope = EvalPoly3Sequence(l.widths, ds) > 0 ? EvalPoly3SequenceSlope(l.widths, ds) : 0.0;
    if (id == lane_id) return slope + step * 0.5 * w_slope;
    slope += step * w_slope;
  }
}

Eigen::Vector3d RoadToWorld(const Road& road, double s, double t, double* heading) {
  const Pose2 p = EvaluateReferenceLine(road.plan_view, s);
  if (heading) *heading = p.hdg;
  return {p.x - t * std::sin(p.hdg), p.y + t * std::cos(p.hdg), RoadElevation(road, s)};
}

}  // namespace lockstep::map
