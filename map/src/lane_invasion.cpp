#include "lockstep/map/lane_invasion.h"

#include <algorithm>
#include <cmath>

#include "map_internal.h"

namespace lockstep::map {

Footprint MakeFootprint(const Eigen::Vector2d& c, double yaw, double hl, double hw) {
  const Eigen::Vector2d f(std::cos(yaw), std::sin(yaw)), l(-std::sin(yaw), std::cos(yaw));
  return {c + hl * f + hw * l, c + hl * f - hw * l, c - hl * f - hw * l, c - hl * f + hw * l};
}

namespace {

// Lateral coordinate of (x, y) on a road near s_seed; false if it projects past the road's ends.
bool RoadT(const Road& road, double x, double y, double s_seed, double* s_out, double* t_out) {
  const double s = ProjectToReference(road, x, y, s_seed, 0.0, road.length);
  const Pose2 ref = EvaluateReferenceLine(road.plan_view, s);
  const double dx = x - ref.x, dy = y - ref.y;
  if (std::fabs(dx * std::cos(ref.hdg) + dy * std::sin(ref.hdg)) > 0.1) return false;
  *s_out = s;
  *t_out = -dx * std::sin(ref.hdg) + dy * std::cos(ref.hdg);
  return true;
}

}  // namespace

std::vector<CrossedMarking> CrossedLaneMarkings(const Map& map, const Footprint& previous, const Footprint& current) {
  std::vector<CrossedMarking> out;
  std::vector<LaneSpan> spans;
  for (std::size_t k = 0; k < 4; ++k) {
    const Eigen::Vector2d& a = previous[k];
    const Eigen::Vector2d& b = current[k];
    if ((a - b).squaredNorm() < 1e-12) continue;
    const auto lanes_a = map.LanesAt(a.x(), a.y());
    if (lanes_a.empty()) continue;
    // Measure both corners on the road the corner was on: the borders between the two
    // lateral positions are the ones it crossed.
    const LanePoint& lp = lanes_a.front();
    const LaneNode& n = map.Nodes()[static_cast<std::size_t>(lp.node)];
    const Road& road = map.Data().roads[static_cast<std::size_t>(n.road)];
    double sb, tb;
    if (!RoadT(road, b.x(), b.y(), lp.s, &sb, &tb)) continue;
    const double s_mid = 0.5 * (lp.s + sb);
    const std::size_t sec = FindSection(road, s_mid);
    LaneSpans(road, sec, s_mid, &spans);
    const double lo = std::min(lp.t, tb), hi = std::max(lp.t, tb);
    const LaneSection& section = road.sections[sec];
    for (std::size_t i = 0; i < spans.size(); ++i) {
      const Lane& lane = section.lanes[i];
      // Lane i owns its outer border (the centre lane owns the centre line).
      const double border = lane.id == 0 ? spans[i].t_inner : spans[i].t_outer;
      if (border <= lo || border > hi) continue;
      const RoadMark* m = MarkAt(lane, s_mid - section.s);
      if (!m || m->type == RoadMarkType::None) continue;
      CrossedMarking c;
      c.road = n.road;
      c.between_a = lane.id;
      c.between_b = lane.id == 0 ? 0 : (lane.id > 0 ? lane.id + 1 : lane.id - 1);
      if (lane.id == 0) {
        c.between_a = 1;
        c.between_b = -1;
      }
      c.marking.type = m->type;
      c.marking.color = m->color;
      c.marking.width = m->width;
      c.marking.lane_change = m->lane_change == MarkLaneChange::Both ? LaneChange::Both
                              : m->lane_change == MarkLaneChange::None ? LaneChange::None
                              : m->lane_change == MarkLaneChange::Increase ? LaneChange::Left
                                                                           : LaneChange::Right;
      const bool dup = std::any_of(out.begin(), out.end(), [&](const CrossedMarking& o) {
        return o.road == c.road && o.between_a == c.between_a && o.between_b == c.between_b;
      });
      if (!dup) out.push_back(c);
    }
  }
  return out;
}

FootprintOverlap ComputeFootprintOverlap(const Map& map, const Footprint& fp, double yaw, int samples) {
  FootprintOverlap r;
  samples = std::clamp(samples, 1, 64);
  int opposite = 0, offroad = 0, sidewalk = 0, total = 0;
  const Eigen::Vector2d heading(std::cos(yaw), std::sin(yaw));
  for (int i = 0; i < samples; ++i) {
    for (int j = 0; j < samples; ++j) {
      const double u = (i + 0.5) / samples, v = (j + 0.5) / samples;
      // Bilinear point inside the quadrilateral.
      const Eigen::Vector2d p = (1 - u) * ((1 - v) * fp[0] + v * fp[1]) + u * ((1 - v) * fp[3] + v * fp[2]);
      ++total;
      bool on_driving = false, same_dir = false, on_sidewalk = false;
      for (const LanePoint& lp : map.LanesAt(p.x(), p.y())) {
        const LaneNode& n = map.Nodes()[static_cast<std::size_t>(lp.node)];
        if (n.type == LaneType::Sidewalk) on_sidewalk = true;
        if (n.type != LaneType::Driving) continue;
        on_driving = true;
        const double hdg = EvaluateReferenceLine(map.Data().roads[static_cast<std::size_t>(n.road)].plan_view, lp.s).hdg;
        const Eigen::Vector2d lane_dir = (n.Forward() ? 1.0 : -1.0) * Eigen::Vector2d(std::cos(hdg), std::sin(hdg));
        if (lane_dir.dot(heading) > 0) same_dir = true;
      }
      if (!on_driving) {
        ++offroad;
        if (on_sidewalk) ++sidewalk;
      } else if (!same_dir) {
        ++opposite;
      }
    }
  }
  r.opposite_lane = static_cast<double>(opposite) / total;
  r.offroad = static_cast<double>(offroad) / total;
  r.sidewalk = static_cast<double>(sidewalk) / total;
  return r;
}

}  // namespace lockstep::map
