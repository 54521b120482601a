// Issue 19, item 4: the work budget bounds work, not accepted steps. Before, a radau5 step was
// one step of the budget however many Newton iterations, Jacobians and factorizations it took
// (on stiff friction 10-20 dop853 steps of CPU), so the default allowance bounded radau5 at
// hours instead of minutes. These tests count the model's evaluations of f with a counting model
// (not the methods' own counters) and hold the budget to them; see work_budget.hpp.
#include <gtest/gtest.h>

#include <cstdio>

#include "core_test_support.hpp"
#include "spinning_top/case_run.hpp"
#include "spinning_top/integrators/registry_rows.hpp"
#include "spinning_top/simulator.hpp"

namespace spinning_top {
namespace {

/// A scene model that counts the evaluations of its derivative (f), wherever a method, its
/// Jacobian, its dense output or the driver asks for them.
template <class Model>
class Counting : public Model {
 public:
  using Model::Model;
  using State = typename Model::State;
  void derivative(const State& y, State& dydt) const {
    ++evaluations;
    Model::derivative(y, dydt);
  }
  mutable long evaluations = 0;
};
using CountingViscous = Counting<Viscous>;
template <class Model>
using StiffRadauOf = Driver<Model, EmbeddedStepper<Model, RadauIIA5<Model>>, Radau5Controller>;
using StiffRadau = StiffRadauOf<CountingViscous>;

/// Stiff friction whose direction turns with the spin (radau.hpp, header): the low-rank Newton
/// with the model's stiff part (the factors of 3 stages and a 6 x 6 LU per attempt), or without
/// it (Model: Counting<ViscousByDifferences>) the per-stage Newton, a Jacobian per stage
/// (3 x 12 evaluations) and a factorization in every step.
template <class Model = CountingViscous>
Model stiff_slipping_top() { return core_test::slipping_top<Model>(1e5); }

// One call with a budget of N steps: the evaluations of f it makes are at most N x 16 (a dop853
// step's, work_budget.hpp) plus the last step's overrun, and the budget runs out at its
// allowance, which the linear algebra's work (radau_work, measured in evaluations) fills up.
// Before, the budget counted N accepted radau5 steps: about 40 evaluations each here (per
// stage), and as much again in linear algebra.
template <class Model>
void check_budget_of_a_stiff_radau5_call(bool low_rank) {
  const Model model = stiff_slipping_top<Model>();
  StiffRadauOf<Model> driver(1e-12);
  driver.reset(model, 0.0, model.initial_state());
  // Past the initial slip's transient.
  ASSERT_EQ(driver.advance_to(model, 0.1), Event::kNone);
  const RadauStatistics before = driver.stepper().method().statistics();
  const long steps_before = driver.steps(), work_before = driver.work();
  const long n = 400;
  model.evaluations = 0;
  ASSERT_EQ(driver.advance_to(model, 1.0, WorkBudget::steps(n)), Event::kNone);
  RadauStatistics s = driver.stepper().method().statistics();
  s.newton_iterations -= before.newton_iterations;
  s.jacobians -= before.jacobians;
  s.decompositions -= before.decompositions;
  s.per_stage_attempts -= before.per_stage_attempts;
  s.low_rank_attempts -= before.low_rank_attempts;
  const long steps = driver.steps() - steps_before;
  std::printf("[ measured ] a budget of %ld steps: %ld radau5 steps, %ld evaluations of f, %ld Newton iterations, "
              "%ld Jacobians, %ld factorizations, %ld per-stage attempts, %ld low-rank attempts, work %ld\n",
              n, steps, model.evaluations, s.newton_iterations, s.jacobians, s.decompositions, s.per_stage_attempts,
              s.low_rank_attempts, driver.work() - work_before);
  EXPECT_LT(driver.time(), 1.0) << "the budget never ran out";
  EXPECT_GT(low_rank ? s.low_rank_attempts : s.per_stage_attempts, steps / 2) << "not the stiff case the test means";
  EXPECT_LE(model.evaluations, n * kWorkPerStep);
  // The budget ran out at its allowance, not long before it.
  EXPECT_GE(driver.work() - work_before, n * kWorkPerStep);
}

TEST(WorkBudget, BoundsTheEvaluationsOfAStiffRadau5Call) {
  check_budget_of_a_stiff_radau5_call<CountingViscous>(true);
  check_budget_of_a_stiff_radau5_call<Counting<core_test::ViscousByDifferences>>(false);
}

// The same over a run of many calls, as simulate, the Python module and a sweep spend a run's
// allowance: a request every 1 ms, each call with what is left (WorkBudget::steps_left of the
// run's work()). Requests inside radau5's steps cost Newton solves of their own (dense output),
// which count too.
TEST(WorkBudget, BoundsTheEvaluationsOfAStiffRadau5RunOfManyCalls) {
  const CountingViscous model = stiff_slipping_top();
  StiffRadau driver(1e-12);
  driver.reset(model, 0.0, model.initial_state());
  const double allowance = 2000;
  model.evaluations = 0;
  int requests = 0;
  for (int i = 1; i <= 1000; ++i) {
    const double t = i * 1e-3;
    ASSERT_EQ(driver.advance_to(model, t, WorkBudget::steps_left(allowance, work_in_steps(driver.work()))),
              Event::kNone);
    ++requests;
    if (driver.time() < t) break;
  }
  std::printf("[ measured ] an allowance of %.0f steps: %d requests, %ld radau5 steps, %ld evaluations of f\n",
              allowance, requests, driver.steps(), model.evaluations);
  EXPECT_LT(requests, 1000) << "the allowance never ran out";
  EXPECT_LE(model.evaluations, static_cast<long>(allowance) * kWorkPerStep);
}

// Work only grows, also across a hybrid run's transitions (each contact phase restarts its
// driver, which restarts radau5's counters) and its closed-form restarts, and it is never less
// than the accepted steps: stiff friction that hops (its skims and flights), and a frictionless
// top hopping in closed form (exact builds its solution again at each landing, which counts).
TEST(WorkBudget, RunWorkNeverDecreasesAndCountsAtLeastTheSteps) {
  SceneConfig stiff;
  stiff.scene = SceneType::kViscous;
  stiff.top.friction = 1e7;
  stiff.initial = core_test::slipping_start(2000.0);
  stiff.integrator.type = IntegratorType::kRadau5;
  stiff.integrator.tolerance = 1e-14;
  SceneConfig hops;
  hops.scene = SceneType::kFrictionless;
  hops.initial.tilt = 0.8;
  hops.initial.precession_rate = 60.0;
  for (const SceneConfig& config : {stiff, hops}) {
    const auto simulator = make_simulator(config);
    long work = simulator->work(), transitions = 0;
    for (int i = 1; i <= 300 && simulator->event() == Event::kNone; ++i) {
      simulator->advance_to(i * 1e-3);
      transitions += static_cast<long>(simulator->take_transitions().size());
      ASSERT_GE(simulator->work(), work) << to_string(config.scene) << " at t = " << simulator->time();
      ASSERT_GE(simulator->work(), simulator->steps()) << to_string(config.scene);
      work = simulator->work();
    }
    std::printf("[ measured ] %s: %ld transitions, %ld steps, work %ld steps of the budget\n", to_string(config.scene),
                transitions, simulator->steps(), simulator->work());
    EXPECT_GT(transitions, 2) << to_string(config.scene) << ": no transition, nothing tested";
  }
}

// A front end's run (simulate, run_case and the sweep, the Python module's run: sample_run)
// counts its allowance against Simulator::work(): with stiff friction and a request every 1 ms,
// an allowance of 2000 steps ends at 2000 steps of work (plus the last step's overrun). Counted
// against accepted steps, each request's call had 2000 - steps() steps of work to spend again.
TEST(WorkBudget, ASampledRunSpendsItsAllowanceInWork) {
  SceneConfig config;
  config.scene = SceneType::kViscous;
  config.top.friction = 1e5;
  config.initial = core_test::slipping_start();
  config.integrator.type = IntegratorType::kRadau5;
  config.integrator.tolerance = 1e-12;
  const auto simulator = make_simulator(config);
  long samples = 0;
  const SampledRun run = sample_run(*simulator, 1001, [](long long i) { return 1e-3 * static_cast<double>(i); }, 2000.0,
                                    StateWhereStepsRunOut::kDrop, [&](double, const Snapshot&, Event) { ++samples; });
  std::printf("[ measured ] an allowance of 2000 steps: %ld samples, %ld radau5 steps, work %ld\n", samples,
              simulator->steps(), simulator->work());
  EXPECT_TRUE(run.out_of_steps);
  EXPECT_GE(simulator->work(), 2000);
  EXPECT_LE(simulator->work(), 2000 + 50);  // a radau5 step here is about 15 steps of work
}

}  // namespace
}  // namespace spinning_top
