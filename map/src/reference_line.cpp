#include <algorithm>
#include <cmath>
#include <numbers>

#include "lockstep/map/reference_line.h"

namespace lockstep::map {
namespace {

constexpr int kArcTableSize = 128;          // arc-length table entries at least
constexpr int kMaxArcTableSize = 8192;      // and at most (bounded memory on hostile input)
constexpr double kArcTableStep = 0.1;       // target arc-length step of the table (m)
constexpr int kMinSimpsonSteps = 64, kMaxSimpsonSteps = 16384;  // Simpson steps over the parameter range

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

// Curve parameter (poly3: u, paramPoly3: p) at arc length ds, from the table that
// PrepareGeometry fills (linear between samples). Without a table: the parameter
// proportional to ds (pRange as if the curve's speed were constant).
double ParameterAt(const Geometry& g, double ds, double p_end) {
  const auto& tab = g.arc_table;
  if (tab.size() < 2 || !(g.length > 0)) return g.length > 0 ? ds / g.length * p_end : 0.0;
  const double f = std::clamp(ds / g.length, 0.0, 1.0) * static_cast<double>(tab.size() - 1);
  const std::size_t i = std::min(static_cast<std::size_t>(f), tab.size() - 2);
  const double w = f - static_cast<double>(i);
  return tab[i] * (1 - w) + tab[i + 1] * w;
}

double ParamEnd(const Geometry& g) {
  if (g.kind == GeometryKind::ParamPoly3) return g.p_range_normalized ? 1.0 : g.length;
  return g.length;  // poly3: u <= arc length
}

Pose2 Poly3Geom(const Geometry& g, double ds) {
  const double u = ParameterAt(g, ds, ParamEnd(g));
  return Local(g, u, Poly(g.a, g.b, g.c, g.d, u), 1.0, PolyD(g.b, g.c, g.d, u), 0.0, PolyDD(g.c, g.d, u));
}

Pose2 ParamPoly3(const Geometry& g, double ds) {
  const double p = ParameterAt(g, ds, ParamEnd(g));
  return Local(g, Poly(g.au, g.bu, g.cu, g.du, p), Poly(g.av, g.bv, g.cv, g.dv, p),
               PolyD(g.bu, g.cu, g.du, p), PolyD(g.bv, g.cv, g.dv, p), PolyDD(g.cu, g.du, p),
               PolyDD(g.cv, g.dv, p));
}

}  // namespace

void PrepareGeometry(Geometry& g) {
  if ((g.kind != GeometryKind::Poly3 && g.kind != GeometryKind::ParamPoly3) || !(g.length > 0)) return;
  // Integrate arc length over the curve parameter with Simpson steps, then sample the
  // parameter at equal arc-length steps (the reader's table, interpolated linearly).
  // The record's length is authoritative: the table spans arc length [0, length], so
  // a curve whose parameter range is longer is cut there, and one whose range is
  // shorter is continued along its polynomial (up to 4x the range).
  auto speed = [&](double p) {
    if (g.kind == GeometryKind::Poly3) {
      const double dv = PolyD(g.b, g.c, g.d, p);
      return std::sqrt(1 + dv * dv);
    }
    const double du = PolyD(g.bu, g.cu, g.du, p), dv = PolyD(g.bv, g.cv, g.dv, p);
    return std::sqrt(du * du + dv * dv);
  };
  const double p_end = ParamEnd(g);
  const int steps = std::clamp(static_cast<int>(g.length / 0.05), kMinSimpsonSteps, kMaxSimpsonSteps);
  const double h = p_end / steps;
  std::vector<double> ps{0.0}, ss{0.0};
  for (int i = 1; i <= 4 * steps && ss.back() < g.length; ++i) {
    const double a = (i - 1) * h, b = i * h;
    ps.push_back(b);
    ss.push_back(ss.back() + h / 6 * (speed(a) + 4 * speed(0.5 * (a + b)) + speed(b)));
  }
  const int size = std::clamp(static_cast<int>(g.length / kArcTableStep), kArcTableSize, kMaxArcTableSize);
  g.arc_table.assign(static_cast<std::size_t>(size) + 1, 0.0);
  std::size_t j = 0;
  for (int k = 0; k <= size; ++k) {
    const double target = g.length * k / size;
    while (j + 1 < ss.size() && ss[j + 1] < target) ++j;
    if (j + 1 >= ss.size()) {  // the curve stops moving before `length`
      g.arc_table[static_cast<std::size_t>(k)] = ps.back();
      continue;
    }
    const double span = ss[j + 1] - ss[j];
    const double w = span > 0 ? (target - ss[j]) / span : 0.0;
    g.arc_table[static_cast<std::size_t>(k)] = ps[j] + std::clamp(w, 0.0, 1.0) * h;
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
