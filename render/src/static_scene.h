#pragma once
// The static town on the GPU: one vertex buffer, triangles grouped by grid cell and by
// level of detail so a camera draws only the cells in its frustum, at the detail their
// distance needs.
#include <cstdint>
#include <vector>

#include "gl_util.h"
#include "lockstep/render/renderer.h"

namespace lockstep::render {

struct Aabb {
  Eigen::Vector3f lo{1e30f, 1e30f, 1e30f}, hi{-1e30f, -1e30f, -1e30f};
  void Add(const Eigen::Vector3f& p) {
    lo = lo.cwiseMin(p);
    hi = hi.cwiseMax(p);
  }
  bool Empty() const { return lo.x() > hi.x(); }
};

// Frustum planes from a view-projection matrix; true if the box may be visible.
struct Frustum {
  Eigen::Vector4f planes[6];
  explicit Frustum(const Eigen::Matrix4f& view_proj);
  bool Visible(const Aabb& box) const;
  bool Visible(const Eigen::Vector3f& centre, float radius) const;
};

struct Range {
  GLint first = 0;
  GLsizei count = 0;
};

// Per cell, in buffer order: base (roads, ground: always), large (buildings, trees:
// full detail near), small (poles, signs, fences: near only), markings (nearer still),
// then far (boxes standing in for the large objects).
struct Cell {
  Aabb box;
  GLint first = 0;
  GLsizei base = 0, large = 0, small = 0, markings = 0;
  Range far;
};

struct StaticScene {
  GLuint vao = 0, vbo = 0;
  std::vector<Cell> cells;
  std::vector<Vec3> lamps;
  std::uint64_t triangles = 0;
  StaticSceneOptions options;

  void Build(const std::vector<map::Mesh>& meshes, const std::vector<Vec3>& lamp_positions, const StaticSceneOptions& opt);
  // Appends the draws for one camera; returns the triangles drawn. casters_only: the sun's
  // shadow pass, which leaves out the ground level (roads, sidewalks, terrain cast nothing).
  // front_to_back: cells nearest the eye first. draw_calls, if given, is incremented per draw.
  std::uint64_t Draw(const Frustum& frustum, const Eigen::Vector3f& eye, bool casters_only = false, bool front_to_back = false,
                     std::uint64_t* draw_calls = nullptr) const;
  void Release();
};

void SetupVertexLayout();  // attribute pointers of render::Vertex on the bound VAO/VBO

}  // namespace lockstep::render
