// The factory that binds each scene model to each integrator at compile time, so that every
// combination runs with its own minimal, fixed-size state.
#include "spinning_top/simulator.hpp"

#include <cmath>
#include <cstdio>
#include <limits>
#include <type_traits>

#include "spinning_top/drivers.hpp"
#include "spinning_top/integrators/dop853.hpp"
#include "spinning_top/integrators/dormand_prince.hpp"
#include "spinning_top/integrators/exact.hpp"
#include "spinning_top/integrators/gauss.hpp"
#include "spinning_top/integrators/radau.hpp"
#include "spinning_top/integrators/rk4.hpp"
#include "spinning_top/integrators/rosenbrock.hpp"
#include "spinning_top/integrators/splitting.hpp"
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
    case IntegratorType::kAuto: return "auto";
    case IntegratorType::kRk4: return "rk4";
    case IntegratorType::kDopri5: return "dopri5";
    case IntegratorType::kDop853: return DormandPrince853<FixedTip>::kName;
    case IntegratorType::kSplitting4: return BlanesMoan4::kName;
    case IntegratorType::kSplitting6: return KahanLi6::kName;
    case IntegratorType::kSplitting8: return KahanLi8::kName;
    case IntegratorType::kGauss6: return "gauss6";
    case IntegratorType::kRadau5: return "radau5";
    case IntegratorType::kRodas4: return "rodas4";
    case IntegratorType::kExact: return ExactDriver<FixedTip>::kName;
  }
  return "";
}

namespace {
// auto in the viscous scene (auto_settings(), doc/integrators.md "Viscous: the default"):
// radau5 when lambda = k (1/m + h^2/A) exceeds this many times the fastest motion's rate, at
// this fraction of the `tolerance` key (dop853 runs at the key itself).
constexpr double kStiffFrictionRatio = 450.0;
constexpr double kRadauToleranceFactor = 0.01;

constexpr IntegratorType kAllIntegrators[] = {
    IntegratorType::kAuto,       IntegratorType::kRk4,        IntegratorType::kDopri5, IntegratorType::kDop853,
    IntegratorType::kSplitting4,
    IntegratorType::kSplitting6, IntegratorType::kSplitting8, IntegratorType::kGauss6,      IntegratorType::kRadau5,
    IntegratorType::kRodas4,     IntegratorType::kExact};

bool is_splitting(IntegratorType type) {
  return type == IntegratorType::kSplitting4 || type == IntegratorType::kSplitting6 ||
         type == IntegratorType::kSplitting8;
}

std::string format_seconds(double value) {
  char buffer[32];
  std::snprintf(buffer, sizeof buffer, "%.3g", value);
  return buffer;
}
}  // namespace

SceneType parse_scene(const std::string& name) {
  for (SceneType s : {SceneType::kFixedTip, SceneType::kFrictionless, SceneType::kViscous})
    if (name == to_string(s)) return s;
  throw InvalidParameter("scene", "'" + name + "' is not one of fixed_tip, frictionless, viscous");
}

IntegratorType parse_integrator(const std::string& name) {
  std::string names;
  for (IntegratorType i : kAllIntegrators) {
    if (name == to_string(i)) return i;
    names += (names.empty() ? "" : ", ") + std::string(to_string(i));
  }
  throw InvalidParameter("integrator", "'" + name + "' is not one of " + names);
}

void validate(const IntegratorSettings& settings) {
  if (!std::isfinite(settings.step) || !(settings.step > 0.0))
    throw InvalidParameter("step", "must be a positive number of seconds");
  // Below ~100 ulps the error estimate is round-off and the controller cannot converge.
  if (!std::isfinite(settings.tolerance) || !(settings.tolerance >= 1e-14) || !(settings.tolerance < 1.0))
    throw InvalidParameter("tolerance", "must lie in [1e-14, 1)");
}

double MotionRates::fastest_oscillation() const { return std::max({nutation, pendulum, attitude}); }

MotionRates motion_rates(const SceneConfig& config) {
  const TopParameters& p = config.top;
  // The sliding top's transverse inertia about G lies between A and A + m h^2 sin^2(theta):
  // A gives the upper bound of its nutation rate.
  const double transverse = config.scene == SceneType::kFixedTip ? p.inertia_about_tip() : p.inertia_transverse;
  MotionRates rates;
  rates.nutation = p.inertia_axial * std::abs(config.initial.spin) / transverse;
  rates.pendulum = std::sqrt(p.mass * p.gravity * p.tip_distance / transverse);
  rates.attitude = 0.5 * initial_body_rates(config.initial).norm();
  if (config.scene == SceneType::kViscous)
    rates.friction = p.friction * (1.0 / p.mass + p.tip_distance * p.tip_distance / p.inertia_transverse);
  return rates;
}

double largest_fixed_step(const SceneConfig& config, IntegratorType type) {
  if (type == IntegratorType::kAuto || type == IntegratorType::kDopri5 || type == IntegratorType::kDop853 ||
      type == IntegratorType::kRadau5 || type == IntegratorType::kExact)
    return std::numeric_limits<double>::infinity();
  const MotionRates rates = motion_rates(config);
  double fastest = rates.fastest_oscillation();
  if (type == IntegratorType::kRk4) fastest = std::max(fastest, rates.friction);
  return fastest > 0.0 ? 2.0 / fastest : std::numeric_limits<double>::infinity();
}

IntegratorSettings auto_settings(const SceneConfig& config) {
  IntegratorSettings chosen = config.integrator;
  switch (config.scene) {
    case SceneType::kFixedTip: chosen.type = IntegratorType::kSplitting6; break;
    case SceneType::kFrictionless: chosen.type = IntegratorType::kGauss6; break;
    case SceneType::kViscous: {
      // Stiff when friction relaxes the slip much faster than the top moves: dop853's step is
      // then bounded by its stability (|h lambda| <~ 5) rather than by accuracy, and radau5,
      // whose step only the motion bounds, is cheaper (doc/integrators.md, measured crossover).
      const MotionRates rates = motion_rates(config);
      const bool stiff = rates.friction > kStiffFrictionRatio * rates.fastest_oscillation();
      chosen.type = stiff ? IntegratorType::kRadau5 : IntegratorType::kDop853;
      // radau5's error estimate filters the stiff components (they are damped), but R reads the
      // slip velocity times k: its error, O(h^3) at a step's end, needs a tighter tolerance.
      if (stiff) chosen.tolerance = std::max(1e-14, config.integrator.tolerance * kRadauToleranceFactor);
      break;
    }
  }
  if (largest_fixed_step(config, chosen.type) < std::numeric_limits<double>::infinity())
    chosen.step = std::min(config.integrator.step, 0.5 * largest_fixed_step(config, chosen.type));
  return chosen;
}

IntegratorType auto_integrator(const SceneConfig& config) { return auto_settings(config).type; }

namespace {

/// Refuses a fixed step that the method cannot resolve, naming the limit and its cause.
void validate_step_against_motion(const SceneConfig& config) {
  const IntegratorType type = config.integrator.type;
  if (is_splitting(type) && config.scene != SceneType::kFixedTip)
    throw InvalidParameter("integrator", std::string(to_string(type)) +
                                             " integrates the fixed tip only (its free rotation is exact only "
                                             "about a fixed pivot); use auto, gauss6, dopri5, rk4 or radau5");
  if (type == IntegratorType::kGauss6 && config.scene == SceneType::kViscous)
    throw InvalidParameter("integrator",
                           "gauss6 integrates the fixed tip and the frictionless top (whose attitude dynamics "
                           "close on the vertical and the body rates); use auto, radau5, dopri5 or rk4");
  if (type == IntegratorType::kExact && config.scene == SceneType::kViscous)
    throw InvalidParameter("integrator",
                           "exact solves the fixed tip and the frictionless top by quadrature (they are integrable: "
                           "energy, L_z and omega_Z are conserved); viscous friction dissipates energy, so the viscous "
                           "top has no such solution; use auto, radau5, dop853 or dopri5");
  const double limit = largest_fixed_step(config, type);
  if (config.integrator.step <= limit) return;
  const MotionRates rates = motion_rates(config);
  std::string cause;
  if (type == IntegratorType::kRk4 && rates.friction >= rates.fastest_oscillation()) {
    cause = "the friction relaxation rate k (1/m + h^2/A) = " + format_seconds(rates.friction) +
            " 1/s (rk4 is unstable beyond 2.78/rate; use rodas4 or auto for stiff friction)";
  } else if (rates.nutation >= std::max(rates.pendulum, rates.attitude)) {
    cause = "the nutation, C |omega_Z| / A = " + format_seconds(rates.nutation) + " rad/s (period " +
            format_seconds(2.0 * M_PI / rates.nutation) + " s)";
  } else if (rates.pendulum >= rates.attitude) {
    cause = "the pendulum motion, sqrt(m g h / A) = " + format_seconds(rates.pendulum) + " rad/s";
  } else {
    cause = "the rotation, |omega| / 2 = " + format_seconds(rates.attitude) + " rad/s";
  }
  throw InvalidParameter("step", format_seconds(config.integrator.step) + " s exceeds the largest step " +
                                     format_seconds(limit) + " s that " + to_string(type) +
                                     " can resolve (2 / rate of the fastest motion: " + cause +
                                     "); use a smaller step or integrator: auto");
}

}  // namespace

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
  validate_step_against_motion(config);
}

namespace {

/// The step or tolerance a driver runs at: the configured ones, or those auto chose.
IntegratorSettings effective_settings(const SceneConfig& config) {
  return config.integrator.type == IntegratorType::kAuto ? auto_settings(config) : config.integrator;
}

/// True for drivers without a step or tolerance (the closed-form ExactDriver).
template <class Driver, class = void>
struct is_closed_form : std::false_type {};
template <class Driver>
struct is_closed_form<Driver, std::void_t<decltype(Driver::kClosedForm)>> : std::bool_constant<Driver::kClosedForm> {};

template <class Driver>
Driver make_driver(const SceneConfig& config) {
  if constexpr (is_closed_form<Driver>::value) {
    return Driver();
  } else if constexpr (Driver::kAdaptive) {
    return Driver(effective_settings(config).tolerance);
  } else {
    return Driver(effective_settings(config).step);
  }
}

template <class Model, class Driver>
class SceneSimulator final : public Simulator {
 public:
  SceneSimulator(const SceneConfig& config, Driver driver)
      : config_(config), model_(config.top, config.initial), driver_(std::move(driver)) {
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

template <class Model, class Driver>
std::unique_ptr<Simulator> make_scene(const SceneConfig& config) {
  return std::make_unique<SceneSimulator<Model, Driver>>(config, make_driver<Driver>(config));
}

template <class Model>
std::unique_ptr<Simulator> make_for_model(const SceneConfig& config) {
  const IntegratorType type =
      config.integrator.type == IntegratorType::kAuto ? auto_integrator(config) : config.integrator.type;
  switch (type) {
    case IntegratorType::kAuto: break;
    case IntegratorType::kRk4: return make_scene<Model, FixedStepDriver<Model, ClassicalRk4<Model>>>(config);
    case IntegratorType::kDopri5: return make_scene<Model, AdaptiveDriver<Model, DormandPrince54<Model>>>(config);
    case IntegratorType::kDop853: return make_scene<Model, AdaptiveDriver<Model, DormandPrince853<Model>>>(config);
    case IntegratorType::kGauss6:
      if constexpr (!std::is_same_v<Model, Viscous>)
        return make_scene<Model, FixedStepDriver<Model, ReducedGauss6<Model>>>(config);
      break;  // refused by validate()
    case IntegratorType::kRadau5: return make_scene<Model, AdaptiveDriver<Model, RadauIIA5<Model>>>(config);
    case IntegratorType::kRodas4: return make_scene<Model, FixedStepDriver<Model, Rodas4<Model>>>(config);
    case IntegratorType::kExact:
      if constexpr (!std::is_same_v<Model, Viscous>) return make_scene<Model, ExactDriver<Model>>(config);
      break;  // refused by validate()
    case IntegratorType::kSplitting4:
    case IntegratorType::kSplitting6:
    case IntegratorType::kSplitting8:
      if constexpr (std::is_same_v<Model, FixedTip>) {
        if (type == IntegratorType::kSplitting4)
          return make_scene<Model, FixedStepDriver<Model, Splitting<Model, BlanesMoan4>>>(config);
        if (type == IntegratorType::kSplitting6)
          return make_scene<Model, FixedStepDriver<Model, Splitting<Model, KahanLi6>>>(config);
        return make_scene<Model, FixedStepDriver<Model, Splitting<Model, KahanLi8>>>(config);
      }
      break;  // refused by validate() for the other scenes
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
