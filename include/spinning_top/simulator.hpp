// The front ends' view of the core: a scene (model type + integrator) built from a
// configuration, stepped to a time. The node and the batch simulator use only this header.
#pragma once

#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "spinning_top/events.hpp"
#include "spinning_top/kinematics.hpp"
#include "spinning_top/model_outputs.hpp"
#include "spinning_top/motion_rates.hpp"
#include "spinning_top/parameters.hpp"
#include "spinning_top/work_budget.hpp"

namespace spinning_top {

/// What the run does where the tip would leave the floor (HYBRID.md, "lift_off"): fly on (and
/// land, bounce, skim), or stop there with the event `lift_off` (the seed's contact model alone).
enum class AfterLiftOff { kFly, kStop };
/// The phase of the motion (HYBRID.md, "Phases"): the tip on the floor (the scene's contact
/// model), in the air (torque-free about G, G on a parabola), or skimming (viscous: on the floor
/// with R = 0 and reduced friction).
enum class Phase { kContact, kFlight, kSkim };
/// The integrators; integrator_registry.hpp says what each is, which scenes it serves and its
/// kind (integrators/registry_rows.hpp defines them). kAuto runs auto_plan()'s choice.
/// doc/integrators.md explains them.
enum class IntegratorType {
  kAuto, kRk4, kDopri5, kDop853, kSplitting4, kSplitting6, kSplitting8, kGauss6, kRadau5, kRadau9, kRodas4, kExact
};

const char* to_string(SceneType scene);
const char* to_string(IntegratorType integrator);
const char* to_string(AfterLiftOff rule);  ///< "fly" | "stop"
const char* to_string(Phase phase);        ///< "contact" | "flight" | "skim"
/// Parses "fly" | "stop"; throws InvalidParameter("after_lift_off", ...).
AfterLiftOff parse_after_lift_off(const std::string& name);
/// Parses "fixed_tip" | "frictionless" | "viscous"; throws InvalidParameter("scene", ...).
SceneType parse_scene(const std::string& name);
/// Parses "auto" | "rk4" | "dopri5" | "dop853" | "splitting4" | "splitting6" | "splitting8" | "gauss6" |
/// "radau5" | "radau9" | "rodas4" | "exact";
/// throws InvalidParameter("integrator", ...).
IntegratorType parse_integrator(const std::string& name);

/// Defaults: step and tolerance from defaults.def; `type` here (the key table shows its name as the
/// `integrator` key's default).
struct IntegratorSettings {
  IntegratorType type = IntegratorType::kAuto;
  double step = defaults::kStep;            ///< fixed-step methods: largest substep [s]
  double tolerance = defaults::kTolerance;  ///< adaptive methods: relative and absolute local error tolerance
};

/// Throws InvalidParameter unless step and tolerance are positive and finite (and the
/// tolerance is not below what double precision can meet).
void validate(const IntegratorSettings& settings);

/// Defaults: its parts'; `scene` here (the key table shows its name as the `scene` key's default).
struct SceneConfig {
  SceneType scene = SceneType::kFixedTip;
  AfterLiftOff after_lift_off = AfterLiftOff::kFly;
  TopParameters top;
  InitialConditions initial;
  IntegratorSettings integrator;
};

/// Validates everything, including what only makes sense in some scenes (initial horizontal
/// velocity only in the viscous scene, friction only there). Throws InvalidParameter.
void validate(const SceneConfig& config);

/// motion_rates.hpp's rates of the configuration's top.
MotionRates motion_rates(const SceneConfig& config);

/// The largest fixed step [s] that `type` can take on this configuration: 2 / (fastest rate),
/// i.e. at least pi steps per period of the fastest oscillation, and, for an explicit method
/// (rk4) in the viscous scene, 2 / lambda (inside its stability interval, |R(-2)| < 1): the
/// registry's StepLimit of the row. Infinity for every kind but fixed step (auto shortens its
/// substep instead). validate() refuses a larger step with InvalidParameter("step", ...) naming
/// this limit.
double largest_fixed_step(const SceneConfig& config, IntegratorType type);

/// What `integrator: auto` runs for a configuration (doc/integrators.md, "The auto rule").
struct AutoPlan {
  IntegratorSettings first;     ///< the first choice, with the step or tolerance auto runs it at
  IntegratorSettings fallback;  ///< run instead where `first` refuses the state; type kAuto: none
  std::string reason;           ///< why `first` (shown in the description), "" when it needs none
};

/// The largest local error tolerance at which dop853 stays within 1e-9 rad of exact over 10 s
/// on the toy tops, measured (doc/integrators.md, "Fallback tolerance"): auto's fallback runs at
/// this tolerance, or at the configured one if that is smaller.
constexpr double kAutoFallbackTolerance = 1e-12;

/// auto's rule: auto_rule_summary() states it, built from the constants auto_plan() runs on
/// (kAutoFallbackTolerance and simulator.cpp's); why each: simulator.cpp and doc/integrators.md
/// ("The auto rule", "Viscous: the default").
AutoPlan auto_plan(const SceneConfig& config);

/// auto's rule in one line, the one that the help texts show (the integrator registry's auto
/// row, and through it `simulate --help`).
std::string auto_rule_summary();

/// The integrators auto_plan() chooses among, as first choices or fallbacks: auto's driver
/// (auto_driver.hpp) holds the drivers of those that serve its scene, and no other.
inline constexpr IntegratorType kAutoCandidates[] = {IntegratorType::kExact, IntegratorType::kDop853,
                                                     IntegratorType::kRadau9};

/// Which method runs, and why.
struct IntegratorChoice {
  IntegratorType configured = IntegratorType::kAuto;  ///< the `integrator` setting
  IntegratorType method = IntegratorType::kAuto;      ///< what runs (never kAuto)
  bool fallback = false;  ///< auto's first choice refused the state it (re)started from; `method` is the fallback
  std::string reason;     ///< auto: the first choice's refusal (fallback), or why it is the first choice; may be ""
};

/// Extremes of a run over [0, time()].
struct MotionRange {
  double max_tilt = 0.0;          ///< [rad] the largest angle of the axis from the vertical
  double min_normal_force = 0.0;  ///< [N] the least R (0 once the tip has been off the floor)
};

/// The hops of a run over [0, time()] (HYBRID.md): counted at their transitions.
struct HopSummary {
  long lift_offs = 0;   ///< transitions contact -> flight or skim (`lift_off` rows)
  long take_offs = 0;   ///< skim -> flight
  long landings = 0;    ///< flight -> floor
  double first_lift_off_time = -1.0;  ///< [s] the first lift_off (a transition or the terminal event), -1: none
  double max_hop_height = 0.0;        ///< [m] the highest the tip rose above the floor
  double impact_loss = 0.0;           ///< [J] kinetic energy lost in landings
};

/// What a front end shows of the simulation at one instant.
struct Snapshot {
  double time = 0.0;                          ///< simulated time [s]
  Quaternion attitude = Quaternion::Identity();  ///< body -> world, unit norm
  Vector3 body_rates = Vector3::Zero();       ///< (omega_X, omega_Y, omega_Z) [rad/s]
  Phase phase = Phase::kContact;
  /// contact_point is the tip P, its z the tip's height (0 on the floor); normal_force and
  /// contact_force are 0 in flight; dissipated_energy includes the impacts' losses.
  ModelOutputs outputs;
};

/// A transition of the hybrid model, where the run goes on (HYBRID.md): `lift_off` (contact ->
/// flight or skim), `take_off` (skim -> flight), `landing` (flight -> contact, or a bounce), with
/// the state at that instant (state.time).
struct Transition {
  Event event = Event::kNone;
  Snapshot state;
};

class Simulator {
 public:
  virtual ~Simulator() = default;

  /// Advances the simulation to time t [s] (no-op for t <= time()). Stops early at the first
  /// terminal event (fallen, non_finite, energy_drift, or lift_off where the run cannot fly on),
  /// which it returns (then time() is the event time); kNone otherwise. Transitions on the way
  /// (lift_off, take_off, landing) do not stop it: take_transitions() hands them over. Throws
  /// std::invalid_argument for a non-finite t.
  Event advance_to(double t) { return advance_to(t, WorkBudget::unlimited()); }
  /// The same within a work budget (work_budget.hpp): if it runs out first, returns kNone with
  /// time() < t and snapshot() still at time(); call again with the same t to go on. The states
  /// reached are those of an unbounded call, bit for bit, wherever the budget ran out.
  virtual Event advance_to(double t, const WorkBudget& budget) = 0;
  virtual double time() const = 0;
  /// The event that ended the run, or kNone while it goes on.
  virtual Event event() const = 0;
  /// The state at time(): always finite, and physically valid (R >= 0, e_Zz > 0).
  virtual Snapshot snapshot() const = 0;
  /// Back to the configured initial state at time 0. auto chooses again for that state.
  /// Returns true if auto now runs another method than before (integrator_choice() says which
  /// and why).
  virtual bool reset() = 0;
  /// Changes physical parameters and integrator settings during a run, keeping the state
  /// and time. The scene, the initial conditions and the top's mass properties cannot
  /// change this way. Throws InvalidParameter (and changes nothing) if the update is invalid.
  /// auto chooses again for the current state (exact may now refuse it, or accept it again):
  /// returns true if it switched method; time and state continue across the switch.
  virtual bool update(const TopParameters& top, const IntegratorSettings& integrator) = 0;
  virtual const SceneConfig& config() const = 0;
  /// What runs and why, e.g. "dopri5, tolerance 1e-12", "rk4, step 0.001 s" or, for auto,
  /// "auto: exact: closed form, nutation period 0.0559 s, 12 Fourier terms" or
  /// "auto: dop853, tolerance 1e-12 (exact refused: <its reason>)".
  virtual std::string integrator_description() const = 0;
  virtual IntegratorChoice integrator_choice() const = 0;
  /// The run's extremes over [0, time()], where the method has them (no peak between samples can
  /// be missed):
  ///  - exact: in closed form, from the turning points of the nutation and R as a function of
  ///    e_Zz;
  ///  - a method that answers from an interpolant (dopri5, dop853, radau5, and auto's choices of
  ///    them) once track_motion_range() was called at the run's start: from the interpolants of
  ///    its steps (integration/range_tracker.hpp), to the method's own accuracy.
  /// nullopt otherwise (fixed-step methods: their states are the step ends a front end samples),
  /// after an update() (the run then had two models) and once the tip has left the floor.
  virtual std::optional<MotionRange> motion_range() const = 0;
  /// Makes motion_range() available for a time-stepper that answers from an interpolant: from
  /// now on, and after every reset(), it follows the extremes through its steps. Its steps and
  /// states stay the same, bit for bit; each step costs a screen more, and each new extreme a
  /// search (still 1.1-1.5x cheaper than the 1 kHz samples it replaces in a sweep's viscous case:
  /// bench/sweep_throughput.py). Called after the run has started, the range begins at the next
  /// reset().
  virtual void track_motion_range() = 0;
  /// Accepted integration steps since the last reset (a transition counts one).
  virtual long steps() const = 0;
  /// The work since the last reset in steps of the work budget (work_budget.hpp), what a run's
  /// allowance counts: WorkBudget::steps_left(max_steps, work()). At least steps(); more where
  /// steps cost more than a dop853 step (rejected attempts, Newton iterations, Jacobians and
  /// factorizations, collocation sweeps, dense solves), so that one allowance bounds the CPU
  /// time of every method within a few times.
  virtual long work() const = 0;
  /// The transitions passed since the last call (or reset), in time order, each with its state:
  /// what the front ends show as rows or event messages between their requested times. At most
  /// the newest 16384 are kept for a caller that does not take them.
  virtual std::vector<Transition> take_transitions() = 0;
  /// The hops so far (since the last reset).
  virtual HopSummary hops() const = 0;
  /// The phase now.
  virtual Phase phase() const = 0;
};

/// Builds the scene's model with the chosen integrator. Throws InvalidParameter.
std::unique_ptr<Simulator> make_simulator(const SceneConfig& config);

}  // namespace spinning_top
