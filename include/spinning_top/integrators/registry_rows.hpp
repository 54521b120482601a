// The integrator registry's rows: one specialisation of Integrator<type> per integrator, the one
// place that gives its name, the scenes it serves, its step limit, its help line and the driver
// that runs it: the one driver loop (integration/driver.hpp) over the method's stepper and its
// controller. Its kind (fixed step, adaptive, closed form) is the controller's, so changing a
// controller (e.g. radau5 from SubstepPlan to its PI control) changes how the core builds it,
// validates its step and documents it, in one line.
// Read by src/integrator_registry.cpp (the run-time view, integrator_registry.hpp) and by the
// scene factories (src/scenes/*_simulator.cpp), which instantiate the drivers of their scene.
#pragma once

#include <type_traits>

#include "spinning_top/integration/driver.hpp"
#include "spinning_top/integrator_registry.hpp"
#include "spinning_top/integrators/dop853.hpp"
#include "spinning_top/integrators/dormand_prince.hpp"
#include "spinning_top/integrators/exact_stepper.hpp"
#include "spinning_top/integrators/gauss.hpp"
#include "spinning_top/integrators/radau.hpp"
#include "spinning_top/integrators/radau9.hpp"
#include "spinning_top/integrators/rk4.hpp"
#include "spinning_top/integrators/rosenbrock.hpp"
#include "spinning_top/integrators/splitting.hpp"
#include "spinning_top/scenes/fixed_tip.hpp"
#include "spinning_top/scenes/frictionless.hpp"
#include "spinning_top/scenes/viscous.hpp"

namespace spinning_top {

/// The scene a model type simulates.
template <class Model>
struct SceneOf;
template <>
struct SceneOf<FixedTip> : std::integral_constant<SceneType, SceneType::kFixedTip> {};
template <>
struct SceneOf<Frictionless> : std::integral_constant<SceneType, SceneType::kFrictionless> {};
template <>
struct SceneOf<Viscous> : std::integral_constant<SceneType, SceneType::kViscous> {};

constexpr unsigned kFixedTipOnly = scene_bit(SceneType::kFixedTip);
constexpr unsigned kIntegrableScenes = scene_bit(SceneType::kFixedTip) | scene_bit(SceneType::kFrictionless);

template <class Model>
class AutoDriver;  // auto_driver.hpp: runs other rows' drivers

/// A one-step method at equal substeps of at most `step` per request.
template <class Model, class Method>
using FixedStepDriver = Driver<Model, OneStepStepper<Model, Method>, SubstepPlan>;
/// An embedded pair with dense output under the controller its error estimate calls for.
template <class Model, class Method>
using AdaptiveDriver = Driver<Model, EmbeddedStepper<Model, Method>, typename Method::Controller>;

/// One row per IntegratorType: kName, kScenes, kStepLimit, kHelp (auto's: auto_rule_summary()),
/// kSceneNote and Driver<Model>.
template <IntegratorType type>
struct Integrator;

/// IntegratorType's values run from kAuto to kExact: a new integrator goes before kExact's row
/// in the enum or moves this bound.
constexpr int kIntegratorCount = static_cast<int>(IntegratorType::kExact) + 1;

template <>
struct Integrator<IntegratorType::kAuto> {
  static constexpr const char* kName = "auto";
  static constexpr unsigned kScenes = kAllScenes;
  static constexpr StepLimit kStepLimit = StepLimit::kNone;
  // Its help line is auto_rule_summary() (src/integrator_registry.cpp), built from auto_plan()'s constants.
  static constexpr const char* kSceneNote = "";
  template <class Model>
  using Driver = AutoDriver<Model>;
};

template <>
struct Integrator<IntegratorType::kRk4> {
  static constexpr const char* kName = "rk4";
  static constexpr unsigned kScenes = kAllScenes;
  static constexpr StepLimit kStepLimit = StepLimit::kOscillationsAndFriction;  // explicit: unstable beyond 2.79 / lambda
  static constexpr const char* kHelp = "classical Runge-Kutta, order 4";
  static constexpr const char* kSceneNote = "";
  template <class Model>
  using Driver = FixedStepDriver<Model, ClassicalRk4<Model>>;
};

template <>
struct Integrator<IntegratorType::kDopri5> {
  static constexpr const char* kName = "dopri5";
  static constexpr unsigned kScenes = kAllScenes;
  static constexpr StepLimit kStepLimit = StepLimit::kNone;
  static constexpr const char* kHelp = "Dormand-Prince 5(4), dense output";
  static constexpr const char* kSceneNote = "";
  template <class Model>
  using Driver = AdaptiveDriver<Model, DormandPrince54<Model>>;
};

template <>
struct Integrator<IntegratorType::kDop853> {
  static constexpr const char* kName = "dop853";
  static constexpr unsigned kScenes = kAllScenes;
  static constexpr StepLimit kStepLimit = StepLimit::kNone;
  static constexpr const char* kHelp = "Dormand-Prince 8(5,3), dense output of order 7";
  static constexpr const char* kSceneNote = "";
  template <class Model>
  using Driver = AdaptiveDriver<Model, DormandPrince853<Model>>;
};

/// The three splittings differ only in their composition scheme.
template <class Scheme>
struct SplittingRow {
  static constexpr const char* kName = Scheme::kName;
  static constexpr unsigned kScenes = kFixedTipOnly;
  static constexpr StepLimit kStepLimit = StepLimit::kOscillations;
  static constexpr const char* kSceneNote = "its free rotation is exact only about a fixed pivot";
  template <class Model>
  using Driver = FixedStepDriver<Model, Splitting<Model, Scheme>>;
};

template <>
struct Integrator<IntegratorType::kSplitting4> : SplittingRow<BlanesMoan4> {
  static constexpr const char* kHelp =
      "exact free rotation + gravity kick, Blanes-Moan order 4: exact omega_Z and L_z, bounded energy error";
};

template <>
struct Integrator<IntegratorType::kSplitting6> : SplittingRow<KahanLi6> {
  static constexpr const char* kHelp = "the same, Kahan-Li order 6";
};

template <>
struct Integrator<IntegratorType::kSplitting8> : SplittingRow<KahanLi8> {
  static constexpr const char* kHelp = "the same, Kahan-Li order 8";
};

template <>
struct Integrator<IntegratorType::kGauss6> {
  static constexpr const char* kName = "gauss6";
  static constexpr unsigned kScenes = kIntegrableScenes;
  static constexpr StepLimit kStepLimit = StepLimit::kOscillations;
  static constexpr const char* kHelp =
      "Gauss-Legendre collocation on (q, Gamma, omega_perp), order 6: exact omega_Z and L_z, bounded energy error";
  static constexpr const char* kSceneNote =
      "its reduced variables close only when the attitude dynamics depend on the vertical and the body rates "
      "alone, i.e. without friction";
  template <class Model>
  using Driver = FixedStepDriver<Model, ReducedGauss6<Model>>;
};

template <>
struct Integrator<IntegratorType::kRadau5> {
  static constexpr const char* kName = "radau5";
  static constexpr unsigned kScenes = kAllScenes;
  static constexpr StepLimit kStepLimit = StepLimit::kNone;  // adaptive; L-stable: friction does not limit it
  static constexpr const char* kHelp =
      "Radau IIA order 5 with Hairer's RADAU5 error estimate and step control, L-stable: stiff friction";
  static constexpr const char* kSceneNote = "";
  template <class Model>
  using Driver = AdaptiveDriver<Model, RadauIIA5<Model>>;  // its controller: radau.hpp's Radau5Controller
};

template <>
struct Integrator<IntegratorType::kRadau9> {
  static constexpr const char* kName = "radau9";
  static constexpr unsigned kScenes = kAllScenes;
  static constexpr StepLimit kStepLimit = StepLimit::kNone;  // adaptive; L-stable
  static constexpr const char* kHelp =
      "Radau IIA order 9 (5 stages) with radau.f's error estimate, L-stable: stiff friction at tight tolerances, "
      "with several times fewer steps than radau5";
  static constexpr const char* kSceneNote = "";
  template <class Model>
  using Driver = AdaptiveDriver<Model, RadauIIA9<Model>>;  // its controller: radau9.hpp's Radau9Controller
};

template <>
struct Integrator<IntegratorType::kRodas4> {
  static constexpr const char* kName = "rodas4";
  static constexpr unsigned kScenes = kAllScenes;
  // L-stable on paper, but it freezes J over the step while the stiff direction turns with the
  // body: stable to lambda dt ~ 60, blown up at 200 (doc/integrators.md).
  static constexpr StepLimit kStepLimit = StepLimit::kOscillationsAndStiffFriction;
  static constexpr const char* kHelp = "Rosenbrock RODAS, L-stable: moderately stiff friction (see radau.hpp)";
  static constexpr const char* kSceneNote = "";
  template <class Model>
  using Driver = FixedStepDriver<Model, Rodas4<Model>>;
};

template <>
struct Integrator<IntegratorType::kExact> {
  static constexpr const char* kName = ExactStepper<FixedTip>::kName;
  static constexpr unsigned kScenes = kIntegrableScenes;  // as ExactSolution's static_assert
  static constexpr StepLimit kStepLimit = StepLimit::kNone;
  static constexpr const char* kHelp =
      "closed-form solution by quadrature, evaluated at each requested time; refuses a few degenerate states "
      "(doc/integrators.md)";
  static constexpr const char* kSceneNote =
      "they are integrable: energy, L_z and omega_Z are conserved; viscous friction dissipates energy, so the "
      "viscous top has no such solution";
  template <class Model>
  using Driver = ExactDriver<Model>;
};

template <class Model, IntegratorType type>
using DriverFor = typename Integrator<type>::template Driver<Model>;

template <IntegratorType type, class Model>
constexpr bool serves() {
  return (Integrator<type>::kScenes & scene_bit(SceneOf<Model>::value)) != 0;
}

/// The kind of a row: its driver's (Driver::kKind, its controller's), for the first scene it serves.
template <IntegratorType type>
constexpr IntegratorKind kind_of() {
  constexpr unsigned scenes = Integrator<type>::kScenes;
  if constexpr ((scenes & scene_bit(SceneType::kFixedTip)) != 0)
    return DriverFor<FixedTip, type>::kKind;
  else if constexpr ((scenes & scene_bit(SceneType::kFrictionless)) != 0)
    return DriverFor<Frictionless, type>::kKind;
  else
    return DriverFor<Viscous, type>::kKind;
}

}  // namespace spinning_top
