// "Integrator" exact: the closed-form solution of the two integrable scenes (fixed tip =
// Lagrange top, frictionless top), evaluated at any requested time from constants of motion
// computed once per (re)start. No time step.
//
// One closed form per kind of motion, each in a header of its own under exact/, with the
// numerics they share beside them:
//   quadrature.hpp     the Lagrange top and the frictionless top in general: the nutation by
//                      Jacobi's elliptic functions, the attitude by Fourier series in its phase,
//                      the events in closed form (items 1, 2 and 4 there);
//   free_rotation.hpp  torque-free tops with a fixed G (m g h = 0 and alpha_D = 0: the free
//                      symmetric top);
//   sleeping.hpp       the sleeping top (axis vertical, omega_perp = 0: an equilibrium);
//   series.hpp         Fourier sums by Clenshaw's recurrence, their coefficients by DCT-I / FFT;
//   polynomial.hpp     low-degree polynomials, their sign changes, a safeguarded Newton root finder;
//   common.hpp         the motion, the extremes and the start the closed forms share.
// ExactSolution below is what the driver (exact_driver.hpp) sees: it chooses the kind from the
// start and passes each query to it.
//
// 1. The nutation: exact/quadrature.hpp, item 1.
//
// 2. The attitude, without Euler angles: exact/quadrature.hpp, item 2.
//
// 3. Serving requests. Over one nutation period T = 2K t'(mean) the pair (alpha, beta) turns by
// fixed phases: alpha(t + T) = -e^{i 2K a_r'(mean)} alpha(t), beta likewise, Omega by their
// ratio. One period from the start is interpolated, lazily, by piecewise Chebyshev series
// (chebyshev.hpp) of alpha, beta and Omega; a request is then one Clenshaw sum of six short
// series and, once per period, the period's two phase factors. If the top leaves the model's
// validity (below), the interpolated span ends at that event instead.
//
// 4. Events in closed form: exact/quadrature.hpp, item 4; the free rotation's in
// exact/free_rotation.hpp.
//
// Refused with MethodRefusal("exact", why, "dop853") (method_refusal.hpp), so that auto falls back to a time-stepper:
// the viscous scene (not integrable), a motion exactly on the separatrix (k = 1: it approaches
// the unstable vertical for ever, the period is infinite) and series that do not converge within
// Quadrature::kMaxSamples samples.
#pragma once

#include <Eigen/Core>
#include <type_traits>
#include <variant>

#include "spinning_top/events.hpp"
#include "spinning_top/integrators/exact/common.hpp"
#include "spinning_top/integrators/exact/free_rotation.hpp"
#include "spinning_top/integrators/exact/quadrature.hpp"
#include "spinning_top/integrators/exact/sleeping.hpp"
#include "spinning_top/kinematics.hpp"
#include "spinning_top/parameters.hpp"
#include "spinning_top/scenes/fixed_tip.hpp"
#include "spinning_top/scenes/frictionless.hpp"

namespace spinning_top {

/// The exact motion from one state (t0, y0). Throws MethodRefusal (an InvalidParameter of the key integrator) for the
/// cases it refuses (header comment).
template <class Model>
class ExactSolution {
 public:
  using State = typename Model::State;
  using Complex = exact_detail::Complex;
  static_assert(std::is_same_v<Model, FixedTip> || std::is_same_v<Model, Frictionless>,
                "exact: only the integrable scenes (fixed tip, frictionless)");
  enum class Kind { kQuadrature, kFreeRotation, kSleeping };
  using Motion = exact_detail::Motion;
  using Range = exact_detail::Range;

  ExactSolution() = default;

  ExactSolution(const Model& model, double t0, const State& y0) {
    const TopParameters& p = model.parameters();
    constexpr bool sliding = std::is_same_v<Model, Frictionless>;
    const double h = p.tip_distance;
    exact_detail::Start from;
    from.t0 = t0;
    from.transverse = sliding ? p.inertia_transverse : p.inertia_about_tip();  // A'
    from.alpha_d = sliding ? p.mass * h * h / p.inertia_transverse : 0.0;
    from.kappa = 2.0 * p.mass * p.gravity * h / from.transverse;
    from.gravity = p.gravity;
    from.tip_distance = h;
    from.spin = model.spin();
    from.axial = p.inertia_axial;
    from.fallen_vertical = p.fallen_vertical();
    State unit = y0;
    normalize_attitude(unit);
    from.q0 = attitude_of(unit);
    from.wx0 = unit[state_index::kOmegaX];
    from.wy0 = unit[state_index::kOmegaY];
    const Vector3 gamma = vertical_in_body(unit);
    if (from.kappa == 0.0 && from.alpha_d == 0.0) {
      solution_.template emplace<exact_detail::FreeRotation>(from);
      return;
    }
    const double sin2 = gamma.x() * gamma.x() + gamma.y() * gamma.y();
    if (sin2 == 0.0 && from.wx0 == 0.0 && from.wy0 == 0.0) {
      solution_.template emplace<exact_detail::Sleeping>(from);  // an equilibrium
      return;
    }
    solution_.template emplace<exact_detail::Quadrature>(from, gamma, sin2);
  }

  Kind kind() const {
    if (quadrature()) return Kind::kQuadrature;
    return std::holds_alternative<exact_detail::FreeRotation>(solution_) ? Kind::kFreeRotation : Kind::kSleeping;
  }

  // The quadrature's own quantities. The other kinds have none and answer 0 (turning points:
  // u = 1; period factors: 1), as the one class of all three did.
  /// Nutation period T [s] of the quadrature (0 otherwise), turning points u1 <= u2.
  double nutation_period() const { return quadrature() ? quadrature()->period() : 0.0; }
  double turning_point_low() const { return quadrature() ? quadrature()->turning_point_low() : 1.0; }
  double turning_point_high() const { return quadrature() ? quadrature()->turning_point_high() : 1.0; }
  /// Fourier terms per series in w (what the start computed; requests do not sum them).
  int terms() const { return quadrature() ? quadrature()->terms() : 0; }
  /// Samples per half period the series needed (a cost measure).
  int samples() const { return quadrature() ? quadrature()->samples() : 0; }
  /// Period factors of the quadrature: alpha(t + T) = alpha_turn * alpha(t), beta likewise.
  Complex alpha_turn() const { return quadrature() ? quadrature()->alpha_turn() : Complex(1.0, 0.0); }
  Complex beta_turn() const { return quadrature() ? quadrature()->beta_turn() : Complex(1.0, 0.0); }
  /// The angle the interpolated functions turn through in one period (Quadrature::phase_per_period).
  double phase_per_period() const { return quadrature() ? quadrature()->phase_per_period() : 0.0; }
  /// A bound of |omega| over the motion (the scale of the body rates and of their round-off).
  double rate_scale() const { return quadrature() ? quadrature()->rate_scale() : 0.0; }

  /// The first time after the start at which the motion leaves the model's validity, and
  /// which way (kNone and infinity if it never does).
  Event first_event() const {
    return std::visit([](const auto& s) { return s.first_event(); }, solution_);
  }
  double first_event_time() const {
    return std::visit([](const auto& s) { return s.first_event_time(); }, solution_);
  }
  double start_time() const {
    return std::visit([](const auto& s) { return s.start_time(); }, solution_);
  }

  /// The motion at time t, from the closed form.
  Motion motion(double t) const {
    return std::visit([t](const auto& s) { return s.motion(t); }, solution_);
  }

  /// The state at time t.
  State at(double t) const { return state_of(motion(t)); }

  /// The extremes of the motion over [t0, t] (t >= t0): the largest 1 - u (u = e_Zz = cos tilt),
  /// and the least R / m (each kind's range_until says how).
  Range range_until(double t) const {
    return std::visit([t](const auto& s) { return s.range_until(t); }, solution_);
  }

  static State state_of(const Motion& m) {
    State y;
    y[state_index::kQw] = m.alpha.real();
    y[state_index::kQx] = m.beta.real();
    y[state_index::kQy] = m.beta.imag();
    y[state_index::kQz] = m.alpha.imag();
    y[state_index::kOmegaX] = m.omega.real();
    y[state_index::kOmegaY] = m.omega.imag();
    return y;
  }

 private:
  const exact_detail::Quadrature* quadrature() const { return std::get_if<exact_detail::Quadrature>(&solution_); }

  /// A default solution is a sleeping top at rest at t = 0.
  std::variant<exact_detail::Sleeping, exact_detail::FreeRotation, exact_detail::Quadrature> solution_;
};
}  // namespace spinning_top
