#include "static_scene.h"

#include <algorithm>
#include <cmath>
#include <map>

namespace lockstep::render {
namespace {

enum class Level { kBase, kLarge, kSmall, kMarkings };

Level LevelOf(std::uint8_t t) {
  switch (t) {
    case tag::kRoads:
    case tag::kSideWalks:
    case tag::kTerrain:
    case tag::kGround:
    case tag::kUnlabeled: return Level::kBase;
    case tag::kBuilding:
    case tag::kVegetation: return Level::kLarge;
    case tag::kRoadLine: return Level::kMarkings;
    default: return Level::kSmall;
  }
}

std::array<std::uint8_t, 3> StaticColor(std::uint8_t t, std::uint32_t instance) {
  const std::uint32_t h = instance * 2654435761u;
  switch (t) {
    case tag::kRoads: return {62, 62, 66};
    case tag::kSideWalks: return {150, 146, 138};
    case tag::kBuilding: {
      static const std::array<std::uint8_t, 3> walls[] = {{165, 85, 60}, {205, 190, 160}, {150, 150, 150}, {225, 220, 210},
                                                          {120, 95, 80}, {180, 160, 120}, {110, 120, 130}};
      return walls[(h >> 8) % 7];
    }
    case tag::kWall: return {160, 150, 130};
    case tag::kFence: return {120, 100, 80};
    case tag::kPole: return {85, 88, 92};
    case tag::kTrafficLight: return {35, 35, 35};
    case tag::kTrafficSign: return {210, 210, 210};
    case tag::kVegetation: return {((h >> 8) % 2) ? std::uint8_t{55} : std::uint8_t{70}, 105, 40};
    case tag::kTerrain: return {92, 118, 62};
    case tag::kRoadLine: return {235, 235, 230};
    case tag::kGround: return {100, 90, 75};
    default: return {128, 128, 128};
  }
}

Material StaticMaterial(std::uint8_t t) {
  if (t == tag::kRoads) return kMatRoad;
  if (t == tag::kBuilding) return kMatWindow;
  return kMatPlain;
}

Aabb MeshBox(const map::Mesh& m) {
  Aabb b;
  for (std::size_t i = 0; i + 2 < m.vertices.size(); i += 3) b.Add({m.vertices[i], m.vertices[i + 1], m.vertices[i + 2]});
  return b;
}

}  // namespace

Frustum::Frustum(const Eigen::Matrix4f& m) {
  const Eigen::Vector4f r0 = m.row(0), r1 = m.row(1), r2 = m.row(2), r3 = m.row(3);
  planes[0] = r3 + r0;
  planes[1] = r3 - r0;
  planes[2] = r3 + r1;
  planes[3] = r3 - r1;
  planes[4] = r3 + r2;
  planes[5] = r3 - r2;
}

bool Frustum::Visible(const Aabb& b) const {
  for (const auto& p : planes) {
    const Eigen::Vector3f v(p.x() >= 0 ? b.hi.x() : b.lo.x(), p.y() >= 0 ? b.hi.y() : b.lo.y(), p.z() >= 0 ? b.hi.z() : b.lo.z());
    if (p.head<3>().dot(v) + p.w() < 0) return false;
  }
  return true;
}

bool Frustum::Visible(const Eigen::Vector3f& c, float r) const {
  for (const auto& p : planes) {
    if (p.head<3>().dot(c) + p.w() < -r * p.head<3>().norm()) return false;
  }
  return true;
}

void SetupVertexLayout() {
  glEnableVertexAttribArray(0);
  glVertexAttribPointer(0, 3, GL_FLOAT, GL_FALSE, sizeof(Vertex), reinterpret_cast<void*>(offsetof(Vertex, position)));
  glEnableVertexAttribArray(1);
  glVertexAttribPointer(1, 3, GL_FLOAT, GL_FALSE, sizeof(Vertex), reinterpret_cast<void*>(offsetof(Vertex, normal)));
  glEnableVertexAttribArray(2);
  glVertexAttribPointer(2, 4, GL_UNSIGNED_BYTE, GL_TRUE, sizeof(Vertex), reinterpret_cast<void*>(offsetof(Vertex, rgba)));
  glEnableVertexAttribArray(3);
  glVertexAttribIPointer(3, 1, GL_UNSIGNED_INT, sizeof(Vertex), reinterpret_cast<void*>(offsetof(Vertex, label)));
}

void StaticScene::Build(const std::vector<map::Mesh>& meshes, const std::vector<Vec3>& lamp_positions, const StaticSceneOptions& opt) {
  Release();
  options = opt;
  lamps = lamp_positions;
  struct Bins {
    std::vector<Vertex> level[4], far;
    Aabb box;
  };
  std::map<std::pair<int, int>, Bins> bins;
  auto cell_of = [&](float x, float y) {
    return std::make_pair(static_cast<int>(std::floor(x / opt.cell_size)), static_cast<int>(std::floor(y / opt.cell_size)));
  };
  std::vector<Vertex> tmp;
  triangles = 0;
  std::vector<std::pair<Aabb, std::uint32_t>> poles;
  for (const auto& m : meshes) {
    const std::uint32_t inst = m.instance_id ? m.instance_id + kStaticInstanceBase : 0;
    const std::uint32_t label = m.semantic_tag | (inst << 8);
    tmp.clear();
    AppendMesh(&tmp, m, StaticColor(m.semantic_tag, m.instance_id), StaticMaterial(m.semantic_tag), label);
    triangles += tmp.size() / 3;
    const Level level = LevelOf(m.semantic_tag);
    // Triangles go to the cell of their centroid (roads are long); a large object's far
    // box goes to the cell of its centre.
    for (std::size_t t = 0; t + 2 < tmp.size(); t += 3) {
      const float cx = (tmp[t].position[0] + tmp[t + 1].position[0] + tmp[t + 2].position[0]) / 3;
      const float cy = (tmp[t].position[1] + tmp[t + 1].position[1] + tmp[t + 2].position[1]) / 3;
      Bins& b = bins[cell_of(cx, cy)];
      for (int k = 0; k < 3; ++k) {
        b.level[static_cast<int>(level)].push_back(tmp[t + k]);
        b.box.Add(Eigen::Vector3f(tmp[t + k].position));
      }
    }
    const Aabb mb = MeshBox(m);
    if (m.semantic_tag == tag::kPole) poles.emplace_back(mb, label);
    if (level == Level::kLarge && !mb.Empty()) {
      map::Mesh box;
      const Eigen::Vector3d lo = mb.lo.cast<double>(), hi = mb.hi.cast<double>();
      map::AddBox(box, Eigen::Vector3d((lo.x() + hi.x()) / 2, (lo.y() + hi.y()) / 2, lo.z()), hi.x() - lo.x(), hi.y() - lo.y(),
                  hi.z() - lo.z(), 0, false);
      Bins& b = bins[cell_of((mb.lo.x() + mb.hi.x()) / 2, (mb.lo.y() + mb.hi.y()) / 2)];
      AppendMesh(&b.far, box, StaticColor(m.semantic_tag, m.instance_id), kMatPlain, label);
      b.box.Add(mb.lo);
      b.box.Add(mb.hi);
    }
  }
  // Lamp bulbs: small glowing boxes under the lamp heads, labelled as their pole.
  for (const Vec3& l : lamps) {
    std::uint32_t label = tag::kPole;
    for (const auto& [box, pole_label] : poles) {
      const Eigen::Vector3f p = l.cast<float>();
      if ((p.array() >= box.lo.array() - 0.3f).all() && (p.array() <= box.hi.array() + 0.3f).all()) label = pole_label;
    }
    map::Mesh bulb;
    map::AddBox(bulb, l - Vec3(0, 0, 0.04), 0.35, 0.2, 0.05, 0, true);
    tmp.clear();
    AppendMesh(&tmp, bulb, {255, 240, 200}, kMatLamp, label);
    Bins& b = bins[cell_of(static_cast<float>(l.x()), static_cast<float>(l.y()))];
    b.level[static_cast<int>(Level::kSmall)].insert(b.level[static_cast<int>(Level::kSmall)].end(), tmp.begin(), tmp.end());
  }
  std::vector<Vertex> all;
  for (auto& [key, b] : bins) {
    Cell c;
    c.box = b.box;
    c.first = static_cast<GLint>(all.size());
    for (int l = 0; l < 4; ++l) all.insert(all.end(), b.level[l].begin(), b.level[l].end());
    c.base = static_cast<GLsizei>(b.level[0].size());
    c.large = static_cast<GLsizei>(b.level[1].size());
    c.small = static_cast<GLsizei>(b.level[2].size());
    c.markings = static_cast<GLsizei>(b.level[3].size());
    c.far.first = static_cast<GLint>(all.size());
    c.far.count = static_cast<GLsizei>(b.far.size());
    all.insert(all.end(), b.far.begin(), b.far.end());
    if (!c.box.Empty()) cells.push_back(c);
  }
  glGenVertexArrays(1, &vao);
  glBindVertexArray(vao);
  glGenBuffers(1, &vbo);
  glBindBuffer(GL_ARRAY_BUFFER, vbo);
  glBufferData(GL_ARRAY_BUFFER, static_cast<GLsizeiptr>(all.size() * sizeof(Vertex)), all.data(), GL_STATIC_DRAW);
  SetupVertexLayout();
  glBindVertexArray(0);
}

std::uint64_t StaticScene::Draw(const Frustum& frustum, const Eigen::Vector3f& eye, bool casters_only, bool front_to_back,
                                std::uint64_t* draw_calls) const {
  if (!vao) return 0;
  glBindVertexArray(vao);
  std::vector<std::pair<float, const Cell*>> visible;
  visible.reserve(cells.size());
  for (const Cell& c : cells) {
    if (!frustum.Visible(c.box)) continue;
    const Eigen::Vector3f nearest = eye.cwiseMax(c.box.lo).cwiseMin(c.box.hi);
    visible.emplace_back((nearest - eye).head<2>().norm(), &c);
  }
  if (front_to_back) {
    std::stable_sort(visible.begin(), visible.end(), [](const auto& a, const auto& b) { return a.first < b.first; });
  }
  std::uint64_t drawn = 0, calls = 0;
  for (const auto& [d, cell] : visible) {
    const Cell& c = *cell;
    GLsizei count = c.base;
    if (d < options.detail_distance) count += c.large;
    if (d < options.detail_distance && d < options.small_distance) count += c.small;
    if (d < options.detail_distance && d < options.small_distance && d < options.marking_distance) count += c.markings;
    const GLint first = casters_only ? c.first + c.base : c.first;
    if (casters_only) count = std::min<GLsizei>(count - c.base, c.large + c.small);
    if (count > 0) {
      glDrawArrays(GL_TRIANGLES, first, count);
      ++calls;
    }
    drawn += static_cast<std::uint64_t>(std::max<GLsizei>(count, 0)) / 3;
    if (d >= options.detail_distance && c.far.count > 0) {
      glDrawArrays(GL_TRIANGLES, c.far.first, c.far.count);
      drawn += static_cast<std::uint64_t>(c.far.count) / 3;
      ++calls;
    }
  }
  if (draw_calls) *draw_calls += calls;
  return drawn;
}

void StaticScene::Release() {
  if (vbo) glDeleteBuffers(1, &vbo);
  if (vao) glDeleteVertexArrays(1, &vao);
  vbo = vao = 0;
  cells.clear();
}

}  // namespace lockstep::render
