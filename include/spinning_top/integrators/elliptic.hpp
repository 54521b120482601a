// Jacobi's elliptic functions and Carlson's integral R_F, for the closed-form solution of the
// integrable tops (integrators/exact.hpp). The modulus is given by its complement k' = sqrt(1 -
// k^2), because the tops near the separatrix (a slow top released near the vertical, an
// unstable sleeping top) have k' ~ 1e-7: from k itself, k' would keep only a few digits.
#pragma once

#include <array>
#include <cmath>
#include <limits>

namespace spinning_top::elliptic {

/// sn, cn, dn of one argument.
struct JacobiValues {
  double sn = 0.0, cn = 1.0, dn = 1.0;
};

/// A modulus k (given by k' in (0, 1]) with its arithmetic-geometric mean sequence computed once,
/// so that each evaluation of sn, cn, dn is only the descending part of Gauss' transformation.
/// K = pi / (2 AGM(1, k')) (DLMF 19.8.5).
class JacobiModulus {
 public:
  JacobiModulus() = default;
  /// k' in (0, 1]; k' = 1 is k = 0 (sn = sin). k' = 0 (k = 1) has K = infinity: not allowed.
  explicit JacobiModulus(double complement) : complement_(complement) {
    k2_ = (1.0 - complement) * (1.0 + complement);
    // Bulirsch's sequence (sncndn): m_l = a_{l-1}, n_l = b_l = sqrt(a_{l-1} b_{l-1}), stopped
    // when |a - b| <= 1e-8 a: the AGM converges quadratically, so the next level's error is
    // below 1e-16 (Numerical Recipes' CA, the square root of the accuracy).
    double a = 1.0, b2 = complement * complement, mean = 1.0;
    for (int level = 1; level < kMaxLevels; ++level) {
      levels_ = level;
      m_[level] = a;
      const double b = std::sqrt(b2);
      n_[level] = b;
      mean = 0.5 * (a + b);
      if (std::abs(a - b) <= 1e-8 * a) break;
      b2 = a * b;
      a = mean;
    }
    mean_ = mean;
    quarter_period_ = 0.5 * kPi / mean;
  }

  double complement() const { return complement_; }  ///< k'
  double k2() const { return k2_; }                  ///< k^2
  double quarter_period() const { return quarter_period_; }  ///< K(k)

  /// sn, cn, dn at any w. The argument is reduced to [0, K/2] by the periods and reflections
  /// (DLMF 22.4.3, 22.6.1): sn(w + 2K) = -sn, cn(w + 2K) = -cn; sn(2K - w) = sn, cn(2K - w) = -cn;
  /// sn(K - x) = cn(x)/dn(x), cn(K - x) = k' sn(x)/dn(x), dn(K - x) = k'/dn(x). Near K, where cn and
  /// dn are small (dn(K) = k'), they then keep their relative precision, which cos(am(w)) would
  /// lose (an absolute error eps in am(w) is a relative error eps / k' in dn).
  JacobiValues at(double w) const {
    const double half_period = 2.0 * quarter_period_;
    double r = w;
    double sign = 1.0;
    if (!(r >= 0.0 && r < half_period)) {
      const double turns = std::floor(r / half_period);
      r = std::fma(-turns, half_period, r);
      if (std::fmod(turns, 2.0) != 0.0) sign = -1.0;
      r = std::min(std::max(r, 0.0), half_period);
    }
    double cn_sign = sign;
    if (r > quarter_period_) {
      r = half_period - r;
      cn_sign = -cn_sign;
    }
    JacobiValues v;
    if (r > 0.5 * quarter_period_) {
      const JacobiValues x = first_half(quarter_period_ - r);
      v.sn = sign * x.cn / x.dn;
      v.cn = cn_sign * complement_ * x.sn / x.dn;
      v.dn = complement_ / x.dn;
    } else {
      v = first_half(r);
      v.sn *= sign;
      v.cn *= cn_sign;
    }
    return v;
  }

 private:
  /// Bulirsch's descending Landen transformation (R. Bulirsch, Numer. Math. 7 (1965) 78, procedure
  /// sncndn; Numerical Recipes, 2nd ed., sec. 6.11) for 0 <= w <= K/2: one sin/cos and a few
  /// divisions per level of the stored sequence.
  JacobiValues first_half(double w) const {
    JacobiValues v;
    if (k2_ == 0.0) {
      v.sn = std::sin(w), v.cn = std::cos(w), v.dn = 1.0;
      return v;
    }
    const double u = w * mean_;
    double sn = std::sin(u), cn = std::cos(u), dn = 1.0;
    if (sn != 0.0) {
      double a = cn / sn, c = mean_ * a;
      for (int level = levels_; level >= 1; --level) {
        const double b = m_[level];
        a *= c;
        c *= dn;
        dn = (n_[level] + a) / (b + a);
        a = c / b;
      }
      a = 1.0 / std::sqrt(c * c + 1.0);
      sn = sn >= 0.0 ? a : -a;
      cn = c * sn;
    }
    v.sn = sn, v.cn = cn, v.dn = dn;
    return v;
  }

  static constexpr double kPi = 3.14159265358979323846;
  static constexpr int kMaxLevels = 32;  // k' = 1e-300 needs 13
  double complement_ = 1.0, k2_ = 0.0, mean_ = 1.0, quarter_period_ = 0.5 * kPi;
  int levels_ = 0;
  std::array<double, kMaxLevels> m_{}, n_{};
};

/// Carlson's symmetric integral R_F(x, y, z) = 1/2 int_0^inf dt / sqrt((t+x)(t+y)(t+z)), x, y, z
/// >= 0, at most one zero, by the duplication theorem and the fifth-order series (B. C. Carlson,
/// Numer. Algorithms 10 (1995) 13, Algorithm 1; DLMF 19.36.1). With the stopping rule
/// max|1 - x/mu| < 1e-3 the truncation is below 1e-19 relative.
inline double carlson_rf(double x, double y, double z) {
  for (int iteration = 0; iteration < 100; ++iteration) {
    const double mu = (x + y + z) / 3.0;
    const double dx = 1.0 - x / mu, dy = 1.0 - y / mu, dz = 1.0 - z / mu;
    if (std::max({std::abs(dx), std::abs(dy), std::abs(dz)}) < 1e-3) {
      const double e2 = dx * dy - dz * dz, e3 = dx * dy * dz;
      return (1.0 - e2 / 10.0 + e3 / 14.0 + e2 * e2 / 24.0 - 3.0 * e2 * e3 / 44.0) / std::sqrt(mu);
    }
    const double sx = std::sqrt(x), sy = std::sqrt(y), sz = std::sqrt(z);
    const double lambda = sx * (sy + sz) + sy * sz;
    x = 0.25 * (x + lambda);
    y = 0.25 * (y + lambda);
    z = 0.25 * (z + lambda);
  }
  return std::numeric_limits<double>::quiet_NaN();
}

/// The argument w in [0, K] with sn(w) = sn, cn(w) = cn >= 0, dn(w) = dn, i.e. the incomplete
/// integral F(phi | k) = sin(phi) R_F(cos^2 phi, 1 - k^2 sin^2 phi, 1) (DLMF 19.25.5), from the
/// squares, each computed by the caller without cancellation.
inline double inverse_sn(double sn, double cn2, double dn2) { return sn * carlson_rf(cn2, dn2, 1.0); }

}  // namespace spinning_top::elliptic
