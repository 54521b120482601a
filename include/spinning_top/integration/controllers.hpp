// Controllers: which step the driver (driver.hpp) tries next, and whether an attempt is kept.
//   SubstepPlan  fixed-step methods: each request in equal substeps of at most `step`;
//   PiController embedded pairs: Hairer's PI control of a scaled error norm (with an ErrorMap
//                for methods that report their estimate on another scale: radau5, radau9),
//                each step at most the one that resolves the model's fastest motion;
//   WholeSpan    a closed form: one step over all time, never rejected.
// Each declares the integrator kind it makes (IntegratorKind, integrator_registry.hpp): the
// registry, validation and the documentation read it from here.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <stdexcept>
#include <string>
#include <type_traits>
#include <utility>

#include "spinning_top/hot_path.hpp"
#include "spinning_top/integrator_registry.hpp"
#include "spinning_top/parameters.hpp"

namespace spinning_top {

/// The next step a controller proposes: its size and its end (t + dt, rounded as the clock rounds).
struct StepProposal {
  double dt = 0.0, t_end = 0.0;
};

/// Fixed steps: a request for t_target is taken in n equal substeps of at most `step`, the last
/// one ending exactly at t_target, so that requests are answered by step ends. A plan interrupted
/// by a work budget goes on with its remaining substeps at the next request for the same target
/// (the same states, bit for bit).
class SubstepPlan {
 public:
  static constexpr IntegratorKind kKind = IntegratorKind::kFixedStep;

  explicit SubstepPlan(double max_step) : max_step_(max_step) {
    if (!(max_step_ > 0.0) || !std::isfinite(max_step_)) throw std::invalid_argument("step must be positive and finite");
  }
  explicit SubstepPlan(const IntegratorSettings& settings) : SubstepPlan(settings.step) {}

  double max_step() const { return max_step_; }
  /// ", step 0.001 s" (for the driver's description).
  std::string settings_text() const {
    char buffer[40];
    std::snprintf(buffer, sizeof buffer, ", step %g s", max_step_);
    return buffer;
  }

  template <class Model, class State>
  void start(const Model& /*model*/, const State& /*y*/, const State& /*f*/) {
    plan_ = Plan();
  }

  /// The substep from t towards t_target: a new plan unless t is where the plan for this target
  /// stopped. Throws InvalidParameter("step") for a request that needs more than kMaxSubsteps.
  bool propose(double t, double t_target, StepProposal& step) {
    if (!(plan_.target == t_target && plan_.next <= plan_.count && t == plan_.reached)) {
      const double span = t_target - t;
      // A request of exactly max_step arrives as t_target - t rounded at the size of t (relative
      // error ~ eps t / span, 1e-9 at t = 1e4 s, 1 ms): allow substeps up to 1e-6 above max_step
      // rather than taking a second, tiny substep for rounding.
      // The substep count, checked before the conversion: past ~9.2e18 the cast overflowed and one
      // substep spanned the whole request (step 1e-300 s gave a lift-off with 5x the energy).
      const double count = std::ceil(span / max_step_ * (1.0 - 1e-6));
      if (!(count <= kMaxSubsteps))
        throw InvalidParameter("step", "a request of " + std::to_string(span) + " s needs " + std::to_string(count) +
                                           " substeps of " + std::to_string(max_step_) + " s, more than the " +
                                           std::to_string(kMaxSubsteps) + " one request may take");
      plan_.start = t;
      plan_.reached = t;
      plan_.target = t_target;
      plan_.count = std::max(1L, static_cast<long>(count));
      plan_.dt = span / static_cast<double>(plan_.count);
      plan_.next = 1;
    }
    const long i = plan_.next;
    step.t_end = (i == plan_.count) ? t_target : plan_.start + static_cast<double>(i) * plan_.dt;
    step.dt = step.t_end - t;
    return true;
  }

  /// A fixed step has no error estimate: every attempt is kept.
  template <class Attempt, class State>
  bool accept(const Attempt& /*attempt*/, const State& /*y0*/) {
    return true;
  }
  void accepted(const StepProposal& step) {
    ++plan_.next;
    plan_.reached = step.t_end;
  }

 private:
  /// Substeps one request may take: 1e12 (hours of CPU), far below the count's overflow.
  static constexpr double kMaxSubsteps = 1e12;
  /// The substeps of the request in progress: substep i ends at start + i dt (the last at
  /// target); `next` is the first not yet taken, `reached` the time it starts from.
  struct Plan {
    double start = 0.0, target = -std::numeric_limits<double>::infinity(), dt = 0.0, reached = 0.0;
    long count = 0, next = 1;
  };
  Plan plan_;
  double max_step_;
};

/// The error vector as the method reports it (the embedded pairs' y1 - y1_hat).
struct UnmappedError {
  template <class State>
  static const State& map(const State& error, const State& /*y0*/, const State& /*y1*/) {
    return error;
  }
};

/// The largest step that resolves a model's fastest oscillation (Model::largest_resolving_step(),
/// motion_rates.hpp), or infinity for a model that does not say.
template <class Model, class = void>
struct ResolvingStep {
  static double of(const Model& /*model*/) { return std::numeric_limits<double>::infinity(); }
};
template <class Model>
struct ResolvingStep<Model, std::void_t<decltype(std::declval<const Model&>().largest_resolving_step())>> {
  static double of(const Model& model) { return model.largest_resolving_step(); }
};

/// Hairer's step-size control with a PI stabilisation (Solving ODEs I, sec. II.4 and IV.2) on
/// the error norm e = RMS(error / (tolerance (1 + max(|y0|, |y1|)))), which the method's estimate
/// makes O(dt^kErrorPower): e <= 1 keeps the step, and the next is dt (0.9 / e^(1/p - 0.03)
/// e_prev^0.04), between 0.2 and 10 times this one, and at most the step that resolves the
/// model's fastest oscillation (ResolvingStep): the event locator clears only resolved steps
/// without searching their interpolant (event_locator.hpp), and a search costs radau9 two
/// collocation solves per sample (at tolerance 1e-4 on very stiff friction, k = 1e5: 10x the steps' work).
template <int kErrorPower, class ErrorMap = UnmappedError>
class PiController {
 public:
  static constexpr IntegratorKind kKind = IntegratorKind::kAdaptive;

  explicit PiController(double tolerance) : tolerance_(tolerance) {
    if (!(tolerance_ > 0.0) || !std::isfinite(tolerance_)) throw std::invalid_argument("tolerance must be positive and finite");
  }
  explicit PiController(const IntegratorSettings& settings) : PiController(settings.tolerance) {}

  double tolerance() const { return tolerance_; }
  /// ", tolerance 1e-12" (for the driver's description).
  std::string settings_text() const {
    char buffer[48];
    std::snprintf(buffer, sizeof buffer, ", tolerance %g", tolerance_);
    return buffer;
  }

  /// (Re)starts at y with f = f(y): the first step by Hairer's heuristic (Solving ODEs I, sec.
  /// II.4, "Starting step size").
  template <class Model, class State>
  void start(const Model& model, const State& y, const State& f) {
    const State scale = tolerance_ * (1.0 + y.cwiseAbs().array()).matrix();
    const double d0 = y.cwiseQuotient(scale).norm(), d1 = f.cwiseQuotient(scale).norm();
    const double h0 = (d0 < 1e-5 || d1 < 1e-5) ? 1e-6 : 0.01 * d0 / d1;
    State f1;
    model.derivative(y + h0 * f, f1);
    const double d2 = (f1 - f).cwiseQuotient(scale).norm() / h0;
    const double dmax = std::max(d1, d2);
    const double h1 = (dmax <= 1e-15) ? std::max(1e-6, h0 * 1e-3) : std::pow(0.01 / dmax, kExponent);
    const double h = std::min(100.0 * h0, h1);
    largest_step_ = ResolvingStep<Model>::of(model);  // propose() caps every step with it
    dt_ = std::isfinite(h) && h > 0.0 ? h : 1e-6;
    previous_error_ = 1e-4;
  }

  /// The next attempt from t; false if the step size underflows (the solution cannot be
  /// continued with finite values).
  bool propose(double t, double /*t_target*/, StepProposal& step) {
    // The step may shrink to what the clock resolves at t (16 ulps), however short: an absolute
    // floor (1e-14 s) ended a stiff initial transient (a slip relaxing in 5e-14 s) in non_finite.
    if (!(dt_ > 16.0 * std::numeric_limits<double>::epsilon() * std::abs(t) + std::numeric_limits<double>::min()))
      return false;
    // Step by the increment the clock can represent, (t + dt) - t, so that t and the state
    // advance by the same amount: otherwise t picks up a rounding of ~eps |t| per step that the
    // state does not, a random walk in time that a spin of 2000 rad/s turns into 1e-10 rad of
    // attitude over 10 s (measured against exact, dop853 at 1e-14).
    dt_ = (t + std::min(dt_, largest_step_)) - t;
    step.dt = dt_;
    step.t_end = t + dt_;
    return true;
  }

  /// Keeps the attempt if its error norm is at most 1 and its end is finite, and sizes the next
  /// attempt either way.
  template <class Attempt, class State>
  SPINNING_TOP_FLATTEN bool accept(const Attempt& attempt, const State& y0) {
    const double err = error_norm(ErrorMap::map(attempt.error, y0, attempt.y1), y0, attempt.y1);
    if (std::isfinite(err) && err <= 1.0 && attempt.f1.array().isFinite().all()) {
      const double factor = std::pow(err, kExponent - 0.75 * kBeta) / std::pow(previous_error_, kBeta);
      previous_error_ = std::max(err, 1e-4);
      dt_ *= std::min(kMaxGrowth, std::max(kMaxShrink, kSafety / std::max(factor, 1e-10)));
      return true;
    }
    const double shrink = std::isfinite(err) ? std::max(kMaxShrink, kSafety * std::pow(err, -kExponent)) : kMaxShrink;
    dt_ *= std::min(1.0, shrink);
    return false;
  }
  void accepted(const StepProposal& /*step*/) {}

 private:
  static constexpr double kSafety = 0.9, kMaxGrowth = 10.0, kMaxShrink = 0.2, kBeta = 0.04;
  static constexpr double kExponent = 1.0 / kErrorPower;

  template <class State>
  double error_norm(const State& error, const State& y0, const State& y1) const {
    const State scale = tolerance_ * (1.0 + y0.cwiseAbs().cwiseMax(y1.cwiseAbs()).array()).matrix();
    return std::sqrt((error.cwiseQuotient(scale)).squaredNorm() / static_cast<double>(error.size()));
  }

  double tolerance_;
  double dt_ = 0.0, previous_error_ = 1e-4;
  double largest_step_ = std::numeric_limits<double>::infinity();
};

/// A closed form: one step from the start over all time (or to its first event, which the
/// stepper knows in closed form), never rejected; requests are answered from its interpolant.
class WholeSpan {
 public:
  static constexpr IntegratorKind kKind = IntegratorKind::kClosedForm;

  WholeSpan() = default;
  explicit WholeSpan(const IntegratorSettings& /*settings*/) {}
  std::string settings_text() const { return ""; }
  template <class Model, class State>
  void start(const Model& /*model*/, const State& /*y*/, const State& /*f*/) {}
  bool propose(double t, double /*t_target*/, StepProposal& step) {
    step.t_end = std::numeric_limits<double>::infinity();
    step.dt = step.t_end - t;
    return true;
  }
  template <class Attempt, class State>
  bool accept(const Attempt& /*attempt*/, const State& /*y0*/) {
    return true;
  }
  void accepted(const StepProposal& /*step*/) {}
};

}  // namespace spinning_top
