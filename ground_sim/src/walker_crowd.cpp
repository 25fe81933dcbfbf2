// Walkers among walkers: capsules never move into each other (StepWalkers asks
// WalkerSweep::Blocks for every step), overlapping ones are pushed apart, and the AI
// controllers steer round a walker ahead on a closing course (local avoidance, in place
// of CARLA's Detour crowd). Neighbours come from a sweep of the walkers sorted by x.
#include <algorithm>
#include <cmath>

#include "internal.h"
#include "walker_crowd.h"

namespace lockstep::ground {
namespace {

using Vec2 = Eigen::Vector2d;

bool SameLevel(const WalkerSweep::Entry& a, const Vec3& p, const WalkerSweep::Entry& b) {
  return std::abs(p.z() - b.position.z()) < a.half_height + b.half_height;
}

double Cross(const Vec2& a, const Vec2& b) { return a.x() * b.y() - a.y() * b.x(); }

Vec2 Rotate(const Vec2& d, double angle) {
  const double c = std::cos(angle), s = std::sin(angle);
  return {c * d.x() - s * d.y(), s * d.x() + c * d.y()};
}

}  // namespace

void WalkerSweep::Build(const std::map<uint32_t, std::unique_ptr<WalkerActor>>& walkers) {
  entries.clear();
  ids.clear();
  max_radius = 0;
  for (const auto& [id, w] : walkers) {
    Entry e;
    e.position = BodyPose(w->body).position;
    e.x = e.position.x();
    e.id = id;
    e.velocity = w->velocity;
    e.radius = w->spec->radius;
    e.half_height = w->spec->height / 2;
    max_radius = std::max(max_radius, e.radius);
    entries.push_back(e);
    ids.push_back(id);
  }
  std::sort(entries.begin(), entries.end(), [](const Entry& a, const Entry& b) { return a.x != b.x ? a.x < b.x : a.id < b.id; });
  slot.assign(ids.size(), 0);
  for (size_t k = 0; k < entries.size(); ++k) {
    slot[static_cast<size_t>(std::lower_bound(ids.begin(), ids.end(), entries[k].id) - ids.begin())] = k;
  }
}

size_t WalkerSweep::Find(uint32_t id) const {
  return slot[static_cast<size_t>(std::lower_bound(ids.begin(), ids.end(), id) - ids.begin())];
}

std::pair<size_t, size_t> WalkerSweep::Range(double x, double reach) const {
  const auto lo = std::lower_bound(entries.begin(), entries.end(), x - reach, [](const Entry& e, double v) { return e.x < v; });
  const auto hi = std::upper_bound(lo, entries.end(), x + reach, [](double v, const Entry& e) { return v < e.x; });
  return {static_cast<size_t>(lo - entries.begin()), static_cast<size_t>(hi - entries.begin())};
}

bool WalkerSweep::Blocks(size_t self, const Vec3& from, const Vec3& to, double reach) const {
  const Entry& me = entries[self];
  const auto [lo, hi] = Range(to.x(), reach);
  for (size_t k = lo; k < hi; ++k) {
    if (k == self || !SameLevel(me, to, entries[k])) continue;
    const Entry& o = entries[k];
    const double rs = me.radius + o.radius;
    const double d_to = (to - o.position).head<2>().norm();
    if (d_to >= rs + kWalkerGap) continue;
    const double d_from = (from - o.position).head<2>().norm();
    // Closer while too close; a pair that overlaps already (spawned so) does not block
    // (Push parts it).
    if (d_from >= rs && d_to < d_from - 1e-9) return true;
  }
  return false;
}

Vec2 WalkerSweep::Push(size_t self, double push_speed, double dt) const {
  const Entry& me = entries[self];
  const auto [lo, hi] = Range(me.position.x(), 2 * max_radius + kPersonalSpace);
  Vec2 push = Vec2::Zero();
  for (size_t k = lo; k < hi; ++k) {
    if (k == self || !SameLevel(me, me.position, entries[k])) continue;
    const Entry& o = entries[k];
    const Vec2 r = (me.position - o.position).head<2>();
    const double d = r.norm(), rs = me.radius + o.radius;
    if (d >= rs + kPersonalSpace) continue;
    // On top of each other: apart along a direction from the ids (deterministic).
    const Vec2 away = d > 1e-6 ? Vec2(r / d) : Rotate(Vec2(1, 0), (me.id < o.id ? 0.0 : 3.14159265358979) + 2.39996 * std::min(me.id, o.id));
    push += away * (rs + kPersonalSpace - d);
  }
  const double cap = push_speed * dt;
  if (push.norm() > cap) push *= cap / push.norm();
  return push;
}

bool WalkerSweep::Occupied(size_t self, const Vec3& target) const {
  const Entry& me = entries[self];
  const auto [lo, hi] = Range(target.x(), 2 * max_radius + 0.05);
  for (size_t k = lo; k < hi; ++k) {
    if (k == self || !SameLevel(me, target, entries[k])) continue;
    if ((target - entries[k].position).head<2>().norm() < me.radius + entries[k].radius + 0.05) return true;
  }
  return false;
}

// Local avoidance: the nearest walker ahead (within kAvoidRange between the capsules) on
// a closing course that the walker would brush (less than the radii + kPassGap to the
// side of its heading) is passed on the side it already leans to, on the right when
// straight ahead (so two walkers meeting head on both keep right): the heading turns
// until that walker lies the radii + kPassGap to the side, at most kMaxTurn. A turn that
// would lead off the sidewalk onto a driving lane (not on a crossing) tries the other
// side, else the walker keeps its heading (the step's block stops it).
Vec3 World::Impl::AvoidWalkers(size_t self, const Vec3& dir, double speed, bool on_road) const {
  const WalkerSweep::Entry& me = crowd.entries[self];
  const Vec2 d = dir.head<2>().normalized();
  const Vec2 v = d * speed;
  const auto [lo, hi] = crowd.Range(me.position.x(), 2 * crowd.max_radius + kAvoidRange);
  const WalkerSweep::Entry* threat = nullptr;
  double nearest = kAvoidRange;
  for (size_t k = lo; k < hi; ++k) {
    const WalkerSweep::Entry& o = crowd.entries[k];
    if (k == self || !SameLevel(me, me.position, o)) continue;
    const Vec2 r = (o.position - me.position).head<2>();
    const double rs = me.radius + o.radius, gap = r.norm() - rs;
    if (gap > nearest || r.dot(d) <= 0) continue;
    if (std::abs(Cross(d, r)) >= rs + kPassGap) continue;  // it passes clear
    if ((v - o.velocity.head<2>()).dot(r) <= 0) continue;   // not closing in
    threat = &o;
    nearest = gap;
  }
  if (!threat) return dir;
  const Vec2 r = (threat->position - me.position).head<2>();
  const double ahead = r.dot(d), lateral = Cross(d, r);  // lateral > 0: it is to the left
  const double want = std::asin(std::min(1.0, (me.radius + threat->radius + kPassGap) / r.norm()));
  const double right = std::clamp(want - std::atan2(lateral, ahead), 0.0, kMaxTurn);
  const double left = std::clamp(want - std::atan2(-lateral, ahead), 0.0, kMaxTurn);
  const bool right_first = lateral > -kSide;
  for (const double turn : {right_first ? -right : left, right_first ? left : -right}) {
    const Vec2 nd = Rotate(d, turn);
    if (!on_road && WalkerGraph::OnDrivingLane(town->Map(), me.position + Vec3(nd.x(), nd.y(), 0) * kOffRoadProbe)) continue;
    return Vec3(nd.x(), nd.y(), 0);
  }
  return dir;
}

}  // namespace lockstep::ground
