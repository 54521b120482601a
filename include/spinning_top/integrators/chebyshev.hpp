// Piecewise Chebyshev interpolation of a smooth vector-valued function of time, built lazily,
// piece by piece, the first time a piece is asked for. The closed-form solution (exact.hpp)
// uses it to answer many requests cheaply: one evaluation is one Clenshaw sum of a short
// Chebyshev series per component, a few dozen multiply-adds, instead of the closed form's
// elliptic functions, square roots and Fourier series. This is how planetary ephemerides are
// served (JPL's DE files: Chebyshev coefficients per granule of time; Newhall, Celest. Mech. 45
// (1989) 305).
#pragma once

#include <Eigen/Core>
#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <memory>
#include <vector>

namespace spinning_top {

/// Dim components, each a Chebyshev series of degree Degree on every one of `pieces` equal
/// pieces of [0, span). Coefficients come from the values at the Chebyshev points of the
/// first kind (interpolation; Trefethen, Approximation Theory and Approximation Practice, ch. 3
/// and 8): for a function analytic in a Bernstein ellipse of parameter rho about a piece, the
/// error decays as rho^-Degree, so halving the pieces' length squares it.
template <int Dim, int Degree>
class PiecewiseChebyshev {
 public:
  static constexpr int kCoefficients = Degree + 1;
  using Values = std::array<double, Dim>;

  PiecewiseChebyshev() = default;
  PiecewiseChebyshev(double span, int pieces) { assign(span, pieces); }

  /// Forgets every piece and splits [0, span) into `pieces` pieces.
  void assign(double span, int pieces) {
    span_ = span;
    pieces_ = std::max(1, pieces);
    width_ = span_ / pieces_;
    inverse_width_ = pieces_ / span_;
    built_.assign(pieces_, 0);
    // Not zeroed: a piece is written whole before it is marked built (thousands of pieces of a
    // hard motion would otherwise cost a megabyte of stores at every start).
    coefficients_.reset(new Values[static_cast<std::size_t>(pieces_) * kCoefficients]);
  }

  double span() const { return span_; }
  int pieces() const { return pieces_; }
  int built_pieces() const { return static_cast<int>(std::count(built_.begin(), built_.end(), 1)); }

  /// Index of the piece that holds r in [0, span) (r at or beyond span: the last piece).
  int piece_of(double r) const { return std::min(pieces_ - 1, std::max(0, static_cast<int>(r * inverse_width_))); }
  bool built(int piece) const { return built_[piece] != 0; }
  void forget(int piece) { built_[piece] = 0; }

  /// Interpolates f: r -> Values on piece `piece` at its Chebyshev points. Returns the largest
  /// of the last two coefficients of each component divided by `scale` of that component: the
  /// caller's test of convergence (an analytic function's coefficients decay geometrically, so
  /// the last two bound what is neglected).
  template <class F>
  double build(int piece, const F& f, const Values& scale) {
    std::array<Values, kCoefficients> samples;
    const double left = piece * width_;
    for (int j = 0; j < kCoefficients; ++j) samples[j] = f(left + 0.5 * width_ * (1.0 + node(j)));
    Values* c = &coefficients_[static_cast<std::size_t>(piece) * kCoefficients];
    for (int k = 0; k < kCoefficients; ++k) {
      Values sum{};
      for (int j = 0; j < kCoefficients; ++j) {
        const double weight = cosine(k, j);
        for (int i = 0; i < Dim; ++i) sum[i] += weight * samples[j][i];
      }
      for (int i = 0; i < Dim; ++i) c[k][i] = (k == 0 ? 1.0 : 2.0) / kCoefficients * sum[i];
    }
    built_[piece] = 1;
    double tail = 0.0;
    for (int i = 0; i < Dim; ++i)
      tail = std::max(tail, std::max(std::abs(c[Degree][i]), std::abs(c[Degree - 1][i])) / scale[i]);
    // Stored as monomial coefficients in x, for Estrin's scheme (evaluate(): one multiply-add
    // per degree instead of Clenshaw's two, in a short dependency chain). The change of basis costs accuracy only if the coefficients
    // do not decay: the monomial sum's rounding is eps sum_j |c_j| |T_j(i)| <= eps sum_j |c_j|
    // (1 + sqrt 2)^j, and converged pieces have |c_j| falling much faster than (1 + sqrt 2)^-j
    // (their last ones are ~eps, so |c_j| ~ rho^-j with rho ~ eps^(-1/Degree) > 10).
    std::array<Values, kCoefficients> monomial{};
    for (int j = 0; j < kCoefficients; ++j)
      for (int k = 0; k <= j; ++k) {
        const double t = chebyshev_monomials()[j][k];
        if (t == 0.0) continue;
        for (int i = 0; i < Dim; ++i) monomial[k][i] += c[j][i] * t;
      }
    for (int k = 0; k < kCoefficients; ++k) c[k] = monomial[k];
    return tail;
  }

  /// The interpolant at r (its piece must be built), all components at once, by Estrin's
  /// scheme: pairs c_2i + x c_2i+1, then pairs of those with x^2, x^4, ... (Knuth, TAOCP vol. 2,
  /// sec. 4.6.4). Horner's rule is one multiply-add per degree but each waits for the last: its
  /// dependency chain is the whole polynomial (13 x (multiply + add) latency, ~90 cycles without
  /// FMA), Estrin's is log2(14) = 4 levels, and its independent multiply-adds fill the pipelines.
  Values evaluate(double r) const {
    const double position = r * inverse_width_;
    const int piece = std::min(pieces_ - 1, std::max(0, static_cast<int>(position)));
    const double x = 2.0 * (position - piece) - 1.0;
    const Values* c = &coefficients_[static_cast<std::size_t>(piece) * kCoefficients];
    using Packet = Eigen::Array<double, Dim, 1>;
    Packet level[kCoefficients];
    int n = kCoefficients;
    for (int k = 0; k + 1 < n; k += 2)
      level[k / 2] = Eigen::Map<const Packet>(c[k].data()) + x * Eigen::Map<const Packet>(c[k + 1].data());
    if (n % 2) level[n / 2] = Eigen::Map<const Packet>(c[n - 1].data());
    n = (n + 1) / 2;
    for (double power = x * x; n > 1; power *= power) {
      for (int k = 0; k + 1 < n; k += 2) level[k / 2] = level[k] + power * level[k + 1];
      if (n % 2) level[n / 2] = level[n - 1];
      n = (n + 1) / 2;
    }
    Values out;
    Eigen::Map<Packet>(out.data()) = level[0];
    return out;
  }

 private:
  static constexpr double kPi = 3.14159265358979323846;
  /// x_j = cos(pi (j + 1/2) / n), n = Degree + 1: the Chebyshev points of the first kind.
  static double node(int j) { return cosines()[1][j]; }
  /// cos(pi k (j + 1/2) / n), tabulated once per instantiation.
  static double cosine(int k, int j) { return cosines()[k][j]; }
  /// Monomial coefficients of T_j: T_0 = 1, T_1 = x, T_{j+1} = 2x T_j - T_{j-1} (exact integers).
  static const std::array<std::array<double, kCoefficients>, kCoefficients>& chebyshev_monomials() {
    static const auto table = [] {
      std::array<std::array<double, kCoefficients>, kCoefficients> t{};
      t[0][0] = 1.0;
      if (kCoefficients > 1) t[1][1] = 1.0;
      for (int j = 1; j + 1 < kCoefficients; ++j)
        for (int k = 0; k < kCoefficients; ++k) t[j + 1][k] = (k > 0 ? 2.0 * t[j][k - 1] : 0.0) - t[j - 1][k];
      return t;
    }();
    return table;
  }
  static const std::array<std::array<double, kCoefficients>, kCoefficients>& cosines() {
    static const auto table = [] {
      std::array<std::array<double, kCoefficients>, kCoefficients> t{};
      for (int k = 0; k < kCoefficients; ++k)
        for (int j = 0; j < kCoefficients; ++j) t[k][j] = std::cos(kPi * k * (j + 0.5) / kCoefficients);
      return t;
    }();
    return table;
  }

  double span_ = 0.0, width_ = 0.0, inverse_width_ = 0.0;
  int pieces_ = 0;
  std::vector<unsigned char> built_;
  std::unique_ptr<Values[]> coefficients_;
};

}  // namespace spinning_top
