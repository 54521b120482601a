// A sweep's case (issue 11): exact's closed-form extremes of the motion (Simulator::motion_range)
// against a dense sampling of dop853, and run_case's outcome against its definition.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

#include "core_test_support.hpp"
#include "spinning_top/case_run.hpp"

namespace spinning_top {
namespace {

using core_test::report;

SceneConfig toy(SceneType scene, double tilt, double spin, IntegratorType method) {
  SceneConfig c;
  c.scene = scene;
  c.initial.tilt = tilt;
  c.initial.spin = spin;
  c.initial.precession_rate = 2.0;
  c.integrator.type = method;
  c.integrator.tolerance = 1e-13;
  return c;
}

/// Least R and largest tilt of dop853's states every dt up to `duration` (or its event).
MotionRange sampled(SceneConfig c, double duration, double dt) {
  c.integrator.type = IntegratorType::kDop853;
  const auto sim = make_simulator(c);
  MotionRange r{0.0, std::numeric_limits<double>::infinity()};
  const long n = std::lround(std::ceil(duration / dt));
  for (long i = 0; i <= n; ++i) {
    const Event e = sim->advance_to(std::min(i * dt, duration));  // the end itself is a sample
    const Snapshot s = sim->snapshot();
    r.max_tilt = std::max(r.max_tilt, tilt_of(s.attitude));
    r.min_normal_force = std::min(r.min_normal_force, s.outputs.normal_force);
    if (e != Event::kNone) break;
  }
  return r;
}

// Closed form against 2e5 samples of a 1e-13 dop853 run: the extremes agree to what sampling
// every 5 us resolves (the toy top nutates at 18 Hz: (2 pi 18 x 5e-6)^2 / 8 ~ 4e-8 of the
// amplitude, and dop853's own error ~1e-11), and the closed form is never inside the sampled
// range by more than round-off: samples cannot find a larger tilt or a smaller R.
TEST(MotionRange, ExactExtremesBoundDenseSamplesOfTheIntegrableScenes) {
  for (SceneType scene : {SceneType::kFixedTip, SceneType::kFrictionless}) {
    for (double tilt : {0.05, 0.3, 1.0}) {
      for (double duration : {0.013, 1.0}) {  // less than one nutation, and many
        const SceneConfig c = toy(scene, tilt, 150.0, IntegratorType::kExact);
        const auto sim = make_simulator(c);
        sim->advance_to(duration);
        const std::optional<MotionRange> exact = sim->motion_range();
        ASSERT_TRUE(exact.has_value());
        const MotionRange dense = sampled(c, duration, 5e-6);
        const double mg = c.top.mass * c.top.gravity;
        EXPECT_GE(exact->max_tilt, dense.max_tilt - 1e-10) << to_string(scene) << " tilt " << tilt;
        EXPECT_NEAR(exact->max_tilt, dense.max_tilt, 1e-7 * tilt) << to_string(scene) << " tilt " << tilt;
        EXPECT_LE(exact->min_normal_force, dense.min_normal_force + 1e-10 * mg) << to_string(scene);
        EXPECT_NEAR(exact->min_normal_force, dense.min_normal_force, 1e-6 * mg) << to_string(scene);
        if (duration == 1.0 && tilt == 0.3)
          report(scene == SceneType::kFixedTip ? "fixed_tip: exact - sampled least R [N]"
                                                : "frictionless: exact - sampled least R [N]",
                 exact->min_normal_force - dense.min_normal_force);
      }
    }
  }
}

// A torque-free top (g = 0) on the pivot: e_Zz = a + rho cos(w t - delta), R = -m h w^2 rho
// cos(...): the free-rotation branch of the closed form. Released below the mean of e_Zz (R > 0)
// and tilting further, it passes its largest tilt (a turning point inside the run) and tilts
// back up until R reaches 0: a lift-off, where the contact phase ends. (Released with R < 0 it
// ended at t = 0, and the test compared a range of one sample with itself.)
TEST(MotionRange, TorqueFreeTopMatchesSamples) {
  SceneConfig c = toy(SceneType::kFixedTip, 0.4, 30.0, IntegratorType::kExact);
  c.top.gravity = 0.0;
  c.after_lift_off = AfterLiftOff::kStop;  // the closed form's range of the contact phase
  c.initial.precession_rate = 5.0;
  c.initial.nutation_rate = 1.0;  // [rad/s] tilting further at the release
  const auto sim = make_simulator(c);
  ASSERT_GT(sim->snapshot().outputs.normal_force, 0.0);
  const Event event = sim->advance_to(2.0);
  ASSERT_EQ(event, Event::kLiftOff);
  ASSERT_GT(sim->time(), 0.01);  // a part of a nutation, not the release alone
  const std::optional<MotionRange> exact = sim->motion_range();
  ASSERT_TRUE(exact.has_value());
  const MotionRange dense = sampled(c, sim->time(), 5e-6);
  EXPECT_NEAR(exact->max_tilt, dense.max_tilt, 1e-8) << to_string(event);
  EXPECT_GT(exact->max_tilt, c.initial.tilt + 1e-3);  // the turning point, inside the run
  EXPECT_NEAR(exact->min_normal_force, dense.min_normal_force, 1e-8);
  report("torque-free: contact phase [s]", sim->time());
  report("torque-free: exact - sampled largest tilt [rad]", exact->max_tilt - dense.max_tilt);
}

TEST(MotionRange, NoneForAnUntrackedTimeStepperAndAfterALiveUpdate) {
  EXPECT_FALSE(make_simulator(toy(SceneType::kFixedTip, 0.3, 150.0, IntegratorType::kDop853))->motion_range());
  const auto sim = make_simulator(toy(SceneType::kFixedTip, 0.3, 150.0, IntegratorType::kAuto));
  ASSERT_TRUE(sim->motion_range());
  TopParameters top = sim->config().top;
  top.gravity = 9.0;
  sim->update(top, sim->config().integrator);
  EXPECT_FALSE(sim->motion_range());  // one closed form would describe only part of the run
  sim->reset();
  EXPECT_TRUE(sim->motion_range());

  // Tracked (issue 21): from the start, through an update (none) and a reset (again).
  const auto dop853 = make_simulator(toy(SceneType::kViscous, 0.3, 150.0, IntegratorType::kDop853));
  dop853->track_motion_range();
  ASSERT_TRUE(dop853->motion_range());
  dop853->advance_to(0.1);
  EXPECT_TRUE(dop853->motion_range());
  dop853->update(top, dop853->config().integrator);
  EXPECT_FALSE(dop853->motion_range());
  dop853->reset();
  EXPECT_TRUE(dop853->motion_range());
  // Asked for after the start, the range would miss the start: none until the next reset.
  const auto late = make_simulator(toy(SceneType::kViscous, 0.3, 150.0, IntegratorType::kAuto));
  late->advance_to(0.1);
  late->track_motion_range();
  EXPECT_FALSE(late->motion_range());
  late->reset();
  EXPECT_TRUE(late->motion_range());
  // A fixed step has no interpolant to track: its states are its samples.
  SceneConfig fixed = toy(SceneType::kViscous, 0.3, 150.0, IntegratorType::kRk4);
  fixed.integrator.step = 1e-4;
  const auto rk4 = make_simulator(fixed);
  rk4->track_motion_range();
  EXPECT_FALSE(rk4->motion_range());
}

// dop853's tracked extremes (issue 21) against exact's closed form over 10 s of the fixed tip
// (a 1e-13 run: its own error ~1e-11 rad), both tops of toy() and a near-vertical one where
// 1 - cos(tilt) = 4.5e-9 (the tracker's tilt function is exact there, where 1 - e_Zz would
// keep 8 digits).
TEST(MotionRange, TrackedExtremesOfDop853MatchTheClosedForm) {
  for (double tilt : {1e-4, 0.3, 1.0}) {
    const SceneConfig c = toy(SceneType::kFixedTip, tilt, 150.0, IntegratorType::kDop853);
    const auto tracked = make_simulator(c);
    tracked->track_motion_range();
    ASSERT_EQ(tracked->advance_to(10.0), Event::kNone);
    SceneConfig e = c;
    e.integrator.type = IntegratorType::kExact;
    const auto exact = make_simulator(e);
    exact->advance_to(10.0);
    const std::optional<MotionRange> a = tracked->motion_range(), b = exact->motion_range();
    ASSERT_TRUE(a && b);
    const double mg = c.top.mass * c.top.gravity;
    EXPECT_NEAR(a->max_tilt, b->max_tilt, 1e-10 * std::max(tilt, 0.1)) << "tilt " << tilt;
    EXPECT_NEAR(a->min_normal_force, b->min_normal_force, 1e-9 * mg) << "tilt " << tilt;
    if (tilt == 0.3) {
      report("fixed_tip 10 s: tracked dop853 - exact largest tilt [rad]", a->max_tilt - b->max_tilt);
      report("fixed_tip 10 s: tracked dop853 - exact least R [m g]", (a->min_normal_force - b->min_normal_force) / mg);
    }
  }
}

// The viscous top has no closed form: the tracked extremes bound dense samples (every 5 us over
// 1 s, which resolve a nutation peak to ~4e-8 of its amplitude, and every 0.25 us over the slip's
// relaxation at the start) and exceed them by no more than that, from weak friction to the stiff end (k = 500: lambda = 5e4/s, radau9 under auto); and
// tracking changes no state of the run, bit for bit.
TEST(MotionRange, TrackedExtremesOfTheViscousTopBoundDenseSamples) {
  for (double friction : {0.02, 5.0, 500.0}) {
    SceneConfig c = toy(SceneType::kViscous, 0.3, 150.0, IntegratorType::kAuto);
    c.top.friction = friction;
    c.integrator.tolerance = defaults::kTolerance;
    const double duration = 1.0;
    const auto tracked = make_simulator(c);
    tracked->track_motion_range();
    const auto plain = make_simulator(c);
    MotionRange dense{0.0, std::numeric_limits<double>::infinity()};
    // Every 0.25 us over the first 2 ms, where the slip relaxes at lambda (20 us at k = 500),
    // then every 5 us.
    std::vector<double> times;
    for (long i = 0; i < 8000; ++i) times.push_back(i * 2.5e-7);
    for (long i = 400; i <= std::lround(duration / 5e-6); ++i) times.push_back(i * 5e-6);
    for (double t : times) {
      ASSERT_EQ(tracked->advance_to(t), Event::kNone);
      ASSERT_EQ(plain->advance_to(t), Event::kNone);
      const Snapshot s = plain->snapshot(), u = tracked->snapshot();
      ASSERT_TRUE(s.attitude.coeffs() == u.attitude.coeffs() && s.body_rates == u.body_rates) << "t " << t;
      dense.max_tilt = std::max(dense.max_tilt, tilt_of(s.attitude));
      dense.min_normal_force = std::min(dense.min_normal_force, s.outputs.normal_force);
    }

    const std::optional<MotionRange> range = tracked->motion_range();
    ASSERT_TRUE(range);
    const double mg = c.top.mass * c.top.gravity;
    EXPECT_GE(range->max_tilt, dense.max_tilt - 1e-13) << "k " << friction;
    EXPECT_LE(range->max_tilt, dense.max_tilt + 1e-8) << "k " << friction;
    EXPECT_LE(range->min_normal_force, dense.min_normal_force + 1e-13 * mg) << "k " << friction;
    EXPECT_GE(range->min_normal_force, dense.min_normal_force - 1e-8 * mg) << "k " << friction;
    if (friction == 5.0) {
      report("viscous k 5, 1 s: tracked - dense largest tilt [rad]", range->max_tilt - dense.max_tilt);
      report("viscous k 5, 1 s: tracked - dense least R [m g]", (range->min_normal_force - dense.min_normal_force) / mg);
    }
  }
}

// A spinless top released at 0.3 rad falls: run_case ends at the fall with the tilt at pi/2,
// the same time and least R as the simulator run to its event.
TEST(RunCase, EndsAtTheFirstEventWithTheSimulatorsTimeAndState) {
  const SceneConfig c = toy(SceneType::kFixedTip, 0.3, 0.0, IntegratorType::kAuto);
  const CaseOutcome o = run_case(c, CaseSettings{});
  const auto sim = make_simulator(c);
  const Event event = sim->advance_to(10.0);
  EXPECT_EQ(o.event, Event::kFallen);
  EXPECT_EQ(event, Event::kFallen);
  EXPECT_EQ(o.end_time, sim->time());
  EXPECT_NEAR(o.max_tilt, M_PI / 2, 1e-12);
  EXPECT_NEAR(o.final_tilt, M_PI / 2, 1e-12);
  EXPECT_EQ(o.method, IntegratorType::kExact);
  EXPECT_LE(o.energy_balance_error, 1e-14);
}

// A fixed-step case samples at sample_rate; its extremes are those of the samples.
TEST(RunCase, FixedStepExtremesAreThoseOfItsSamples) {
  SceneConfig c = toy(SceneType::kFixedTip, 0.3, 150.0, IntegratorType::kRk4);
  c.integrator.step = 1e-4;
  CaseSettings settings;
  settings.duration = 0.5;
  settings.sample_rate = 1000.0;
  const CaseOutcome o = run_case(c, settings);
  const auto sim = make_simulator(c);
  MotionRange samples{0.0, std::numeric_limits<double>::infinity()};
  for (int i = 0; i <= 500; ++i) {
    sim->advance_to(i / 1000.0);
    samples.max_tilt = std::max(samples.max_tilt, tilt_of(sim->snapshot().attitude));
    samples.min_normal_force = std::min(samples.min_normal_force, sim->snapshot().outputs.normal_force);
  }
  EXPECT_EQ(o.event, Event::kNone);
  EXPECT_EQ(o.end_time, 0.5);
  EXPECT_EQ(o.max_tilt, samples.max_tilt);
  EXPECT_EQ(o.min_normal_force, samples.min_normal_force);
  EXPECT_LT(o.energy_balance_error, 1e-8);
  EXPECT_GT(o.steps, 0);
}

// dop853's case takes its extremes from the tracked interpolants (issue 21), not from samples:
// at a sample rate of 50 Hz (which a tracked case does not use) the extremes are still those of
// dense samples, where samples every 20 ms miss the nutation's peaks (its least R is at the
// release, a sample too); the case's end state is the simulator's.
TEST(RunCase, Dop853ExtremesAreTrackedNotSampled) {
  SceneConfig c = toy(SceneType::kViscous, 0.3, 150.0, IntegratorType::kDop853);
  c.initial.precession_rate = 0.0;  // released at rest but for the spin: a nutation of ~0.01 rad
  CaseSettings settings;
  settings.duration = 0.5;
  settings.sample_rate = 50.0;
  const CaseOutcome o = run_case(c, settings);
  const MotionRange coarse = sampled(c, 0.5, 1.0 / settings.sample_rate), dense = sampled(c, 0.5, 5e-6);
  const double mg = c.top.mass * c.top.gravity;
  EXPECT_EQ(o.event, Event::kNone);
  EXPECT_EQ(o.end_time, 0.5);
  EXPECT_GE(o.max_tilt, dense.max_tilt - 1e-13);
  EXPECT_LE(o.max_tilt, dense.max_tilt + 1e-8);
  EXPECT_GT(o.max_tilt, coarse.max_tilt + 1e-6);  // the peaks between the 50 Hz samples
  EXPECT_LE(o.min_normal_force, dense.min_normal_force + 1e-13 * mg);
  EXPECT_GE(o.min_normal_force, dense.min_normal_force - 1e-8 * mg);
  const auto sim = make_simulator(c);
  sim->advance_to(0.5);
  EXPECT_EQ(o.final_tilt, tilt_of(sim->snapshot().attitude));
  EXPECT_LT(o.energy_balance_error, 1e-10);
  report("dop853 case, 0.5 s: tracked - 50 Hz samples largest tilt [rad]", o.max_tilt - coarse.max_tilt);
  report("dop853 case, 0.5 s: tracked - dense largest tilt [rad]", o.max_tilt - dense.max_tilt);
}

TEST(RunCase, StopsAtItsStepBudget) {
  SceneConfig c = toy(SceneType::kViscous, 0.3, 150.0, IntegratorType::kRk4);
  c.top.friction = 1e-3;
  c.integrator.step = 1e-5;
  CaseSettings settings;
  settings.max_steps = 1000;
  const CaseOutcome o = run_case(c, settings);
  EXPECT_TRUE(o.out_of_steps);
  EXPECT_EQ(o.event, Event::kNone);
  EXPECT_LE(o.steps, 1000);
  EXPECT_LT(o.end_time, settings.duration);
}

TEST(RunCase, RefusesBadSettingsNamingThem) {
  const SceneConfig c = toy(SceneType::kFixedTip, 0.3, 150.0, IntegratorType::kAuto);
  // Issue 19: a duration of 1e300 s at the default rate is the duration's fault (it blamed
  // sample_rate), and a message shows 1e+300, not std::to_string's 301 digits.
  for (auto [settings, key] : {std::pair{CaseSettings{-1.0, 1e3, 1e8}, "duration"},
                               std::pair{CaseSettings{10.0, 0.0, 1e8}, "sample_rate"},
                               std::pair{CaseSettings{10.0, 1e3, 0.5}, "max_steps"},
                               std::pair{CaseSettings{1e300, 1e3, 1e8}, "duration"},
                               std::pair{CaseSettings{1e7, 1e3, 1e8}, "duration"},
                               std::pair{CaseSettings{2e9, 1e-3, 1e8}, "duration"},  // beyond 1e9 s
                               std::pair{CaseSettings{10.0, 1e300, 1e8}, "sample_rate"},
                               std::pair{CaseSettings{-1e300, 1e3, 1e8}, "duration"},
                               std::pair{CaseSettings{10.0, 1e3, 1e300}, "max_steps"}}) {
    try {
      run_case(c, settings);
      ADD_FAILURE() << key << " accepted";
    } catch (const InvalidParameter& e) {
      EXPECT_EQ(e.parameter(), key) << e.what();
      EXPECT_LT(std::string(e.what()).size(), 120u) << e.what();
    }
  }
}

/// (time, state, event) of each sample of sample_run.
struct Sample {
  double t;
  Snapshot state;
  Event event;
};

std::vector<Sample> samples_of(const SceneConfig& c, const SampleTimes& times, double max_steps,
                               StateWhereStepsRunOut steps_run_out, SampledRun& run) {
  const auto sim = make_simulator(c);
  std::vector<Sample> samples;
  run = sample_run(*sim, times.count(), [&](long long i) { return times.at(i); }, max_steps, steps_run_out,
                   [&](double t, const Snapshot& s, Event e) { samples.push_back({t, s, e}); });
  return samples;
}

bool same_state(const Snapshot& a, const Snapshot& b) {
  return a.time == b.time && a.attitude.coeffs() == b.attitude.coeffs() && a.body_rates == b.body_rates &&
         a.outputs.energy == b.outputs.energy;
}

// The one sampling loop (simulate's rows, run_case, Simulator.run): where the steps run out, a
// case keeps the state reached and a trajectory drops it; every state sampled is the unbounded
// run's at the same time, bit for bit.
TEST(SampleRun, KeepsOrDropsTheStateWhereTheStepsRunOut) {
  const SceneConfig c = toy(SceneType::kFixedTip, 0.3, 150.0, IntegratorType::kRk4);  // 1 ms steps
  const SampleTimes times(1.0, 100.0);  // 10 steps per sample
  SampledRun unbounded, dropped, kept;
  const std::vector<Sample> all = samples_of(c, times, 1e8, StateWhereStepsRunOut::kDrop, unbounded);
  const std::vector<Sample> drop = samples_of(c, times, 45, StateWhereStepsRunOut::kDrop, dropped);
  const std::vector<Sample> keep = samples_of(c, times, 45, StateWhereStepsRunOut::kKeep, kept);
  EXPECT_FALSE(unbounded.out_of_steps);
  EXPECT_EQ(all.size(), 101u);
  EXPECT_TRUE(dropped.out_of_steps && kept.out_of_steps);
  EXPECT_EQ(dropped.event, Event::kNone);
  ASSERT_EQ(drop.size(), 5u);  // t = 0 .. 0.04; 0.05 is 5 steps beyond the 45
  ASSERT_EQ(keep.size(), 6u);  // and the state after 45 steps, at its own time
  for (std::size_t i = 0; i < drop.size(); ++i) {
    EXPECT_EQ(drop[i].t, times.at(static_cast<long long>(i)));
    EXPECT_TRUE(same_state(drop[i].state, all[i].state) && same_state(keep[i].state, all[i].state)) << i;
  }
  EXPECT_EQ(keep.back().t, keep.back().state.time);
  EXPECT_GT(keep.back().t, times.at(4));
  EXPECT_LT(keep.back().t, times.at(5));
  EXPECT_EQ(keep.back().event, Event::kNone);
}

// On an event the sample has the event's time instead of the one asked for, and is the last.
TEST(SampleRun, EndsAtTheFirstEventWithItsTime) {
  const SceneConfig c = toy(SceneType::kFixedTip, 0.3, 0.0, IntegratorType::kDop853);  // spinless: falls
  SampledRun run;
  const std::vector<Sample> samples = samples_of(c, SampleTimes(10.0, 100.0), 1e8, StateWhereStepsRunOut::kDrop, run);
  EXPECT_EQ(run.event, Event::kFallen);
  EXPECT_FALSE(run.out_of_steps);
  ASSERT_GE(samples.size(), 2u);
  EXPECT_EQ(samples.back().event, Event::kFallen);
  EXPECT_EQ(samples.back().t, samples.back().state.time);
  EXPECT_LT(samples.back().t, (samples.size() - 1) / 100.0);
  for (std::size_t i = 0; i + 1 < samples.size(); ++i) EXPECT_EQ(samples[i].event, Event::kNone);
}

TEST(SampleTimes, DecimalDurationsGiveTheirRowCount) {
  EXPECT_EQ(SampleTimes(1.1, 100.0).count(), 111);  // 110.00000000000001 intervals
  EXPECT_EQ(SampleTimes(1.005, 100.0).count(), 102);  // 100 intervals and the end
  EXPECT_EQ(SampleTimes(1.005, 100.0).at(101), 1.005);
}

}  // namespace
}  // namespace spinning_top
