// Validity events of the contact model (PHYSICS.md, "Validity of the model"), and the check of
// every step for them: the event functions are bounded over the whole step through the step's
// interpolant, not only at its ends, so that a dip below zero that recovers within one step is
// found (doc/integrators.md, "Events").
#pragma once

#include <Eigen/Core>
#include <algorithm>
#include <cmath>
#include <limits>
#include <string>

#include "spinning_top/hot_path.hpp"
#include "spinning_top/kinematics.hpp"
#include "spinning_top/parameters.hpp"

// The search inside a step runs only in the few steps the screen cannot clear: kept out of line
// so that the flattened per-step code (hot_path.hpp) does not carry it.
#if defined(__GNUC__) || defined(__clang__)
#define SPINNING_TOP_NOINLINE __attribute__((noinline))
#else
#define SPINNING_TOP_NOINLINE
#endif

namespace spinning_top {

enum class Event {
  kNone,
  kLiftOff,    ///< R < 0: the floor would have to pull the tip down
  kFallen,     ///< e_Zz <= 0: the axis has reached the floor
  kNonFinite,  ///< the solution could not be continued with finite values
  /// The integrator broke the energy balance: E + W (energy plus work against friction) moved by
  /// more than kEnergyBalanceTolerance of its scale (EventMonitor). A numerical failure (step too
  /// large, tolerance too loose for the motion), never physics; the run stops at the last step
  /// that kept the balance.
  kEnergyDrift,
};

/// The energy balance that a step may not break: |B(t) - B(0)| <= kEnergyBalanceTolerance
/// (|B(0)| + m g h), where B = E - C wZ^2 / 2 + W (the spin's energy C wZ^2 / 2 is a constant of
/// the model, and would hide a drift of the motion behind a fast spin; W is the work against
/// friction, 0 without it). A guard against garbage, not an accuracy target: the benchmark's long
/// runs (bench/results/long_run_energy.csv: 1000 s, rk4 at step 1e-3 s and the others at their
/// settings) stay below 2e-4 m g h, while a diverging step (rk4 at 2e-6 s on a spin of 1e6 rad/s,
/// dop853 at tolerance 9e-5 with friction) breaks it within a few steps.
constexpr double kEnergyBalanceTolerance = 1e-3;

/// "lift_off", "fallen", "non_finite", "energy_drift", or "" for kNone (the CSV and ROS spelling).
const char* to_string(Event event);

template <class State>
bool all_finite(const State& y) {
  return y.array().isFinite().all();
}

/// The event functions g(y) = (R, e_Zz): the model is valid while both are positive. The
/// first to turn negative (or e_Zz to reach zero) ends the run.
template <class Model>
Eigen::Vector2d event_functions(const Model& model, const typename Model::State& y) {
  return Eigen::Vector2d(model.normal_force(y), vertical_in_body(y).z());
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
/// screens a step (EventMonitor), for which this is ample. q + eps f_q leaves the unit sphere only
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

/// Locates, in (t_lo, t_hi], every event function that is valid at t_lo and triggered at
/// t_hi, and returns the earliest one's last valid time (locate_root) with the event in
/// `which` (kNone if none triggers at t_hi). For a closed form that brackets its crossings
/// itself (integrators/exact.hpp); the stepping drivers use EventMonitor, which also finds
/// the crossings that leave no sign change at the step's ends.
template <class Model, class StateAt>
double locate_event(const Model& model, double t_lo, const Eigen::Vector2d& g_lo, double t_hi,
                    const Eigen::Vector2d& g_hi, const StateAt& state_at, Event& which) {
  double best_t = t_hi;
  which = Event::kNone;
  for (int i = 0; i < event_index::kCount; ++i) {
    if (!is_triggered(i, g_hi[i])) continue;
    const double t = locate_root(model, i, t_lo, g_lo[i], t_hi, g_hi[i], state_at);
    if (t < best_t || which == Event::kNone) {
      best_t = t;
      which = event_raised_by(i);
    }
  }
  return best_t;
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
  bool clears_zero() const {
    const double margin = allowance();
    // First the convex hull of H's Bernstein control points g0, g0 + m0/3, g1 - m1/3, g1 (the
    // convex hull property of the Bezier form; Farin, Curves and Surfaces for CAGD), which lies
    // below H: no root-finding. It settles most steps of most runs (g far above zero).
    constexpr double kThird = 1.0 / 3.0;
    if (std::min(std::min(g0, g1), std::min(g0 + kThird * m0, g1 - kThird * m1)) > margin) return true;
    return minimum() > margin;
  }
};

/// The check of every step for the validity events, shared by the stepping drivers (and meant
/// for a closed-form driver as well): after a step it projects the attitude, checks that the
/// state is finite, bounds the event functions over the whole step through the step's
/// interpolant, and locates the first event in it.
///
/// Why not only the signs at the step's ends (Hairer's and SUNDIALS' root finding): R can dip
/// below zero and recover within one step (a lift-off of 0.1 ms between 1 ms steps), which no
/// sign change shows (Shampine & Thompson, "Event location for ordinary differential
/// equations", Comput. Math. Appl. 39 (2000) 43: an even number of roots in a step).
///
/// How, per event function g and step [t0, t1] (x = (t - t0) / dt):
///  1. Screen, every step, no evaluation of the interpolant: the cubic Hermite H of g from the
///     values and rates g, g' = grad g . f at both ends (the end's are the next step's start's:
///     one more evaluation of g per step, event_rates()). If min H over the step exceeds the
///     allowance (EventCubic::allowance(), twice H's departure from a straight line, which bounds
///     the Hermite remainder for any step that resolves g), g cannot reach zero in the step and
///     nothing more is done. This is what most steps cost.
///  2. Search, only in steps that the screen does not clear or whose end is triggered: g on the
///     interpolant at x = 1/4, 1/2, 3/4 and at H's interior minimum; each local minimum of these
///     samples (with the ends, using the signs of g' there) whose value is below its drop to the
///     neighbours is refined by Brent's minimisation (golden section and parabolic steps, Brent,
///     Algorithms for Minimization without Derivatives, 1973, ch. 5) down to 1e-9 of the step.
///     For a parabola sampled at spacing d the sampled minimum lies at most 1/8 of that drop
///     above the true one, so no minimum that can be below zero is skipped.
///  3. The first sample or Brent point where g is triggered brackets the first root with the
///     last valid point before it; the root is located by locate_root (Illinois) to round-off
///     and the driver reports the last valid time (a few ulps before the root).
/// Guarantee: along the interpolant, a dip below zero is found whatever its depth (down to the
/// rounding of g, ~1e-16 of its scale) and duration, if the step resolves the event function
/// (the screen's bound: harmonics of g up to 4 / dt, e.g. w dt <= 2 for a fundamental with a
/// second harmonic twice as large; w dt <= 5 for a single one) and the search's samples bracket
/// each of its minima (at most one local minimum of g per quarter step, again a resolved step). The
/// event time is that of the interpolant: the method's own error in g moves it by
/// error / |g'| (and decides whether a dip shallower than that error exists at all).
template <class Model>
class EventMonitor {
 public:
  using State = typename Model::State;

  struct StepOutcome {
    Event event = Event::kNone;  ///< kNone: the step is valid throughout (its end is the next start)
    double time = 0.0;           ///< the event's time (last valid time before the root)
    State state;                 ///< the state at that time (valid; set only with an event)
  };

  /// (Re)starts at (t, y), y projected and valid, f = f(y).
  void start(const Model& model, double t, const State& y, const State& f) {
    t_ = t;
    g_ = event_functions(model, y);
    rate_ = event_rates(model, y, g_, f);
    const TopParameters& top = model.parameters();
    balance_ = model.energy_balance(y);
    allowed_drift_ = kEnergyBalanceTolerance * (std::abs(balance_) + top.mass * top.gravity * top.tip_distance);
  }

  /// Checks the step (t_start, t_end] from y_start (the state at the last start() or check),
  /// whose end state y_end is projected here (in place), with f_end = f at the end (a stepper's
  /// FSAL stage: f at the unprojected end, which differs by the local error, is close enough for
  /// the screen). state_at(t) is the step's interpolant (projected), evaluated only if the screen
  /// cannot clear the step.
  template <class StateAt>
  SPINNING_TOP_FLATTEN StepOutcome check_step(const Model& model, const State& y_start, double t_end, State& y_end,
                                              const State& f_end, const StateAt& state_at) {
    normalize_attitude(y_end);
    if (!all_finite(y_end)) return non_finite();
    return check_projected(model, y_start, t_end, y_end, f_end, state_at);
  }

  /// The same for a one-step method without an FSAL stage: f at the end is evaluated here, once
  /// (the next step's start reuses its rates).
  template <class StateAt>
  SPINNING_TOP_FLATTEN StepOutcome check_step(const Model& model, const State& y_start, double t_end, State& y_end,
                                              const StateAt& state_at) {
    normalize_attitude(y_end);
    if (!all_finite(y_end)) return non_finite();
    State f_end;
    model.derivative(y_end, f_end);
    return check_projected(model, y_start, t_end, y_end, f_end, state_at);
  }

  /// Whether a state keeps the energy balance of the run (|B - B0| within kEnergyBalanceTolerance).
  bool keeps_balance(const Model& model, const State& y) const {
    return std::abs(model.energy_balance(y) - balance_) <= allowed_drift_;
  }

  /// Steps that the screen could not clear, and the interpolant's evaluations their search took
  /// (diagnostics: the cost of the search).
  long searches() const { return searches_; }
  long interpolant_evaluations() const { return interpolant_evaluations_; }

 private:
  static constexpr int kMaxSamples = 7;  // both ends, 3 fixed interior points, 2 cubic minima

  static StepOutcome non_finite() {
    StepOutcome outcome;
    outcome.event = Event::kNonFinite;
    return outcome;
  }

  /// The step broke the energy balance: the run stops at its start, the last state that kept it.
  StepOutcome energy_drift(const State& y_start) const {
    StepOutcome outcome;
    outcome.event = Event::kEnergyDrift;
    outcome.time = t_;
    outcome.state = y_start;
    return outcome;
  }

  /// Step 1 of the class comment (the screen), and the search if it cannot clear the step.
  template <class StateAt>
  SPINNING_TOP_FLATTEN StepOutcome check_projected(const Model& model, const State& y_start, double t_end,
                                                   const State& y_end, const State& f_end, const StateAt& state_at) {
    const Eigen::Vector2d g_end = event_functions(model, y_end);
    if (!std::isfinite(g_end[0]) || !std::isfinite(g_end[1])) return non_finite();
    // A step that breaks the energy balance is garbage throughout (an event inside it too).
    if (!keeps_balance(model, y_end)) return energy_drift(y_start);
    const Eigen::Vector2d rate_end = event_rates(model, y_end, g_end, f_end);
    const double dt = t_end - t_;
    bool search = false, suspect[event_index::kCount];
    EventCubic cubic[event_index::kCount];
    for (int i = 0; i < event_index::kCount; ++i) {
      cubic[i] = EventCubic{g_[i], g_end[i], dt * rate_[i], dt * rate_end[i]};
      // Non-finite rates (a singular f) cannot clear the step: it is searched.
      suspect[i] = is_triggered(i, g_end[i]) || !cubic[i].clears_zero();
      search = search || suspect[i];
    }
    if (search) {
      ++searches_;
      const StepOutcome outcome = search_step(model, y_start, t_end, g_end, cubic, suspect, state_at);
      // The located state comes from the step's interpolant, which may break the balance where
      // the step's end keeps it (dop853 at tolerance 9e-3 with stiff friction: 700x the allowed
      // drift at a located lift-off, found by the fuzz test).
      if (outcome.event != Event::kNone)
        return keeps_balance(model, outcome.state) ? outcome : energy_drift(y_start);
    }
    t_ = t_end;
    g_ = g_end;
    rate_ = rate_end;
    return StepOutcome();
  }

  struct Bracket {
    bool found = false;
    double valid_offset = 0.0, valid_value = 0.0, triggered_offset = 0.0, triggered_value = 0.0;
  };

  /// Steps 2 and 3 of the class comment for the screened functions; the earliest event wins.
  template <class StateAt>
  SPINNING_TOP_NOINLINE StepOutcome search_step(const Model& model, const State& y_start, double t_end,
                                                const Eigen::Vector2d& g_end, const EventCubic (&cubic)[2],
                                                const bool (&suspect)[2], const StateAt& uncounted_state_at) {
    auto state_at = [&](double t) {
      ++interpolant_evaluations_;
      return uncounted_state_at(t);
    };
    const double t0 = t_, dt = t_end - t0;
    double offsets[kMaxSamples] = {0.0, 0.25 * dt, 0.5 * dt, 0.75 * dt, dt};
    int n = 5;
    for (int i = 0; i < event_index::kCount; ++i) {
      const double x = suspect[i] ? cubic[i].interior_minimum() : -1.0;
      if (!(x > 0.0)) continue;
      // Inserted in time order (0 < x dt < dt: between the ends), unless already a sample.
      const double offset = x * dt;
      int k = n;
      while (offsets[k - 1] > offset) --k;
      if (offsets[k - 1] == offset) continue;
      for (int j = n; j > k; --j) offsets[j] = offsets[j - 1];
      offsets[k] = offset;
      ++n;
    }
    Eigen::Vector2d values[kMaxSamples];
    values[0] = g_;
    values[n - 1] = g_end;
    for (int k = 1; k + 1 < n; ++k) values[k] = event_functions(model, state_at(t0 + offsets[k]));

    StepOutcome outcome;
    for (int i = 0; i < event_index::kCount; ++i) {
      if (!suspect[i]) continue;
      const Bracket bracket = first_crossing(model, i, cubic[i], t0, offsets, values, n, state_at);
      if (!bracket.found) continue;
      const double t = locate_root(model, i, t0 + bracket.valid_offset, bracket.valid_value,
                                   t0 + bracket.triggered_offset, bracket.triggered_value, state_at);
      if (outcome.event == Event::kNone || t < outcome.time) {
        outcome.event = event_raised_by(i);
        outcome.time = t;
      }
    }
    if (outcome.event != Event::kNone) outcome.state = outcome.time > t0 ? state_at(outcome.time) : y_start;
    return outcome;
  }

  /// Walks the samples in time order: the first triggered sample brackets a crossing with the
  /// sample before it; before that, every sampled local minimum that could hide a dip below zero
  /// is refined by Brent's method, and a triggered point found there brackets the crossing.
  template <class StateAt>
  Bracket first_crossing(const Model& model, int i, const EventCubic& cubic, double t0, const double* offsets,
                         const Eigen::Vector2d* values, int n, const StateAt& state_at) const {
    Bracket bracket;
    constexpr double kInfinity = std::numeric_limits<double>::infinity();
    auto value = [&](int k) { return std::isfinite(values[k][i]) ? values[k][i] : kInfinity; };
    // A local minimum at sample j, the ends by the sign of g' there (g falling into the step at
    // its start, rising out of it at its end).
    auto may_dip_at = [&](int j) {
      const bool left = j == 0 ? cubic.m0 < 0.0 : value(j) <= value(j - 1);
      const bool right = j == n - 1 ? cubic.m1 > 0.0 : value(j) <= value(j + 1);
      if (!left || !right) return false;
      if (j == 0 || j == n - 1) return true;  // an end's neighbourhood: always refined
      const double drop = std::max(value(j - 1), value(j + 1)) - value(j);
      return value(j) < drop;  // a parabola's minimum lies at most drop / 8 below the sample
    };
    for (int k = 0; k < n; ++k) {
      if (k > 0 && is_triggered(i, values[k][i])) {
        bracket = {true, offsets[k - 1], values[k - 1][i], offsets[k], values[k][i]};
        return bracket;
      }
      if (may_dip_at(k)) {
        const int lo = std::max(k - 1, 0), hi = std::min(k + 1, n - 1);
        double found_offset = 0.0, found_value = 0.0;
        if (dip_below_zero(model, i, t0, offsets[lo], offsets[hi], offsets[k], value(k), state_at, found_offset,
                           found_value)) {
          bracket = {true, offsets[lo], values[lo][i], found_offset, found_value};
          return bracket;
        }
      }
    }
    return bracket;
  }

  /// Brent's minimisation of g_i on [t0 + a, t0 + b] from the sample x (value fx), stopped at
  /// the first triggered point (returned in found_*). The tolerance 1e-9 of the step puts the
  /// minimum's value within g'' (1e-9 dt)^2 of the true one: round-off.
  template <class StateAt>
  bool dip_below_zero(const Model& model, int i, double t0, double a, double b, double x, double fx,
                      const StateAt& state_at, double& found_offset, double& found_value) const {
    constexpr double kGolden = 0.3819660112501051;  // (3 - sqrt(5)) / 2
    const double tolerance = 1e-9 * (b - a) + std::numeric_limits<double>::min();
    double w = x, v = x, fw = fx, fv = fx, d = 0.0, e = 0.0;
    for (int iteration = 0; iteration < 100; ++iteration) {
      const double middle = 0.5 * (a + b);
      if (std::abs(x - middle) <= 2.0 * tolerance - 0.5 * (b - a)) break;
      bool parabolic = false;
      if (std::abs(e) > tolerance) {
        double r = (x - w) * (fx - fv), q = (x - v) * (fx - fw), p = (x - v) * q - (x - w) * r;
        q = 2.0 * (q - r);
        if (q > 0.0) p = -p;
        q = std::abs(q);
        const double previous = e;
        e = d;
        if (std::abs(p) < std::abs(0.5 * q * previous) && p > q * (a - x) && p < q * (b - x)) {
          d = p / q;
          const double u = x + d;
          if (u - a < 2.0 * tolerance || b - u < 2.0 * tolerance) d = x < middle ? tolerance : -tolerance;
          parabolic = true;
        }
      }
      if (!parabolic) {
        e = (x < middle ? b : a) - x;
        d = kGolden * e;
      }
      const double u = x + (std::abs(d) >= tolerance ? d : std::copysign(tolerance, d));
      const double gu = event_functions(model, state_at(t0 + u))[i];
      if (std::isfinite(gu) && is_triggered(i, gu)) {
        found_offset = u;
        found_value = gu;
        return true;
      }
      const double fu = std::isfinite(gu) ? gu : std::numeric_limits<double>::infinity();
      if (fu <= fx) {
        (u < x ? b : a) = x;
        v = w, fv = fw, w = x, fw = fx, x = u, fx = fu;
      } else {
        (u < x ? a : b) = u;
        if (fu <= fw || w == x) {
          v = w, fv = fw, w = u, fw = fu;
        } else if (fu <= fv || v == x || v == w) {
          v = u, fv = fu;
        }
      }
    }
    return false;
  }

  double t_ = 0.0;
  Eigen::Vector2d g_ = Eigen::Vector2d::Zero(), rate_ = Eigen::Vector2d::Zero();  // at the step's start
  double balance_ = 0.0, allowed_drift_ = 0.0;  // B(0) of the run and the drift it may take
  long searches_ = 0, interpolant_evaluations_ = 0;
};

}  // namespace spinning_top
