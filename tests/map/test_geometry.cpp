#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

#include "lockstep/map/reference_line.h"

namespace lockstep::map {
namespace {

TEST(map_fresnel, KnownValues) {
  // Reference values (Abramowitz & Stegun table 7.7).
  double s, c;
  Fresnel(1.0, &s, &c);
  EXPECT_NEAR(c, 0.7798934003768228, 1e-12);
  EXPECT_NEAR(s, 0.4382591473903548, 1e-12);
  Fresnel(2.0, &s, &c);
  EXPECT_NEAR(c, 0.4882534060753408, 1e-12);
  Fresnel(-2.0, &s, &c);
  EXPECT_NEAR(s, -0.3434156783636982, 1e-12);
  Fresnel(100.0, &s, &c);
  EXPECT_NEAR(c, 0.5, 1e-5);  // tends to 1/2
  EXPECT_NEAR(s, 0.5 - 1.0 / (std::numbers::pi * 100.0), 1e-6);  // S(x) ~ 1/2 - cos(pi x^2/2)/(pi x)
}

TEST(map_geometry, ArcEndpointClosedForm) {
  Geometry g;
  g.kind = GeometryKind::Arc;
  g.x = 3;
  g.y = -2;
  g.hdg = 0.3;
  g.curvature = 1.0 / 20.0;
  g.length = std::numbers::pi * 10.0;  // half of a 20 m radius half-circle: 90 degrees
  const Pose2 p = EvaluateGeometry(g, g.length);
  // Centre of the circle is 20 m to the left of the start.
  const double cx = g.x - 20 * std::sin(g.hdg), cy = g.y + 20 * std::cos(g.hdg);
  EXPECT_NEAR(std::hypot(p.x - cx, p.y - cy), 20.0, 1e-9);
  EXPECT_NEAR(p.hdg, g.hdg + std::numbers::pi / 2, 1e-12);
  EXPECT_NEAR(p.x, cx + 20 * std::sin(g.hdg + std::numbers::pi / 2), 1e-9);
  EXPECT_NEAR(p.y, cy - 20 * std::cos(g.hdg + std::numbers::pi / 2), 1e-9);
}

// Midpoint-rule integral of the clothoid, as an independent check of the Fresnel form.
Pose2 IntegrateSpiral(const Geometry& g, double L) {
  const int n = 200000;
  const double h = L / n, c = (g.curv_end - g.curv_start) / g.length;
  double x = g.x, y = g.y;
  for (int i = 0; i < n; ++i) {
    const double u = (i + 0.5) * h;
    const double th = g.hdg + g.curv_start * u + 0.5 * c * u * u;
    x += h * std::cos(th);
    y += h * std::sin(th);
  }
  return {x, y, g.hdg + g.curv_start * L + 0.5 * c * L * L, g.curv_start + c * L};
}

TEST(map_geometry, SpiralMatchesIntegral) {
  for (auto [k0, k1] : {std::pair{0.0, 0.05}, std::pair{0.02, -0.04}, std::pair{-0.1, -0.01}, std::pair{0.03, 0.03}}) {
    Geometry g;
    g.kind = GeometryKind::Spiral;
    g.x = 10;
    g.y = 5;
    g.hdg = -1.0;
    g.length = 60;
    g.curv_start = k0;
    g.curv_end = k1;
    const Pose2 a = EvaluateGeometry(g, g.length), b = IntegrateSpiral(g, g.length);
    EXPECT_NEAR(a.x, b.x, 1e-6) << k0 << " " << k1;
    EXPECT_NEAR(a.y, b.y, 1e-6);
    EXPECT_NEAR(a.hdg, b.hdg, 1e-12);
    EXPECT_NEAR(a.curvature, k1, 1e-12);
  }
}

TEST(map_geometry, ClothoidFromZeroCurvatureIsFresnel) {
  // Standard clothoid x = A sqrt(pi) C(s / (A sqrt(pi))), with A^2 = L / k_end.
  Geometry g;
  g.kind = GeometryKind::Spiral;
  g.length = 50;
  g.curv_end = 0.04;
  const double A = std::sqrt(g.length / g.curv_end);
  double S, C;
  Fresnel(g.length / (A * std::sqrt(std::numbers::pi)), &S, &C);
  const Pose2 p = EvaluateGeometry(g, g.length);
  EXPECT_NEAR(p.x, A * std::sqrt(std::numbers::pi) * C, 1e-9);
  EXPECT_NEAR(p.y, A * std::sqrt(std::numbers::pi) * S, 1e-9);
}

TEST(map_geometry, Poly3AndParamPoly3) {
  Geometry g;
  g.kind = GeometryKind::ParamPoly3;
  g.p_range_normalized = false;
  g.hdg = 0.5;
  g.bu = 1.0;  // u = p, v = 0.01 p^2 (arcLength range); its arc length to p = 10 in closed form:
  g.cv = 0.01;
  g.length = 5 * std::sqrt(1.04) + std::asinh(0.2) / 0.04;
  PrepareGeometry(g);
  Pose2 p = EvaluateGeometry(g, g.length);
  EXPECT_NEAR(p.x, 10 * std::cos(0.5) - 1.0 * std::sin(0.5), 1e-6);
  EXPECT_NEAR(p.y, 10 * std::sin(0.5) + 1.0 * std::cos(0.5), 1e-6);
  EXPECT_NEAR(p.hdg, 0.5 + std::atan(0.2), 1e-6);
  g.p_range_normalized = true;  // the same curve over p in [0, 1]
  g.bu = 10.0;
  g.cv = 1.0;
  PrepareGeometry(g);
  p = EvaluateGeometry(g, g.length);
  EXPECT_NEAR(p.x, 10 * std::cos(0.5) - 1.0 * std::sin(0.5), 1e-6);
  // poly3: straight line v = 0.5 u has arc length sqrt(1.25) per u.
  Geometry q;
  q.kind = GeometryKind::Poly3;
  q.b = 0.5;
  q.length = std::sqrt(1.25) * 8;
  PrepareGeometry(q);
  p = EvaluateGeometry(q, q.length);
  EXPECT_NEAR(p.x, 8.0, 1e-6);
  EXPECT_NEAR(p.y, 4.0, 1e-6);
  EXPECT_NEAR(p.hdg, std::atan(0.5), 1e-12);
}

TEST(map_geometry, ReferenceLineLookup) {
  std::vector<Geometry> pv(2);
  pv[0].length = 10;
  pv[1].s = 10;
  pv[1].x = 10;
  pv[1].kind = GeometryKind::Arc;
  pv[1].curvature = 0.1;
  pv[1].length = 5;
  EXPECT_NEAR(EvaluateReferenceLine(pv, 5).x, 5, 1e-12);
  EXPECT_NEAR(EvaluateReferenceLine(pv, 15).hdg, 0.5, 1e-12);
  EXPECT_EQ(FindGeometry(pv, 10.0), 1u);
}

}  // namespace
}  // namespace lockstep::map
