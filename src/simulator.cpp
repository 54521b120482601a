// The scene-independent part of the core's API: names, validation, motion rates and step
// limits, the auto rule, and make_simulator, which hands each scene to its own factory unit
// (src/scenes/*_simulator.cpp). What each integrator is and serves comes from the registry.
#include "spinning_top/simulator.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>

#include "scene_factories.hpp"
#include "spinning_top/integrator_registry.hpp"
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
    case Event::kEnergyDrift: return "energy_drift";
    case Event::kTakeOff: return "take_off";
    case Event::kLanding: return "landing";
  }
  return "";
}

const char* to_string(AfterLiftOff rule) { return rule == AfterLiftOff::kFly ? "fly" : "stop"; }

const char* to_string(Phase phase) {
  switch (phase) {
    case Phase::kContact: return "contact";
    case Phase::kFlight: return "flight";
    case Phase::kSkim: return "skim";
  }
  return "";
}

AfterLiftOff parse_after_lift_off(const std::string& name) {
  for (AfterLiftOff rule : {AfterLiftOff::kFly, AfterLiftOff::kStop})
    if (name == to_string(rule)) return rule;
  throw InvalidParameter("after_lift_off", "'" + name + "' is not one of fly, stop");
}

const char* to_string(SceneType scene) {
  switch (scene) {
    case SceneType::kFixedTip: return FixedTip::kName;
    case SceneType::kFrictionless: return Frictionless::kName;
    case SceneType::kViscous: return Viscous::kName;
  }
  return "";
}

namespace {
std::string format_seconds(double value) {
  char buffer[32];
  std::snprintf(buffer, sizeof buffer, "%.3g", value);
  return buffer;
}

/// The least tolerance accepted: below ~100 ulps the error estimate is round-off and the
/// controller cannot converge.
constexpr double kLeastTolerance = 1e-14;
}  // namespace

SceneType parse_scene(const std::string& name) {
  for (SceneType s : {SceneType::kFixedTip, SceneType::kFrictionless, SceneType::kViscous})
    if (name == to_string(s)) return s;
  throw InvalidParameter("scene", "'" + name + "' is not one of fixed_tip, frictionless, viscous");
}

void validate(const IntegratorSettings& settings) {
  if (!std::isfinite(settings.step) || !(settings.step > 0.0))
    throw InvalidParameter("step", "must be a positive number of seconds");
  // 1e-9 s resolves the fastest motion accepted (1e6 rad/s) to 1e-3 rad per step; below it a
  // step only adds substeps (1e-300 s overflowed their count).
  if (!(settings.step >= 1e-9)) throw InvalidParameter("step", "must be at least 1e-9 s");
  if (!std::isfinite(settings.tolerance) || !(settings.tolerance >= kLeastTolerance) || !(settings.tolerance < 1.0))
    throw InvalidParameter("tolerance", "must lie in [" + format_seconds(kLeastTolerance) + ", 1)");
}

double MotionRates::fastest_oscillation() const { return std::max({nutation, pendulum, attitude}); }

MotionRates motion_rates(SceneType scene, const TopParameters& p, const InitialConditions& initial) {
  // The sliding top's transverse inertia about G lies between A and A + m h^2 sin^2(theta):
  // A gives the upper bound of its nutation rate.
  const double transverse = scene == SceneType::kFixedTip ? p.inertia_about_tip() : p.inertia_transverse;
  MotionRates rates;
  rates.nutation = p.inertia_axial * std::abs(initial.spin) / transverse;
  rates.pendulum = std::sqrt(p.mass * p.gravity * p.tip_distance / transverse);
  rates.attitude = 0.5 * initial_body_rates(initial).norm();
  if (scene == SceneType::kViscous)
    rates.friction = p.friction * (1.0 / p.mass + p.tip_distance * p.tip_distance / p.inertia_transverse);
  return rates;
}

MotionRates motion_rates(const SceneConfig& config) { return motion_rates(config.scene, config.top, config.initial); }

double largest_resolving_step(SceneType scene, const TopParameters& top, const InitialConditions& initial) {
  const double fastest = motion_rates(scene, top, initial).fastest_oscillation();
  return fastest > 0.0 ? 2.0 / fastest : std::numeric_limits<double>::infinity();
}

namespace {
/// rodas4's largest lambda dt: measured stable at 0.2 ... 60, blown up at 200 (E 0.694 -> 7496 J
/// at k = 1e5 and 1 ms, then a published R = -80 N); 50 keeps a margin.
constexpr double kLinearlyImplicitFrictionLimit = 50.0;
}  // namespace

double largest_fixed_step(const SceneConfig& config, IntegratorType type) {
  const IntegratorInfo& row = integrator_info(type);
  if (row.kind != IntegratorKind::kFixedStep || row.step_limit == StepLimit::kNone)
    return std::numeric_limits<double>::infinity();
  const MotionRates rates = motion_rates(config);
  double fastest = rates.fastest_oscillation();
  if (row.step_limit == StepLimit::kOscillationsAndFriction) fastest = std::max(fastest, rates.friction);
  if (row.step_limit == StepLimit::kOscillationsAndStiffFriction)
    fastest = std::max(fastest, rates.friction / kLinearlyImplicitFrictionLimit * 2.0);
  return fastest > 0.0 ? 2.0 / fastest : std::numeric_limits<double>::infinity();
}

namespace {
// auto in the viscous scene: radau9 when lambda = k (1/m + h^2/A) exceeds this many times the
// fastest motion's rate, else dop853; each at its fraction of the `tolerance` key. The cost
// crossover with radau5's low-rank Newton, measured at 25-35 (doc/integrators.md); 100 before it.
// radau9 (order 9) has replaced radau5 (order 5) above it: the same low-rank Newton, ~15x fewer
// steps at the default's accuracy (doc/integrators.md, "Viscous: RADAU9").
constexpr double kStiffFrictionRatio = 30.0;
constexpr double kRadauToleranceFactor = 0.1;
constexpr double kDop853ToleranceFactor = 0.1;
/// A fixed step auto chooses is at most this share of the largest the method can take, so that
/// auto is never refused a step.
constexpr double kAutoStepShare = 0.5;

std::string format_number(double value) {
  char buffer[32];
  std::snprintf(buffer, sizeof buffer, "%g", value);
  return buffer;
}
}  // namespace

std::string auto_rule_summary() {
  return "exact where it serves the scene, and dop853 for a state exact refuses, at the tolerance but at most " +
         format_number(kAutoFallbackTolerance) + "; in the other scenes radau9 at tolerance x " +
         format_number(kRadauToleranceFactor) + " where friction relaxes the slip more than " +
         format_number(kStiffFrictionRatio) + " times faster than the fastest motion, k (1/m + h^2/A) > " +
         format_number(kStiffFrictionRatio) + " max(C |omega_Z|/A', sqrt(m g h/A'), |omega|/2), else dop853 at " +
         "tolerance x " + format_number(kDop853ToleranceFactor) + " (either at least " +
         format_number(kLeastTolerance) + "); a fixed step at most " + format_number(kAutoStepShare) +
         " x the largest the method can take";
}

AutoPlan auto_plan(const SceneConfig& config) {
  const IntegratorSettings& settings = config.integrator;
  AutoPlan plan;
  if (integrator_info(IntegratorType::kExact).serves(config.scene)) {
    plan.first = {IntegratorType::kExact, settings.step, settings.tolerance};
    plan.fallback = {IntegratorType::kDop853, settings.step, std::min(settings.tolerance, kAutoFallbackTolerance)};
    return plan;
  }
  // Viscous: stiff when friction relaxes the slip much faster than the top moves. dop853's step
  // is then bounded by its stability (|dt lambda| <~ 5) rather than by its accuracy, and an
  // L-stable Radau IIA method, whose step only the motion bounds, is cheaper: kStiffFrictionRatio
  // is the measured cost crossover (doc/integrators.md, "Viscous: the default"). radau9 rather
  // than radau5: at the default's accuracy its order 9 takes ~2 ms steps where radau5's order 5
  // needs ~0.1 ms (doc/integrators.md, "Viscous: RADAU9"). Its error estimate filters the stiff
  // components (they are damped), but R reads the slip velocity times k, whose error needs a
  // tighter tolerance: kRadauToleranceFactor (after a sideways start at 0.3 m/s, k = 1e3, R was
  // off by up to 5.7e-9 m g at the key itself, 2.7e-9 at a tenth of it, which also costs less
  // at 1 kHz: better starting guesses). dop853 runs 10x tighter than the key because
  // friction changes omega_Z, which the error norm weighs relative to its size (2000 rad/s x
  // 1e-12 per step), and an error in omega_Z grows linearly into the spin angle: at the key
  // itself a 2000 rad/s top under k = 50 N s/m ends 1.1e-9 rad off after 10 s, at a tenth of it
  // 1e-10 (against dop853 at 1e-14 and radau5 at 1e-14, which agree to 4e-12).
  const MotionRates rates = motion_rates(config);
  const double motion = rates.fastest_oscillation();
  const bool stiff = rates.friction > kStiffFrictionRatio * motion;
  plan.first = settings;
  plan.first.type = stiff ? IntegratorType::kRadau9 : IntegratorType::kDop853;
  plan.first.tolerance =
      std::max(kLeastTolerance, settings.tolerance * (stiff ? kRadauToleranceFactor : kDop853ToleranceFactor));
  plan.first.step = std::min(settings.step, kAutoStepShare * largest_fixed_step(config, plan.first.type));
  plan.fallback.type = IntegratorType::kAuto;  // neither refuses a state
  plan.reason = std::string(stiff ? "stiff" : "not stiff") + ": friction rate k (1/m + h^2/A) " +
                format_seconds(rates.friction) + " 1/s " + (stiff ? ">" : "<=") + " " +
                format_seconds(kStiffFrictionRatio) + " x fastest motion " + format_seconds(motion) + " rad/s";
  return plan;
}

namespace {

/// Refuses a fixed step that the method cannot resolve, naming the limit and its cause.
void validate_step_against_motion(const SceneConfig& config) {
  const IntegratorType type = config.integrator.type;
  const IntegratorInfo& row = integrator_info(type);
  if (!row.serves(config.scene))
    throw InvalidParameter("integrator", std::string(row.name) + " integrates " + row.scene_names() + " only (" +
                                             row.scene_note + "); for " + to_string(config.scene) + " use " +
                                             integrators_serving(config.scene));
  const double limit = largest_fixed_step(config, type);
  if (config.integrator.step <= limit) return;
  const MotionRates rates = motion_rates(config);
  std::string cause;
  if (row.step_limit == StepLimit::kOscillationsAndFriction && rates.friction >= rates.fastest_oscillation()) {
    cause = "the friction relaxation rate k (1/m + h^2/A) = " + format_seconds(rates.friction) +
            " 1/s (" + std::string(row.name) + " is unstable beyond 2.78/rate; use radau5 or auto for stiff friction)";
  } else if (row.step_limit == StepLimit::kOscillationsAndStiffFriction &&
             rates.friction / kLinearlyImplicitFrictionLimit * 2.0 >= rates.fastest_oscillation()) {
    cause = "the friction relaxation rate k (1/m + h^2/A) = " + format_seconds(rates.friction) + " 1/s (" +
            std::string(row.name) + " freezes its Jacobian over a step while the stiff direction turns with the "
            "body, and is unstable beyond rate x step ~ 60: it takes at most " +
            format_seconds(kLinearlyImplicitFrictionLimit) + " / rate; use radau5 or auto for stiff friction)";
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

namespace {

/// The fastest motion the core accepts [rad/s]: 1e6 rad/s, a top spinning at 160 000 turns per
/// second. Beyond it a time-stepper needs more than ~1e6 steps per simulated second (over a
/// second of CPU per simulated second: the node could not keep its tick), and the closed form's
/// phase, ~rate x t x 1e-16, drifts by more than 1e-9 rad per second. Without it a spin of 1e22
/// rad/s ran `exact` into quaternions of 1e290 and NaN forces, and a spin of 1.4e154 overflowed
/// the rates themselves (issue 10).
constexpr double kMaxMotionRate = 1e6;

/// The stiffest friction the core accepts, as the ratio of the slip's relaxation rate
/// lambda = k (1/m + h^2/A) to the fastest motion (at least 1 rad/s). An implicit method's Newton
/// systems have a condition ~ this ratio, so double precision keeps ~16 - log10(ratio) digits:
/// with an initial slip, k = 1e12, 1e14, 1e16 N s/m on the toy top (ratios 2e11 to 2e15) gave
/// lift-offs at 0.086, 0.035, 0.0088 s; near 1e10 the tip already sticks, and R at 1 s moves by
/// 2e-10 (relative) from k = 1e10 to 1e11 (issue 10, doc/integrators.md "Motion rates").
constexpr double kMaxFrictionStiffness = 1e10;

/// Refuses a configuration whose fastest motion exceeds kMaxMotionRate, naming the key that
/// drives it, and friction stiffer than kMaxFrictionStiffness.
void validate_motion_rates(const SceneConfig& config) {
  const MotionRates rates = motion_rates(config);
  const InitialConditions& ic = config.initial;
  auto refuse = [&](const std::string& key, const std::string& motion, double rate) {
    throw InvalidParameter(key, "the " + motion + " would be " + format_seconds(rate) + " rad/s, above the " +
                                    format_seconds(kMaxMotionRate) +
                                    " rad/s the simulator resolves (doc/integrators.md, \"Motion rates\")");
  };
  if (!(rates.nutation <= kMaxMotionRate)) refuse("initial/spin", "nutation C |omega_Z| / A", rates.nutation);
  if (!(rates.pendulum <= kMaxMotionRate)) {
    // sqrt(m g h / A) has four keys: name the one whose shipped value (the toy top's) brings the
    // rate down the most, so that a mass of 1e20 is blamed and not gravity (the first of a tie).
    const TopParameters shipped;
    const std::pair<const char*, double TopParameters::*> factors[] = {{"gravity", &TopParameters::gravity},
                                                                        {"mass", &TopParameters::mass},
                                                                        {"tip_distance", &TopParameters::tip_distance},
                                                                        {"inertia_transverse", &TopParameters::inertia_transverse}};
    const char* culprit = factors[0].first;
    double lowest = rates.pendulum;
    for (const auto& [key, field] : factors) {
      TopParameters reset = config.top;
      reset.*field = shipped.*field;
      const double rate = motion_rates(config.scene, reset, ic).pendulum;
      if (rate < lowest) {
        lowest = rate;
        culprit = key;
      }
    }
    const TopParameters& p = config.top;
    refuse(culprit,
           "pendulum rate sqrt(m g h / A) (m = " + format_seconds(p.mass) + " kg, g = " + format_seconds(p.gravity) +
               " m/s^2, h = " + format_seconds(p.tip_distance) + " m, A = " + format_seconds(p.inertia_transverse) +
               " kg m^2" + (config.scene == SceneType::kFixedTip ? " + m h^2 about the tip)" : ")"),
           rates.pendulum);
  }
  if (!(rates.attitude <= kMaxMotionRate)) {
    // The body rate |omega| / 2 comes from the initial rates: name the largest.
    const std::pair<const char*, double> candidates[] = {{"initial/spin", std::abs(ic.spin)},
                                                         {"initial/precession_rate", std::abs(ic.precession_rate)},
                                                         {"initial/nutation_rate", std::abs(ic.nutation_rate)}};
    const auto* largest = &candidates[0];
    for (const auto& c : candidates)
      if (!(c.second <= largest->second)) largest = &c;
    refuse(largest->first, "rotation rate |omega| / 2", rates.attitude);
  }
  const double motion = std::max(rates.fastest_oscillation(), 1.0);
  if (!(rates.friction <= kMaxFrictionStiffness * motion))
    throw InvalidParameter("friction", "the slip's relaxation rate k (1/m + h^2/A) = " + format_seconds(rates.friction) +
                                           " 1/s is more than " + format_seconds(kMaxFrictionStiffness) +
                                           " times the fastest motion (" + format_seconds(motion) +
                                           " rad/s): beyond what double precision resolves, and the tip "
                                           "already sticks well below it (doc/integrators.md, \"Motion rates\")");
}

}  // namespace

void validate(const SceneConfig& config) {
  validate(config.top);
  validate(config.initial);
  if (!(std::cos(config.initial.tilt) > config.top.fallen_vertical()))
    throw InvalidParameter("initial/tilt", "the rim (rim_radius, rim_distance) starts on or under the floor: need |tilt| < " +
                                               format_seconds(std::atan2(config.top.rim_distance, config.top.rim_radius)) +
                                               " rad, got " + format_seconds(config.initial.tilt));
  validate(config.integrator);
  validate_motion_rates(config);
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

std::unique_ptr<Simulator> make_simulator(const SceneConfig& config) {
  validate(config);
  switch (config.scene) {
    case SceneType::kFixedTip: return scene_factory::make_fixed_tip_simulator(config);
    case SceneType::kFrictionless: return scene_factory::make_frictionless_simulator(config);
    case SceneType::kViscous: return scene_factory::make_viscous_simulator(config);
  }
  throw InvalidParameter("scene", "unknown scene");
}

}  // namespace spinning_top
