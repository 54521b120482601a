// Issue 10: bounded work, and runs that break physics stopped or refused instead of published.
//   - A work budget (work_budget.hpp) that runs out leaves the run where an unbounded one would
//     pass: the states reached are the same bit for bit, wherever the budget ran out.
//   - A step that breaks the energy balance ends the run with `energy_drift` at its start, and
//     the state reported keeps the balance (events.hpp, kEnergyBalanceTolerance).
//   - Friction stiffer than double precision resolves is refused naming `friction`; below the
//     bound, a stiff initial slip runs (it ended in non_finite at t = 0 before).
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <limits>
#include <stdexcept>
#include <vector>

#include "core_test_support.hpp"

namespace spinning_top {
namespace {

using core_test::fixed_step;

InitialConditions toy_initial() {
  InitialConditions initial;
  initial.tilt = 0.3;
  initial.spin = 150.0;
  initial.precession_rate = 2.0;
  return initial;
}

SceneConfig with_integrator(SceneType scene, IntegratorType type, double tolerance, double step) {
  SceneConfig config;
  config.scene = scene;
  config.initial = toy_initial();
  if (scene == SceneType::kViscous) {
    config.top.friction = 0.02;
    config.initial.velocity_x = 0.01;
  }
  config.integrator.type = type;
  config.integrator.tolerance = tolerance;
  config.integrator.step = step;
  return config;
}

bool bitwise_equal(const Snapshot& a, const Snapshot& b) {
  const double left[] = {a.time, a.attitude.w(), a.attitude.x(), a.attitude.y(), a.attitude.z(),
                         a.body_rates.x(), a.body_rates.y(), a.outputs.normal_force, a.outputs.energy,
                         a.outputs.contact_point.x(), a.outputs.contact_point.y(), a.outputs.dissipated_energy};
  const double right[] = {b.time, b.attitude.w(), b.attitude.x(), b.attitude.y(), b.attitude.z(),
                          b.body_rates.x(), b.body_rates.y(), b.outputs.normal_force, b.outputs.energy,
                          b.outputs.contact_point.x(), b.outputs.contact_point.y(), b.outputs.dissipated_energy};
  return std::memcmp(left, right, sizeof left) == 0;
}

// Every kind of driver (fixed step, adaptive explicit, adaptive implicit, closed form, auto):
// samples every 10 ms over 0.5 s, once unbounded and once one step per call (the call repeated
// until it reaches the sample). A budget that runs out returns kNone short of the target.
TEST(WorkBudget, OneStepPerCallGivesTheUnboundedRunBitForBit) {
  struct Case {
    SceneType scene;
    IntegratorType type;
    double tolerance, step;
  };
  const Case cases[] = {
      {SceneType::kFixedTip, IntegratorType::kRk4, 1e-10, 1e-4},
      {SceneType::kFixedTip, IntegratorType::kSplitting6, 1e-10, 2e-3},
      {SceneType::kFrictionless, IntegratorType::kDop853, 1e-12, 1e-3},
      {SceneType::kViscous, IntegratorType::kRadau5, 1e-10, 1e-3},
      {SceneType::kViscous, IntegratorType::kAuto, 1e-12, 1e-3},
      {SceneType::kFixedTip, IntegratorType::kAuto, 1e-12, 1e-3},
  };
  for (const Case& c : cases) {
    const SceneConfig config = with_integrator(c.scene, c.type, c.tolerance, c.step);
    const auto unbounded = make_simulator(config);
    const auto bounded = make_simulator(config);
    long calls = 0, short_calls = 0;
    for (int i = 1; i <= 50; ++i) {
      const double t = 0.01 * i;
      ASSERT_EQ(unbounded->advance_to(t), Event::kNone) << to_string(c.type);
      for (;;) {
        ++calls;
        const Event event = bounded->advance_to(t, WorkBudget::steps(1));
        ASSERT_EQ(event, Event::kNone);
        if (bounded->time() == t) break;
        ASSERT_LT(bounded->time(), t);
        ++short_calls;
        ASSERT_LT(short_calls, 1000000) << "no progress";
      }
      ASSERT_TRUE(bitwise_equal(unbounded->snapshot(), bounded->snapshot()))
          << to_string(c.scene) << ", " << to_string(c.type) << ", t = " << t;
    }
    // The closed form answers a request in one evaluation: its budget never runs out.
    if (c.type == IntegratorType::kAuto && c.scene == SceneType::kFixedTip)
      EXPECT_EQ(short_calls, 0);
    else
      EXPECT_GT(short_calls, 0) << to_string(c.type) << ": the budget never ran out, so nothing was tested";
  }
}

// A deadline already past still lets one step through: a run always makes progress.
TEST(WorkBudget, PastDeadlineStillTakesAStep) {
  const auto simulator = make_simulator(with_integrator(SceneType::kFixedTip, IntegratorType::kRk4, 1e-10, 1e-5));
  const WorkBudget past = WorkBudget::until(WorkBudget::Clock::now() - std::chrono::seconds(1));
  EXPECT_EQ(simulator->advance_to(1.0, past), Event::kNone);
  EXPECT_GT(simulator->time(), 0.0);
  EXPECT_LT(simulator->time(), 1.0);
}

// rk4 at 0.99 of the largest step validate() accepts (2 / fastest rate): |R(i omega dt)| ~ 0.75,
// the nutation's energy is lost within a few steps. The run must stop with energy_drift, at a
// state whose balance is within the documented tolerance.
// A request for t = inf or NaN is a front end's error: refused with nothing changed, for the
// closed form (which would evaluate at t = inf) and a stepper alike.
TEST(AdvanceTo, NonFiniteTargetIsRefusedAndChangesNothing) {
  for (IntegratorType method : {IntegratorType::kAuto, IntegratorType::kDop853, IntegratorType::kRk4}) {
    InitialConditions initial;
    initial.tilt = 0.3;
    initial.spin = 150.0;
    SceneConfig c = fixed_step(SceneType::kFixedTip, initial, 1e-3);
    c.integrator.type = method;
    const auto sim = make_simulator(c);
    for (double t : {std::numeric_limits<double>::infinity(), std::numeric_limits<double>::quiet_NaN()})
      EXPECT_THROW(sim->advance_to(t), std::invalid_argument) << to_string(method);
    EXPECT_EQ(sim->time(), 0.0);
    EXPECT_EQ(sim->event(), Event::kNone);
    EXPECT_EQ(sim->advance_to(0.5), Event::kNone);
    EXPECT_EQ(sim->time(), 0.5);
  }
}

TEST(EnergyBalance, DivergingStepStopsWithEnergyDrift) {
  for (SceneType scene : {SceneType::kFixedTip, SceneType::kFrictionless, SceneType::kViscous}) {
    SceneConfig config = with_integrator(scene, IntegratorType::kRk4, 1e-10, 1.0);
    config.initial.nutation_rate = 5.0;
    config.integrator.step = 0.99 * largest_fixed_step(config, IntegratorType::kRk4);
    const auto simulator = make_simulator(config);
    const ModelOutputs start = simulator->snapshot().outputs;
    const Event event = simulator->advance_to(10.0);
    EXPECT_EQ(event, Event::kEnergyDrift) << to_string(scene) << ": step " << config.integrator.step;
    const Snapshot s = simulator->snapshot();
    const double spin_energy = 0.5 * config.top.inertia_axial * config.initial.spin * config.initial.spin;
    const double mgh = config.top.mass * config.top.gravity * config.top.tip_distance;
    const double b0 = start.energy - spin_energy + start.dissipated_energy;
    const double b = s.outputs.energy - spin_energy + s.outputs.dissipated_energy;
    // The reported state kept the balance (plus the rounding of subtracting C wZ^2 / 2 here).
    EXPECT_LE(std::abs(b - b0), kEnergyBalanceTolerance * (std::abs(b0) + mgh) + 1e-15 * spin_energy)
        << to_string(scene);
    EXPECT_LT(s.time, 10.0);
    EXPECT_STREQ(to_string(Event::kEnergyDrift), "energy_drift");
  }
}

// The default and a fine rk4 keep the balance over 10 s: the guard does not fire on good runs.
TEST(EnergyBalance, AccurateRunsNeverTripTheGuard) {
  for (SceneType scene : {SceneType::kFixedTip, SceneType::kFrictionless, SceneType::kViscous}) {
    for (IntegratorType type : {IntegratorType::kAuto, IntegratorType::kRk4}) {
      const auto simulator = make_simulator(with_integrator(scene, type, 1e-12, 1e-4));
      EXPECT_EQ(simulator->advance_to(10.0), Event::kNone) << to_string(scene) << ", " << to_string(type);
    }
  }
}

// lambda = k (1/m + h^2/A) = 20 k /(kg) on the toy top; its fastest motion is the nutation
// C wZ / A = 225 rad/s (sliding): the bound 1e10 x 225 is k ~ 1.1e11 N s/m.
TEST(FrictionStiffness, BeyondDoublePrecisionIsRefusedNamingFriction) {
  SceneConfig config = with_integrator(SceneType::kViscous, IntegratorType::kAuto, 1e-12, 1e-3);
  config.initial.precession_rate = 0.0;
  config.initial.velocity_x = 1.0;
  config.top.friction = 1e12;
  try {
    make_simulator(config);
    ADD_FAILURE() << "k = 1e12 accepted";
  } catch (const InvalidParameter& refusal) {
    EXPECT_EQ(refusal.parameter(), "friction") << refusal.what();
  }
  // Just below the bound, a slip of 1 m/s relaxes within ~1e-13 s and the run goes on.
  config.top.friction = 5e10;
  const auto simulator = make_simulator(config);
  EXPECT_EQ(simulator->advance_to(0.05), Event::kNone);
  EXPECT_TRUE(simulator->snapshot().outputs.dissipated_energy > 0.0);
}

}  // namespace
}  // namespace spinning_top
