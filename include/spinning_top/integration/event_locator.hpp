// The EventLocator: finds the validity events (events.hpp) of a time-stepper inside each step,
// through the step's interpolant, including the dips of R that leave no sign change at the step's
// ends (doc/integrators.md, "Events within a step"). A closed form locates its events itself
// (integrators/exact_stepper.hpp).
#pragma once

#include <Eigen/Core>
#include <algorithm>
#include <cmath>
#include <limits>

#include "spinning_top/events.hpp"
#include "spinning_top/hot_path.hpp"

namespace spinning_top {

/// Brent's minimisation of f on [a, b] (golden section and parabolic steps; Brent, Algorithms for
/// Minimization without Derivatives, 1973, ch. 5) from an inner point x with value fx, down to
/// `tolerance` in x. A non-finite f counts as +infinity. stop(u, f(u)) sees every new point;
/// true ends the search there and returns true. On return (x, fx) is the least point found.
/// The EventLocator stops it at the first triggered point; the RangeTracker runs it to the end.
template <class F, class Stop>
bool brent_minimum(const F& f, double a, double b, double& x, double& fx, double tolerance, const Stop& stop) {
  constexpr double kGolden = 0.3819660112501051;  // (3 - sqrt(5)) / 2
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
    const double fu_raw = f(u);
    if (stop(u, fu_raw)) return true;
    const double fu = std::isfinite(fu_raw) ? fu_raw : std::numeric_limits<double>::infinity();
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

/// The event locator of the stepping methods: after each accepted step (projected and guarded by
/// the StepGuard), it bounds the event functions over the whole step through the step's
/// interpolant, and locates the first event in it. Any interpolant will do: a method's dense
/// output, or the step re-taken with a shorter size (steppers.hpp).
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
class EventLocator {
 public:
  using State = typename Model::State;

  /// The first event in a step, or kNone: the step is valid throughout.
  struct Outcome {
    Event event = Event::kNone;
    double time = 0.0;  ///< the event's time (last valid time before the root)
    State state;        ///< the state at that time (valid; set only with an event)
  };

  /// (Re)starts at (t, y), y projected and valid, f = f(y).
  void start(const Model& model, double t, const State& y, const State& f) {
    t_ = t;
    g_ = event_functions(model, y);
    rate_ = event_rates(model, y, g_, f);
  }

  /// The step (t_start, t_end] from y_start (the state at the last start() or locate()) to
  /// y_end (projected, finite), whose event functions g_end = event_functions(y_end) are finite;
  /// f_end = f at the end (a stepper's FSAL stage: f at the unprojected end, which differs by the
  /// local error, is close enough for the screen). state_at(t) is the step's interpolant
  /// (projected), evaluated only if the screen cannot clear the step. Step 1 of the class
  /// comment (the screen), and the search if it cannot clear the step; without an event the
  /// locator moves on to the step's end.
  template <class StateAt>
  SPINNING_TOP_FLATTEN Outcome locate(const Model& model, const State& y_start, double t_end, const State& y_end,
                                      const Eigen::Vector2d& g_end, const State& f_end, const StateAt& state_at) {
    const Eigen::Vector2d rate_end = event_rates(model, y_end, g_end, f_end);
    const double dt = t_end - t_;
    bool search = false, suspect[event_index::kCount];
    EventCubic (&cubic)[event_index::kCount] = cubic_;
    for (int i = 0; i < event_index::kCount; ++i) {
      cubic[i] = EventCubic{g_[i], g_end[i], dt * rate_[i], dt * rate_end[i]};
      // Non-finite rates (a singular f) cannot clear the step: it is searched.
      suspect[i] = is_triggered(i, g_end[i]) || !cubic[i].clears_zero();
      search = search || suspect[i];
    }
    if (search) {
      ++searches_;
      const Outcome outcome = search_step(model, y_start, t_end, g_end, cubic, suspect, state_at);
      if (outcome.event != Event::kNone) return outcome;
    }
    t_ = t_end;
    g_ = g_end;
    rate_ = rate_end;
    return Outcome();
  }

  /// Steps that the screen could not clear, and the interpolant's evaluations their search took
  /// (diagnostics: the cost of the search).
  long searches() const { return searches_; }
  long interpolant_evaluations() const { return interpolant_evaluations_; }
  /// The event functions' cubics over the last step located (whether or not it held an event),
  /// which the RangeTracker screens with.
  using StepCubics = EventCubic[event_index::kCount];
  const StepCubics& step_cubics() const { return cubic_; }

 private:
  static constexpr int kMaxSamples = 7;  // both ends, 3 fixed interior points, 2 cubic minima

  struct Bracket {
    bool found = false;
    double valid_offset = 0.0, valid_value = 0.0, triggered_offset = 0.0, triggered_value = 0.0;
  };

  /// Steps 2 and 3 of the class comment for the screened functions; the earliest event wins.
  /// It runs only in the few steps the screen cannot clear: kept out of line (hot_path.hpp), so
  /// that the flattened per-step code does not carry it.
  template <class StateAt>
  SPINNING_TOP_NOINLINE Outcome search_step(const Model& model, const State& y_start, double t_end,
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

    Outcome outcome;
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
    const double tolerance = 1e-9 * (b - a) + std::numeric_limits<double>::min();
    auto g = [&](double u) { return event_functions(model, state_at(t0 + u))[i]; };
    auto triggered = [&](double u, double gu) {
      if (!(std::isfinite(gu) && is_triggered(i, gu))) return false;
      found_offset = u;
      found_value = gu;
      return true;
    };
    return brent_minimum(g, a, b, x, fx, tolerance, triggered);
  }

  double t_ = 0.0;
  Eigen::Vector2d g_ = Eigen::Vector2d::Zero(), rate_ = Eigen::Vector2d::Zero();  // at the step's start
  EventCubic cubic_[event_index::kCount] = {};  // of the last step located
  long searches_ = 0, interpolant_evaluations_ = 0;
};

}  // namespace spinning_top
