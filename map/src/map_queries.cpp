// Spatial index and point queries: nearest waypoint, lanes containing a point.
#include <algorithm>
#include <cmath>
#include <limits>

#include "lockstep/map/map.h"
#include "map_internal.h"

namespace lockstep::map {

std::vector<double> SampleStations(const Road& road, double s0, double s1, double max_step, double curve_step) {
  std::vector<double> out;
  if (!(s1 > s0)) {
    out.push_back(s0);
    out.push_back(s0);
    return out;
  }
  double s = s0;
  out.push_back(s);
  const bool wavy_offset = std::any_of(road.lane_offset.begin(), road.lane_offset.end(),
                                       [](const Poly3& p) { return p.c != 0 || p.d != 0; });
  while (s < s1 - 1e-9) {
    const std::size_t gi = FindGeometry(road.plan_view, s + 1e-9);
    const Geometry& g = road.plan_view[gi];
    const bool straight = g.kind == GeometryKind::Line ||
                          (g.kind == GeometryKind::Arc && std::fabs(g.curvature) < 1e-9);
    const double step = (straight && !wavy_offset) ? max_step : curve_step;
    double next = s + step;
    const double g_end = gi + 1 < road.plan_view.size() ? road.plan_view[gi + 1].s : road.length;
    if (g_end > s + 1e-6 && g_end < next) next = g_end;
    if (next > s1) next = s1;
    s = next;
    out.push_back(s);
  }
  return out;
}

double ProjectToReference(const Road& road, double x, double y, double s, double lo, double hi) {
  for (int it = 0; it < 4; ++it) {
    const Pose2 p = EvaluateReferenceLine(road.plan_view, s);
    const double c = std::cos(p.hdg), sn = std::sin(p.hdg);
    const double dx = x - p.x, dy = y - p.y;
    const double along = dx * c + dy * sn;
    const double normal = -dx * sn + dy * c;
    double denom = 1.0 - p.curvature * normal;
    if (denom < 0.2) denom = 0.2;  // near the centre of curvature the projection is ill-posed
    const double next = std::clamp(s + along / denom, lo, hi);
    if (std::fabs(next - s) < 1e-6) return next;
    s = next;
  }
  return s;
}

// Lanes wider than this (only in broken files) are indexed as if this wide, so one
// segment cannot fill the whole grid.
constexpr double kMaxIndexedHalfWidth = 100.0;

std::unique_ptr<SegmentIndex> BuildSegmentIndex(const Map& map, Eigen::Vector2d* bmin, Eigen::Vector2d* bmax) {
  auto idx = std::make_unique<SegmentIndex>();
  const OpenDrive& od = map.Data();
  double total = 0;
  for (const LaneNode& n : map.Nodes()) total += n.Length();
  // Bound the sample count so hostile files with huge roads stay cheap.
  const double scale = std::max(1.0, total / 400000.0);
  double minx = std::numeric_limits<double>::infinity(), miny = minx, maxx = -minx, maxy = -minx;
  std::vector<LaneSpan> spans;
  for (std::size_t ni = 0; ni < map.Nodes().size(); ++ni) {
    const LaneNode& n = map.Nodes()[ni];
    const Road& road = od.roads[static_cast<std::size_t>(n.road)];
    const std::vector<double> st = SampleStations(road, n.s_begin, n.s_end, 5.0 * scale, 1.0 * scale);
    double px = 0, py = 0, pw = 0;
    for (std::size_t k = 0; k < st.size(); ++k) {
      const LaneCentre span = LaneCentreOf(road, static_cast<std::size_t>(n.section), n.lane, st[k]);
      const Eigen::Vector3d p = RoadToWorld(road, st[k], span.t);
      if (!p.allFinite() || p.head<2>().cwiseAbs().maxCoeff() > 1e9) {
        break;  // geometry blew up (hostile input): stop indexing this lane
      }
      const double hw = std::min(0.5 * span.width, kMaxIndexedHalfWidth);
      if (k > 0) {
        idx->segments.push_back(LaneSegment{px, py, p.x(), p.y(), st[k - 1], st[k],
                                            static_cast<float>(std::max(hw, pw)), static_cast<int>(ni)});
      }
      px = p.x();
      py = p.y();
      pw = hw;
      minx = std::min(minx, p.x() - hw);
      maxx = std::max(maxx, p.x() + hw);
      miny = std::min(miny, p.y() - hw);
      maxy = std::max(maxy, p.y() + hw);
    }
  }
  if (idx->segments.empty()) {
    minx = miny = 0;
    maxx = maxy = 1;
  }
  *bmin = {minx, miny};
  *bmax = {maxx, maxy};
  const double margin = 1.0;
  idx->x0 = minx - margin;
  idx->y0 = miny - margin;
  const double w = maxx - minx + 2 * margin, h = maxy - miny + 2 * margin;
  // At most ~2M cells and 4096 per axis, whatever the map's shape.
  idx->cell = std::max({8.0, std::sqrt(w * h / 2.0e6), w / 4096.0, h / 4096.0});
  idx->nx = std::max(1, static_cast<int>(std::ceil(w / idx->cell)));
  idx->ny = std::max(1, static_cast<int>(std::ceil(h / idx->cell)));
  const std::size_t ncell = static_cast<std::size_t>(idx->nx) * static_cast<std::size_t>(idx->ny);
  std::vector<std::uint32_t> counts(ncell + 1, 0);
  auto for_cells = [&](const LaneSegment& s, auto&& fn) {
    const double g = s.half_width + 0.5;
    const int cx0 = std::clamp(static_cast<int>((std::min(s.ax, s.bx) - g - idx->x0) / idx->cell), 0, idx->nx - 1);
    const int cx1 = std::clamp(static_cast<int>((std::max(s.ax, s.bx) + g - idx->x0) / idx->cell), 0, idx->nx - 1);
    const int cy0 = std::clamp(static_cast<int>((std::min(s.ay, s.by) - g - idx->y0) / idx->cell), 0, idx->ny - 1);
    const int cy1 = std::clamp(static_cast<int>((std::max(s.ay, s.by) + g - idx->y0) / idx->cell), 0, idx->ny - 1);
    for (int cy = cy0; cy <= cy1; ++cy)
      for (int cx = cx0; cx <= cx1; ++cx) fn(static_cast<std::size_t>(cy) * static_cast<std::size_t>(idx->nx) + static_cast<std::size_t>(cx));
  };
  for (const LaneSegment& s : idx->segments) for_cells(s, [&](std::size_t c) { ++counts[c + 1]; });
  for (std::size_t c = 0; c < ncell; ++c) counts[c + 1] += counts[c];
  idx->cell_start = counts;
  idx->items.resize(counts[ncell]);
  std::vector<std::uint32_t> fill(counts.begin(), counts.end() - 1);
  for (std::size_t i = 0; i < idx->segments.size(); ++i)
    for_cells(idx->segments[i], [&](std::size_t c) { idx->items[fill[c]++] = static_cast<std::uint32_t>(i); });
  return idx;
}

namespace {

// Squared distance from (x, y) to segment s and the parameter of the foot point.
inline double SegmentDist2(const LaneSegment& s, double x, double y, double* u_out) {
  const double dx = s.bx - s.ax, dy = s.by - s.ay;
  const double len2 = dx * dx + dy * dy;
  double u = len2 > 0 ? ((x - s.ax) * dx + (y - s.ay) * dy) / len2 : 0.0;
  u = std::clamp(u, 0.0, 1.0);
  const double ex = s.ax + u * dx - x, ey = s.ay + u * dy - y;
  *u_out = u;
  return ex * ex + ey * ey;
}

// Grid coordinate of x, clamped to one cell outside the grid (the ring search and the
// containment lookup both work with that), computed in double so it cannot overflow.
inline int CellCoord(double x, double x0, double cell, int n) {
  return static_cast<int>(std::clamp(std::floor((x - x0) / cell), -1.0, static_cast<double>(n)));
}

}  // namespace

std::optional<Waypoint> Map::NearestWaypoint(const Eigen::Vector3d& p, bool project_to_road, LaneTypeMask types) const {
  if (!project_to_road) {
    std::optional<Waypoint> best;
    double best_off = std::numeric_limits<double>::infinity();
    for (const LanePoint& lp : LanesAt(p.x(), p.y())) {
      const LaneNode& n = nodes_[static_cast<std::size_t>(lp.node)];
      if (!types.Has(n.type)) continue;
      const double off = std::fabs(lp.t - LaneCentreOf(data_.roads[static_cast<std::size_t>(n.road)],
                                                         static_cast<std::size_t>(n.section), n.lane, lp.s).t);
      if (off < best_off) {
        best_off = off;
        best = MakeWaypoint(n.road, n.section, n.lane, lp.s);
      }
    }
    return best;
  }
  const SegmentIndex& ix = *index_;
  if (ix.segments.empty()) return std::nullopt;
  const double x = p.x(), y = p.y();
  if (!std::isfinite(x) || !std::isfinite(y)) return std::nullopt;
  const int cx = CellCoord(x, ix.x0, ix.cell, ix.nx);
  const int cy = CellCoord(y, ix.y0, ix.cell, ix.ny);
  const int max_r = std::max({std::abs(cx), std::abs(cy), std::abs(ix.nx - cx), std::abs(ix.ny - cy)}) + 1;
  double best_d2 = std::numeric_limits<double>::infinity(), best_u = 0;
  int best_seg = -1;
  auto visit = [&](int gx, int gy) {
    if (gx < 0 || gy < 0 || gx >= ix.nx || gy >= ix.ny) return;
    const std::size_t c = static_cast<std::size_t>(gy) * static_cast<std::size_t>(ix.nx) + static_cast<std::size_t>(gx);
    for (std::uint32_t k = ix.cell_start[c]; k < ix.cell_start[c + 1]; ++k) {
      const LaneSegment& s = ix.segments[ix.items[k]];
      if (!types.Has(nodes_[static_cast<std::size_t>(s.node)].type)) continue;
      double u;
      const double d2 = SegmentDist2(s, x, y, &u);
      if (d2 < best_d2) {
        best_d2 = d2;
        best_u = u;
        best_seg = static_cast<int>(ix.items[k]);
      }
    }
  };
  for (int r = 0; r <= max_r; ++r) {
    if (r == 0) {
      visit(cx, cy);
    } else {
      for (int gx = cx - r; gx <= cx + r; ++gx) {
        visit(gx, cy - r);
        visit(gx, cy + r);
      }
      for (int gy = cy - r + 1; gy <= cy + r - 1; ++gy) {
        visit(cx - r, gy);
        visit(cx + r, gy);
      }
    }
    // Cells of the next ring are at least r cells away from the query point.
    const double reach = r * ix.cell;
    if (best_seg >= 0 && best_d2 <= reach * reach) break;
  }
  if (best_seg < 0) return std::nullopt;
  const LaneSegment& s = ix.segments[static_cast<std::size_t>(best_seg)];
  const LaneNode& n = nodes_[static_cast<std::size_t>(s.node)];
  const Road& road = data_.roads[static_cast<std::size_t>(n.road)];
  const double seed = s.s0 + best_u * (s.s1 - s.s0);
  const double sp = ProjectToReference(road, x, y, seed, n.s_begin, n.s_end);
  return MakeWaypoint(n.road, n.section, n.lane, sp);
}

std::vector<LanePoint> Map::LanesAt(double x, double y) const {
  std::vector<LanePoint> out;
  const SegmentIndex& ix = *index_;
  if (!std::isfinite(x) || !std::isfinite(y)) return out;
  const int cx = CellCoord(x, ix.x0, ix.cell, ix.nx);
  const int cy = CellCoord(y, ix.y0, ix.cell, ix.ny);
  if (cx < 0 || cy < 0 || cx >= ix.nx || cy >= ix.ny) return out;
  const std::size_t c = static_cast<std::size_t>(cy) * static_cast<std::size_t>(ix.nx) + static_cast<std::size_t>(cx);
  // Best segment per node (few nodes per cell, so a flat vector beats a hash map).
  struct Cand { int node; double d2; double s; };
  Cand cands[64];
  int count = 0;
  for (std::uint32_t k = ix.cell_start[c]; k < ix.cell_start[c + 1]; ++k) {
    const LaneSegment& s = ix.segments[ix.items[k]];
    double u;
    const double d2 = SegmentDist2(s, x, y, &u);
    const double reach = s.half_width + 0.5;
    if (d2 > reach * reach) continue;
    const double sv = s.s0 + u * (s.s1 - s.s0);
    int j = 0;
    while (j < count && cands[j].node != s.node) ++j;
    if (j == count) {
      if (count == 64) continue;
      cands[count++] = Cand{s.node, d2, sv};
    } else if (d2 < cands[j].d2) {
      cands[j] = Cand{s.node, d2, sv};
    }
  }
  for (int j = 0; j < count; ++j) {
    const LaneNode& n = nodes_[static_cast<std::size_t>(cands[j].node)];
    const Road& road = data_.roads[static_cast<std::size_t>(n.road)];
    const double s = ProjectToReference(road, x, y, cands[j].s, n.s_begin, n.s_end);
    const Pose2 ref = EvaluateReferenceLine(road.plan_view, s);
    const double dx = x - ref.x, dy = y - ref.y;
    const double along = dx * std::cos(ref.hdg) + dy * std::sin(ref.hdg);
    if (std::fabs(along) > 0.1) continue;  // beyond the end of the section
    const double t = -dx * std::sin(ref.hdg) + dy * std::cos(ref.hdg);
    const LaneSpan span = LaneSpanOf(road, static_cast<std::size_t>(n.section), n.lane, s);
    const double lo = std::min(span.t_inner, span.t_outer), hi = std::max(span.t_inner, span.t_outer);
    if (t >= lo && t <= hi && hi > lo) out.push_back(LanePoint{cands[j].node, s, t});
  }
  return out;
}

}  // namespace lockstep::map
