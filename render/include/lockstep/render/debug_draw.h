#pragma once
// CARLA's world.debug shapes in the render pass: what each shape is made of (CARLA's
// DebugShapeDrawer: a box is its 12 edges, an arrow its line and four head strokes), which
// shapes a frame shows (life time in simulation seconds), and the triangles a camera draws
// for them (lines `thickness` m wide facing the camera, points 100 x size px squares).
#include <array>
#include <cstdint>
#include <deque>
#include <vector>

#include "lockstep/render/camera.h"
#include "lockstep/render/state_io.h"
#include "lockstep/render/types.h"

namespace lockstep::render {

using DebugColor = std::array<std::uint8_t, 3>;  // r, g, b

struct DebugLine {
  Vec3 begin = Vec3::Zero(), end = Vec3::Zero();  // world, m
  double thickness = 0.1;                          // m (0: one pixel)
  DebugColor color{255, 0, 0};
};

struct DebugPoint {
  Vec3 location = Vec3::Zero();  // world, m
  double size = 0.1;             // CARLA's size: a square of 100 x size px
  DebugColor color{255, 0, 0};
};

// What one frame draws.
struct DebugDrawList {
  std::vector<DebugLine> lines;
  std::vector<DebugPoint> points;
  bool empty() const { return lines.empty() && points.empty(); }
  void AddArrow(const Vec3& begin, const Vec3& end, double thickness, double arrow_size, const DebugColor& c);
  // A box of half sizes `extent` (box frame) at `pose`.
  void AddBox(const Pose& pose, const Vec3& extent, double thickness, const DebugColor& c);
};

// Shapes with their life: a shape issued at simulation time t (the frame before the tick
// that carries it) shows in the frames from `first_frame` on whose time is before
// t + life_time (CARLA's persistent line batcher counts the life down by each step's dt and
// drops it at 0); life_time <= 0 keeps it until Clear(). At most kMaxShapes are kept (the
// oldest go first).
class DebugShapes {
 public:
  static constexpr std::size_t kMaxShapes = 100000;
  void AddLine(const DebugLine& l, std::uint64_t first_frame, double issued, double life_time);
  void AddPoint(const DebugPoint& p, std::uint64_t first_frame, double issued, double life_time);
  // The shapes of frame `frame` at time `sim_time`; forgets those that ended before it.
  DebugDrawList Visible(std::uint64_t frame, double sim_time);
  void Clear() { items_.clear(); }
  std::size_t size() const { return items_.size(); }
  // Every shape with its first frame and end (snapshots and the state hash).
  void Save(StateOut& out) const;
  void Restore(StateIn& in);

 private:
  struct Item {
    bool point = false;
    DebugLine line;
    DebugPoint pt;
    std::uint64_t first_frame = 0;
    double end = 0;  // simulation time it is gone at; +inf: until Clear
  };
  void Push(Item item);
  std::deque<Item> items_;
};

// One vertex of the debug pass: world position and colour 0..1.
struct DebugVertex {
  float x, y, z;
  float r, g, b, a;
};
// The triangles `cam` draws for `list`.
std::vector<DebugVertex> DebugTriangles(const DebugDrawList& list, const Camera& cam);

}  // namespace lockstep::render
