#include "lockstep/render/debug_draw.h"

#include <cmath>
#include <limits>

namespace lockstep::render {

void DebugDrawList::AddArrow(const Vec3& begin, const Vec3& end, double thickness, double arrow_size, const DebugColor& c) {
  lines.push_back({begin, end, thickness, c});
  const Vec3 d = end - begin;
  const double length = d.norm();
  if (length < 1e-9) return;
  // CARLA: four strokes from (length - size, +-size, +-size) in the line's frame to the tip.
  const Vec3 x = d / length;
  const Vec3 up = std::abs(x.z()) < 1 - 1e-4 ? Vec3::UnitZ() : Vec3::UnitX();
  const Vec3 y = up.cross(x).normalized(), z = x.cross(y);
  for (double sy : {1.0, -1.0}) {
    for (double sz : {1.0, -1.0}) {
      lines.push_back({begin + x * (length - arrow_size) + y * (sy * arrow_size) + z * (sz * arrow_size), end, thickness, c});
    }
  }
}

void DebugDrawList::AddBox(const Pose& pose, const Vec3& e, double thickness, const DebugColor& c) {
  auto corner = [&](int i) {
    return pose.Apply(Vec3((i & 1) ? e.x() : -e.x(), (i & 2) ? e.y() : -e.y(), (i & 4) ? e.z() : -e.z()));
  };
  for (int i = 0; i < 8; ++i) {
    for (int bit : {1, 2, 4}) {
      if (!(i & bit)) lines.push_back({corner(i), corner(i | bit), thickness, c});
    }
  }
}

void DebugShapes::Push(Item item) {
  items_.push_back(std::move(item));
  while (items_.size() > kMaxShapes) items_.pop_front();
}

void DebugShapes::AddLine(const DebugLine& l, std::uint64_t first_frame, double issued, double life_time) {
  Item it;
  it.line = l;
  it.first_frame = first_frame;
  it.end = life_time > 0 ? issued + life_time : std::numeric_limits<double>::infinity();
  Push(std::move(it));
}

void DebugShapes::AddPoint(const DebugPoint& p, std::uint64_t first_frame, double issued, double life_time) {
  Item it;
  it.point = true;
  it.pt = p;
  it.first_frame = first_frame;
  it.end = life_time > 0 ? issued + life_time : std::numeric_limits<double>::infinity();
  Push(std::move(it));
}

DebugDrawList DebugShapes::Visible(std::uint64_t frame, double sim_time) {
  // 1 ns of slack: a life of exactly n steps ends at the n-th step, as CARLA's countdown.
  constexpr double kSlack = 1e-9;
  std::erase_if(items_, [&](const Item& i) { return sim_time >= i.end - kSlack; });
  DebugDrawList out;
  for (const Item& i : items_) {
    if (frame < i.first_frame) continue;
    if (i.point) out.points.push_back(i.pt);
    else out.lines.push_back(i.line);
  }
  return out;
}

std::vector<DebugVertex> DebugTriangles(const DebugDrawList& list, const Camera& cam) {
  std::vector<DebugVertex> out;
  out.reserve(list.lines.size() * 6 + list.points.size() * 6);
  const Vec3 eye = cam.pose.position;
  const Vec3 forward = cam.pose.orientation * Vec3::UnitX();
  const Vec3 left = cam.pose.orientation * Vec3::UnitY(), up = cam.pose.orientation * Vec3::UnitZ();
  const double px = 1.0 / cam.Focal();  // m per pixel at 1 m depth
  auto colour = [](const DebugColor& c) {
    return std::array<float, 4>{c[0] / 255.0f, c[1] / 255.0f, c[2] / 255.0f, 1.0f};
  };
  auto quad = [&](const Vec3& a0, const Vec3& a1, const Vec3& b0, const Vec3& b1, const std::array<float, 4>& c) {
    for (const Vec3* p : {&a0, &a1, &b0, &a1, &b1, &b0}) {
      out.push_back({static_cast<float>(p->x()), static_cast<float>(p->y()), static_cast<float>(p->z()), c[0], c[1], c[2], c[3]});
    }
  };
  // Half the width at a point: half the thickness, at least half a pixel.
  auto half_width = [&](const Vec3& p, double thickness) {
    const double depth = (p - eye).dot(forward);
    return std::max(thickness / 2, depth > 0 ? 0.5 * depth * px : 0.0);
  };
  for (const DebugLine& l : list.lines) {
    const Vec3 d = l.end - l.begin;
    Vec3 side = d.cross(0.5 * (l.begin + l.end) - eye);
    if (side.norm() < 1e-12) side = d.cross(up);
    if (side.norm() < 1e-12) continue;
    side.normalize();
    const double wa = half_width(l.begin, l.thickness), wb = half_width(l.end, l.thickness);
    quad(l.begin + side * wa, l.begin - side * wa, l.end + side * wb, l.end - side * wb, colour(l.color));
  }
  for (const DebugPoint& p : list.points) {
    const double depth = (p.location - eye).dot(forward);
    if (depth <= kNearPlane) continue;
    const double h = 0.5 * 100.0 * p.size * depth * px;  // 100 x size px wide on screen
    quad(p.location + (left + up) * h, p.location + (left - up) * h, p.location + (-left + up) * h, p.location + (-left - up) * h,
         colour(p.color));
  }
  return out;
}

void DebugShapes::Save(StateOut& out) const {
  out.Put<std::uint64_t>(items_.size());
  for (const Item& i : items_) {
    out.Put<std::uint8_t>(i.point).Put(i.first_frame).Put(i.end);
    if (i.point) {
      out.Put(i.pt.location).Put(i.pt.size).Put(i.pt.color[0]).Put(i.pt.color[1]).Put(i.pt.color[2]);
    } else {
      out.Put(i.line.begin).Put(i.line.end).Put(i.line.thickness).Put(i.line.color[0]).Put(i.line.color[1]).Put(i.line.color[2]);
    }
  }
}

void DebugShapes::Restore(StateIn& in) {
  items_.clear();
  for (std::uint64_t n = in.Count(1 + 8 + 8 + 24 + 8 + 3); n > 0; --n) {
    Item i;
    std::uint8_t point = 0;
    in.Get(point).Get(i.first_frame).Get(i.end);
    i.point = point != 0;
    if (i.point) {
      in.Get(i.pt.location).Get(i.pt.size).Get(i.pt.color[0]).Get(i.pt.color[1]).Get(i.pt.color[2]);
    } else {
      in.Get(i.line.begin).Get(i.line.end).Get(i.line.thickness).Get(i.line.color[0]).Get(i.line.color[1]).Get(i.line.color[2]);
    }
    items_.push_back(i);
  }
}

}  // namespace lockstep::render
