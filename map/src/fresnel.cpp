// Fresnel integrals by power series for small arguments and a continued fraction
// (modified Lentz) for large ones, as in Numerical Recipes' frenel: accurate to ~1e-15.
#include <cmath>
#include <complex>
#include <numbers>

#include "lockstep/map/reference_line.h"

namespace lockstep::map {

void Fresnel(double x, double* S, double* C) {
  constexpr double kPi = std::numbers::pi;
  constexpr double kEps = 1e-16;
  constexpr double kTiny = 1e-300;
  constexpr int kMaxIter = 200;
  const double ax = std::fabs(x);
  double s = 0, c = 0;
  if (ax < std::sqrt(1e-300)) {
    s = 0;
    c = ax;
  } else if (ax <= 1.5) {
    // Alternating series: C = sum (-1)^n (pi/2)^(2n) x^(4n+1) / ((2n)! (4n+1)), S likewise odd terms.
    double sum_s = 0, sum_c = 1, sign = 1, fact = 1, term = 1;
    bool odd = true;
    const double t = 0.5 * kPi * ax * ax;
    for (int k = 1; k <= kMaxIter; ++k) {
      fact *= t / k;
      term = fact / (2 * k + 1);
      if (odd) {
        sum_s += sign * term;
        sign = -sign;
      } else {
        sum_c += sign * term;
      }
      if (term < kEps * std::fabs(odd ? sum_s : sum_c)) break;
      odd = !odd;
    }
    s = sum_s * ax;
    c = sum_c * ax;
  } else {
    const double pix2 = kPi * ax * ax;
    std::complex<double> b(1.0, -pix2);
    std::complex<double> cc(1.0 / kTiny, 0.0);
    std::complex<double> d = 1.0 / b;
    std::complex<double> h = d;
    int n = -1;
    for (int k = 2; k <= kMaxIter; ++k) {
      n += 2;
      const double a = -n * (n + 1.0);
      b += 4.0;
      d = 1.0 / (a * d + b);
      cc = b + a / cc;
      const std::complex<double> del = cc * d;
      h *= del;
      if (std::fabs(del.real() - 1.0) + std::fabs(del.imag()) < kEps) break;
    }
    h *= std::complex<double>(ax, -ax);
    const std::complex<double> cs =
        std::complex<double>(0.5, 0.5) *
        (1.0 - std::complex<double>(std::cos(0.5 * pix2), std::sin(0.5 * pix2)) * h);
    c = cs.real();
    s = cs.imag();
  }
  if (x < 0) {
    c = -c;
    s = -s;
  }
  *S = s;
  *C = c;
}

}  // namespace lockstep::map
