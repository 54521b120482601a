// Drivers step a scene model to a requested time with an integrator, keep the attitude on
// the unit sphere, and stop at the first validity event, located within the step.
//   FixedStepDriver: any one-step method at a fixed maximal step, equal substeps per request.
//   AdaptiveDriver: an embedded pair with error control; requests are answered by dense
//   output, so the output rate never forces the step size.
// Both hand every step to the one EventMonitor (events.hpp), which projects the attitude,
// checks finiteness and bounds the event functions over the whole step through the step's
// interpolant: the method's dense output (adaptive) or the step re-taken from its start with a
// shorter size (fixed step).
#pragma once

#include <algorithm>
#include <cmath>
#include <limits>
#include <optional>
#include <stdexcept>
#include <string>
#include <type_traits>
#include <utility>

#include "spinning_top/events.hpp"
#include "spinning_top/hot_path.hpp"
#include "spinning_top/kinematics.hpp"
#include "spinning_top/parameters.hpp"
#include "spinning_top/work_budget.hpp"

namespace spinning_top {

/// The extremes of a motion since its start, where a method knows them in closed form.
struct ClosedFormRange {
  double one_minus_cos_max_tilt = 0.0;       ///< 1 - e_Zz at the largest tilt
  double least_normal_force_per_mass = 0.0;  ///< least R / m [m/s^2]
};

/// Common state of a driver: the reported time and state, and the event that ended the run.
template <class Model>
class DriverBase {
 public:
  using State = typename Model::State;
  /// A time-stepper knows its motion only at its steps: no closed-form range (exact.hpp has one).
  std::optional<ClosedFormRange> closed_form_range() const { return std::nullopt; }
  double time() const { return t_out_; }
  const State& state() const { return y_out_; }
  Event event() const { return event_; }
  long steps() const { return steps_; }                ///< accepted steps since reset
  long rejected_steps() const { return rejected_; }    ///< rejected attempts since reset
  /// Ends the run with the given event (kept until the next reset).
  void stop(Event event) { event_ = event; }

 protected:
  /// Starts a run at (t, y); an initial state that already violates the model is an event at t.
  void start(const Model& model, double t, const State& y) {
    t_out_ = t;
    y_out_ = y;
    normalize_attitude(y_out_);
    steps_ = rejected_ = 0;
    event_ = all_finite(y_out_) ? triggered_event(event_functions(model, y_out_)) : Event::kNonFinite;
  }

  double t_out_ = 0.0;
  State y_out_ = State::Zero();
  Event event_ = Event::kNone;
  long steps_ = 0, rejected_ = 0;
};

template <class Model, class Method>
class FixedStepDriver : public DriverBase<Model> {
 public:
  using State = typename Model::State;
  static constexpr bool kAdaptive = false;

  explicit FixedStepDriver(double max_step) : max_step_(max_step) {
    if (!(max_step > 0.0) || !std::isfinite(max_step)) throw std::invalid_argument("step must be positive and finite");
  }

  void reset(const Model& model, double t, const State& y) {
    this->start(model, t, y);
    plan_ = Plan();
    if (this->event_ != Event::kNone) return;
    State f;
    model.derivative(this->y_out_, f);
    monitor_.start(model, t, this->y_out_, f);
  }

  double max_step() const { return max_step_; }
  std::string description() const { return std::string(Method::kName) + ", step " + format_step(max_step_); }
  /// The per-step event check (its counts of searched steps: the cost of the events).
  const EventMonitor<Model>& event_monitor() const { return monitor_; }

  /// Advances to t_target in n equal substeps of at most max_step. Returns the event that
  /// stopped the run (then time() < t_target is the event time), or kNone. With a budget that
  /// runs out first it returns kNone with time() < t_target, and the next call for the same
  /// target takes the remaining substeps of the same plan (the same states, bit for bit).
  Event advance_to(const Model& model, double t_target, const WorkBudget& budget = WorkBudget()) {
    if (this->event_ != Event::kNone || t_target <= this->t_out_) return this->event_;
    if (!(plan_.target == t_target && plan_.next <= plan_.count && this->t_out_ == plan_.reached)) {
      const double t_start = this->t_out_;
      const double span = t_target - t_start;
      // A request of exactly max_step arrives as t_target - t_start rounded at the size of t
      // (relative error ~ eps t / span, 1e-9 at t = 1e4 s, 1 ms): allow substeps up to 1e-6
      // above max_step rather than taking a second, tiny substep for rounding.
      // The substep count, checked before the conversion: past ~9.2e18 the cast overflowed and one
      // substep spanned the whole request (step 1e-300 s gave a lift-off with 5x the energy).
      const double count = std::ceil(span / max_step_ * (1.0 - 1e-6));
      if (!(count <= kMaxSubsteps))
        throw InvalidParameter("step", "a request of " + std::to_string(span) + " s needs " + std::to_string(count) +
                                           " substeps of " + std::to_string(max_step_) + " s, more than the " +
                                           std::to_string(kMaxSubsteps) + " one request may take");
      plan_.start = t_start;
      plan_.target = t_target;
      plan_.count = std::max(1L, static_cast<long>(count));
      plan_.dt = span / static_cast<double>(plan_.count);
      plan_.next = 1;
    }
    BudgetMeter meter(budget);
    for (; plan_.next <= plan_.count; ++plan_.next) {
      if (!meter.allows_step()) {
        plan_.reached = this->t_out_;
        return Event::kNone;
      }
      const long i = plan_.next;
      const double t_new = (i == plan_.count) ? t_target : plan_.start + static_cast<double>(i) * plan_.dt;
      const State& y0 = this->y_out_;
      const double t0 = this->t_out_;
      State y_new = y0;
      method_.step(model, y_new, t_new - t0);
      ++this->steps_;
      // The step's interpolant: the step re-taken from its start with the shorter size, so the
      // state at t0 + tau has the method's own accuracy, and so does the event time.
      auto state_at = [&](double t) {
        State y = y0;
        method_.step(model, y, t - t0);
        normalize_attitude(y);
        return y;
      };
      const auto outcome = monitor_.check_step(model, y0, t_new, y_new, state_at);
      if (outcome.event != Event::kNone) {
        if (outcome.event != Event::kNonFinite) {
          this->y_out_ = outcome.state;
          this->t_out_ = outcome.time;
        }
        return this->event_ = outcome.event;
      }
      this->y_out_ = y_new;
      this->t_out_ = t_new;
    }
    return Event::kNone;
  }

 private:
  static std::string format_step(double s) {
    char buffer[32];
    std::snprintf(buffer, sizeof buffer, "%g s", s);
    return buffer;
  }
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
  Method method_;
  EventMonitor<Model> monitor_;
};

/// True for embedded pairs whose dense output needs extra evaluations of f (DOP853): the
/// driver completes it (Method::complete_dense) only for a step where it is used.
template <class Method, class = void>
struct has_lazy_dense_output : std::false_type {};
template <class Method>
struct has_lazy_dense_output<Method, std::void_t<decltype(Method::kLazyDense)>>
    : std::bool_constant<Method::kLazyDense> {};

/// True for methods that keep state from step to step (RADAU5: Jacobian, LU decompositions,
/// Newton's starting guess): the driver's reset() restarts them.
template <class Method, class = void>
struct has_restart : std::false_type {};
template <class Method>
struct has_restart<Method, std::void_t<decltype(std::declval<Method&>().restart())>> : std::true_type {};

template <class Model, class Method>
class AdaptiveDriver : public DriverBase<Model> {
 public:
  using State = typename Model::State;
  static constexpr bool kAdaptive = true;

  explicit AdaptiveDriver(double tolerance) : tolerance_(tolerance) {
    if (!(tolerance > 0.0) || !std::isfinite(tolerance)) throw std::invalid_argument("tolerance must be positive and finite");
  }

  /// (Re)starts the integration at (t, y); the step size is chosen afresh.
  void reset(const Model& model, double t, const State& y) {
    this->start(model, t, y);
    if constexpr (has_restart<Method>::value) method_.restart();
    t_ = t;
    y_ = this->y_out_;
    model.derivative(y_, f_);
    if (this->event_ == Event::kNone) monitor_.start(model, t, y_, f_);
    dt_ = initial_step(model);
    has_dense_ = dense_complete_ = false;
    pending_ = Event::kNone;
    previous_error_ = 1e-4;
  }

  double tolerance() const { return tolerance_; }
  /// The per-step event check (its counts of searched steps: the cost of the events).
  const EventMonitor<Model>& event_monitor() const { return monitor_; }
  /// The method and its work counters (e.g. RadauIIA5::statistics()).
  const Method& method() const { return method_; }
  /// The size of the last accepted step [s] (0 before the first).
  double last_step() const { return has_dense_ ? dense_.dt : 0.0; }
  std::string description() const {
    char buffer[64];
    std::snprintf(buffer, sizeof buffer, "%s, tolerance %g", Method::kName, tolerance_);
    return buffer;
  }

  /// Advances to t_target (dense output). With a budget that runs out first it returns kNone
  /// with time() < t_target; the steps already taken are kept (the reported state stays at the
  /// last answered time), so the next call goes on with the same steps, bit for bit.
  Event advance_to(const Model& model, double t_target, const WorkBudget& budget = WorkBudget()) {
    if (this->event_ != Event::kNone || t_target <= this->t_out_) return this->event_;
    BudgetMeter meter(budget);
    while (t_ < t_target && pending_ == Event::kNone) {
      if (!meter.allows_step()) return Event::kNone;
      if (!take_step(model)) return this->event_ = Event::kNonFinite;
    }
    if (pending_ != Event::kNone && t_target >= t_) {
      this->t_out_ = t_;
      this->y_out_ = y_;
      return this->event_ = pending_;
    }
    State y = Method::dense(dense_step(model), t_target);
    normalize_attitude(y);
    // The monitor checks the balance at the steps' ends; an interpolated state between them can
    // break it where the steps do not (dopri5 at tolerance 1e-3: 1.4x the allowed drift, found
    // by the fuzz test). The run then stops at the last state it answered.
    if (!monitor_.keeps_balance(model, y)) return this->event_ = Event::kEnergyDrift;
    this->t_out_ = t_target;
    this->y_out_ = y;
    return Event::kNone;
  }

 private:
  // Hairer's step-size control with a PI stabilisation (Solving ODEs I, sec. II.4 and IV.2).
  static constexpr double kSafety = 0.9, kMaxGrowth = 10.0, kMaxShrink = 0.2, kBeta = 0.04;

  double error_norm(const State& error, const State& y0, const State& y1) const {
    const State scale = tolerance_ * (1.0 + y0.cwiseAbs().cwiseMax(y1.cwiseAbs()).array()).matrix();
    return std::sqrt((error.cwiseQuotient(scale)).squaredNorm() / static_cast<double>(error.size()));
  }

  /// Hairer's starting step heuristic (Solving ODEs I, sec. II.4, "Starting step size").
  double initial_step(const Model& model) const {
    const State scale = tolerance_ * (1.0 + y_.cwiseAbs().array()).matrix();
    const double d0 = y_.cwiseQuotient(scale).norm(), d1 = f_.cwiseQuotient(scale).norm();
    const double h0 = (d0 < 1e-5 || d1 < 1e-5) ? 1e-6 : 0.01 * d0 / d1;
    State f1;
    model.derivative(y_ + h0 * f_, f1);
    const double d2 = (f1 - f_).cwiseQuotient(scale).norm() / h0;
    const double dmax = std::max(d1, d2);
    const double h1 = (dmax <= 1e-15) ? std::max(1e-6, h0 * 1e-3)
                                      : std::pow(0.01 / dmax, 1.0 / (Method::kEmbeddedOrder + 1));
    const double h = std::min(100.0 * h0, h1);
    return std::isfinite(h) && h > 0.0 ? h : 1e-6;
  }

  /// The continuous extension of the last accepted step, completed on first use: with output
  /// every 1 ms and steps of ~4 ms, or output only at the end, most steps never need it.
  const typename Method::DenseStep& dense_step(const Model& model) {
    if constexpr (has_lazy_dense_output<Method>::value) {
      if (!dense_complete_) method_.complete_dense(model, dense_);
    }
    dense_complete_ = true;
    return dense_;
  }

  /// One accepted step (with as many rejected attempts as needed). False if the step size
  /// underflows: the solution cannot be continued with finite values.
  /// Flattened (hot_path.hpp): the attempt, the error norm and the event functions are inlined.
  SPINNING_TOP_FLATTEN bool take_step(const Model& model) {
    typename Method::Attempt attempt;
    for (;;) {
      // The step may shrink to what the clock resolves at t (16 ulps), however short: an absolute
      // floor (1e-14 s) ended a stiff initial transient (a slip relaxing in 5e-14 s) in non_finite.
      if (!(dt_ > 16.0 * std::numeric_limits<double>::epsilon() * std::abs(t_) + std::numeric_limits<double>::min()))
        return false;
      // Step by the increment the clock can represent, (t + dt) - t, so that t_ and the state
      // advance by the same amount: otherwise t_ picks up a rounding of ~eps |t| per step that
      // the state does not, a random walk in time that a spin of 2000 rad/s turns into 1e-10 rad
      // of attitude over 10 s (measured against exact, dop853 at 1e-14).
      dt_ = (t_ + dt_) - t_;
      method_.attempt(model, y_, f_, dt_, attempt);
      const double err = error_norm(attempt.error, y_, attempt.y1);
      const double exponent = 1.0 / (Method::kEmbeddedOrder + 1);
      if (std::isfinite(err) && err <= 1.0 && all_finite(attempt.f1)) {
        const double factor = std::pow(err, exponent - 0.75 * kBeta) / std::pow(previous_error_, kBeta);
        // Lazy methods complete the dense output only if asked for in this step (dense_step()).
        method_.prepare_dense(y_, f_, attempt, t_, dt_, dense_);
        has_dense_ = true;
        dense_complete_ = false;
        const double t_new = t_ + dt_;
        State y_new = attempt.y1;
        ++this->steps_;
        // The step's interpolant: the method's dense output (completed here if lazy).
        auto state_at = [&](double t) {
          State y = Method::dense(dense_step(model), t);
          normalize_attitude(y);
          return y;
        };
        const auto outcome = monitor_.check_step(model, y_, t_new, y_new, attempt.f1, state_at);
        if (outcome.event == Event::kNonFinite) return false;
        if (outcome.event != Event::kNone) {
          pending_ = outcome.event;
          y_ = outcome.state;
          t_ = outcome.time;
          return true;
        }
        y_ = y_new;
        // FSAL: f(y1) is reused although the projection moved y1 by O(local error); the
        // mismatch enters the next step multiplied by dt, below its local error.
        f_ = attempt.f1;
        t_ = t_new;
        previous_error_ = std::max(err, 1e-4);
        dt_ *= std::min(kMaxGrowth, std::max(kMaxShrink, kSafety / std::max(factor, 1e-10)));
        return true;
      }
      ++this->rejected_;
      const double shrink = std::isfinite(err) ? std::max(kMaxShrink, kSafety * std::pow(err, -exponent)) : kMaxShrink;
      dt_ *= std::min(1.0, shrink);
    }
  }

  double tolerance_;
  Method method_;
  double t_ = 0.0, dt_ = 0.0, previous_error_ = 1e-4;
  State y_ = State::Zero(), f_ = State::Zero();
  EventMonitor<Model> monitor_;
  typename Method::DenseStep dense_;
  bool has_dense_ = false, dense_complete_ = false;
  Event pending_ = Event::kNone;
};

}  // namespace spinning_top
