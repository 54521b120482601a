#include "spinning_top/case_run.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <optional>

namespace spinning_top {

SampleTimes::SampleTimes(double duration, double rate) : duration_(duration), rate_(rate) {
  const double intervals = duration * rate;
  const double slack = 1e-9 * std::max(1.0, intervals);
  intervals_ = static_cast<long long>(std::floor(intervals + slack));
  extra_last_ = intervals - static_cast<double>(intervals_) > slack;
}

SampledRun sample_run(Simulator& simulator, long long count, const std::function<double(long long i)>& time_at,
                      double max_steps, StateWhereStepsRunOut steps_run_out,
                      const std::function<void(double t, const Snapshot& state, Event event)>& sample) {
  SampledRun run;
  run.event = simulator.event();  // an initial state that already violates the model
  for (long long i = 0; i < count && (i == 0 || run.event == Event::kNone); ++i) {
    const double t = time_at(i);
    run.event = simulator.advance_to(t, WorkBudget::steps_left(max_steps, simulator.work()));
    // The transitions passed on the way (hybrid model), each a sample at its own time.
    for (const Transition& transition : simulator.take_transitions())
      sample(transition.state.time, transition.state, transition.event);
    if (run.event == Event::kNone && simulator.time() < t) {
      run.out_of_steps = true;
      if (steps_run_out == StateWhereStepsRunOut::kKeep) sample(simulator.time(), simulator.snapshot(), run.event);
      break;
    }
    sample(run.event == Event::kNone ? t : simulator.time(), simulator.snapshot(), run.event);
  }
  return run;
}

namespace {
/// A number as a message shows it: 6 significant digits (never the 301 digits of std::to_string(1e300)).
std::string brief_number(double value) {
  char text[32];
  std::snprintf(text, sizeof text, "%.6g", value);
  return text;
}
}  // namespace

void validate(const CaseSettings& settings) {
  auto positive = [](const char* key, double value) {
    if (!(std::isfinite(value) && value > 0.0))
      throw InvalidParameter(key, "must be a finite number > 0, got " + brief_number(value));
  };
  positive("duration", settings.duration);
  positive("sample_rate", settings.sample_rate);
  if (!(settings.duration <= kMaxSimulatedTime))
    throw InvalidParameter("duration", "must be at most " + brief_number(kMaxSimulatedTime) +
                                           " s (32 years; beyond it the state loses its meaning), got " +
                                           brief_number(settings.duration));
  if (!(settings.duration * settings.sample_rate <= 1e9)) {
    // Blame the one further beyond its default: CaseSettings(1e300) is the duration's fault.
    const CaseSettings defaults;
    const bool duration = settings.duration / defaults.duration >= settings.sample_rate / defaults.sample_rate;
    throw InvalidParameter(duration ? "duration" : "sample_rate",
                           "duration x sample_rate = " + brief_number(settings.duration) + " s x " +
                               brief_number(settings.sample_rate) + " Hz asks for more than 1e9 samples");
  }
  if (!(settings.max_steps >= 1.0 && settings.max_steps <= 1e15 && settings.max_steps == std::floor(settings.max_steps)))
    throw InvalidParameter("max_steps", "must be a whole number in [1, 1e15], got " + brief_number(settings.max_steps));
}

double tilt_of(const Quaternion& q) {
  // With the Cayley-Klein pair alpha = w + i z, beta = x + i y: tan(theta/2) = |beta| / |alpha|
  // (exact.hpp, part 2). Accurate at every angle, unlike acos(e_Zz) near the vertical.
  return 2.0 * std::atan2(std::hypot(q.x(), q.y()), std::hypot(q.w(), q.z()));
}

namespace {
CaseOutcome run_case_with(const SceneConfig& config, const CaseSettings& settings, bool allow_closed_form) {
  const std::unique_ptr<Simulator> simulator = make_simulator(config);
  const TopParameters& top = config.top;
  const double axial = top.inertia_axial;
  auto balance = [axial](const Snapshot& s) {
    return s.outputs.energy - 0.5 * axial * s.body_rates.z() * s.body_rates.z() + s.outputs.dissipated_energy;
  };

  CaseOutcome outcome;
  Snapshot s = simulator->snapshot();
  const double balance0 = balance(s);
  const double scale = std::abs(balance0) + top.mass * top.gravity * top.tip_distance;
  double worst_drift = 0.0;
  outcome.min_normal_force = std::numeric_limits<double>::infinity();
  auto take = [&](double, const Snapshot& sample, Event) {
    s = sample;
    outcome.min_normal_force = std::min(outcome.min_normal_force, sample.outputs.normal_force);
    outcome.max_tilt = std::max(outcome.max_tilt, tilt_of(sample.attitude));
    worst_drift = std::max(worst_drift, std::abs(balance(sample) - balance0));
  };
  // The start, then: where the method has the run's extremes (exact's closed form, an
  // interpolating time-stepper's tracked range), one request to the end, and the extremes over
  // the whole run from the method, which no peak between samples escapes; a fixed step, its
  // samples. The state where the steps ran out is the case's end.
  if (allow_closed_form) simulator->track_motion_range();
  const bool closed_form = allow_closed_form && simulator->motion_range().has_value();
  const SampleTimes times(settings.duration, settings.sample_rate);
  const SampledRun run =
      closed_form ? sample_run(*simulator, 2, [&](long long i) { return i == 0 ? 0.0 : settings.duration; },
                               settings.max_steps, StateWhereStepsRunOut::kKeep, take)
                  : sample_run(*simulator, times.count(), [&](long long i) { return times.at(i); }, settings.max_steps,
                               StateWhereStepsRunOut::kKeep, take);
  if (closed_form) {
    const std::optional<MotionRange> range = simulator->motion_range();
    if (range) {
      outcome.min_normal_force = std::min(outcome.min_normal_force, range->min_normal_force);
      outcome.max_tilt = std::max(outcome.max_tilt, range->max_tilt);
    }
  }
  if (closed_form && simulator->hops().lift_offs > 0) {
    // The tip left the floor: the extremes of the first contact phase no longer cover the run.
    // Run the case again, sampled (the hops' own figures are exact).
    return run_case_with(config, settings, /*allow_closed_form=*/false);
  }
  outcome.event = run.event;
  outcome.out_of_steps = run.out_of_steps;
  outcome.end_time = simulator->time();
  outcome.final_tilt = tilt_of(s.attitude);
  outcome.final_energy = s.outputs.energy;
  outcome.friction_work = s.outputs.dissipated_energy;
  outcome.energy_balance_error = scale > 0.0 ? worst_drift / scale : worst_drift;
  const IntegratorChoice choice = simulator->integrator_choice();
  outcome.method = choice.method;
  outcome.fallback = choice.fallback;
  outcome.steps = simulator->steps();
  const HopSummary hops = simulator->hops();
  outcome.lift_offs = hops.lift_offs;
  outcome.landings = hops.landings;
  outcome.first_lift_off_time = hops.first_lift_off_time;
  outcome.max_hop_height = hops.max_hop_height;
  return outcome;
}

}  // namespace

CaseOutcome run_case(const SceneConfig& config, const CaseSettings& settings) {
  validate(settings);
  return run_case_with(config, settings, /*allow_closed_form=*/true);
}

}  // namespace spinning_top
