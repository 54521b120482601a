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
enum class IntegratorType { kRk4, kDopri5 };

const char* to_string(SceneType scene);
const char* to_string(IntegratorType integrator);
/// Parses "fixed_tip" | "frictionless" | "viscous"; throws InvalidParameter("scene", ...).
SceneType parse_scene(const std::string& name);
/// Parses "rk4" | "dopri5"; throws InvalidParameter("integrator", ...).
IntegratorType parse_integrator(const std::string& name);

struct IntegratorSettings {
  IntegratorType type = IntegratorType::kDopri5;
  double step = 1e-3;        ///< fixed-step methods: largest substep [s]
  double tolerance = 1e-10;  ///< adaptive methods: relative and absolute local error tolerance
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
  /// e.g. "dopri5, tolerance 1e-10" or "rk4, step 0.001 s".
  virtual std::string integrator_description() const = 0;
  /// Accepted integration steps since the last reset (a cost measure).
  virtual long steps() const = 0;
};

/// Builds the scene's model with the chosen integrator. Throws InvalidParameter.
std::unique_ptr<Simulator> make_simulator(const SceneConfig& config);

}  // namespace spinning_top
