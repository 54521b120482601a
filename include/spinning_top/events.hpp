// Validity events of the contact model (PHYSICS.md, "Validity of the model"): the event
// functions, their rates, the root finder and the cubic that screens a step. The search of every
// step (integration/event_locator.hpp) bounds them over the whole step through the step's
// interpolant, not only at its ends, so that a dip below zero that recovers within one step is
// found (doc/integrators.md, "Events").
#pragma once

#include <Eigen/Core>
#include <algorithm>
#include <cmath>
#include <limits>
#include <string>
#include <type_traits>
#include <utility>

#include "spinning_top/hot_path.hpp"
#include "spinning_top/kinematics.hpp"
#include "spinning_top/parameters.hpp"

namespace spinning_top {

enum class Event {
  kNone,
  kLiftOff,    ///< R < 0: the floor would have to pull the tip down
  kFallen,     ///< e_Zz <= 0: the axis has reached the floor
  kNonFinite,  ///< the solution could not be continued with finite values
  /// The integrator broke the energy balance: E + W (energy plus work against friction) moved by
  /// more than kEnergyBalanceTolerance of its scale (StepGuard). A numerical failure (step too
  /// large, tolerance too loose for the motion), never physics; the run stops at the last step
  /// that kept the balance.
  kEnergyDrift,
  // Transitions of the hybrid model (HYBRID.md), after which the run goes on; kLiftOff above is
  // one too where the top flies on.
  kTakeOff,  ///< a skimming tip leaves the floor
  kLanding,  ///< the tip reaches the floor from the air
};

/// The energy balance that a step may not break: |B(t) - B(0)| <= kEnergyBalanceTolerance
/// (|B(0)| + m g h), where B = E - C wZ^2 / 2 + W (the spin's energy C wZ^2 / 2 is a constant of
/// the model, and would hide a drift of the motion behind a fast spin; W is the work against
/// friction, 0 without it). A guard against garbage, not an accuracy target: the benchmark's long
/// runs (bench/results/long_run_energy.csv: 1000 s, rk4 at step 1e-3 s and the others at their
/// settings) stay below 2e-4 m g h, while a diverging step (rk4 at 2e-6 s on a spin of 1e6 rad/s,
/// dop853 at tolerance 9e-5 with friction) breaks it within a few steps.
constexpr double kEnergyBalanceTolerance = 1e-3;

/// "lift_off", "fallen", "non_finite", "energy_drift", "take_off", "landing", or "" for kNone (the
/// CSV and ROS spelling).
const char* to_string(Event event);

template <class State>
bool all_finite(const State& y) {
  return y.array().isFinite().all();
}

/// The floor's validity function of a contact model: R, or where the model says otherwise
/// (viscous skimming, scenes/viscous.hpp: contact_validity) its own function of the same sign rule.
template <class Model, class = void>
struct HasContactValidity : std::false_type {};
template <class Model>
struct HasContactValidity<Model, std::void_t<decltype(std::declval<const Model&>().contact_validity(
                                      std::declval<const typename Model::State&>()))>> : std::true_type {};

/// The event functions g(y) = (R, e_Zz - u_fall): the model is valid while both are positive. The
/// first to turn negative (or the second to reach zero) ends the contact phase. u_fall =
/// TopParameters::fallen_vertical(), where the rim touches the floor (0 for a needle: the axis
/// on the floor, the seed's rule, bit for bit).
template <class Model>
Eigen::Vector2d event_functions(const Model& model, const typename Model::State& y) {
  double floor;
  if constexpr (HasContactValidity<Model>::value)
    floor = model.contact_validity(y);
  else
    floor = model.normal_force(y);
  return Eigen::Vector2d(floor, vertical_in_body(y).z() - model.parameters().fallen_vertical());
}

/// Index of each event function in event_functions() and the event it raises.
namespace event_index {
constexpr int kNormalForce = 0, kVerticalAxis = 1, kCount = 2;
}  // namespace event_index

/// Whether event function i has passed its threshold: R < 0 (R = 0 is still a valid contact),
/// e_Zz <= 0 (the axis on the floor is already fallen).
inline bool is_triggered(int i, double value) { return i == event_index::kNormalForce ? value < 0.0 : value <= 0.0; }
inline Event event_raised_by(int i) { return i == event_index::kNormalForce ? Event::kLiftOff : Event::kFallen; }

inline Event triggered_event(const Eigen::Vector2d& g) {
  if (!std::isfinite(g[0]) || !std::isfinite(g[1])) return Event::kNonFinite;
  if (is_triggered(event_index::kVerticalAxis, g[1])) return Event::kFallen;
  if (is_triggered(event_index::kNormalForce, g[0])) return Event::kLiftOff;
  return Event::kNone;
}

/// dg/dt = grad g . f along the flow, by a forward difference along f = f(y): one more
/// evaluation of g. The increment moves the largest component of y by sqrt(eps) of its size, so
/// the rates carry a relative error ~1e-8 (truncation and rounding balanced; Dennis & Schnabel,
/// Numerical Methods for Unconstrained Optimization and Nonlinear Equations, on finite-difference
/// derivatives). They only shape the cubic that
/// screens a step (EventLocator), for which this is ample. q + eps f_q leaves the unit sphere only
/// at second order (f_q is tangent to it), below the increment's own rounding.
template <class Model>
Eigen::Vector2d event_rates(const Model& model, const typename Model::State& y, const Eigen::Vector2d& g,
                            const typename Model::State& f) {
  const double f_size = f.cwiseAbs().maxCoeff();
  if (f_size == 0.0) return Eigen::Vector2d::Zero();  // an equilibrium
  if (!std::isfinite(f_size)) return Eigen::Vector2d::Constant(std::numeric_limits<double>::quiet_NaN());
  const double increment = 1.4901161193847656e-8 * (1.0 + y.cwiseAbs().maxCoeff()) / f_size;  // sqrt(eps)
  const typename Model::State shifted = y + increment * f;
  return (event_functions(model, shifted) - g) * (1.0 / increment);
}

/// Finds, in (t_lo, t_hi], where event function i turns from valid at t_lo to triggered at t_hi,
/// by the Illinois variant of regula falsi on state_at(t) (superlinear, and bracketing like
/// bisection; Dowell & Jarratt, BIT 11 (1971) 168). A non-finite value counts as
/// triggered. Returns the last valid time, at most a few ulps of t before the root (4e-15
/// relative), so that the state reported with the event is still a valid one.
template <class Model, class StateAt>
double locate_root(const Model& model, int i, double t_lo, double g_lo, double t_hi, double g_hi,
                   const StateAt& state_at) {
  double a = t_lo, fa = g_lo, b = t_hi, fb = g_hi;
  int side = 0;
  const double tolerance = 4e-15 * std::max(1.0, std::abs(t_hi)) + 1e-300;
  for (int iteration = 0; iteration < 200 && (b - a) > tolerance; ++iteration) {
    double c = (fa - fb != 0.0) ? b - fb * (b - a) / (fb - fa) : 0.5 * (a + b);
    if (!(c > a && c < b)) c = 0.5 * (a + b);
    const double fc = event_functions(model, state_at(c))[i];
    if (!std::isfinite(fc) || is_triggered(i, fc)) {
      b = c;
      fb = std::isfinite(fc) ? fc : fb;
      if (side == -1) fa *= 0.5;  // Illinois: halve the stale end's weight
      side = -1;
    } else {
      a = c;
      fa = fc;
      if (side == +1) fb *= 0.5;
      side = +1;
    }
  }
  return a;
}


/// The cubic Hermite interpolant of one event function over a step, in the step's fraction
/// x in [0, 1]: H(0) = g0, H(1) = g1, H'(0) = m0 = dt g0', H'(1) = m1 = dt g1'.
struct EventCubic {
  double g0, g1, m0, m1;

  double operator()(double x) const {
    const double c2 = 3.0 * (g1 - g0) - 2.0 * m0 - m1, c3 = 2.0 * (g0 - g1) + m0 + m1;
    return g0 + x * (m0 + x * (c2 + x * c3));
  }
  /// Where H has a local minimum in (0, 1), or -1 if it has none there (then its minimum over
  /// the step is at an end). H' = m0 + 2 c2 x + 3 c3 x^2; its roots by the cancellation-free
  /// form of the quadratic formula, a minimum where H'' = 2 c2 + 6 c3 x > 0.
  double interior_minimum() const {
    const double c2 = 3.0 * (g1 - g0) - 2.0 * m0 - m1, c3 = 2.0 * (g0 - g1) + m0 + m1;
    const double a = 3.0 * c3, b = 2.0 * c2, c = m0;
    double roots[2];
    int n = 0;
    if (a == 0.0) {
      if (b != 0.0) roots[n++] = -c / b;
    } else {
      const double discriminant = b * b - 4.0 * a * c;
      if (discriminant >= 0.0) {
        const double q = -0.5 * (b + std::copysign(std::sqrt(discriminant), b));
        roots[n++] = q / a;
        if (q != 0.0) roots[n++] = c / q;
      }
    }
    for (int k = 0; k < n; ++k)
      if (roots[k] > 0.0 && roots[k] < 1.0 && b + 2.0 * a * roots[k] > 0.0) return roots[k];
    return -1.0;
  }
  double minimum() const {
    const double x = interior_minimum();
    return std::min({g0, g1, x >= 0.0 ? (*this)(x) : g0});
  }
  /// The screen's allowance for the difference between the event function G and H: twice the
  /// cubic's departure from a straight line, W = 2 (|c2| + |c3|) (H = g0 + m0 x + c2 x^2 + c3 x^3).
  /// Why W bounds the interpolation error of a step that resolves G: the remainder is
  /// G - H = G''''(xi) dt^4 x^2 (1 - x)^2 / 24, at most dt^4 max|G''''| / 384 (Hermite remainder;
  /// Stoer & Bulirsch, Introduction to Numerical Analysis, sec. 2.1.5), one order of
  /// the Taylor series beyond c2 ~ G'' dt^2 / 2 and c3 ~ G''' dt^3 / 6. For a single harmonic
  /// a cos(w t + p), over all phases p, the remainder is at most 0.4 % of W at w dt = 1, 1.7 % at
  /// w dt = 2 (the largest step validate() admits for the fastest motion), 26 % at w dt = 5
  /// (computed). With harmonics the phases can cancel c2 and c3 while G'''' stays:
  /// measured on 1e6 random steps of cos(w t + p1) + b cos(2 w t + p2), none was cleared wrongly
  /// for w dt <= 2 (b <= 2: harmonics up to 4 / dt) or, without the second harmonic, w dt <= 5;
  /// the first failures came with harmonics at 6 / dt (5 in 1e6 for w dt <= 3, b <= 1), where
  /// the step no longer resolves G (the allowance |g1 - g0| + |m0| + |m1|, which clears 2-3 times
  /// fewer steps, failed there as often). test_events_within_step.cpp checks this.
  double allowance() const {
    const double c2 = 3.0 * (g1 - g0) - 2.0 * m0 - m1, c3 = 2.0 * (g0 - g1) + m0 + m1;
    return 2.0 * (std::abs(c2) + std::abs(c3));
  }
  /// True if the event function cannot reach its threshold within the step (see allowance()).
  bool clears_zero() const { return stays_above(0.0); }
  /// True if the function stays above `level` throughout the step: H's minimum exceeds it by
  /// more than allowance(). The run's extremes (integration/range_tracker.hpp) skip with it the
  /// steps that cannot hold a new least value.
  bool stays_above(double level) const {
    const double margin = level + allowance();
    // First the convex hull of H's Bernstein control points g0, g0 + m0/3, g1 - m1/3, g1 (the
    // convex hull property of the Bezier form; Farin, Curves and Surfaces for CAGD), which lies
    // below H: no root-finding. It settles most steps of most runs (g far above the level).
    constexpr double kThird = 1.0 / 3.0;
    if (std::min(std::min(g0, g1), std::min(g0 + kThird * m0, g1 - kThird * m1)) > margin) return true;
    return minimum() > margin;
  }
};

}  // namespace spinning_top
