#include "lockstep/air/collision.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

namespace lockstep::air {

const char* ToString(ObjectKind k) {
  switch (k) {
    case ObjectKind::kNone: return "none";
    case ObjectKind::kGround: return "ground";
    case ObjectKind::kStatic: return "static";
    case ObjectKind::kVehicle: return "vehicle";
    case ObjectKind::kDrone: return "drone";
  }
  return "?";
}

Pose ExtrapolateVehicle(const VehicleBox& v, double t) {
  Pose p;
  p.position = v.pose.position + v.velocity * t;
  const double w = v.angular_velocity.norm();
  if (w * t > 1e-12) {
    p.orientation = Quat(Eigen::AngleAxisd(w * t, v.angular_velocity / w)) * v.pose.orientation.normalized();
    p.orientation.normalize();
  } else {
    p.orientation = v.pose.orientation.normalized();
  }
  return p;
}

Vec3 ClosestPointOnTriangle(const Vec3& p, const Vec3& a, const Vec3& b, const Vec3& c) {
  const Vec3 ab = b - a, ac = c - a, ap = p - a;
  const double d1 = ab.dot(ap), d2 = ac.dot(ap);
  if (d1 <= 0 && d2 <= 0) return a;
  const Vec3 bp = p - b;
  const double d3 = ab.dot(bp), d4 = ac.dot(bp);
  if (d3 >= 0 && d4 <= d3) return b;
  const double vc = d1 * d4 - d3 * d2;
  if (vc <= 0 && d1 >= 0 && d3 <= 0) return a + ab * (d1 / (d1 - d3));
  const Vec3 cp = p - c;
  const double d5 = ab.dot(cp), d6 = ac.dot(cp);
  if (d6 >= 0 && d5 <= d6) return c;
  const double vb = d5 * d2 - d1 * d6;
  if (vb <= 0 && d2 >= 0 && d6 <= 0) return a + ac * (d2 / (d2 - d6));
  const double va = d3 * d6 - d5 * d4;
  if (va <= 0 && (d4 - d3) >= 0 && (d5 - d6) >= 0) {
    return b + (c - b) * ((d4 - d3) / ((d4 - d3) + (d5 - d6)));
  }
  const double denom = 1.0 / (va + vb + vc);
  return a + ab * (vb * denom) + ac * (vc * denom);
}

bool SphereBoxContact(const Vec3& center, double radius, const Pose& box, const Vec3& half,
                      ContactPoint* out) {
  const Mat3 r = box.orientation.toRotationMatrix();
  const Vec3 local = r.transpose() * (center - box.position);
  const Vec3 clamped = local.cwiseMax(-half).cwiseMin(half);
  const Vec3 diff = local - clamped;
  const double d2 = diff.squaredNorm();
  Vec3 n_local, q_local;
  double depth;
  if (d2 > 0) {
    if (d2 >= radius * radius) return false;
    const double d = std::sqrt(d2);
    n_local = diff / d;
    q_local = clamped;
    depth = radius - d;
  } else {
    // Centre inside the box: leave through the nearest face.
    int axis = 0;
    double best = half[0] - std::abs(local[0]);
    for (int i = 1; i < 3; ++i) {
      const double gap = half[i] - std::abs(local[i]);
      if (gap < best) {
        best = gap;
        axis = i;
      }
    }
    n_local = Vec3::Zero();
    n_local[axis] = local[axis] >= 0 ? 1.0 : -1.0;
    q_local = local;
    q_local[axis] = n_local[axis] * half[axis];
    depth = radius + best;
  }
  out->point = box.position + r * q_local;
  out->normal = r * n_local;
  out->depth = depth;
  return true;
}

std::shared_ptr<const StaticMesh> StaticMesh::Build(std::span<const float> xyz,
                                                    std::span<const std::uint32_t> indices,
                                                    double cell_size, std::uint32_t id) {
  if (xyz.size() % 3 != 0) throw std::invalid_argument("static mesh: vertex array size is not a multiple of 3");
  if (indices.size() % 3 != 0) throw std::invalid_argument("static mesh: index array size is not a multiple of 3");
  if (!(cell_size > 0) || !std::isfinite(cell_size)) throw std::invalid_argument("static mesh: cell_size must be > 0");
  const std::size_t nv = xyz.size() / 3;
  for (float f : xyz) {
    if (!std::isfinite(f)) throw std::invalid_argument("static mesh: non-finite vertex coordinate");
  }
  auto mesh = std::make_shared<StaticMesh>();
  mesh->id_ = id;
  mesh->cell_ = cell_size;
  mesh->tris_.reserve(indices.size() / 3);
  Vec3 lo = Vec3::Constant(1e300), hi = Vec3::Constant(-1e300);
  for (std::size_t t = 0; t < indices.size(); t += 3) {
    Tri tri;
    Vec3* v[3] = {&tri.a, &tri.b, &tri.c};
    for (int k = 0; k < 3; ++k) {
      const std::uint32_t i = indices[t + k];
      if (i >= nv) {
        throw std::invalid_argument("static mesh: index " + std::to_string(i) + " of triangle " +
                                    std::to_string(t / 3) + " is out of range (" +
                                    std::to_string(nv) + " vertices)");
      }
      *v[k] = Vec3(xyz[3 * i], xyz[3 * i + 1], xyz[3 * i + 2]);
    }
    if ((tri.b - tri.a).cross(tri.c - tri.a).squaredNorm() < 1e-24) continue;  // degenerate
    tri.lo = tri.a.cwiseMin(tri.b).cwiseMin(tri.c);
    tri.hi = tri.a.cwiseMax(tri.b).cwiseMax(tri.c);
    lo = lo.cwiseMin(tri.lo);
    hi = hi.cwiseMax(tri.hi);
    mesh->tris_.push_back(tri);
  }
  if (mesh->tris_.empty()) {
    mesh->nx_ = mesh->ny_ = 0;
    mesh->cell_start_.assign(1, 0);
    return mesh;
  }
  mesh->lo_ = lo;
  mesh->hi_ = hi;
  mesh->nx_ = std::max(1, static_cast<int>(std::ceil((hi.x() - lo.x()) / cell_size)));
  mesh->ny_ = std::max(1, static_cast<int>(std::ceil((hi.y() - lo.y()) / cell_size)));
  const std::size_t cells = static_cast<std::size_t>(mesh->nx_) * mesh->ny_;
  if (cells > 64u * 1024u * 1024u) throw std::invalid_argument("static mesh: grid too fine for the mesh extent; raise cell_size");
  auto cell_range = [&](const Tri& t, int* x0, int* x1, int* y0, int* y1) {
    *x0 = std::clamp(static_cast<int>((t.lo.x() - lo.x()) / cell_size), 0, mesh->nx_ - 1);
    *x1 = std::clamp(static_cast<int>((t.hi.x() - lo.x()) / cell_size), 0, mesh->nx_ - 1);
    *y0 = std::clamp(static_cast<int>((t.lo.y() - lo.y()) / cell_size), 0, mesh->ny_ - 1);
    *y1 = std::clamp(static_cast<int>((t.hi.y() - lo.y()) / cell_size), 0, mesh->ny_ - 1);
  };
  std::vector<std::uint32_t> counts(cells + 1, 0);
  for (const Tri& t : mesh->tris_) {
    int x0, x1, y0, y1;
    cell_range(t, &x0, &x1, &y0, &y1);
    for (int y = y0; y <= y1; ++y)
      for (int x = x0; x <= x1; ++x) ++counts[static_cast<std::size_t>(y) * mesh->nx_ + x + 1];
  }
  for (std::size_t i = 1; i <= cells; ++i) counts[i] += counts[i - 1];
  mesh->cell_start_ = counts;
  mesh->cell_tris_.resize(counts[cells]);
  std::vector<std::uint32_t> fill(counts.begin(), counts.end() - 1);
  for (std::uint32_t ti = 0; ti < mesh->tris_.size(); ++ti) {
    int x0, x1, y0, y1;
    cell_range(mesh->tris_[ti], &x0, &x1, &y0, &y1);
    for (int y = y0; y <= y1; ++y)
      for (int x = x0; x <= x1; ++x) mesh->cell_tris_[fill[static_cast<std::size_t>(y) * mesh->nx_ + x]++] = ti;
  }
  return mesh;
}

int StaticMesh::QuerySphere(const Vec3& center, double radius, ContactPoint* out, int max_out) const {
  if (tris_.empty() || max_out <= 0 || !center.allFinite() || !std::isfinite(radius)) return 0;
  const Vec3 slo = center.array() - radius, shi = center.array() + radius;
  if ((shi.array() < lo_.array()).any() || (slo.array() > hi_.array()).any()) return 0;
  const int x0 = std::clamp(static_cast<int>((slo.x() - lo_.x()) / cell_), 0, nx_ - 1);
  const int x1 = std::clamp(static_cast<int>((shi.x() - lo_.x()) / cell_), 0, nx_ - 1);
  const int y0 = std::clamp(static_cast<int>((slo.y() - lo_.y()) / cell_), 0, ny_ - 1);
  const int y1 = std::clamp(static_cast<int>((shi.y() - lo_.y()) / cell_), 0, ny_ - 1);
  int n = 0;
  const double r2 = radius * radius;
  for (int y = y0; y <= y1; ++y) {
    for (int x = x0; x <= x1; ++x) {
      const std::size_t cell = static_cast<std::size_t>(y) * nx_ + x;
      for (std::uint32_t k = cell_start_[cell]; k < cell_start_[cell + 1]; ++k) {
        const Tri& t = tris_[cell_tris_[k]];
        if ((shi.array() < t.lo.array()).any() || (slo.array() > t.hi.array()).any()) continue;
        const Vec3 q = ClosestPointOnTriangle(center, t.a, t.b, t.c);
        const Vec3 d = center - q;
        const double dist2 = d.squaredNorm();
        if (dist2 >= r2) continue;
        ContactPoint cp;
        const double dist = std::sqrt(dist2);
        if (dist > 1e-9) {
          cp.normal = d / dist;
        } else {
          cp.normal = (t.b - t.a).cross(t.c - t.a).normalized();
        }
        cp.point = q;
        cp.depth = radius - dist;
        cp.kind = ObjectKind::kStatic;
        cp.object_id = id_;
        // Merge with a contact of (nearly) the same normal: the same triangle seen from another
        // cell, or a coplanar neighbour. Keep the deepest.
        bool merged = false;
        for (int i = 0; i < n; ++i) {
          if (out[i].normal.dot(cp.normal) > 0.999) {
            if (cp.depth > out[i].depth) out[i] = cp;
            merged = true;
            break;
          }
        }
        if (merged) continue;
        if (n < max_out) {
          out[n++] = cp;
        } else {
          int shallow = 0;
          for (int i = 1; i < n; ++i)
            if (out[i].depth < out[shallow].depth) shallow = i;
          if (cp.depth > out[shallow].depth) out[shallow] = cp;
        }
      }
    }
  }
  return n;
}

double StaticMesh::HeightBelow(const Vec3& p, double max_drop) const {
  if (tris_.empty() || !p.allFinite()) return -1;
  if (p.x() < lo_.x() || p.x() > hi_.x() || p.y() < lo_.y() || p.y() > hi_.y()) return -1;
  const int x = std::clamp(static_cast<int>((p.x() - lo_.x()) / cell_), 0, nx_ - 1);
  const int y = std::clamp(static_cast<int>((p.y() - lo_.y()) / cell_), 0, ny_ - 1);
  const std::size_t cell = static_cast<std::size_t>(y) * nx_ + x;
  double best = -1;
  for (std::uint32_t k = cell_start_[cell]; k < cell_start_[cell + 1]; ++k) {
    const Tri& t = tris_[cell_tris_[k]];
    // Vertical ray p - s z against the triangle (barycentric in XY).
    const double det = (t.b.y() - t.c.y()) * (t.a.x() - t.c.x()) + (t.c.x() - t.b.x()) * (t.a.y() - t.c.y());
    if (std::abs(det) < 1e-15) continue;
    const double l1 = ((t.b.y() - t.c.y()) * (p.x() - t.c.x()) + (t.c.x() - t.b.x()) * (p.y() - t.c.y())) / det;
    const double l2 = ((t.c.y() - t.a.y()) * (p.x() - t.c.x()) + (t.a.x() - t.c.x()) * (p.y() - t.c.y())) / det;
    const double l3 = 1 - l1 - l2;
    if (l1 < 0 || l2 < 0 || l3 < 0) continue;
    const double z = l1 * t.a.z() + l2 * t.b.z() + l3 * t.c.z();
    const double drop = p.z() - z;
    if (drop >= 0 && drop <= max_drop && (best < 0 || drop < best)) best = drop;
  }
  return best;
}

}  // namespace lockstep::air
