// Steppers: a method's attempt of one step, and the interpolant of each accepted step, which the
// event locator searches and the driver answers requests from (driver.hpp).
//   OneStepStepper   a one-step method (rk4, splittings, gauss6, rodas4): no error estimate, no
//                    FSAL stage; its interpolant is the step re-taken from its start with the
//                    shorter size, so a state inside the step has the method's own accuracy.
//   EmbeddedStepper  an embedded pair with continuous output (dopri5, dop853, radau5): attempt /
//                    prepare_dense / complete_dense (on first use in a step: most steps of a run
//                    sampled every few steps never need it) / dense.
// A closed form is a stepper too (integrators/exact_stepper.hpp): one span-long step.
// What a stepper declares for the driver:
//   kFsal                 the attempt carries f at its end (f1), reused by the next step;
//   kInterpolatedAnswers  requests fall inside steps and are answered by the interpolant, which
//                         the StepGuard checks (else they are step ends, already checked);
//   kClosedForm           the step is a closed form: exact, so no guard, and its events come in
//                         closed form instead of from the EventLocator.
// And its work (work()): the units of the work budget (work_budget.hpp, about one evaluation of
// the derivative each) it has spent since it was built (restarts do not reset it), in attempts
// (accepted or not), in its interpolant (a re-taken step, a dense output), in answers and in
// restarts (a closed form's construction); the driver charges the difference over each. A method states its work per step as kWorkPerStep,
// or counts it itself (work(): gauss6's sweeps, radau5's Newton iterations and factorizations).
#pragma once

#include <optional>
#include <string>
#include <type_traits>

#include "spinning_top/hot_path.hpp"
#include "spinning_top/kinematics.hpp"

namespace spinning_top {

/// The extremes of a motion since its start, where a method knows them in closed form.
struct ClosedFormRange {
  double one_minus_cos_max_tilt = 0.0;       ///< 1 - e_Zz at the largest tilt
  double least_normal_force_per_mass = 0.0;  ///< least R / m [m/s^2]
};

namespace stepper_detail {
/// True if Method counts its own work (a long work() const), else it states kWorkPerStep.
template <class Method, class = void>
struct CountsItsWork : std::false_type {};
template <class Method>
struct CountsItsWork<Method, std::void_t<decltype(std::declval<const Method&>().work())>> : std::true_type {};
}  // namespace stepper_detail

template <class Model, class Method>
class OneStepStepper {
 public:
  using State = typename Model::State;
  static constexpr bool kFsal = false, kInterpolatedAnswers = false, kClosedForm = false;

  struct Attempt {
    State y1;
  };

  std::string description() const { return Method::kName; }
  void restart(const Model& /*model*/, double /*t*/, const State& /*y*/) {}

  SPINNING_TOP_FLATTEN void attempt(const Model& model, const State& y0, const State& /*f0*/, double dt, Attempt& out) {
    out.y1 = y0;
    step(model, out.y1, dt);
  }
  void accepted(const State& /*y0*/, const State& /*f0*/, const Attempt& /*attempt*/, double /*t0*/, double /*dt*/) {}

  /// The step from (t0, y0) re-taken with the shorter size t - t0, projected.
  auto interpolant(const Model& model, double t0, const State& y0) {
    return [this, &model, t0, &y0](double t) {
      State y = y0;
      step(model, y, t - t0);
      normalize_attitude(y);
      return y;
    };
  }

  /// Requests are step ends (the SubstepPlan ends a request's last substep at it).
  bool answer(const Model& /*model*/, double /*t*/, const State& y_end, State& y) const {
    y = y_end;
    return true;
  }

  std::optional<ClosedFormRange> closed_form_range(double /*t*/) const { return std::nullopt; }

  /// Work units spent since the stepper was built (this file's header).
  long work() const {
    if constexpr (stepper_detail::CountsItsWork<Method>::value)
      return method_.work();
    else
      return work_;
  }

 private:
  SPINNING_TOP_FLATTEN void step(const Model& model, State& y, double dt) {
    method_.step(model, y, dt);
    if constexpr (!stepper_detail::CountsItsWork<Method>::value) work_ += Method::kWorkPerStep;
  }

  Method method_;
  long work_ = 0;  // for a method of constant work per step
};

template <class Model, class Method>
class EmbeddedStepper {
 public:
  using State = typename Model::State;
  using Attempt = typename Method::Attempt;
  static constexpr bool kFsal = true, kInterpolatedAnswers = true, kClosedForm = false;

  std::string description() const { return Method::kName; }
  /// A run starts afresh (RADAU5: no Jacobian, no starting guess, counters at zero).
  void restart(const Model& /*model*/, double /*t*/, const State& /*y*/) {
    method_.restart();
    has_dense_ = dense_complete_ = false;
  }

  SPINNING_TOP_FLATTEN void attempt(const Model& model, const State& y0, const State& f0, double dt, Attempt& out) {
    method_.attempt(model, y0, f0, dt, out);
  }
  /// The step is kept: its continuous extension (completed on first use, dense_at()).
  SPINNING_TOP_FLATTEN void accepted(const State& y0, const State& f0, const Attempt& attempt, double t0, double dt) {
    method_.prepare_dense(y0, f0, attempt, t0, dt, dense_);
    has_dense_ = true;
    dense_complete_ = false;
  }

  /// The method's dense output over the last accepted step, projected.
  auto interpolant(const Model& model, double /*t0*/, const State& /*y0*/) {
    return [this, &model](double t) { return dense_at(model, t); };
  }
  bool answer(const Model& model, double t, const State& /*y_end*/, State& y) {
    y = dense_at(model, t);
    return true;
  }

  std::optional<ClosedFormRange> closed_form_range(double /*t*/) const { return std::nullopt; }

  /// The method and its work counters (e.g. RadauIIA5::statistics()).
  const Method& method() const { return method_; }
  /// Work units spent (this file's header): the method counts them, in its attempts and its
  /// dense output.
  long work() const { return method_.work(); }
  /// The size of the last accepted step [s] (0 before the first).
  double last_step() const { return has_dense_ ? dense_.dt : 0.0; }

 private:
  State dense_at(const Model& model, double t) {
    if (!dense_complete_) method_.complete_dense(model, dense_);
    dense_complete_ = true;
    State y = Method::dense(dense_, t);
    normalize_attitude(y);
    return y;
  }

  Method method_;
  typename Method::DenseStep dense_;
  bool has_dense_ = false, dense_complete_ = false;
};

}  // namespace spinning_top
