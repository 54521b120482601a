// The closed-form solution (exact.hpp) as a stepper of the one driver loop
// (integration/driver.hpp): one step over all time, answered from the table of one nutation
// period (exact/period_table.hpp), its events known in closed form from the start.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <optional>
#include <string>

#include "spinning_top/integration/driver.hpp"
#include "spinning_top/integrators/exact.hpp"
#include "spinning_top/integrators/exact/period_table.hpp"

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
  static constexpr bool kFsal = false, kInterpolatedAnswers = false, kClosedForm = true;
  static constexpr const char* kName = "exact";

  struct Attempt {};  // the span needs no attempt: the solution is built at restart()

  /// Builds the solution from (t, y) (projected and finite): constants of motion and series.
  /// Throws MethodRefusal for a refused case, before anything changes, so that the stepper
  /// (and its driver) goes on where it was. A restart from the same state with the same model
  /// (a reset to the initial state) reuses what was built. Built even when the start itself is an
  /// event, so that a refusal depends on the parameters and the state, not on the sign of R there.
  void restart(const Model& model, double t, const State& y) {
    table_.restart();
    if (built_ && t == start_t_ && y == start_y_ && same_model(model)) return;
    Solution next(model, t, y);
    work_ += kBuildWork + kWorkPerFourierTerm * next.terms();
    built_ = false;
    solution_ = std::move(next);
    parameters_ = model.parameters();
    spin_ = model.spin();
    start_t_ = t;
    start_y_ = y;
    built_ = true;
    table_.assign(solution_);
  }

  void attempt(const Model& /*model*/, const State& /*y0*/, const State& /*f0*/, double /*dt*/, Attempt& /*out*/) {}
  /// Work units spent (work_budget.hpp): the solutions built by restart(), about 4 us and 0.23 us
  /// per Fourier term (bench/budget_time.cpp, in evaluations of the fixed tip's f, 0.014 us).
  /// The span itself is one step of the budget. Its answers are not counted: each costs at most
  /// one piece of the table and one evaluation, and a caller's count of requests bounds them.
  long work() const { return work_; }
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
    bool directly = false;
    y = table_.state_at(solution_, t, directly);
    if (!directly) return true;
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

 private:
  bool same_model(const Model& model) const {
    const TopParameters& a = model.parameters();
    const TopParameters& b = parameters_;
    return model.spin() == spin_ && a.mass == b.mass && a.inertia_transverse == b.inertia_transverse &&
           a.inertia_axial == b.inertia_axial && a.tip_distance == b.tip_distance && a.gravity == b.gravity &&
           a.friction == b.friction;
  }

  static constexpr long kBuildWork = 300, kWorkPerFourierTerm = 16;

  Solution solution_;
  PeriodTable<Model> table_;
  long work_ = 0;
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
