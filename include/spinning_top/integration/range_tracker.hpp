// The RangeTracker: the least normal force and the largest tilt of a time-stepper's run, taken
// from its steps' interpolants, so that a sweep's case needs no dense samples and misses no peak
// between them (issue 21; doc/integrators.md, "The extremes of a run"). The driver (driver.hpp)
// folds every piece of every step into it, in time order, while the step's interpolant is valid.
#pragma once

#include <algorithm>
#include <cmath>
#include <limits>

#include "spinning_top/events.hpp"
#include "spinning_top/integration/event_locator.hpp"
#include "spinning_top/kinematics.hpp"

namespace spinning_top {

/// Tracks over a run, for the two functions
///   phi_0 = event_functions(y)[0]  (R; in a skim, the skim's validity function, never reported),
///   phi_1 = -2 (q_x^2 + q_y^2) = e_Zz - 1 = cos(tilt) - 1  (exact near the vertical, where
///           1 - e_Zz would lose the small tilt to the rounding of e_Zz),
/// their least values, in two tiers: over everything folded so far (pending), and over what the
/// run has reported (committed: up to its time()). A budget that runs out stops a run at its last
/// answer with steps beyond it; those stay pending until the next answer commits them.
///
/// How, per function and piece [from, to] of a step [t0, t1] (the whole step, or the part up to
/// an answer or an event), with the EventLocator's cubic Hermite H of the event function over the
/// step (no evaluation):
///  1. Screen: if H stays above the least value so far by more than its allowance
///     (EventCubic::stays_above, the locator's bound of the Hermite remainder for a resolved
///     step), the piece cannot hold a new least value. Most steps end here.
///  2. Ends: if H has no inner minimum in the piece, the piece is monotone (up to the remainder)
///     and its least value is at an end: `to`'s (from's was folded before).
///  3. Search: the function on the interpolant at 1/4, 1/2, 3/4 of the piece and at H's inner
///     minimum; Brent's minimisation (brent_minimum) from the least sample, between its
///     neighbours, down to 1e-9 of the step: its value is then within phi'' (1e-9 dt)^2 of the
///     interpolant's minimum, round-off. About one search per nutation per function while the
///     extremes grow (a top that falls or rises), none once they repeat.
/// The extremes are those of the interpolant: the method's own error in the state (1e-11 rad for
/// dop853 at its default) is theirs too, instead of the sampling's (up to 1.6e-5 rad at 1 kHz
/// for the toy tops).
template <class Model>
class RangeTracker {
 public:
  using State = typename Model::State;

  /// Starts at y: both tiers hold its values.
  void start(const Model& model, const State& y) {
    last_ = values(model, y);
    least_ = committed_ = last_;
  }

  /// Folds the piece [from, to] of the step [t0, t1] (t0 <= from < to <= t1), whose event
  /// functions' cubic over the whole step is cubic[i]; y_to is the state at `to` (projected),
  /// g_to = event_functions(y_to) (the driver has them at a step's end), and state_at(t) the
  /// step's interpolant (projected), evaluated only by a search. Pieces come in time order, each
  /// starting where the last ended.
  template <class StateAt>
  void fold(const Model& model, double t0, double t1, const EventCubic (&cubic)[event_index::kCount], double from,
            double to, const State& y_to, const Eigen::Vector2d& g_to, const StateAt& state_at) {
    const Eigen::Vector2d at_to(g_to[0], tilt_function(y_to));
    const double dt = t1 - t0;
    // The cubic is of the event functions: g_0 = phi_0, g_1 = e_Zz - u_fall = 1 + phi_1 - u_fall.
    const double shift[event_index::kCount] = {0.0, 1.0 - model.parameters().fallen_vertical()};
    for (int i = 0; i < event_index::kCount; ++i) {
      double least_here = at_to[i];
      if (!cubic[i].stays_above(least_[i] + shift[i])) {
        const double x = cubic[i].interior_minimum();
        const double inner = x > 0.0 ? t0 + x * dt : -1.0;
        if (inner > from && inner < to) least_here = std::min(least_here, search(model, i, t0, dt, from, to, inner, at_to[i], state_at));
      }
      if (least_here < least_[i]) least_[i] = least_here;
      last_[i] = at_to[i];
    }
  }

  /// The run has reported everything folded so far (an answer, an event).
  void commit() { committed_ = least_; }

  /// Least value of event function 0 over the committed part: the least R.
  double least_normal_force() const { return committed_[0]; }
  /// 1 - cos of the largest tilt over the committed part: 2 (q_x^2 + q_y^2) at its state.
  double one_minus_cos_max_tilt() const { return -committed_[1]; }
  /// Pieces searched (diagnostics: the tracker's cost beyond its screens).
  long searches() const { return searches_; }

 private:
  static double tilt_function(const State& y) {
    const double qx = y[state_index::kQx], qy = y[state_index::kQy];
    return -2.0 * (qx * qx + qy * qy);
  }
  static Eigen::Vector2d values(const Model& model, const State& y) {
    return Eigen::Vector2d(event_functions(model, y)[0], tilt_function(y));
  }

  /// Step 3 of the class comment for function i on [from, to], H's inner minimum at `inner`.
  template <class StateAt>
  double search(const Model& model, int i, double t0, double dt, double from, double to, double inner,
                double value_to, const StateAt& state_at) {
    ++searches_;
    auto phi = [&](double offset) {
      const State y = state_at(t0 + offset);
      return i == event_index::kNormalForce ? event_functions(model, y)[0] : tilt_function(y);
    };
    // Offsets from t0 (smaller numbers, finer spacing): the piece's ends, three inner points and
    // H's minimum, in order.
    const double a = from - t0, b = to - t0, length = b - a;
    double offsets[6] = {a, a + 0.25 * length, a + 0.5 * length, a + 0.75 * length, b, b};
    int n = 5;
    const double x = inner - t0;
    int k = n - 1;
    while (offsets[k - 1] > x) --k;
    if (offsets[k - 1] != x) {
      for (int j = n; j > k; --j) offsets[j] = offsets[j - 1];
      offsets[k] = x;
      ++n;
    }
    double samples[6];
    samples[0] = last_[i];
    samples[n - 1] = value_to;
    int best = 0;
    for (int j = 1; j < n; ++j) {
      if (j + 1 < n) {
        const double value = phi(offsets[j]);
        samples[j] = std::isfinite(value) ? value : std::numeric_limits<double>::infinity();
      }
      if (samples[j] < samples[best]) best = j;
    }
    // Brent from the least inner sample between its neighbours (from the next one in where an
    // end of the piece is least: a minimum just inside it).
    const int centre = std::clamp(best, 1, n - 2);
    double at = offsets[centre], least = samples[centre];
    const double tolerance = 1e-9 * dt + std::numeric_limits<double>::min();
    brent_minimum(phi, offsets[centre - 1], offsets[centre + 1], at, least, tolerance,
                  [](double, double) { return false; });
    return std::min(least, samples[best]);
  }

  Eigen::Vector2d last_ = Eigen::Vector2d::Zero();       // at the end of the last piece folded
  Eigen::Vector2d least_ = Eigen::Vector2d::Zero();      // over everything folded (pending)
  Eigen::Vector2d committed_ = Eigen::Vector2d::Zero();  // over what the run has reported
  long searches_ = 0;
};

}  // namespace spinning_top
