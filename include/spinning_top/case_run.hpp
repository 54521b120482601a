// One case of a parameter sweep: a configuration run to a duration or to its first event,
// reduced to one row of numbers (issue 11). The Python module's run_case / run_cases and the
// sweep run this, so that a case is computed by the core alone, without Python per sample.
#pragma once

#include <functional>
#include <string>

#include "spinning_top/simulator.hpp"

namespace spinning_top {

/// The longest simulated time the front ends ask for [s] (simulate --duration, a case's duration,
/// Python's advance_to and run): 1e9 s, 32 years. There the time's own rounding is 1.2e-7 s (a
/// phase of 3e-5 rad for the toy top); far beyond it the state stops meaning anything, and
/// silently: exact gave E = 2e231 at 1e17 s and NaN quaternions at 1e20 s, with no event
/// (issue 19, found by the attack harness: Simulator.run(np.linspace(0, 1e300, 3))).
constexpr double kMaxSimulatedTime = 1e9;

/// Instants t_i = i / rate, i = 0..N, N = floor(duration * rate), each a single division (no
/// accumulated round-off), plus t = duration when that is not one of them. A relative slack of
/// 1e-9 absorbs decimal round-off: 1.1 s at 100 Hz is 110.00000000000001 intervals in doubles
/// and gives 111 instants, not a 112th a few ulps later. `simulate`'s rows and a case's samples.
class SampleTimes {
 public:
  SampleTimes(double duration, double rate);
  long long count() const { return intervals_ + 1 + (extra_last_ ? 1 : 0); }
  double at(long long i) const { return i <= intervals_ ? static_cast<double>(i) / rate_ : duration_; }

 private:
  double duration_, rate_;
  long long intervals_ = 0;
  bool extra_last_ = false;
};

/// What a sampling run keeps of the state where its steps ran out (time() short of the time asked
/// for): a case keeps it as its last sample (its extremes and end state include it); a trajectory
/// (simulate's rows, Simulator.run in Python) has rows at the times asked for only and drops it.
enum class StateWhereStepsRunOut { kKeep, kDrop };

/// How a sampling run ended.
struct SampledRun {
  Event event = Event::kNone;  ///< the event that ended it; kNone: it reached the last time, or ran out of steps
  bool out_of_steps = false;   ///< its allowance of integration steps ran out before the last time
};

/// The sampling loop of every front end (simulate's rows, run_case's samples, Simulator.run):
/// advances `simulator` to time_at(i) for i = 0 .. count - 1 (increasing; time_at(0) may be the
/// simulator's time: then its state there, or its event) within an allowance of max_steps
/// integration steps for the whole run (WorkBudget::steps_left), and hands each state reached to
/// sample(t, state, event). t is the time asked for, or on an event the event's time, which
/// replaces it; the run ends at its first event. Where the steps run out, `steps_run_out` says
/// whether the state reached is sampled too (at its own time, with no event).
SampledRun sample_run(Simulator& simulator, long long count, const std::function<double(long long i)>& time_at,
                      double max_steps, StateWhereStepsRunOut steps_run_out,
                      const std::function<void(double t, const Snapshot& state, Event event)>& sample);

struct CaseSettings {
  double duration = 10.0;       ///< [s] run until then, or to the first event
  /// [Hz] for a fixed-step method, and for any method after a lift-off, the states at which the
  /// row's extremes and energy balance are taken (as `simulate`'s rows; the end state is always
  /// one). 1 kHz is the node's tick: 18 samples per nutation of the toy top. Not used while the
  /// method has the extremes itself (Simulator::motion_range: exact's closed form, the tracked
  /// range of dopri5, dop853, radau5 and auto): those are asked for the end state only.
  double sample_rate = 1000.0;
  /// Integration steps the case may take (as `simulate --max-steps`); `exact` takes none.
  double max_steps = 1e8;
};

/// Throws InvalidParameter("duration" | "sample_rate" | "max_steps", why): each finite and > 0, the
/// duration at most kMaxSimulatedTime, at most 1e9 samples, max_steps a whole number in [1, 1e15].
void validate(const CaseSettings& settings);

/// A case's result. Every number is finite (a case that ends in non_finite reports the last
/// finite state, as the simulator does).
struct CaseOutcome {
  Event event = Event::kNone;    ///< the terminal event, kNone if the run reached the duration
  bool out_of_steps = false;     ///< stopped by max_steps before the duration or an event
  double end_time = 0.0;         ///< [s] the duration, the event's time, or where the steps ran out
  double min_normal_force = 0.0; ///< [N] least R over the run: the method's (motion_range), else the samples
  double max_tilt = 0.0;         ///< [rad] largest angle of the axis from the vertical, likewise
  double final_tilt = 0.0;       ///< [rad] at end_time
  double final_energy = 0.0;     ///< [J] E at end_time
  double friction_work = 0.0;    ///< [J] W, the work done against friction by end_time (viscous)
  /// max |B(t) - B(0)| / (|B(0)| + m g h) over the samples (at the end where the method has the
  /// extremes: motion_range), B = E - C wZ^2/2 + W: the energy balance the monitor guards
  /// (events.hpp); round-off for a correct run.
  double energy_balance_error = 0.0;
  IntegratorType method = IntegratorType::kAuto;  ///< what ran at the end (never kAuto)
  bool fallback = false;         ///< auto ran its fallback (exact refused the state)
  long steps = 0;                ///< accepted integration steps (and one per transition)
  // The hops (HYBRID.md; Simulator::hops): counted at their transitions, the height exact.
  long lift_offs = 0;            ///< lift_off transitions (the run went on)
  long landings = 0;             ///< landings
  double first_lift_off_time = -1.0;  ///< [s] the first lift_off, -1 if none
  double max_hop_height = 0.0;   ///< [m] the highest the tip rose above the floor
};

/// Runs one case. Throws InvalidParameter for an invalid configuration or settings (the
/// simulator's and validate(CaseSettings)'s refusals, naming the key).
CaseOutcome run_case(const SceneConfig& config, const CaseSettings& settings);

/// The tilt of an attitude: the angle of the body axis e_Z from the world's vertical [rad].
double tilt_of(const Quaternion& attitude);

}  // namespace spinning_top
