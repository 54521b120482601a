// The front ends' view of the core: a scene (model type + integrator) built from a
// configuration, stepped to a time. The node and the batch simulator use only this header.
#pragma once

#include <memory>
#include <string>

#include "spinning_top/events.hpp"
#include "spinning_top/kinematics.hpp"
#include "spinning_top/model_outputs.hpp"
#include "spinning_top/parameters.hpp"

namespace spinning_top {

enum class SceneType { kFixedTip, kFrictionless, kViscous };
/// kAuto picks per scene and parameters (see auto_integrator()); the others force a method:
/// rk4 (classical, fixed step), dopri5 (adaptive 5(4), dense output), dop853 (adaptive 8(5,3),
/// dense output of order 7), splitting4/6/8 (fixed
/// tip only: exact free rotation + gravity kick, composed to order 4/6/8; conserves omega_Z
/// and L_z exactly, bounded energy error), gauss6 (fixed tip and frictionless: Gauss-Legendre
/// collocation on (q, Gamma, omega_perp), same invariants), radau5 (Radau IIA order 5, adaptive with
/// Hairer's RADAU5 error estimate, L-stable: stiff friction), rodas4 (L-stable Rosenbrock, fixed step:
/// moderately stiff friction only, see radau.hpp), exact (fixed tip and frictionless: the closed-form solution by quadrature,
/// evaluated at each requested time, no step; integrators/exact.hpp). doc/integrators.md
/// explains the choice.
enum class IntegratorType {
  kAuto, kRk4, kDopri5, kDop853, kSplitting4, kSplitting6, kSplitting8, kGauss6, kRadau5, kRodas4, kExact
};

const char* to_string(SceneType scene);
const char* to_string(IntegratorType integrator);
/// Parses "fixed_tip" | "frictionless" | "viscous"; throws InvalidParameter("scene", ...).
SceneType parse_scene(const std::string& name);
/// Parses "auto" | "rk4" | "dopri5" | "dop853" | "splitting4" | "splitting6" | "splitting8" | "gauss6" |
/// "radau5" | "rodas4" | "exact";
/// throws InvalidParameter("integrator", ...).
IntegratorType parse_integrator(const std::string& name);

struct IntegratorSettings {
  IntegratorType type = IntegratorType::kAuto;
  double step = 1e-3;        ///< fixed-step methods: largest substep [s]
  double tolerance = 1e-12;  ///< adaptive methods: relative and absolute local error tolerance
};

/// Throws InvalidParameter unless step and tolerance are positive and finite (and the
/// tolerance is not below what double precision can meet).
void validate(const IntegratorSettings& settings);

struct SceneConfig {
  SceneType scene = SceneType::kFixedTip;
  TopParameters top;
  InitialConditions initial;
  IntegratorSettings integrator;
};

/// Validates everything, including what only makes sense in some scenes (initial horizontal
/// velocity only in the viscous scene, friction only there). Throws InvalidParameter.
void validate(const SceneConfig& config);

/// Rates [1/s] of the fastest motions of a configuration, which a fixed step must resolve.
struct MotionRates {
  double nutation = 0.0;   ///< C |omega_Z| / A' (A' = A0 for the fixed tip, A when sliding)
  double pendulum = 0.0;   ///< sqrt(m g h / A')
  double attitude = 0.0;   ///< |omega(0)| / 2: the rate of the quaternion ODE q' = q (0, omega) / 2
  double friction = 0.0;   ///< lambda = k (1/m + h^2/A): relaxation rate of v_P (viscous)
  /// The fastest of nutation, pendulum and attitude (what every fixed-step method must resolve).
  double fastest_oscillation() const;
};
MotionRates motion_rates(const SceneConfig& config);

/// The largest fixed step [s] that `type` can take on this configuration: 2 / (fastest rate),
/// i.e. at least pi steps per period of the fastest oscillation, and, for the explicit rk4 in
/// the viscous scene, 2 / lambda (inside its stability interval, |R(-2)| < 1). Infinity for
/// the adaptive dopri5, dop853 and radau5, for exact (no step) and for auto (which shortens its substep instead). validate() refuses
/// a larger step with InvalidParameter("step", ...) naming this limit.
double largest_fixed_step(const SceneConfig& config, IntegratorType type);

/// What `integrator: auto` runs for this configuration, with the step or tolerance it runs at
/// (doc/integrators.md, "auto"): fixed_tip -> splitting6, frictionless -> gauss6 (geometric,
/// fixed step min(step, largest_fixed_step / 2)); viscous -> dop853, or radau5 when friction is
/// stiff against the motion (lambda = k (1/m + h^2/A) above a measured multiple of the fastest
/// motion rate), each at a tolerance derived from `tolerance`. Re-evaluate it after a change of k.
IntegratorSettings auto_settings(const SceneConfig& config);
/// auto_settings(config).type.
IntegratorType auto_integrator(const SceneConfig& config);

/// What a front end shows of the simulation at one instant.
struct Snapshot {
  double time = 0.0;                          ///< simulated time [s]
  Quaternion attitude = Quaternion::Identity();  ///< body -> world, unit norm
  Vector3 body_rates = Vector3::Zero();       ///< (omega_X, omega_Y, omega_Z) [rad/s]
  ModelOutputs outputs;
};

class Simulator {
 public:
  virtual ~Simulator() = default;

  /// Advances the simulation to time t [s] (no-op for t <= time()). Stops early at the first
  /// validity event, which it returns (then time() is the event time); kNone otherwise.
  virtual Event advance_to(double t) = 0;
  virtual double time() const = 0;
  /// The event that ended the run, or kNone while it goes on.
  virtual Event event() const = 0;
  /// The state at time(): always finite, and physically valid (R >= 0, e_Zz > 0).
  virtual Snapshot snapshot() const = 0;
  /// Back to the configured initial state at time 0.
  virtual void reset() = 0;
  /// Changes physical parameters and integrator settings during a run, keeping the state
  /// and time. The scene, the initial conditions and the top's mass properties cannot
  /// change this way. Throws InvalidParameter (and changes nothing) if the update is invalid.
  virtual void update(const TopParameters& top, const IntegratorSettings& integrator) = 0;
  virtual const SceneConfig& config() const = 0;
  /// e.g. "dopri5, tolerance 1e-10", "rk4, step 0.001 s" or, for auto,
  /// "auto: splitting6, step 0.001 s".
  virtual std::string integrator_description() const = 0;
  /// Accepted integration steps since the last reset (a cost measure).
  virtual long steps() const = 0;
};

/// Builds the scene's model with the chosen integrator. Throws InvalidParameter.
std::unique_ptr<Simulator> make_simulator(const SceneConfig& config);

}  // namespace spinning_top
