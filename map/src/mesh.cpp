#include "lockstep/map/mesh.h"

#include <cmath>
#include <numbers>

#include <Eigen/Geometry>

namespace lockstep::map {

std::uint32_t Mesh::AddVertex(const Eigen::Vector3d& p) {
  vertices.push_back(static_cast<float>(p.x()));
  vertices.push_back(static_cast<float>(p.y()));
  vertices.push_back(static_cast<float>(p.z()));
  return static_cast<std::uint32_t>(vertices.size() / 3 - 1);
}

void Mesh::AddTriangle(std::uint32_t a, std::uint32_t b, std::uint32_t c) {
  indices.push_back(a);
  indices.push_back(b);
  indices.push_back(c);
}

void Mesh::AddTriangleFacing(const Eigen::Vector3d& a, const Eigen::Vector3d& b, const Eigen::Vector3d& c,
                             const Eigen::Vector3d& outward) {
  const bool flip = (b - a).cross(c - a).dot(outward) < 0;
  const std::uint32_t ia = AddVertex(a), ib = AddVertex(b), ic = AddVertex(c);
  if (flip) AddTriangle(ia, ic, ib);
  else AddTriangle(ia, ib, ic);
}

void Mesh::AddQuad(const Eigen::Vector3d& p0, const Eigen::Vector3d& p1, const Eigen::Vector3d& p2,
                   const Eigen::Vector3d& p3, const Eigen::Vector3d& outward) {
  const Eigen::Vector3d n = (p2 - p0).cross(p3 - p1);
  const bool flip = n.dot(outward) < 0;
  const std::uint32_t a = AddVertex(p0), b = AddVertex(p1), c = AddVertex(p2), d = AddVertex(p3);
  if (flip) {
    AddTriangle(a, c, b);
    AddTriangle(a, d, c);
  } else {
    AddTriangle(a, b, c);
    AddTriangle(a, c, d);
  }
}

void Mesh::Append(const Mesh& o) {
  const auto base = static_cast<std::uint32_t>(VertexCount());
  vertices.insert(vertices.end(), o.vertices.begin(), o.vertices.end());
  for (std::uint32_t i : o.indices) indices.push_back(base + i);
}

void AddBox(Mesh& m, const Eigen::Vector3d& b, double length, double width, double height, double yaw, bool bottom) {
  const double c = std::cos(yaw), s = std::sin(yaw);
  auto P = [&](double u, double v, double z) {
    return Eigen::Vector3d(b.x() + u * c - v * s, b.y() + u * s + v * c, b.z() + z);
  };
  const double l = 0.5 * length, w = 0.5 * width;
  const Eigen::Vector3d fwd(c, s, 0), left(-s, c, 0), up(0, 0, 1);
  m.AddQuad(P(l, -w, 0), P(l, w, 0), P(l, w, height), P(l, -w, height), fwd);
  m.AddQuad(P(-l, -w, 0), P(-l, w, 0), P(-l, w, height), P(-l, -w, height), -fwd);
  m.AddQuad(P(-l, w, 0), P(l, w, 0), P(l, w, height), P(-l, w, height), left);
  m.AddQuad(P(-l, -w, 0), P(l, -w, 0), P(l, -w, height), P(-l, -w, height), -left);
  m.AddQuad(P(-l, -w, height), P(l, -w, height), P(l, w, height), P(-l, w, height), up);
  if (bottom) m.AddQuad(P(-l, -w, 0), P(l, -w, 0), P(l, w, 0), P(-l, w, 0), -up);
}

void AddCylinder(Mesh& m, const Eigen::Vector3d& b, double r, double h, int sides) {
  const Eigen::Vector3d top = b + Eigen::Vector3d(0, 0, h);
  for (int i = 0; i < sides; ++i) {
    const double a0 = 2 * std::numbers::pi * i / sides, a1 = 2 * std::numbers::pi * (i + 1) / sides;
    const Eigen::Vector3d d0(std::cos(a0), std::sin(a0), 0), d1(std::cos(a1), std::sin(a1), 0);
    m.AddQuad(b + r * d0, b + r * d1, top + r * d1, top + r * d0, d0 + d1);
    m.AddTriangleFacing(top, top + r * d0, top + r * d1, Eigen::Vector3d(0, 0, 1));
  }
}

void AddCone(Mesh& m, const Eigen::Vector3d& b, double r, double h, int sides) {
  const Eigen::Vector3d apex = b + Eigen::Vector3d(0, 0, h);
  for (int i = 0; i < sides; ++i) {
    const double a0 = 2 * std::numbers::pi * i / sides, a1 = 2 * std::numbers::pi * (i + 1) / sides;
    const Eigen::Vector3d d0(std::cos(a0), std::sin(a0), 0), d1(std::cos(a1), std::sin(a1), 0);
    m.AddTriangleFacing(b + r * d0, b + r * d1, apex, d0 + d1);
    m.AddTriangleFacing(b, b + r * d0, b + r * d1, Eigen::Vector3d(0, 0, -1));
  }
}

void AddEllipsoid(Mesh& m, const Eigen::Vector3d& c, const Eigen::Vector3d& r, int sides, int rings) {
  auto P = [&](int i, int j) {
    const double lon = 2 * std::numbers::pi * i / sides, lat = std::numbers::pi * (static_cast<double>(j) / rings - 0.5);
    return Eigen::Vector3d(c.x() + r.x() * std::cos(lat) * std::cos(lon), c.y() + r.y() * std::cos(lat) * std::sin(lon),
                           c.z() + r.z() * std::sin(lat));
  };
  for (int j = 0; j < rings; ++j) {
    for (int i = 0; i < sides; ++i) {
      const Eigen::Vector3d a = P(i, j), b = P(i + 1, j), cc = P(i + 1, j + 1), d = P(i, j + 1);
      const Eigen::Vector3d out = 0.25 * (a + b + cc + d) - c;
      if (j == 0) m.AddTriangleFacing(a, cc, d, out);            // south pole: a == b
      else if (j == rings - 1) m.AddTriangleFacing(a, b, cc, out);  // north pole: c == d
      else m.AddQuad(a, b, cc, d, out);
    }
  }
}

std::size_t TotalTriangles(const std::vector<Mesh>& meshes) {
  std::size_t n = 0;
  for (const Mesh& m : meshes) n += m.TriangleCount();
  return n;
}

}  // namespace lockstep::map
