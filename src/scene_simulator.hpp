// SceneSimulator: one scene model stepped by one driver, behind the Simulator interface, and
// the factory that builds it for each integrator that serves the scene (the registry's rows,
// integrators/registry_rows.hpp). Included only by the per-scene factory units
// (src/scenes/*_simulator.cpp): each instantiates its own scene's drivers, so no unit compiles
// every scene x method.
#pragma once

#include <memory>
#include <string>
#include <utility>

#include "scene_factories.hpp"
#include "spinning_top/integrators/registry_rows.hpp"
#include "spinning_top/simulator.hpp"

namespace spinning_top {
namespace scene_factory {

/// The substep a fixed-step driver runs at: the configured step, or, for auto, at most half
/// the largest step of the method auto picked (auto is never refused: it shortens the substep).
inline double fixed_substep(const SceneConfig& config) {
  if (config.integrator.type != IntegratorType::kAuto) return config.integrator.step;
  return std::min(config.integrator.step, 0.5 * largest_fixed_step(config, auto_integrator(config)));
}

template <class Driver>
Driver make_driver(const SceneConfig& config) {
  constexpr IntegratorKind kind = kind_of_driver<Driver>();
  if constexpr (kind == IntegratorKind::kClosedForm) {
    return Driver();
  } else if constexpr (kind == IntegratorKind::kAdaptive) {
    return Driver(config.integrator.tolerance);
  } else {
    return Driver(fixed_substep(config));
  }
}

template <class Model, class Driver>
class SceneSimulator final : public Simulator {
 public:
  explicit SceneSimulator(const SceneConfig& config)
      : config_(config), model_(config.top, config.initial), driver_(make_driver<Driver>(config)) {
    prefix_ = config.integrator.type == IntegratorType::kAuto ? "auto: " : "";
    driver_.reset(model_, 0.0, model_.initial_state());
  }

  Event advance_to(double t) override { return driver_.advance_to(model_, t); }
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
    return s;
  }

  void reset() override { driver_.reset(model_, 0.0, model_.initial_state()); }

  void update(const TopParameters& top, const IntegratorSettings& integrator) override {
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
    Driver driver = make_driver<Driver>(next);
    Model model(next.top, next.initial);
    const double t = driver_.time();
    const typename Model::State y = driver_.state();
    const Event event = driver_.event();
    driver.reset(model, t, y);
    config_ = next;
    model_ = std::move(model);
    driver_ = std::move(driver);
    if (event != Event::kNone) driver_.stop(event);  // a stopped run stays stopped until reset()
  }

  const SceneConfig& config() const override { return config_; }
  std::string integrator_description() const override { return prefix_ + driver_.description(); }
  long steps() const override { return driver_.steps(); }

 private:
  SceneConfig config_;
  Model model_;
  Driver driver_;
  std::string prefix_;
};

/// The simulator for the integrator `type` on this scene, or null if the row does not serve it
/// (validate() refuses that before).
template <class Model, IntegratorType type>
std::unique_ptr<Simulator> make_with(const SceneConfig& config) {
  if constexpr (serves<type, Model>() && type != IntegratorType::kAuto)
    return std::make_unique<SceneSimulator<Model, DriverFor<Model, type>>>(config);
  else
    return nullptr;
}

template <class Model, int... index>
std::unique_ptr<Simulator> make_any(const SceneConfig& config, IntegratorType type, std::integer_sequence<int, index...>) {
  std::unique_ptr<Simulator> simulator;
  ((type == static_cast<IntegratorType>(index) ? (simulator = make_with<Model, static_cast<IntegratorType>(index)>(config), true)
                                                : false) ||
   ...);
  return simulator;
}

/// Builds the scene's simulator for config.integrator (validated by the caller); auto runs the
/// method auto_integrator() picks.
template <class Model>
std::unique_ptr<Simulator> make_scene_simulator(const SceneConfig& config) {
  const IntegratorType type =
      config.integrator.type == IntegratorType::kAuto ? auto_integrator(config) : config.integrator.type;
  std::unique_ptr<Simulator> simulator =
      make_any<Model>(config, type, std::make_integer_sequence<int, kIntegratorCount>());
  if (!simulator)
    throw InvalidParameter("integrator", std::string(to_string(type)) + " does not serve the " + Model::kName + " scene");
  return simulator;
}

}  // namespace scene_factory
}  // namespace spinning_top
