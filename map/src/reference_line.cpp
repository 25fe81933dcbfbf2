#include <algorithm>
#include <cmath>
#include <numbers>

#include "lockstep/map/reference_line.h"

namespace lockstep::map {
namespace {

constexpr int kArcTableSize = 128;

Pose2 Line(const Geometry& g, double ds) {
  return {g.x + ds * std::cos(g.hdg), g.y + ds * std::sin(g.hdg), g.hdg, 0.0};
}

Pose2 Arc(const Geometry& g, double ds) {
  const double k = g.curvature;
  if (std::fabs(k) < 1e-12) return Line(g, ds);
  const double h = g.hdg + k * ds;
  return {g.x + (std::sin(h) - std::sin(g.hdg)) / k, g.y + (std::cos(g.hdg) - std::cos(h)) / k, h, k};
}

// Clothoid: curvature k(u) = k0 + c u. Heading is quadratic in u; substituting the
// distance from the point of zero curvature turns the position integral into
// Fresnel integrals, which gives the exact closed form below.
Pose2 Spiral(const Geometry& g, double ds) {
  const double k0 = g.curv_start;
  const double c = g.length > 0 ? (g.curv_end - g.curv_start) / g.length : 0.0;
  const double hdg = g.hdg + k0 * ds + 0.5 * c * ds * ds;
  const double k = k0 + c * ds;
  if (std::fabs(c) < 1e-12) {
    Geometry arc = g;
    arc.curvature = k0;
    return Arc(arc, ds);
  }
  const double sign = c > 0 ? 1.0 : -1.0;
  const double scale = std::sqrt(std::numbers::pi / std::fabs(c));
  const double theta0 = g.hdg - 0.5 * k0 * k0 / c;  // heading at the zero-curvature point
  const double t0 = (k0 / c) / scale;
  const double t1 = (k0 / c + ds) / scale;
  double s0, c0, s1, c1;
  Fresnel(t0, &s0, &c0);
  Fresnel(t1, &s1, &c1);
  const double dC = c1 - c0, dS = s1 - s0;
  const double ct = std::cos(theta0), st = std::sin(theta0);
  const double x = g.x + scale * (ct * dC - sign * st * dS);
  const double y = g.y + scale * (st * dC + sign * ct * dS);
  return {x, y, hdg, k};
}

double Poly(double a, double b, double c, double d, double p) { return a + p * (b + p * (c + p * d)); }
double PolyD(double b, double c, double d, double p) { return b + p * (2 * c + p * 3 * d); }
double PolyDD(double c, double d, double p) { return 2 * c + 6 * d * p; }

Pose2 Local(const Geometry& g, double u, double v, double du, double dv, double ddu, double ddv) {
  const double ch = std::cos(g.hdg), sh = std::sin(g.hdg);
  Pose2 p;
  p.x = g.x + u * ch - v * sh;
  p.y = g.y + u * sh + v * ch;
  p.hdg = g.hdg + std::atan2(dv, du);
  const double n = std::pow(du * du + dv * dv, 1.5);
  p.curvature = n > 1e-12 ? (du * ddv - dv * ddu) / n : 0.0;
  return p;
}

// poly3 is given in u; arc length is tabulated at equal u steps and inverted.
Pose2 Poly3Geom(const Geometry& g, double ds) {
  double u = ds;
  const auto& tab = g.arc_table;
  if (tab.size() >= 2 && g.length > 0) {
    const double f = std::clamp(ds / g.length, 0.0, 1.0) * static_cast<double>(tab.size() - 1);
    const std::size_t i = std::min(static_cast<std::size_t>(f), tab.size() - 2);
    const double w = f - static_cast<double>(i);
    u = tab[i] * (1 - w) + tab[i + 1] * w;
  }
  return Local(g, u, Poly(g.a, g.b, g.c, g.d, u), 1.0, PolyD(g.b, g.c, g.d, u), 0.0, PolyDD(g.c, g.d, u));
}

Pose2 ParamPoly3(const Geometry& g, double ds) {
  const double p = g.p_range_normalized ? (g.length > 0 ? ds / g.length : 0.0) : ds;
  return Local(g, Poly(g.au, g.bu, g.cu, g.du, p), Poly(g.av, g.bv, g.cv, g.dv, p),
               PolyD(g.bu, g.cu, g.du, p), PolyD(g.bv, g.cv, g.dv, p), PolyDD(g.cu, g.du, p),
               PolyDD(g.cv, g.dv, p));
}

}  // namespace

void PrepareGeometry(Geometry& g) {
  if (g.kind != GeometryKind::Poly3 || !(g.length > 0)) return;
  // Integrate arc length over u with fine Simpson steps, then sample u(s) at
  // kArcTableSize equal arc-length steps.
  constexpr int kSteps = 2048;
  auto speed = [&](double u) { const double dv = PolyD(g.b, g.c, g.d, u); return std::sqrt(1 + dv * dv); };
  // u_end: the u where arc length reaches g.length (arc length >= u, so u_end <= length).
  std::vector<double> us(kSteps + 1), ss(kSteps + 1);
  const double u_max = g.length;
  const double h = u_max / kSteps;
  us[0] = 0;
  ss[0] = 0;
  for (int i = 1; i <= kSteps; ++i) {
    const double a = (i - 1) * h, b = i * h;
    us[static_cast<std::size_t>(i)] = b;
    ss[static_cast<std::size_t>(i)] = ss[static_cast<std::size_t>(i - 1)] +
                                       h / 6 * (speed(a) + 4 * speed(0.5 * (a + b)) + speed(b));
  }
  g.arc_table.assign(kArcTableSize + 1, 0.0);
  std::size_t j = 0;
  for (int k = 0; k <= kArcTableSize; ++k) {
    const double target = g.length * k / kArcTableSize;
    while (j + 1 < ss.size() && ss[j + 1] < target) ++j;
    if (j + 1 >= ss.size()) {
      g.arc_table[static_cast<std::size_t>(k)] = us.back();
      continue;
    }
    const double span = ss[j + 1] - ss[j];
    const double w = span > 0 ? (target - ss[j]) / span : 0.0;
    g.arc_table[static_cast<std::size_t>(k)] = us[j] + std::clamp(w, 0.0, 1.0) * h;
  }
}

Pose2 EvaluateGeometry(const Geometry& g, double ds) {
  ds = std::clamp(ds, 0.0, std::max(0.0, g.length));
  switch (g.kind) {
    case GeometryKind::Line: return Line(g, ds);
    case GeometryKind::Arc: return Arc(g, ds);
    case GeometryKind::Spiral: return Spiral(g, ds);
    case GeometryKind::Poly3: return Poly3Geom(g, ds);
    case GeometryKind::ParamPoly3: return ParamPoly3(g, ds);
  }
  return Line(g, ds);
}

std::size_t FindGeometry(const std::vector<Geometry>& pv, double s) {
  auto it = std::upper_bound(pv.begin(), pv.end(), s, [](double v, const Geometry& g) { return v < g.s; });
  return it == pv.begin() ? 0 : static_cast<std::size_t>(it - pv.begin() - 1);
}

Pose2 EvaluateReferenceLine(const std::vector<Geometry>& pv, double s) {
  if (pv.empty()) return {};
  const Geometry& g = pv[FindGeometry(pv, s)];
  return EvaluateGeometry(g, s - g.s);
}

}  // namespace lockstep::map
