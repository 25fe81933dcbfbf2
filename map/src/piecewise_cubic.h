#pragma once
// Arithmetic on OpenDRIVE's piecewise cubics (sequences of Poly3 records sorted by s,
// evaluated by EvalPoly3Sequence). Internal to the map library.
#include <algorithm>
#include <vector>

#include "lockstep/map/opendrive.h"

namespace lockstep::map {

// The same cubic expanded about p.s + h instead of p.s.
inline Poly3 ShiftPoly3(const Poly3& p, double h) {
  return Poly3{p.s + h, p.Eval(h), p.Slope(h), p.c + 3 * p.d * h, p.d};
}

// The sequence seen from `origin` on: records re-based so that s = 0 is `origin`, with
// a record starting exactly at 0 (EvalPoly3Sequence holds the first record's start
// value before it, and an empty sequence is 0).
inline std::vector<Poly3> RebasePoly3s(const std::vector<Poly3>& seq, double origin) {
  std::vector<Poly3> out;
  if (seq.empty()) return {Poly3{}};
  auto it = std::upper_bound(seq.begin(), seq.end(), origin, [](double v, const Poly3& p) { return v < p.s; });
  if (it == seq.begin()) {
    out.push_back(Poly3{0.0, seq.front().Eval(0.0), 0, 0, 0});
  } else {
    Poly3 p = ShiftPoly3(*(it - 1), origin - (it - 1)->s);
    p.s = 0;
    out.push_back(p);
  }
  for (; it != seq.end(); ++it) {
    Poly3 p = *it;
    p.s -= origin;
    out.push_back(p);
  }
  return out;
}

// a + k * b for two rebased sequences (both start at s = 0).
inline std::vector<Poly3> CombinePoly3s(const std::vector<Poly3>& a, const std::vector<Poly3>& b, double k) {
  std::vector<double> starts;
  for (const Poly3& p : a) starts.push_back(p.s);
  for (const Poly3& p : b) starts.push_back(p.s);
  std::sort(starts.begin(), starts.end());
  starts.erase(std::unique(starts.begin(), starts.end()), starts.end());
  auto active = [](const std::vector<Poly3>& seq, double s) {
    auto it = std::upper_bound(seq.begin(), seq.end(), s, [](double v, const Poly3& p) { return v < p.s; });
    return ShiftPoly3(*(it == seq.begin() ? it : it - 1), s - (it == seq.begin() ? it : it - 1)->s);
  };
  std::vector<Poly3> out;
  for (double s : starts) {
    const Poly3 pa = active(a, s), pb = active(b, s);
    out.push_back(Poly3{s, pa.a + k * pb.a, pa.b + k * pb.b, pa.c + k * pb.c, pa.d + k * pb.d});
  }
  return out;
}

}  // namespace lockstep::map
