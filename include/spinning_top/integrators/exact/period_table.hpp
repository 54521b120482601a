// The request table of the closed form (exact.hpp, item 3): one nutation period from the start
// (or up to the first event) interpolated lazily by piecewise Chebyshev series (chebyshev.hpp) of
// alpha, beta and Omega; a request is one Clenshaw sum and, once per period, the period's phase
// factors. The equilibrium and the free rotation, which are cheap, are answered directly, as is
// every request of a span the table cannot resolve.
#pragma once

#include <algorithm>
#include <array>
#include <cmath>
#include <complex>
#include <limits>

#include "spinning_top/integrators/chebyshev.hpp"
#include "spinning_top/integrators/exact.hpp"

namespace spinning_top {

template <class Model>
class PeriodTable {
 public:
  using State = typename Model::State;
  using Solution = ExactSolution<Model>;
  using Complex = exact_detail::Complex;

  /// Pieces of the interpolated span and how many are built so far (cost diagnostics).
  int pieces() const { return table_.pieces(); }
  int built_pieces() const { return table_.built_pieces(); }
  /// Forgets the period factors in use (a restart: the next request computes them again).
  void restart() { period_index_ = std::numeric_limits<long>::min(); }

  /// Sets the table up for `solution`: one nutation period from its start, or up to its first
  /// event when there is one.
  void assign(const Solution& solution) {
    period_index_ = std::numeric_limits<long>::min();
    if (solution.kind() != Solution::Kind::kQuadrature) return;
    const double event_span = solution.first_event_time() - solution.start_time();
    periodic_ = !(event_span < solution.nutation_period());
    const double span = periodic_ ? solution.nutation_period() : std::max(event_span, 1e-300);
    // Pieces for the phase the interpolated functions turn through in the span: a Chebyshev
    // series of degree 13 resolves e^{i x} to round-off for |x| <= ~1 rad on [-1, 1] (its
    // coefficients are Bessel functions, J_13(1) ~ 1e-17), so a piece may span ~2 rad. An
    // underestimate costs a halving (build_piece()), an overestimate pieces built for nothing.
    const double phase = span / solution.nutation_period() * solution.phase_per_period();
    int pieces = 2;
    while (pieces < 0.5 * phase && pieces < kMaxPieces) pieces *= 2;
    table_.assign(span, pieces);
    inverse_span_ = 1.0 / span;
    direct_only_ = false;
    scale_ = {1.0, 1.0, 1.0, 1.0, solution.rate_scale(), solution.rate_scale()};
  }

  /// The state at t >= the start of `solution` (the one assign() was given), from the table or,
  /// where `directly` is set, from the closed form itself (not normalised: the caller does).
  State state_at(const Solution& solution, double t, bool& directly) {
    directly = solution.kind() != Solution::Kind::kQuadrature || direct_only_;
    if (directly) return solution.at(t);
    const double elapsed = t - solution.start_time();
    double turns = 0.0, r = elapsed;
    if (periodic_) {
      // elapsed >= 0, so truncation is the floor (std::floor and std::fma are library calls
      // on baseline x86-64). r carries an absolute error ~ eps elapsed, 2e-15 s at 10 s.
      const double span = table_.span();
      turns = static_cast<double>(static_cast<long>(elapsed * inverse_span_));
      r = elapsed - turns * span;
      if (r < 0.0) turns -= 1.0, r += span;  // the rounded quotient may be one off
      if (r >= span) turns += 1.0, r -= span;
    }
    if (!table_.built(table_.piece_of(r)) && !build_piece(solution, r)) {
      directly = true;
      return solution.at(t);
    }
    const std::array<double, 6> v = table_.evaluate(r);
    State y;
    if (turns == 0.0) {
      y[0] = v[0], y[1] = v[2], y[2] = v[3], y[3] = v[1], y[4] = v[4], y[5] = v[5];
      return y;
    }
    const long n = static_cast<long>(turns);
    if (n != period_index_) {
      period_index_ = n;
      alpha_factor_ = power(solution.alpha_turn(), n);
      beta_factor_ = power(solution.beta_turn(), n);
      omega_factor_ = beta_factor_ * std::conj(alpha_factor_);
    }
    // (a + ib)(c + id), written out: std::complex's operator* also handles infinities, a call.
    auto times = [](const Complex& f, double re, double im, double& out_re, double& out_im) {
      out_re = f.real() * re - f.imag() * im;
      out_im = f.real() * im + f.imag() * re;
    };
    double qw, qz, qx, qy, wx, wy;
    times(alpha_factor_, v[0], v[1], qw, qz);
    times(beta_factor_, v[2], v[3], qx, qy);
    times(omega_factor_, v[4], v[5], wx, wy);
    y[0] = qw, y[1] = qx, y[2] = qy, y[3] = qz, y[4] = wx, y[5] = wy;
    return y;
  }

 private:
  /// Degree of the interpolation: 8 pieces per period on the toy top (measured: degree 7 needs
  /// 256 pieces, 13 needs 8, 15 needs 4; a request costs ~20 more instructions per 2 degrees).
  static constexpr int kDegree = 13;
  /// The last Chebyshev coefficients of a piece must be at the closed form's own round-off
  /// (measured ~1e-15 of the scale: alpha, beta ~ 1, Omega ~ rate_scale()).
  static constexpr double kTailTolerance = 32.0 * exact_detail::kEpsilon;
  /// A piece's largest miss of the closed form off its nodes: above the rounding of the two
  /// evaluations (a few eps), well below the 1e-12 the default promises.
  static constexpr double kProbeTolerance = 512.0 * exact_detail::kEpsilon;
  /// A bound on the table (6 kB per piece); a span that needs more is interpolated less
  /// accurately rather than without bound in memory and time.
  static constexpr int kMaxPieces = 1 << 12;
  using Table = PiecewiseChebyshev<6, kDegree>;

  /// z^n for a unit complex z: e^{i n arg z} (one sincos; n arg z is exact to the rounding of
  /// the product, which repeated multiplication would accumulate n times).
  static Complex power(Complex z, long n) {
    const double angle = std::arg(z) * static_cast<double>(n);
    return std::polar(1.0, angle);
  }

  /// Interpolates the piece of r. False if the request must be answered by the closed form
  /// itself: the closed form is not finite there, or the piece's last coefficients are not at
  /// round-off, in which case the pieces are halved (every built piece is forgotten and built
  /// again on demand). One piece per request at most, so that a request's cost is bounded by
  /// one piece (14 closed-form evaluations) and one evaluation.
  bool build_piece(const Solution& solution, double r) {
    const double start = solution.start_time();
    // The closed form's attitude put on the unit sphere before it is fitted, so that the table's
    // answers are unit quaternions to its own accuracy at no cost per request (near u = +-1 the
    // closed form's |q| was off by 6e-12 after a live update, found by the fuzz test).
    auto values = [&](double time) {
      const typename Solution::Motion m = solution.motion(start + time);
      const double norm = std::sqrt(std::norm(m.alpha) + std::norm(m.beta));
      return std::array<double, 6>{m.alpha.real() / norm, m.alpha.imag() / norm, m.beta.real() / norm,
                                   m.beta.imag() / norm, m.omega.real(), m.omega.imag()};
    };
    const int piece = table_.piece_of(r);
    double tail = table_.build(piece, values, scale_);
    if (!std::isfinite(tail)) {
      table_.forget(piece);
      return false;
    }
    // A small tail can hide a series that has not converged (a top swinging from u = 1 to u = -1
    // gave 6e-12 between the nodes, found by the fuzz test): the piece is also checked against the
    // closed form at one point off its nodes, and halved like a large tail if it misses there.
    const double width = table_.span() / table_.pieces();
    const double probe = (piece + 0.3819660112501051) * width;
    const std::array<double, 6> interpolated = table_.evaluate(probe), exact = values(probe);
    double miss = 0.0;
    for (int i = 0; i < 6; ++i) miss = std::max(miss, std::abs(interpolated[i] - exact[i]) / scale_[i]);
    if (tail <= kTailTolerance && miss <= kProbeTolerance) return true;
    if (table_.pieces() >= kMaxPieces) {
      // The span turns through more phase than kMaxPieces pieces resolve (a spin of 1e6 rad/s
      // over a nutation period of 0.08 s: 9e4 rad): interpolating anyway left | |q| - 1 | at
      // 1e-5 (found by the fuzz test). Every request is answered by the closed form instead.
      table_.forget(piece);
      direct_only_ = true;
      return false;
    }
    table_.assign(table_.span(), 2 * table_.pieces());
    return false;
  }

  Table table_;
  std::array<double, 6> scale_{};
  bool periodic_ = true;
  bool direct_only_ = false;  // the table cannot resolve the span: the closed form answers every request
  double inverse_span_ = 0.0;
  long period_index_ = std::numeric_limits<long>::min();
  Complex alpha_factor_{1.0, 0.0}, beta_factor_{1.0, 0.0}, omega_factor_{1.0, 0.0};
};

}  // namespace spinning_top
