// The factory that binds each scene model to each integrator at compile time, so that every
// combination runs with its own minimal, fixed-size state.
#include "spinning_top/simulator.hpp"

#include <cmath>
#include <limits>

#include "spinning_top/drivers.hpp"
#include "spinning_top/integrators/dormand_prince.hpp"
#include "spinning_top/integrators/rk4.hpp"
#include "spinning_top/scenes/fixed_tip.hpp"
#include "spinning_top/scenes/frictionless.hpp"
#include "spinning_top/scenes/viscous.hpp"

namespace spinning_top {

const char* to_string(Event event) {
  switch (event) {
    case Event::kNone: return "";
    case Event::kLiftOff: return "lift_off";
    case Event::kFallen: return "fallen";
    case Event::kNonFinite: return "non_finite";
  }
  return "";
}

const char* to_string(SceneType scene) {
  switch (scene) {
    case SceneType::kFixedTip: return FixedTip::kName;
    case SceneType::kFrictionless: return Frictionless::kName;
    case SceneType::kViscous: return Viscous::kName;
  }
  return "";
}

const char* to_string(IntegratorType integrator) {
  switch (integrator) {
    case IntegratorType::kRk4: return "rk4";
    case IntegratorType::kDopri5: return "dopri5";
  }
  return "";
}

SceneType parse_scene(const std::string& name) {
  for (SceneType s : {SceneType::kFixedTip, SceneType::kFrictionless, SceneType::kViscous})
    if (name == to_string(s)) return s;
  throw InvalidParameter("scene", "'" + name + "' is not one of fixed_tip, frictionless, viscous");
}

IntegratorType parse_integrator(const std::string& name) {
  for (IntegratorType i : {IntegratorType::kRk4, IntegratorType::kDopri5})
    if (name == to_string(i)) return i;
  throw InvalidParameter("integrator", "'" + name + "' is not one of rk4, dopri5");
}

void validate(const IntegratorSettings& settings) {
  if (!std::isfinite(settings.step) || !(settings.step > 0.0))
    throw InvalidParameter("step", "must be a positive number of seconds");
  // Below ~100 ulps the error estimate is round-off and the controller cannot converge.
  if (!std::isfinite(settings.tolerance) || !(settings.tolerance >= 1e-14) || !(settings.tolerance < 1.0))
    throw InvalidParameter("tolerance", "must lie in [1e-14, 1)");
}

void validate(const SceneConfig& config) {
  validate(config.top);
  validate(config.initial);
  validate(config.integrator);
  if (config.scene != SceneType::kViscous) {
    if (config.top.friction != 0.0)
      throw InvalidParameter("friction", "applies to the viscous scene only (this scene is " +
                                             std::string(to_string(config.scene)) + ")");
    if (config.initial.velocity_x != 0.0 || config.initial.velocity_y != 0.0)
      throw InvalidParameter(config.initial.velocity_x != 0.0 ? "initial/velocity_x" : "initial/velocity_y",
                             "G's horizontal velocity applies to the viscous scene only (without friction "
                             "G moves only vertically)");
  }
}

namespace {

template <class Driver>
Driver make_driver(const IntegratorSettings& settings) {
  if constexpr (Driver::kAdaptive) {
    return Driver(settings.tolerance);
  } else {
    return Driver(settings.step);
  }
}

template <class Model, class Driver>
class SceneSimulator final : public Simulator {
 public:
  SceneSimulator(const SceneConfig& config, Driver driver)
      : config_(config), model_(config.top, config.initial), driver_(std::move(driver)) {
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
    Driver driver = make_driver<Driver>(integrator);
    const double t = driver_.time();
    const typename Model::State y = driver_.state();
    const Event event = driver_.event();
    config_ = next;
    model_ = Model(config_.top, config_.initial);
    driver_ = std::move(driver);
    driver_.reset(model_, t, y);
    if (event != Event::kNone) driver_.stop(event);  // a stopped run stays stopped until reset()
  }

  const SceneConfig& config() const override { return config_; }
  std::string integrator_description() const override { return driver_.description(); }
  long steps() const override { return driver_.steps(); }

 private:
  SceneConfig config_;
  Model model_;
  Driver driver_;
};

template <class Model>
std::unique_ptr<Simulator> make_for_model(const SceneConfig& config) {
  switch (config.integrator.type) {
    case IntegratorType::kRk4: {
      using Driver = FixedStepDriver<Model, ClassicalRk4<Model>>;
      return std::make_unique<SceneSimulator<Model, Driver>>(config, make_driver<Driver>(config.integrator));
    }
    case IntegratorType::kDopri5: {
      using Driver = AdaptiveDriver<Model, DormandPrince54<Model>>;
      return std::make_unique<SceneSimulator<Model, Driver>>(config, make_driver<Driver>(config.integrator));
    }
  }
  throw InvalidParameter("integrator", "unknown integrator");
}

}  // namespace

std::unique_ptr<Simulator> make_simulator(const SceneConfig& config) {
  validate(config);
  switch (config.scene) {
    case SceneType::kFixedTip: return make_for_model<FixedTip>(config);
    case SceneType::kFrictionless: return make_for_model<Frictionless>(config);
    case SceneType::kViscous: return make_for_model<Viscous>(config);
  }
  throw InvalidParameter("scene", "unknown scene");
}

}  // namespace spinning_top
