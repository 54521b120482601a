// The one driver loop: it joins a Stepper (steppers.hpp, integrators/exact_stepper.hpp), its
// Controller (controllers.hpp), the StepGuard (step_guard.hpp) and the EventLocator
// (event_locator.hpp) to advance a scene model to a requested time (doc/integrators.md, "The
// integration layer"):
//
//   while the last accepted step ends before the request and no event is pending:
//     controller proposes a step -> stepper attempts it -> controller accepts it (or shrinks it
//     and the stepper tries again) -> the stepper keeps the step's interpolant ->
//     time-stepper: guard (projection, finiteness, energy) -> locator (events inside the step,
//                   through the interpolant) -> guard on the located state;
//     closed form: its events in closed form;
//   an event pending at or before the request ends the run there; otherwise the request is
//   answered from the last step's interpolant (guarded where it interpolates).
//
// An event's handler either ends the run (today's validity events) or, in a hybrid model, maps
// the state into the next phase and goes on: see EventHandling below.
#pragma once

#include <algorithm>
#include <optional>
#include <string>
#include <utility>

#include "spinning_top/events.hpp"
#include "spinning_top/hot_path.hpp"
#include "spinning_top/integration/controllers.hpp"
#include "spinning_top/integration/event_locator.hpp"
#include "spinning_top/integration/range_tracker.hpp"
#include "spinning_top/integration/step_guard.hpp"
#include "spinning_top/integration/steppers.hpp"
#include "spinning_top/work_budget.hpp"

namespace spinning_top {

/// What the driver does at an event: ends the run (the default: the contact model's validity
/// events), or hands the event's state to a handler that maps it into the state the run goes on
/// from (a transition of a hybrid model), after which the driver restarts its stepper,
/// controller, guard and locator there. `handle(model, event, t, y)` returns true if the run
/// goes on from (t, y) (y may be changed in place, its attitude kept a unit quaternion), false
/// to end it with the event. A handler must move the state off the event (here the validity
/// check at the restart ends the run if it does not); each transition costs one step of the
/// work budget, which bounds a handler that keeps the run in place.
struct EndAtEvents {
  template <class Model, class State>
  bool handle(const Model& /*model*/, Event /*event*/, double /*t*/, State& /*y*/) const {
    return false;
  }
};

template <class Model, class Stepper, class Controller, class EventHandling = EndAtEvents>
class Driver {
 public:
  using State = typename Model::State;
  static constexpr IntegratorKind kKind = Controller::kKind;
  /// Whether track_range() can follow the run's extremes: a method that answers from an
  /// interpolant between its steps (dopri5, dop853, radau5). A fixed step's states are its step
  /// ends, which a front end samples; a closed form has its extremes in closed form.
  static constexpr bool kTracksRange = Stepper::kInterpolatedAnswers && !Stepper::kClosedForm;

  /// Built from what its controller takes: the integrator settings, or its step or tolerance alone.
  template <class Setting>
  explicit Driver(const Setting& setting, EventHandling handling = EventHandling())
      : controller_(setting), handling_(std::move(handling)) {}
  Driver() = default;  // a controller without settings (WholeSpan)

  /// (Re)starts the run at (t, y): the attitude projected; a state that already violates the
  /// model is the event at t. A closed form may refuse the state (MethodRefusal): then the
  /// driver is left as it was.
  void reset(const Model& model, double t, const State& y) {
    State start = y;
    const bool finite = StepGuard<Model>::project(start);
    const long before = stepper_.work();
    if (finite) stepper_.restart(model, t, start);
    restart_work_ = stepper_.work() - before;
    steps_ = rejected_ = work_ = 0;
    begin(model, t, start, finite);
    if constexpr (kTracksRange) {
      if (tracking_) start_range(model);
    }
  }

  /// From the current state on, and after every reset, the run's least R and largest tilt are
  /// followed through the steps' interpolants (range_tracker.hpp), at the cost of a screen per
  /// step and a search per new extreme; the steps and states stay the same, bit for bit. Where
  /// kTracksRange is false it does nothing (range_tracker() stays null).
  void track_range(const Model& model) {
    if constexpr (kTracksRange) {
      tracking_ = true;
      start_range(model);
    }
  }
  /// The extremes since the tracking started (or the last reset) up to time(), or null if
  /// track_range() was not called (or cannot track).
  const RangeTracker<Model>* range_tracker() const { return kTracksRange && tracking_ ? &tracker_ : nullptr; }

  /// Advances to t_target. Returns the event that ended the run (then time() is the event's
  /// time, <= t_target), or kNone. With a budget that runs out first it returns kNone with
  /// time() < t_target (out_of_budget()); the steps taken are kept, and the next call goes on
  /// with the same steps (the same states, bit for bit).
  Event advance_to(const Model& model, double t_target, const WorkBudget& budget = WorkBudget()) {
    if (event_ != Event::kNone || t_target <= t_out_) return event_;
    BudgetMeter meter(budget);
    if constexpr (kTracksRange) {
      // The rest of the last step beyond the last answer, while its interpolant is still valid.
      if (tracking_) {
        const long before = stepper_.work();
        fold_range(model, t_target);
        work_ += stepper_.work() - before;
      }
    }
    const long start = work();
    for (;;) {
      while (t_ < t_target && pending_ == Event::kNone) {
        if (!meter.allows_step(work() - start)) return out_of_budget();
        const long before = stepper_.work();
        const bool continued = take_step(model, t_target);
        work_ += stepper_.work() - before + kStepChecksWork;
        if (!continued) return event_ = Event::kNonFinite;
      }
      if (pending_ == Event::kNone || t_target < t_) break;
      if (!continue_after(model)) {
        t_out_ = t_;
        y_out_ = y_;
        if constexpr (kTracksRange) tracker_.commit();
        return event_ = pending_;
      }
      if (event_ != Event::kNone) return event_;  // the mapped state is itself invalid
    }
    State y;
    const long before = stepper_.work();
    const bool answered = stepper_.answer(model, t_target, y_, y);
    work_ += stepper_.work() - before;  // a dense output's stages, a partial collocation step
    if (!answered) return event_ = Event::kNonFinite;
    // A state interpolated between the steps can break the balance where the steps do not
    // (dopri5 at tolerance 1e-3: 1.4x the allowed drift, found by the fuzz test). The run then
    // stops at the last state it answered.
    if constexpr (Stepper::kInterpolatedAnswers) {
      if (!guard_.keeps_balance(model, y)) return event_ = Event::kEnergyDrift;
    }
    t_out_ = t_target;
    y_out_ = y;
    if constexpr (kTracksRange) tracker_.commit();
    return Event::kNone;
  }

  double time() const { return t_out_; }
  const State& state() const { return y_out_; }
  Event event() const { return event_; }
  long steps() const { return steps_; }            ///< accepted steps since reset (a closed form's span: 1)
  long rejected_steps() const { return rejected_; }  ///< rejected attempts since reset
  /// Work since reset in units of the work budget (work_budget.hpp): what the stepper charged
  /// (rejected attempts, Newton iterations, dense output and event searches included) and the
  /// checks after each step, but at least kWorkPerStep per accepted step.
  long work() const { return std::max(steps_ * kWorkPerStep, work_); }
  /// The work units of the last reset's start of the stepper (a closed form's construction),
  /// not in work(): a run charges it where it restarts a phase inside an advance (the hybrid's
  /// transitions), not for its first start.
  long restart_work() const { return restart_work_; }
  /// Ends the run with the given event (kept until the next reset).
  void stop(Event event) { event_ = event; }

  /// "rk4, step 0.001 s", "dop853, tolerance 1e-12", "exact: closed form, ...".
  std::string description() const { return stepper_.description() + controller_.settings_text(); }
  /// The extremes over [start, time()] where the stepper knows them in closed form.
  std::optional<ClosedFormRange> closed_form_range() const { return stepper_.closed_form_range(t_out_); }

  const Stepper& stepper() const { return stepper_; }
  const Controller& controller() const { return controller_; }
  /// The search of the steps for events (its counts are the cost of the events).
  const EventLocator<Model>& event_locator() const { return locator_; }

 private:
  /// The budget ran out before the request: a fixed step's end is a state of the run, reported
  /// as the last one reached (the next request goes on with the plan's remaining substeps); a
  /// method that answers between its steps keeps reporting the last answered time.
  Event out_of_budget() {
    if constexpr (!Stepper::kInterpolatedAnswers && !Stepper::kClosedForm) {
      t_out_ = t_;
      y_out_ = y_;
    }
    return Event::kNone;
  }

  /// Starts the run's state, guard, locator and controller at (t, y) (projected).
  void begin(const Model& model, double t, const State& y, bool finite) {
    t_out_ = t_ = t;
    y_out_ = y_ = y;
    pending_ = Event::kNone;
    event_ = finite ? triggered_event(event_functions(model, y)) : Event::kNonFinite;
    if (event_ != Event::kNone) return;
    model.derivative(y_, f_);
    guard_.start(model, y_);
    locator_.start(model, t, y_, f_);
    controller_.start(model, y_, f_);
  }

  /// The pending event's handler: true if the run goes on from the (mapped) event state, where
  /// the stepper, the controller, the guard and the locator start again (the run's event is then
  /// set if that state is itself invalid). Numerical failures always end the run.
  bool continue_after(const Model& model) {
    if (pending_ == Event::kNonFinite || pending_ == Event::kEnergyDrift) return false;
    State y = y_;
    if (!handling_.handle(model, pending_, t_, y)) return false;
    // Not projected again: the event's state is on the unit sphere, and a handler that changes
    // the attitude keeps it there. Projecting twice moves q by an ulp, which can take a state
    // located just inside the model's validity (e_Zz = 2e-16 at a landing) just outside it.
    const bool finite = all_finite(y);
    const long before = stepper_.work();
    if (finite) stepper_.restart(model, t_, y);
    work_ += stepper_.work() - before;
    begin(model, t_, y, finite);
    return true;
  }

  /// One accepted step (with as many rejected attempts as its controller needs). False if the
  /// step size underflows or the step is not finite: the solution cannot be continued.
  /// Flattened (hot_path.hpp): the attempt, the error norm and the event functions are inlined.
  SPINNING_TOP_FLATTEN bool take_step(const Model& model, double t_target) {
    typename Stepper::Attempt attempt;
    StepProposal step;
    for (;;) {
      if (!controller_.propose(t_, t_target, step)) return false;
      stepper_.attempt(model, y_, f_, step.dt, attempt);
      if (controller_.accept(attempt, y_)) break;
      ++rejected_;
    }
    stepper_.accepted(y_, f_, attempt, t_, step.dt);
    controller_.accepted(step);
    ++steps_;
    if constexpr (Stepper::kClosedForm) {
      // Exact over its whole span: its first event comes in closed form.
      const auto event = stepper_.first_event(model, t_, y_);
      if (event.event == Event::kNone) {
        t_ = step.t_end;
      } else {
        pending_ = event.event;
        t_ = event.time;
        y_ = event.state;
      }
      return true;
    } else {
      if constexpr (kTracksRange) {
        if (tracking_) {
          range_step_t0_ = t_;
          range_step_y0_ = y_;
          range_step_t1_ = step.t_end;
        }
      }
      State y_end = attempt.y1;
      if (!StepGuard<Model>::project(y_end)) return false;
      State f_end;
      if constexpr (Stepper::kFsal) {
        // f(y1) of the attempt, although the projection moved y1 by O(local error): the
        // mismatch enters the next step multiplied by dt, below its local error.
        f_end = attempt.f1;
      } else {
        model.derivative(y_end, f_end);
      }
      const Eigen::Vector2d g_end = event_functions(model, y_end);
      if (!std::isfinite(g_end[0]) || !std::isfinite(g_end[1])) return false;
      // A step that breaks the energy balance is garbage throughout (an event inside it too):
      // the run stops at its start, the last state that kept the balance.
      if (!guard_.keeps_balance(model, y_end)) {
        pending_ = Event::kEnergyDrift;
        return true;
      }
      const auto located = locator_.locate(model, y_, step.t_end, y_end, g_end, f_end, stepper_.interpolant(model, t_, y_));
      if (located.event == Event::kNone) {
        y_ = y_end;
        f_ = f_end;
        t_ = step.t_end;
        if constexpr (kTracksRange) {
          if (tracking_) {
            g_at_t_ = g_end;
            fold_range(model, t_target);
          }
        }
        return true;
      }
      // The located state comes from the step's interpolant, which may break the balance where
      // the step's end keeps it (dop853 at tolerance 9e-3 with stiff friction: 700x the allowed
      // drift at a located lift-off, found by the fuzz test).
      if (!guard_.keeps_balance(model, located.state)) {
        pending_ = Event::kEnergyDrift;
        return true;
      }
      pending_ = located.event;
      t_ = located.time;
      y_ = located.state;
      if constexpr (kTracksRange) {
        if (tracking_) {
          g_at_t_ = event_functions(model, y_);
          fold_range(model, t_target);
        }
      }
      return true;
    }
  }

  /// The range starts at the reported state, the end of the steps so far (a reset, or between
  /// requests that ended at a step's end).
  void start_range(const Model& model) {
    tracker_.start(model, y_out_);
    range_folded_to_ = t_;
  }

  /// Folds the last step's piece from where the range has reached to min(t_, t_target), the part
  /// of the run known so far (the step's end, its event, or the request inside it), while the
  /// step's interpolant is valid (range_tracker.hpp).
  void fold_range(const Model& model, double t_target) {
    const double to = std::min(t_, t_target);
    if (!(to > range_folded_to_)) return;
    auto state_at = stepper_.interpolant(model, range_step_t0_, range_step_y0_);
    if (to == t_) {
      tracker_.fold(model, range_step_t0_, range_step_t1_, locator_.step_cubics(), range_folded_to_, to, y_, g_at_t_,
                    state_at);
    } else {
      const State y = state_at(to);  // the answer's state, computed again
      tracker_.fold(model, range_step_t0_, range_step_t1_, locator_.step_cubics(), range_folded_to_, to, y,
                    event_functions(model, y), state_at);
    }
    range_folded_to_ = to;
  }

  Stepper stepper_;
  Controller controller_;
  StepGuard<Model> guard_;
  EventLocator<Model> locator_;
  EventHandling handling_;
  // The reported time and state (the last answered request, or the event), and the run's event.
  double t_out_ = 0.0;
  State y_out_ = State::Zero();
  Event event_ = Event::kNone;
  // The end of the last accepted step (or the pending event's time and state), f there.
  double t_ = 0.0;
  State y_ = State::Zero(), f_ = State::Zero();
  Event pending_ = Event::kNone;
  long steps_ = 0, rejected_ = 0;
  long work_ = 0;  ///< units charged since reset (work() adds the floor of one budget step per step)
  long restart_work_ = 0;
  // The extremes (track_range()): the tracker, the step it folds ([t0, t1] from y0; the event
  // functions at t_), and how far it has folded.
  bool tracking_ = false;
  RangeTracker<Model> tracker_;
  double range_step_t0_ = 0.0, range_step_t1_ = 0.0, range_folded_to_ = 0.0;
  State range_step_y0_ = State::Zero();
  Eigen::Vector2d g_at_t_ = Eigen::Vector2d::Zero();
  /// The driver's own work after a step, in units: the event functions, the guard and the
  /// projection (1), and f at the step's end where the method does not hand it over (1).
  static constexpr long kStepChecksWork = Stepper::kClosedForm ? 0 : Stepper::kFsal ? 1 : 2;
};

}  // namespace spinning_top
