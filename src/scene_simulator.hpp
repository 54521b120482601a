// SceneSimulator: one scene model stepped by one driver, behind the Simulator interface, and
// the factory that builds it for each integrator that serves the scene (the registry's rows,
// integrators/registry_rows.hpp). Included only by the per-scene factory units
// (src/scenes/*_simulator.cpp): each instantiates its own scene's drivers, so no unit compiles
// every scene x method.
#pragma once

#include <algorithm>
#include <cmath>
#include <memory>
#include <optional>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "scene_factories.hpp"
#include "spinning_top/auto_driver.hpp"
#include "spinning_top/integrators/registry_rows.hpp"
#include "spinning_top/simulator.hpp"

namespace spinning_top {
namespace scene_factory {

/// The driver for a validated configuration: auto's from the whole configuration (it plans
/// per state), the others from the integrator settings as given.
template <class Driver>
Driver make_driver(const SceneConfig& config) {
  if constexpr (Driver::kKind == IntegratorKind::kAutomatic)
    return Driver(config);
  else
    return Driver(config.integrator);
}

/// A contact phase of the hybrid model (hybrid_simulator.hpp): a Simulator whose model and state
/// the hybrid reads and restarts at a transition.
template <class Model>
class ContactPhase : public Simulator {
 public:
  using State = typename Model::State;
  virtual const State& state() const = 0;
  virtual const Model& model() const = 0;
  /// Goes on at (t, y) with `model` (the same top; skimming or not): its driver restarts there,
  /// auto choosing again. Throws MethodRefusal where the configured closed form refuses y.
  /// steps() starts again from 0; work_units() goes on, with the restart's own work (a closed
  /// form's construction).
  virtual void restart(const Model& model, double t, const State& y) = 0;
  /// The work since the last reset() in units of the work budget (work_budget.hpp), across
  /// restarts and updates: work() rounded up to steps.
  virtual long work_units() const = 0;
};

template <class Model, class Driver>
class SceneSimulator final : public ContactPhase<Model> {
 public:
  using State = typename Model::State;
  static constexpr bool kAutomatic = Driver::kKind == IntegratorKind::kAutomatic;

  explicit SceneSimulator(const SceneConfig& config)
      : config_(config), model_(config.top, config.initial), driver_(make_driver<Driver>(config)) {
    driver_.reset(model_, 0.0, model_.initial_state());
  }

  using Simulator::advance_to;
  Event advance_to(double t, const WorkBudget& budget) override {
    // A front end's bad request, not physics: exact would evaluate its closed form at t = inf
    // and a stepper would never arrive (found through the Python module's advance_to(inf)).
    if (!std::isfinite(t)) throw std::invalid_argument("advance_to: the target time must be finite, got " + std::to_string(t));
    return driver_.advance_to(model_, t, budget);
  }
  double time() const override { return driver_.time(); }
  Event event() const override { return driver_.event(); }

  Snapshot snapshot() const override {
    const auto& y = driver_.state();
    Snapshot s;
    s.time = driver_.time();
    s.attitude = attitude_of(y);
    s.body_rates = Vector3(y[state_index::kOmegaX], y[state_index::kOmegaY], model_.spin());
    s.outputs = model_.outputs(y);
    if constexpr (!Model::kConservesVerticalAngularMomentum) s.outputs.vertical_angular_momentum = 0.0;
    if (driver_.event() == Event::kLiftOff && s.outputs.normal_force < 0.0) {
      // A run that starts where R < 0 (after_lift_off: stop) ends with lift_off at once: the floor
      // cannot pull, so what it exerts there is 0, as in the hybrid simulator's snapshot.
      s.outputs.normal_force = 0.0;
      s.outputs.contact_force = Vector3::Zero();
    }
    return s;
  }

  std::optional<MotionRange> motion_range() const override {
    if (updated_) return std::nullopt;  // the driver's range starts at the update
    double one_minus_cos_max_tilt = 0.0, least_normal_force = 0.0;
    if (const std::optional<ClosedFormRange> range = driver_.closed_form_range()) {
      one_minus_cos_max_tilt = range->one_minus_cos_max_tilt;
      least_normal_force = config_.top.mass * range->least_normal_force_per_mass;
    } else if (const RangeTracker<Model>* tracker = driver_.range_tracker(); tracker && range_from_start_) {
      one_minus_cos_max_tilt = tracker->one_minus_cos_max_tilt();
      least_normal_force = tracker->least_normal_force();
    } else {
      return std::nullopt;
    }
    // tilt = 2 asin(sqrt((1 - cos tilt) / 2)): accurate near the vertical, where acos is not.
    const double half = std::clamp(0.5 * one_minus_cos_max_tilt, 0.0, 1.0);
    // A run that ended with lift_off shows R = 0 there, never the floor pulling (snapshot()).
    if (driver_.event() == Event::kLiftOff) least_normal_force = std::max(least_normal_force, 0.0);
    return MotionRange{2.0 * std::asin(std::sqrt(half)), least_normal_force};
  }

  void track_motion_range() override {
    // From the run's start (no step taken since the reset), or from the next reset.
    range_from_start_ = driver_.steps() == 0 && !updated_;
    tracking_range_ = true;
    driver_.track_range(model_);
  }

  bool reset() override {
    const IntegratorChoice before = integrator_choice();
    driver_.reset(model_, 0.0, model_.initial_state());
    updated_ = false;
    range_from_start_ = true;  // a tracking driver starts its range again (inert otherwise)
    earlier_work_ = 0;
    return switched(before);
  }

  bool update(const TopParameters& top, const IntegratorSettings& integrator) override {
    SceneConfig next = config_;
    next.top = top;
    next.integrator = integrator;
    validate(next);
    if (top.mass != config_.top.mass || top.inertia_transverse != config_.top.inertia_transverse ||
        top.inertia_axial != config_.top.inertia_axial || top.tip_distance != config_.top.tip_distance)
      throw InvalidParameter("mass", "the top's mass, inertia and tip distance cannot change during a run");
    if (integrator.type != config_.integrator.type)
      throw InvalidParameter("integrator", "cannot change during a run");
    // The new model and driver start from the current state before anything is replaced:
    // a driver may refuse the state (exact: InvalidParameter), and then nothing has changed.
    // auto's driver chooses again here, for this state.
    const IntegratorChoice before = integrator_choice();
    Driver driver = make_driver<Driver>(next);
    Model model(next.top, next.initial);
    const double t = driver_.time();
    const typename Model::State y = driver_.state();
    const Event event = driver_.event();
    driver.reset(model, t, y);
    // A change that puts the current state off the model's validity at once (a lower g under a
    // nutating top: the floor would have to pull the tip, R < 0) is refused rather than applied
    // as an instant event whose snapshot shows that R: a snapshot is always a valid state.
    if (event == Event::kNone && driver.event() == Event::kLiftOff)
      throw InvalidParameter(top.gravity != config_.top.gravity ? "gravity" : "friction",
                             "at the current state the floor would have to pull the tip down (R = " +
                                 std::to_string(model.outputs(driver.state()).normal_force) +
                                 " N): the change would lift the tip off at once; refused, the run goes on");
    config_ = next;
    model_ = std::move(model);
    earlier_work_ += driver_.work();
    driver_ = std::move(driver);
    if (tracking_range_) driver_.track_range(model_);  // from here, for the ranges after the next reset()
    updated_ = true;
    if (event != Event::kNone) driver_.stop(event);  // a stopped run stays stopped until reset()
    return switched(before);
  }

  const SceneConfig& config() const override { return config_; }
  std::string integrator_description() const override {
    return (kAutomatic ? "auto: " : "") + driver_.description();
  }
  IntegratorChoice integrator_choice() const override {
    if constexpr (kAutomatic)
      return driver_.choice();
    else
      return {config_.integrator.type, config_.integrator.type, false, ""};
  }
  long steps() const override { return driver_.steps(); }
  long work() const override { return work_in_steps(work_units()); }
  long work_units() const override { return earlier_work_ + driver_.work(); }
  std::vector<Transition> take_transitions() override { return {}; }  // a contact phase alone has none
  HopSummary hops() const override {
    HopSummary summary;
    if (driver_.event() == Event::kLiftOff) summary.first_lift_off_time = driver_.time();
    return summary;
  }
  Phase phase() const override { return Phase::kContact; }

  const State& state() const override { return driver_.state(); }
  const Model& model() const override { return model_; }
  void restart(const Model& model, double t, const State& y) override {
    const long spent = driver_.work();
    driver_.reset(model, t, y);  // may throw (MethodRefusal) before anything changes
    // A restart inside a run costs its work (exact builds its solution again); a reset's does not.
    earlier_work_ += spent + driver_.restart_work();
    model_ = model;
    updated_ = true;
  }

 private:
  /// A switch is another method, or the same method for another reason to run it (fallback).
  bool switched(const IntegratorChoice& before) const {
    const IntegratorChoice now = integrator_choice();
    return now.method != before.method || now.fallback != before.fallback;
  }

  SceneConfig config_;
  Model model_;
  Driver driver_;
  bool updated_ = false;  ///< update() restarted the driver mid-run
  bool tracking_range_ = false;   ///< track_motion_range() was called
  bool range_from_start_ = false;  ///< track_motion_range() was called at the run's start (or a reset since)
  long earlier_work_ = 0;  ///< work units of the drivers before the last update() or restart()
};

/// The simulator for the integrator `type` on this scene, or null if the row does not serve it
/// (validate() refuses that before).
template <class Model, IntegratorType type>
std::unique_ptr<ContactPhase<Model>> make_with(const SceneConfig& config) {
  if constexpr (serves<type, Model>())
    return std::make_unique<SceneSimulator<Model, DriverFor<Model, type>>>(config);
  else
    return nullptr;
}

template <class Model, int... index>
std::unique_ptr<ContactPhase<Model>> make_any(const SceneConfig& config, IntegratorType type,
                                             std::integer_sequence<int, index...>) {
  std::unique_ptr<ContactPhase<Model>> simulator;
  ((type == static_cast<IntegratorType>(index) ? (simulator = make_with<Model, static_cast<IntegratorType>(index)>(config), true)
                                                : false) ||
   ...);
  return simulator;
}

/// Builds the scene's simulator for config.integrator (validated by the caller).
template <class Model>
std::unique_ptr<ContactPhase<Model>> make_contact_phase(const SceneConfig& config) {
  const IntegratorType type = config.integrator.type;
  std::unique_ptr<ContactPhase<Model>> simulator =
      make_any<Model>(config, type, std::make_integer_sequence<int, kIntegratorCount>());
  if (!simulator)
    throw InvalidParameter("integrator", std::string(to_string(type)) + " does not serve the " + Model::kName + " scene");
  return simulator;
}

}  // namespace scene_factory
}  // namespace spinning_top
