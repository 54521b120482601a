// The closed-form solution (exact.hpp) as a stepper of the one driver loop
// (integration/driver.hpp): one step over all time, answered from an interpolation table of one
// nutation period, its events known in closed form from the start.
#pragma once

#include <algorithm>
#include <array>
#include <cmath>
#include <complex>
#include <cstdio>
#include <limits>
#include <optional>
#include <string>

#include "spinning_top/integration/driver.hpp"
#include "spinning_top/integrators/chebyshev.hpp"
#include "spinning_top/integrators/exact.hpp"

namespace spinning_top {

/// The closed-form solution as one step of the driver loop (integration/driver.hpp): the step
/// spans all time from its start, or ends at the first validity event, which is known in closed
/// form from the start (exact.hpp, item 4); requests are answered from its interpolant, the
/// table of one nutation period (item 3). Its states are exact to round-off: no guard.
template <class Model>
class ExactStepper {
 public:
  using State = typename Model::State;
  using Solution = ExactSolution<Model>;
  using Complex = exact_detail::Complex;
  static constexpr bool kFsal = false, kInterpolatedAnswers = false, kClosedForm = true;
  static constexpr const char* kName = "exact";

  struct Attempt {};  // the span needs no attempt: the solution is built at restart()

  /// Builds the solution from (t, y) (projected and finite): constants of motion and series.
  /// Throws MethodRefusal for a refused case, before anything changes, so that the stepper
  /// (and its driver) goes on where it was. A restart from the same state with the same model
  /// (a reset to the initial state) reuses what was built. Built even when the start itself is an
  /// event, so that a refusal depends on the parameters and the state, not on the sign of R there.
  void restart(const Model& model, double t, const State& y) {
    period_index_ = std::numeric_limits<long>::min();
    if (built_ && t == start_t_ && y == start_y_ && same_model(model)) return;
    Solution next(model, t, y);
    built_ = false;
    solution_ = std::move(next);
    parameters_ = model.parameters();
    spin_ = model.spin();
    start_t_ = t;
    start_y_ = y;
    built_ = true;
    setup_interpolation();
  }

  void attempt(const Model& /*model*/, const State& /*y0*/, const State& /*f0*/, double /*dt*/, Attempt& /*out*/) {}
  void accepted(const State& /*y0*/, const State& /*f0*/, const Attempt& /*attempt*/, double /*t0*/, double /*dt*/) {}

  /// The first validity event after the start (t0, y0), from the closed form; the state
  /// reported with it is the last valid one (the event time is moved back by ulps while the
  /// model's R or e_Zz at the closed-form state is already past zero by round-off).
  struct Located {
    Event event = Event::kNone;
    double time = 0.0;
    State state;
  };
  Located first_event(const Model& model, double t0, const State& y0) const {
    Located located;
    if (solution_.first_event() == Event::kNone) return located;
    double t = solution_.first_event_time();
    // Checked as reported: normalised (the normalisation alone moved R to -8e-17 N at a located
    // lift-off, found by the fuzz test).
    auto state = [&](double time) {
      State y = solution_.at(time);
      normalize_attitude(y);
      return y;
    };
    State y = state(t);
    double back = std::max(std::abs(t), 1e-300) * exact_detail::kEpsilon;
    for (int i = 0; i < 64 && t > t0 && triggered_event(event_functions(model, y)) != Event::kNone; ++i) {
      t = std::max(t0, t - back);
      back *= 2.0;
      y = state(t);
    }
    located.event = solution_.first_event();
    located.time = t;
    located.state = t > t0 ? y : y0;
    return located;
  }

  /// The state at t from the table; false if the closed form, answering directly, is not finite.
  bool answer(const Model& /*model*/, double t, const State& /*y_end*/, State& y) {
    // The interpolation is finite by construction (a piece's coefficients are checked when it is
    // built, and the period factors have modulus 1); the closed form itself is checked.
    y = state_at(t);
    if (!answered_directly_) return true;
    if (!all_finite(y)) return false;
    // The closed form answered directly is put on the unit sphere as every reported state is (the
    // table is fitted to normalised values: normalising each of its answers would cost 15 % of a
    // request).
    normalize_attitude(y);
    return true;
  }

  std::string description() const {
    char buffer[160];
    switch (solution_.kind()) {
      case Solution::Kind::kQuadrature:
        std::snprintf(buffer, sizeof buffer, "exact: closed form, nutation period %.6g s, %d Fourier terms",
                      solution_.nutation_period(), solution_.terms());
        return buffer;
      case Solution::Kind::kFreeRotation: return "exact: torque-free rotation";
      case Solution::Kind::kSleeping: return "exact: sleeping top";
    }
    return "exact";
  }
  const Solution& solution() const { return solution_; }
  /// The extremes over [start, t] (ExactSolution::range_until).
  std::optional<ClosedFormRange> closed_form_range(double t) const {
    if (!built_) return std::nullopt;
    const typename Solution::Range range = solution_.range_until(t);
    return ClosedFormRange{range.one_minus_u_max, range.least_normal_force_per_mass};
  }
  /// Pieces of the interpolated span and how many are built so far (cost diagnostics).
  int interpolation_pieces() const { return table_.pieces(); }
  int built_interpolation_pieces() const { return table_.built_pieces(); }

  /// The state at t >= the start, from the interpolation table (or the closed form directly
  /// for the equilibrium and the free rotation, which are cheap).
  State state_at(double t) {
    answered_directly_ = solution_.kind() != Solution::Kind::kQuadrature || direct_only_;
    if (answered_directly_) return solution_.at(t);
    const double elapsed = t - solution_.start_time();
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
    if (!table_.built(table_.piece_of(r)) && !build_piece(r)) {
      answered_directly_ = true;
      return solution_.at(t);
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
      alpha_factor_ = power(solution_.alpha_turn(), n);
      beta_factor_ = power(solution_.beta_turn(), n);
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

  bool same_model(const Model& model) const {
    const TopParameters& a = model.parameters();
    const TopParameters& b = parameters_;
    return model.spin() == spin_ && a.mass == b.mass && a.inertia_transverse == b.inertia_transverse &&
           a.inertia_axial == b.inertia_axial && a.tip_distance == b.tip_distance && a.gravity == b.gravity &&
           a.friction == b.friction;
  }

  /// z^n for a unit complex z: e^{i n arg z} (one sincos; n arg z is exact to the rounding of
  /// the product, which repeated multiplication would accumulate n times).
  static Complex power(Complex z, long n) {
    const double angle = std::arg(z) * static_cast<double>(n);
    return std::polar(1.0, angle);
  }

  /// One nutation period from the start, or up to the first event when there is one.
  void setup_interpolation() {
    period_index_ = std::numeric_limits<long>::min();
    if (solution_.kind() != Solution::Kind::kQuadrature) return;
    const double event_span = solution_.first_event_time() - solution_.start_time();
    periodic_ = !(event_span < solution_.nutation_period());
    const double span = periodic_ ? solution_.nutation_period() : std::max(event_span, 1e-300);
    // Pieces for the phase the interpolated functions turn through in the span: a Chebyshev
    // series of degree 13 resolves e^{i x} to round-off for |x| <= ~1 rad on [-1, 1] (its
    // coefficients are Bessel functions, J_13(1) ~ 1e-17), so a piece may span ~2 rad. An
    // underestimate costs a halving (build_piece()), an overestimate pieces built for nothing.
    const double phase = span / solution_.nutation_period() * solution_.phase_per_period();
    int pieces = 2;
    while (pieces < 0.5 * phase && pieces < kMaxPieces) pieces *= 2;
    table_.assign(span, pieces);
    inverse_span_ = 1.0 / span;
    direct_only_ = false;
    scale_ = {1.0, 1.0, 1.0, 1.0, solution_.rate_scale(), solution_.rate_scale()};
  }

  /// Interpolates the piece of r. False if the request must be answered by the closed form
  /// itself: the closed form is not finite there, or the piece's last coefficients are not at
  /// round-off, in which case the pieces are halved (every built piece is forgotten and built
  /// again on demand). One piece per request at most, so that a request's cost is bounded by
  /// one piece (14 closed-form evaluations) and one evaluation.
  bool build_piece(double r) {
    const double start = solution_.start_time();
    // The closed form's attitude put on the unit sphere before it is fitted, so that the table's
    // answers are unit quaternions to its own accuracy at no cost per request (near u = +-1 the
    // closed form's |q| was off by 6e-12 after a live update, found by the fuzz test).
    auto values = [&](double time) {
      const typename Solution::Motion m = solution_.motion(start + time);
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

  Solution solution_;
  Table table_;
  std::array<double, 6> scale_{};
  bool periodic_ = true, answered_directly_ = false;
  bool direct_only_ = false;  // the table cannot resolve the span: the closed form answers every request
  double inverse_span_ = 0.0;
  long period_index_ = std::numeric_limits<long>::min();
  Complex alpha_factor_{1.0, 0.0}, beta_factor_{1.0, 0.0}, omega_factor_{1.0, 0.0};
  // The start the solution was built from (for reset() to the same state).
  bool built_ = false;
  double start_t_ = 0.0, spin_ = 0.0;
  State start_y_ = State::Zero();
  TopParameters parameters_;
};

/// The exact integrator: the closed form as one span-long step of the one driver loop.
template <class Model>
using ExactDriver = Driver<Model, ExactStepper<Model>, WholeSpan>;

}  // namespace spinning_top
