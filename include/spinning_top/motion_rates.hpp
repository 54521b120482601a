// The rates of a top's fastest motions, from its parameters and initial conditions alone: what
// a step must resolve. Fixed steps are refused beyond 2 / rate (largest_fixed_step()), and the
// adaptive controllers (integration/controllers.hpp) cap their steps there: the event locator
// can clear a step only if the step resolves the event functions (event_locator.hpp), and a
// step it cannot clear is searched through the interpolant, which costs two collocation solves
// per sample for radau5 and radau9 (doc/integrators.md, "Events within a step").
#pragma once

#include "spinning_top/parameters.hpp"

namespace spinning_top {

enum class SceneType { kFixedTip, kFrictionless, kViscous };

/// Rates [1/s] of the fastest motions of a configuration, which every step must resolve.
struct MotionRates {
  double nutation = 0.0;   ///< C |omega_Z| / A' (A' = A0 for the fixed tip, A when sliding)
  double pendulum = 0.0;   ///< sqrt(m g h / A')
  double attitude = 0.0;   ///< |omega(0)| / 2: the rate of the quaternion ODE q' = q (0, omega) / 2
  double friction = 0.0;   ///< lambda = k (1/m + h^2/A): relaxation rate of v_P (viscous)
  /// The fastest of nutation, pendulum and attitude (what every step must resolve).
  double fastest_oscillation() const;
};
MotionRates motion_rates(SceneType scene, const TopParameters& top, const InitialConditions& initial);

/// 2 / the fastest oscillation's rate (at least pi steps per period), or infinity for a top at
/// rest: the largest step that resolves the motion.
double largest_resolving_step(SceneType scene, const TopParameters& top, const InitialConditions& initial);

}  // namespace spinning_top
