// The integrators the core offers, one row each, as the front ends, validation, `auto` and the
// benchmark read them: name, the scenes it serves, its kind, its step limit and its help line.
// The rows themselves, with the driver that runs each one, are the Integrator<type>
// specialisations of integrators/registry_rows.hpp; this header is their run-time view and
// needs none of the integrators' headers.
#pragma once

#include <string>
#include <vector>

#include "spinning_top/simulator.hpp"

namespace spinning_top {

/// How an integrator advances: derived from its driver, not declared separately.
enum class IntegratorKind {
  kAutomatic,   ///< auto: runs another integrator, chosen per scene and state
  kFixedStep,   ///< substeps of at most `step`
  kAdaptive,    ///< error control at `tolerance`, dense output
  kClosedForm,  ///< evaluates a solution at each requested time, no step
};
const char* to_string(IntegratorKind kind);  ///< "automatic", "fixed step", "adaptive", "closed form"

/// What bounds a fixed-step method's step (largest_fixed_step); ignored for the other kinds.
enum class StepLimit {
  kNone,
  kOscillations,            ///< 2 / the fastest oscillation (nutation, pendulum, rotation)
  kOscillationsAndFriction,  ///< also 2 / lambda, the friction rate: an explicit method's stability
  kOscillationsAndStiffFriction  ///< also 50 / lambda: a linearly implicit method's (rodas4) stability
};

/// Bit of a scene in IntegratorInfo::scenes.
constexpr unsigned scene_bit(SceneType scene) { return 1u << static_cast<unsigned>(scene); }
constexpr unsigned kAllScenes =
    scene_bit(SceneType::kFixedTip) | scene_bit(SceneType::kFrictionless) | scene_bit(SceneType::kViscous);

struct IntegratorInfo {
  IntegratorType type;
  const char* name;        ///< the `integrator` value
  unsigned scenes;         ///< scene_bit()s of the scenes it integrates
  IntegratorKind kind;
  StepLimit step_limit;
  const char* help;        ///< one line: what it is and what it keeps
  const char* scene_note;  ///< why it serves only its scenes ("" when it serves all)

  bool serves(SceneType scene) const { return (scenes & scene_bit(scene)) != 0; }
  /// "all scenes", "fixed_tip" or "fixed_tip, frictionless".
  std::string scene_names() const;
};

/// Every integrator, in the order of IntegratorType (auto first).
const std::vector<IntegratorInfo>& integrator_registry();
const IntegratorInfo& integrator_info(IntegratorType type);

/// The names of the integrators that serve a scene, e.g. "auto, rk4, dopri5, dop853, radau5 or
/// rodas4" (for messages that say what to use instead).
std::string integrators_serving(SceneType scene);

}  // namespace spinning_top
