// The pedestrian navigation graph (walker_graph.h): sidewalk nodes and edges, the joins
// where sidewalks continue, crossings (crosswalk objects and junction mouths), A*.
#include "lockstep/ground/walker_graph.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <queue>

#include "lockstep/map/crossings.h"

namespace lockstep::ground {
namespace {

using Vec3 = Eigen::Vector3d;
using Vec2 = Eigen::Vector2d;

constexpr double kJoin = 1.5;       // m: sidewalk lane ends this close continue into each other
constexpr double kKerbLink = 3.0;   // m: a crossing end is joined to sidewalk nodes this close

double SegmentDistance(const Vec2& p, const Vec2& a, const Vec2& b, double* t_out) {
  const Vec2 ab = b - a;
  const double len2 = ab.squaredNorm();
  const double t = len2 > 1e-12 ? std::clamp((p - a).dot(ab) / len2, 0.0, 1.0) : 0.0;
  if (t_out) *t_out = t;
  return (a + ab * t - p).norm();
}

// Whether the straight walk from a to b stays off the driving lanes (checked every 0.5 m).
bool WalkableSegment(const map::Map& m, const Vec3& a, const Vec3& b) {
  const int n = std::max(1, static_cast<int>(std::ceil((b - a).head<2>().norm() / 0.5)));
  for (int k = 0; k <= n; ++k) {
    if (WalkerGraph::OnDrivingLane(m, a + (b - a) * (static_cast<double>(k) / n))) return false;
  }
  return true;
}

}  // namespace

bool WalkerGraph::OnDrivingLane(const map::Map& m, const Vec3& p) { return map::OnDrivingLane(m, p); }

int WalkerGraph::AddNode(const Vec3& p) {
  pos_.push_back(p);
  edges_.emplace_back();
  return static_cast<int>(pos_.size()) - 1;
}

void WalkerGraph::Connect(int a, int b, int crossing) {
  if (a == b) return;
  for (const auto& e : edges_[static_cast<size_t>(a)]) {
    if (e.to == b) return;
  }
  const double len = (pos_[static_cast<size_t>(a)] - pos_[static_cast<size_t>(b)]).head<2>().norm();
  edges_[static_cast<size_t>(a)].push_back(WalkerEdge{b, len, crossing});
  edges_[static_cast<size_t>(b)].push_back(WalkerEdge{a, len, crossing});
}

WalkerGraph::WalkerGraph(const map::Map& m, std::vector<TownCrosswalk> crosswalks,
                         const std::function<int(int, int, int, const Eigen::Vector3d&)>& light_of_lane) {
  // 1. Sidewalk lanes: a node every ~kSpacing m, both ends included; points standing on a
  //    driving lane (a junction's sidewalk drawn over another connecting road) are left out.
  std::vector<int> lane_ends;  // nodes at the two ends of every sidewalk lane
  for (const map::LaneNode& ln : m.Nodes()) {
    if (ln.type != map::LaneType::Sidewalk || ln.Length() < 1e-3) continue;
    const int k = std::max(1, static_cast<int>(std::lround(ln.Length() / kSpacing)));
    int prev = -1;
    for (int i = 0; i <= k; ++i) {
      // Just inside the section, so the waypoint belongs to this lane section.
      const double s = std::clamp(ln.s_begin + ln.Length() * i / k, ln.s_begin + 1e-4, ln.s_end - 1e-4);
      const Vec3 p = m.MakeWaypoint(ln.road, ln.section, ln.lane, s).transform.location;
      if (OnDrivingLane(m, p)) {
        prev = -1;
        continue;
      }
      const int id = AddNode(p);
      if (prev >= 0) Connect(prev, id, -1);
      if (i == 0 || i == k) lane_ends.push_back(id);
      prev = id;
    }
  }
  BuildGrid();
  // 2. Where sidewalks continue (next lane section, next road, junction corner): lane ends
  //    that meet.
  for (int a : lane_ends) {
    for (int b : Near(pos_[static_cast<size_t>(a)], kJoin)) {
      if (b != a && std::binary_search(lane_ends.begin(), lane_ends.end(), b)) Connect(a, b, -1);
    }
  }
  // 3. Crossings at junction mouths: where a road enters a junction, from the sidewalk on
  //    one side of its end to the sidewalk on the other, straight across the driving lanes,
  //    kMouthSetback into the junction (past the stop line, where cars wait).
  std::vector<TownCrosswalk> derived;
  for (const map::MouthCrossing& mc : map::JunctionMouthCrossings(m, kMouthSetback)) {
    TownCrosswalk cw;
    cw.ends[0] = mc.ends[0];
    cw.ends[1] = mc.ends[1];
    cw.centre = (cw.ends[0] + cw.ends[1]) / 2;
    cw.derived = true;
    for (int lane : mc.driving_lanes) {
      const int light = light_of_lane(mc.road, mc.section, lane, cw.centre);
      if (light >= 0 && std::find(cw.lights.begin(), cw.lights.end(), light) == cw.lights.end()) cw.lights.push_back(light);
    }
    derived.push_back(std::move(cw));
  }
  crossings_ = std::move(crosswalks);
  for (auto& cw : derived) crossings_.push_back(std::move(cw));
  for (size_t k = 0; k < crossings_.size(); ++k) {
    TownCrosswalk& cw = crossings_[k];
    for (int e = 0; e < 2; ++e) {
      const std::vector<int> near = Near(cw.ends[e], kKerbLink);
      cw.nodes[e] = AddNode(cw.ends[e]);
      for (int n : near) {
        if (WalkableSegment(m, cw.ends[e], pos_[static_cast<size_t>(n)])) Connect(cw.nodes[e], n, -1);
      }
    }
    Connect(cw.nodes[0], cw.nodes[1], static_cast<int>(k));
  }
  BuildGrid();
}

void WalkerGraph::BuildGrid() {
  grid_.clear();
  if (pos_.empty()) return;
  Vec2 lo(std::numeric_limits<double>::infinity(), std::numeric_limits<double>::infinity()), hi = -lo;
  for (const auto& p : pos_) lo = lo.cwiseMin(p.head<2>()), hi = hi.cwiseMax(p.head<2>());
  grid_min_ = lo;
  grid_w_ = static_cast<int>((hi.x() - lo.x()) / kCell) + 1;
  grid_h_ = static_cast<int>((hi.y() - lo.y()) / kCell) + 1;
  grid_.assign(static_cast<size_t>(grid_w_) * static_cast<size_t>(grid_h_), {});
  for (size_t i = 0; i < pos_.size(); ++i) {
    const int gx = static_cast<int>((pos_[i].x() - lo.x()) / kCell), gy = static_cast<int>((pos_[i].y() - lo.y()) / kCell);
    grid_[static_cast<size_t>(gy) * static_cast<size_t>(grid_w_) + static_cast<size_t>(gx)].push_back(static_cast<int>(i));
  }
}

std::vector<int> WalkerGraph::Near(const Vec3& p, double radius) const {
  std::vector<int> out;
  if (grid_.empty()) return out;
  const int x0 = static_cast<int>(std::floor((p.x() - radius - grid_min_.x()) / kCell));
  const int x1 = static_cast<int>(std::floor((p.x() + radius - grid_min_.x()) / kCell));
  const int y0 = static_cast<int>(std::floor((p.y() - radius - grid_min_.y()) / kCell));
  const int y1 = static_cast<int>(std::floor((p.y() + radius - grid_min_.y()) / kCell));
  for (int gy = std::max(0, y0); gy <= std::min(grid_h_ - 1, y1); ++gy) {
    for (int gx = std::max(0, x0); gx <= std::min(grid_w_ - 1, x1); ++gx) {
      for (int n : grid_[static_cast<size_t>(gy) * static_cast<size_t>(grid_w_) + static_cast<size_t>(gx)]) {
        if ((pos_[static_cast<size_t>(n)] - p).head<2>().norm() <= radius) out.push_back(n);
      }
    }
  }
  std::sort(out.begin(), out.end());
  return out;
}

int WalkerGraph::Nearest(const Vec3& p) const {
  if (pos_.empty()) return -1;
  for (double r = kCell; r < 4 * kCell * static_cast<double>(grid_w_ + grid_h_ + 1); r *= 2) {
    const std::vector<int> near = Near(p, r);
    if (near.empty()) continue;
    int best = -1;
    double best_d = std::numeric_limits<double>::infinity();
    for (int n : near) {  // ascending ids: ties go to the lower id
      const double d = (pos_[static_cast<size_t>(n)] - p).head<2>().norm();
      if (d < best_d) best_d = d, best = n;
    }
    return best;
  }
  return -1;
}

Vec3 WalkerGraph::NearestPoint(const Vec3& p, int* node) const {
  const int n = Nearest(p);
  if (node) *node = n;
  if (n < 0) return p;
  Vec3 best = pos_[static_cast<size_t>(n)];
  double best_d = (best - p).head<2>().norm();
  for (const auto& e : edges_[static_cast<size_t>(n)]) {
    if (e.crossing >= 0) continue;
    const Vec3& a = pos_[static_cast<size_t>(n)];
    const Vec3& b = pos_[static_cast<size_t>(e.to)];
    double t = 0;
    const double d = SegmentDistance(p.head<2>(), a.head<2>(), b.head<2>(), &t);
    if (d < best_d - 1e-9) best_d = d, best = a + (b - a) * t;
  }
  return best;
}

std::vector<std::pair<int, int>> WalkerGraph::Route(int from, int to) const {
  std::vector<std::pair<int, int>> out;
  const size_t n = pos_.size();
  if (from < 0 || to < 0 || static_cast<size_t>(from) >= n || static_cast<size_t>(to) >= n) return out;
  const Vec2 goal = pos_[static_cast<size_t>(to)].head<2>();
  std::vector<double> g(n, std::numeric_limits<double>::infinity());
  std::vector<int> parent(n, -1), via(n, -1);
  std::vector<bool> closed(n, false);
  using Item = std::pair<double, int>;  // (f, node): ties by node id, deterministic
  std::priority_queue<Item, std::vector<Item>, std::greater<>> open;
  g[static_cast<size_t>(from)] = 0;
  open.emplace((pos_[static_cast<size_t>(from)].head<2>() - goal).norm(), from);
  int best = from;
  double best_h = (pos_[static_cast<size_t>(from)].head<2>() - goal).norm();
  while (!open.empty()) {
    const int u = open.top().second;
    open.pop();
    if (closed[static_cast<size_t>(u)]) continue;
    closed[static_cast<size_t>(u)] = true;
    const double h = (pos_[static_cast<size_t>(u)].head<2>() - goal).norm();
    if (h < best_h) best_h = h, best = u;
    if (u == to) break;
    for (const auto& e : edges_[static_cast<size_t>(u)]) {
      const double c = g[static_cast<size_t>(u)] + e.length + (e.crossing >= 0 ? kCrossingPenalty : 0.0);
      if (c < g[static_cast<size_t>(e.to)]) {
        g[static_cast<size_t>(e.to)] = c;
        parent[static_cast<size_t>(e.to)] = u;
        via[static_cast<size_t>(e.to)] = e.crossing;
        open.emplace(c + (pos_[static_cast<size_t>(e.to)].head<2>() - goal).norm(), e.to);
      }
    }
  }
  const int end = closed[static_cast<size_t>(to)] ? to : best;
  for (int v = end; v != from && v >= 0; v = parent[static_cast<size_t>(v)]) out.emplace_back(v, via[static_cast<size_t>(v)]);
  std::reverse(out.begin(), out.end());
  return out;
}

}  // namespace lockstep::ground
