// Low-degree real polynomials for the turning points and the events of the quadrature
// (exact/quadrature.hpp, items 1 and 4): their arithmetic, the points where one changes sign,
// and the root finder under both (Newton's method safeguarded by bisection).
#pragma once

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <vector>

#include "spinning_top/integrators/exact/common.hpp"

namespace spinning_top {
namespace exact_detail {

/// Root of f in [lo, hi], where f(lo) and f(hi) differ in sign: Newton's method safeguarded by
/// bisection (Numerical Recipes' rtsafe), to round-off.
template <class F, class DF>
double bracketed_root(const F& f, const DF& df, double lo, double hi) {
  double f_lo = f(lo);
  if (f_lo == 0.0) return lo;
  if (f(hi) == 0.0) return hi;
  double x = 0.5 * (lo + hi);
  for (int iteration = 0; iteration < 200; ++iteration) {
    const double fx = f(x);
    if (fx == 0.0) return x;
    if ((fx < 0.0) == (f_lo < 0.0)) {
      lo = x;
      f_lo = fx;
    } else {
      hi = x;
    }
    const double slope = df(x);
    double next = slope != 0.0 ? x - fx / slope : 0.5 * (lo + hi);
    if (!(next > lo && next < hi)) next = 0.5 * (lo + hi);
    const bool done = std::abs(next - x) <= 2.0 * kEpsilon * std::abs(x) || hi - lo <= 2.0 * kEpsilon * std::abs(x);
    x = next;
    if (done) break;
  }
  return x;
}

/// A real polynomial c[0] + c[1] v + ... (low degree).
using Polynomial = std::vector<double>;

inline double evaluate(const Polynomial& p, double v) {
  double sum = 0.0;
  for (std::size_t i = p.size(); i-- > 0;) sum = sum * v + p[i];
  return sum;
}
inline Polynomial derivative(const Polynomial& p) {
  Polynomial d;
  for (std::size_t i = 1; i < p.size(); ++i) d.push_back(static_cast<double>(i) * p[i]);
  return d;
}
inline Polynomial multiply(const Polynomial& a, const Polynomial& b) {
  if (a.empty() || b.empty()) return {};
  Polynomial c(a.size() + b.size() - 1, 0.0);
  for (std::size_t i = 0; i < a.size(); ++i)
    for (std::size_t j = 0; j < b.size(); ++j) c[i + j] += a[i] * b[j];
  return c;
}
inline Polynomial subtract(Polynomial a, const Polynomial& b) {
  a.resize(std::max(a.size(), b.size()), 0.0);
  for (std::size_t i = 0; i < b.size(); ++i) a[i] -= b[i];
  return a;
}

/// The points of (lo, hi) where p changes sign, in increasing order: the critical points of p
/// (where p' changes sign, recursively) cut [lo, hi] into intervals where p is monotone, and
/// each interval whose ends differ in sign holds exactly one root (Newton-bisection). A root
/// where p only touches zero is not a sign change and is not reported.
inline std::vector<double> sign_changes(Polynomial p, double lo, double hi) {
  while (!p.empty() && p.back() == 0.0) p.pop_back();
  std::vector<double> roots;
  if (p.size() < 2 || !(lo < hi)) return roots;
  const Polynomial dp = derivative(p);
  std::vector<double> cuts = {lo};
  for (double c : sign_changes(dp, lo, hi)) cuts.push_back(c);
  cuts.push_back(hi);
  auto f = [&](double v) { return evaluate(p, v); };
  auto df = [&](double v) { return evaluate(dp, v); };
  for (std::size_t i = 0; i + 1 < cuts.size(); ++i) {
    const double fa = f(cuts[i]), fb = f(cuts[i + 1]);
    if ((fa < 0.0 && fb > 0.0) || (fa > 0.0 && fb < 0.0)) roots.push_back(bracketed_root(f, df, cuts[i], cuts[i + 1]));
  }
  return roots;
}

}  // namespace exact_detail
}  // namespace spinning_top
