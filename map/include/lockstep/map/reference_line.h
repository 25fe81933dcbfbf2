#pragma once
#include <vector>

namespace lockstep::map {

enum class GeometryKind { Line, Arc, Spiral, Poly3, ParamPoly3 };

// One <geometry> record of a road's planView. Angles in radians, lengths in metres,
// curvature in 1/m, all in the OpenDRIVE inertial frame (x east, y north).
struct Geometry {
  double s = 0;        // start of this record along the reference line (m)
  double x = 0, y = 0; // start position (m)
  double hdg = 0;      // start heading (rad, CCW from +x)
  double length = 0;   // (m)
  GeometryKind kind = GeometryKind::Line;
  double curvature = 0;                    // arc (1/m)
  double curv_start = 0, curv_end = 0;     // spiral (1/m)
  double a = 0, b = 0, c = 0, d = 0;       // poly3: v(u) = a + b u + c u^2 + d u^3
  double au = 0, bu = 0, cu = 0, du = 0;   // paramPoly3 u(p)
  double av = 0, bv = 0, cv = 0, dv = 0;   // paramPoly3 v(p)
  // paramPoly3 pRange: "normalized" (p in [0, 1]) or "arcLength" (p in [0, length]).
  // A missing pRange means normalized, as in OpenDRIVE 1.4 and CARLA's reader.
  bool p_range_normalized = true;
  // poly3: u, paramPoly3: p, at equal arc-length steps over [0, length] (filled by
  // PrepareGeometry), so both are evaluated by true arc length.
  std::vector<double> arc_table;
};

struct Pose2 {
  double x = 0, y = 0;     // (m)
  double hdg = 0;          // (rad)
  double curvature = 0;    // (1/m), signed, positive = turning left
};

// Fresnel integrals S(x) = int_0^x sin(pi t^2 / 2) dt, C(x) = int_0^x cos(pi t^2 / 2) dt.
void Fresnel(double x, double* S, double* C);

// Fills derived tables (poly3 arc-length table). Call once after parsing.
void PrepareGeometry(Geometry& g);
// Pose at distance ds in [0, g.length] from the start of the record.
Pose2 EvaluateGeometry(const Geometry& g, double ds);
// Pose at road coordinate s on a planView (records sorted by s); s is clamped.
Pose2 EvaluateReferenceLine(const std::vector<Geometry>& plan_view, double s);
// Index of the record that holds s.
std::size_t FindGeometry(const std::vector<Geometry>& plan_view, double s);

}  // namespace lockstep::map
