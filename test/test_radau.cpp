// RADAU5 (include/spinning_top/integrators/radau.hpp): its order at forced fixed steps, its
// global error against the tolerance, its answers between steps, and the work it saves by
// keeping Jacobians and LU decompositions. References: dop853 at tolerance 1e-14.
#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "core_test_support.hpp"
#include "spinning_top/integrators/registry_rows.hpp"
#include "spinning_top/integrators/dop853.hpp"
#include "spinning_top/integrators/radau.hpp"
#include "spinning_top/integrators/radau9.hpp"
#include "spinning_top/scenes/viscous.hpp"

namespace spinning_top {
namespace {
using core_test::report;
using Radau = RadauIIA5<Viscous>;

using core_test::slipping_top;
using core_test::ViscousByDifferences;

/// The state at `t` of a tight dop853 run (rate lambda = 10 1/s for k = 0.5: not stiff).
Viscous::State dop853_reference(const Viscous& model, double t) {
  AdaptiveDriver<Viscous, DormandPrince853<Viscous>> driver(1e-14);
  driver.reset(model, 0.0, model.initial_state());
  EXPECT_EQ(driver.advance_to(model, t), Event::kNone);
  return driver.state();
}

/// radau5 at fixed steps through the Method interface, as the driver would run it without error
/// control: attempt(), then prepare_dense() to accept (which also hands the step's collocation
/// polynomial to the next step as Newton's starting guess).
template <class Method = Radau>
Viscous::State radau_fixed_steps(const Viscous& model, double dt, double duration) {
  Method method;
  method.restart();
  typename Method::Attempt attempt;
  typename Method::DenseStep dense;
  Viscous::State y = model.initial_state(), f;
  model.derivative(y, f);
  const long n = std::lround(duration / dt);
  for (long i = 0; i < n; ++i) {
    method.attempt(model, y, f, dt, attempt);
    EXPECT_TRUE(attempt.y1.allFinite() && attempt.error.allFinite()) << "Newton failed at step " << i;
    method.prepare_dense(y, f, attempt, i * dt, dt, dense);
    y = attempt.y1;
    normalize_attitude(y);
    model.derivative(y, f);
  }
  return y;
}

TEST(Radau5, FixedStepsConvergeAtFifthOrder) {
  // Halving 2 ms -> 1 ms: an order-5 method divides the global error by 32. Measured errors
  // 3.73e-7 -> 1.18e-8 (ratio 31.5), both far above dop853's 1e-13 reference floor.
  const Viscous model = slipping_top(0.5);
  const Viscous::State exact = dop853_reference(model, 0.5);
  const double coarse = (radau_fixed_steps(model, 2e-3, 0.5) - exact).norm();
  const double fine = (radau_fixed_steps(model, 1e-3, 0.5) - exact).norm();
  report("radau5 fixed 2 ms, state error at 0.5 s", coarse);
  report("radau5 fixed 1 ms, state error at 0.5 s", fine);
  EXPECT_GT(fine, 1e-11);  // above the reference's floor: the ratio is not noise
  EXPECT_NEAR(std::log2(coarse / fine), 5.0, 0.15);
}

TEST(Radau9, FixedStepsConvergeAtNinthOrder) {
  // The 5-stage Radau IIA: halving 10 ms -> 5 ms divides the global error by 2^9 = 512. Measured
  // on the slipping top at k = 0.5: see the output (both far above dop853's ~1e-13 floor).
  const Viscous model = slipping_top(0.5);
  const Viscous::State exact = dop853_reference(model, 0.5);
  const double coarse = (radau_fixed_steps<RadauIIA9<Viscous>>(model, 10e-3, 0.5) - exact).norm();
  const double fine = (radau_fixed_steps<RadauIIA9<Viscous>>(model, 5e-3, 0.5) - exact).norm();
  report("radau9 fixed 10 ms, state error at 0.5 s", coarse);
  report("radau9 fixed 5 ms, state error at 0.5 s", fine);
  EXPECT_GT(fine, 1e-11);  // above the reference's floor: the ratio is not noise
  EXPECT_NEAR(std::log2(coarse / fine), 9.0, 0.3);
}

TEST(Radau9, StiffFrictionAtTheErrorOfRadau5WithAFifthOfItsSteps) {
  // Why radau9 exists (radau9.hpp): on stiff friction (k = 1e3 and 1e5: relaxation rates 2e4 and
  // 2e6 1/s) radau5 needs ~1e-4 s steps at 1e-14, radau9 ~1e-3 s at 1e-12 for an error as small.
  // Both asked every 1 ms over 1 s (dense output: partial collocation steps), against radau5 at
  // 1e-15 (a third method: dop853 crawls at its stability limit here). Measured: see the output.
  for (const double k : {1e3, 1e5}) {
    const Viscous model = slipping_top(k);
    AdaptiveDriver<Viscous, Radau> reference(1e-15), radau5(1e-14);
    AdaptiveDriver<Viscous, RadauIIA9<Viscous>> radau9(1e-12);
    reference.reset(model, 0.0, model.initial_state());
    radau5.reset(model, 0.0, model.initial_state());
    radau9.reset(model, 0.0, model.initial_state());
    double error5 = 0.0, error9 = 0.0, force9 = 0.0;
    for (int i = 1; i <= 1000; ++i) {
      const double t = i * 1e-3;
      ASSERT_EQ(reference.advance_to(model, t), Event::kNone);
      ASSERT_EQ(radau5.advance_to(model, t), Event::kNone);
      ASSERT_EQ(radau9.advance_to(model, t), Event::kNone);
      const Quaternion q = attitude_of(reference.state());
      error5 = std::max(error5, core_test::attitude_difference(attitude_of(radau5.state()), q));
      error9 = std::max(error9, core_test::attitude_difference(attitude_of(radau9.state()), q));
      force9 = std::max(force9, std::abs(model.normal_force(radau9.state()) - model.normal_force(reference.state())));
    }
    const RadauStatistics& s = radau9.stepper().method().statistics();
    const double mg = model.parameters().mass * model.parameters().gravity;
    std::printf("[ measured ] k = %g: radau5 1e-14 %ld steps, %.3g rad; radau9 1e-12 %ld steps (%ld rejected, %ld "
                "low-rank attempts of %ld, %ld Newton failures), %.3g rad, R %.3g m g\n",
                k, radau5.steps(), error5, radau9.steps(), radau9.rejected_steps(), s.low_rank_attempts, s.attempts,
                s.newton_failures, error9, force9 / mg);
    EXPECT_LT(radau9.steps() * 5, radau5.steps());
    EXPECT_LT(error9, std::max(2.0 * error5, 1e-12));
    EXPECT_LT(force9, 1e-8 * mg);  // the default's bar
    EXPECT_GE(s.low_rank_attempts, s.attempts - s.attempts / 100);  // Woodbury, not 55 x 55 LUs
  }
}

/// Largest error of radau5 at `tolerance` over 1 s, asked every 1 ms (dense output), against
/// dop853 at 1e-14: the attitude angle [rad] and the state's max-norm.
struct GlobalError {
  double attitude = 0.0, state = 0.0;
  long steps = 0;
};
GlobalError radau_global_error(const Viscous& model, double tolerance) {
  AdaptiveDriver<Viscous, Radau> radau(tolerance);
  AdaptiveDriver<Viscous, DormandPrince853<Viscous>> reference(1e-14);
  radau.reset(model, 0.0, model.initial_state());
  reference.reset(model, 0.0, model.initial_state());
  GlobalError e;
  for (int i = 1; i <= 1000; ++i) {
    EXPECT_EQ(radau.advance_to(model, i * 1e-3), Event::kNone);
    reference.advance_to(model, i * 1e-3);
    e.attitude = std::max(e.attitude, attitude_of(radau.state()).angularDistance(attitude_of(reference.state())));
    e.state = std::max(e.state, (radau.state() - reference.state()).cwiseAbs().maxCoeff());
  }
  e.steps = radau.steps();
  return e;
}

TEST(Radau5, GlobalErrorIsProportionalToTheTolerance) {
  // radau5.f's tolerance map (rtol' = 0.1 rtol^(2/3) on the O(h^4) estimate) makes the local
  // error of the order-5 solution about proportional to the tolerance, and so the global error.
  // Measured over 1 s (state max-norm): 2.3e-7, 3.9e-9, 8.4e-11 at 1e-7, 1e-9, 1e-11, i.e.
  // 2.3-8.4 tolerances, 58x and 47x per two decades (error ~ tol^0.86). Bounds: within 20
  // tolerances (as tolerance-driven as dop853, held to 50 in test_convergence), and 30-200x per
  // two decades: the estimate without the map (err <= tol on an O(h^4) quantity) would give
  // 100^(3/2) = 1000x.
  const Viscous model = slipping_top(0.5);
  double previous = 0.0;
  for (const double tolerance : {1e-7, 1e-9, 1e-11}) {
    const GlobalError e = radau_global_error(model, tolerance);
    std::printf("[ measured ] radau5 at %g: state error %.3g (%.3g tolerances), attitude %.3g rad, %ld steps\n",
                tolerance, e.state, e.state / tolerance, e.attitude, e.steps);
    EXPECT_LT(e.state, 20.0 * tolerance);
    EXPECT_GT(e.state, 1e-3 * tolerance);  // the test measures the method, not the reference
    if (previous > 0.0) {
      EXPECT_GT(previous / e.state, 30.0);
      EXPECT_LT(previous / e.state, 200.0);
    }
    previous = e.state;
  }
}

TEST(Radau5, AnswersBetweenStepsAreAsAccurateAsTheStepItself) {
  // A request inside a step is answered by collocation steps from the step's start (dense():
  // 3/4 then 1/4 of the way), not by radau5.f's collocation cubic, whose error is O(h^4): compare
  // both with the step's own local error O(h^6), from an exact start. k = 0.5, dt = 1 ms.
  // Measured: end of step 9.4e-10, requests inside at most 9.1e-11; the cubic 1.4e-7 (155x).
  const Viscous model = slipping_top(0.5);
  const double t0 = 0.2, dt = 1e-3;
  const Viscous::State y0 = dop853_reference(model, t0);
  Viscous::State f0;
  model.derivative(y0, f0);
  Radau method;
  method.restart();
  Radau::Attempt attempt;
  Radau::DenseStep dense;
  method.attempt(model, y0, f0, dt, attempt);
  method.prepare_dense(y0, f0, attempt, t0, dt, dense);
  method.complete_dense(model, dense);
  const double step_error = (attempt.y1 - dop853_reference(model, t0 + dt)).cwiseAbs().maxCoeff();
  double partial_error = 0.0, cubic_error = 0.0;
  for (const double x : {0.1, 0.25, 0.5, 0.75, 0.9}) {
    const Viscous::State exact = dop853_reference(model, t0 + x * dt);
    partial_error = std::max(partial_error, (Radau::dense(dense, t0 + x * dt) - exact).cwiseAbs().maxCoeff());
    cubic_error = std::max(cubic_error, (Radau::collocation_polynomial(dense, x) - exact).cwiseAbs().maxCoeff());
  }
  report("radau5 1 ms step from an exact state: error at its end", step_error);
  report("radau5 requests inside it (partial steps): largest error", partial_error);
  report("radau5.f's collocation cubic inside it: largest error", cubic_error);
  EXPECT_GT(step_error, 1e-13);  // a local error to compare with, above the reference's floor
  EXPECT_LT(partial_error, step_error);
  EXPECT_GT(cubic_error, 100.0 * step_error);  // the case tells the two answers apart
}

TEST(Radau5, AnswersBetweenStiffStepsKeepTheNormalForce) {
  // k = 1e5 N s/m (m/k = 1e-6 s, lambda = 2e6 1/s): R = ... - alpha n.F with F = -k v_P, so a
  // slip-velocity error dv enters R as k dv. The collocation cubic interpolates q, omega and v_G
  // separately, and v_P between its nodes leaves the slow manifold; the partial collocation steps
  // lie on it. Reference: radau5 at 1e-14 asked at the same times. One 0.25 ms step (about what
  // radau5 takes here at 1e-14, auto's setting for it before radau9) from t = 0.1 s. Measured: R within 1.5e-11 m g for
  // the partial steps (6.5e-10 with one partial step instead of dense()'s two), 3.1e-7 m g off
  // for the cubic.
  const Viscous model = slipping_top(1e5);
  const double mg = model.parameters().mass * model.parameters().gravity;
  AdaptiveDriver<Viscous, Radau> reference(1e-14);
  reference.reset(model, 0.0, model.initial_state());
  ASSERT_EQ(reference.advance_to(model, 0.1), Event::kNone);
  const Viscous::State y0 = reference.state();
  Viscous::State f0;
  model.derivative(y0, f0);
  Radau method;
  method.restart();
  Radau::Attempt attempt;
  Radau::DenseStep dense;
  const double dt = 2.5e-4;
  method.attempt(model, y0, f0, dt, attempt);
  ASSERT_TRUE(attempt.error.allFinite());
  method.prepare_dense(y0, f0, attempt, 0.1, dt, dense);
  method.complete_dense(model, dense);
  double partial_error = 0.0, cubic_error = 0.0;
  for (const double x : {0.2, 0.4, 0.6, 0.8}) {
    ASSERT_EQ(reference.advance_to(model, 0.1 + x * dt), Event::kNone);
    const double r = model.normal_force(reference.state());
    Viscous::State partial = Radau::dense(dense, 0.1 + x * dt), cubic = Radau::collocation_polynomial(dense, x);
    normalize_attitude(partial);
    normalize_attitude(cubic);
    partial_error = std::max(partial_error, std::abs(model.normal_force(partial) - r) / mg);
    cubic_error = std::max(cubic_error, std::abs(model.normal_force(cubic) - r) / mg);
  }
  report("k = 1e5, 0.25 ms step: R error of the partial steps [m g]", partial_error);
  report("k = 1e5, 0.25 ms step: R error of the collocation cubic [m g]", cubic_error);
  EXPECT_LT(partial_error, 1e-8);   // the default's target
  EXPECT_GT(cubic_error, 1e-7);     // 10x the target: the case tells the two answers apart
}

TEST(Radau5, KeepsTheJacobianWhenNewtonContractsFastAndSolvesTurningStiffnessPerStage) {
  // radau5.f's economy, for a model without a stiff part: without stiffness (k = 0.5) Newton
  // contracts fast and J is kept for many steps. With stiff friction whose direction turns with
  // the spin (k = 1e5, header comment), one J for all stages fails at the steps the accuracy
  // allows and the per-stage Newton takes over. Measured over 1 s at 1e-12: k = 0.5 4983 steps,
  // 170 Jacobians, none per-stage; k = 1e5 3721 of 3867 steps per-stage (the others: the
  // simplified Newton tried again, backing off), 1 and 3 rejected steps.
  for (const double k : {0.5, 1e5}) {
    const ViscousByDifferences model = slipping_top<ViscousByDifferences>(k);
    AdaptiveDriver<ViscousByDifferences, RadauIIA5<ViscousByDifferences>> driver(1e-12);
    driver.reset(model, 0.0, model.initial_state());
    ASSERT_EQ(driver.advance_to(model, 1.0), Event::kNone);
    const RadauStatistics& s = driver.stepper().method().statistics();
    std::printf("[ measured ] k = %g: %ld steps, %ld rejected, %ld Jacobians, %ld decompositions, %ld per-stage, "
                "%.2f Newton iterations per attempt\n",
                k, driver.steps(), driver.rejected_steps(), s.jacobians, s.decompositions, s.per_stage_attempts,
                static_cast<double>(s.newton_iterations) / s.attempts);
    EXPECT_EQ(s.low_rank_attempts, 0);
    if (k < 1.0) {
      EXPECT_LT(s.jacobians, driver.steps() / 4);
      EXPECT_EQ(s.per_stage_attempts, 0);
    } else {
      EXPECT_GT(s.per_stage_attempts, driver.steps() * 9 / 10);
    }
    EXPECT_LT(driver.rejected_steps(), driver.steps() / 20);
  }
}

TEST(Radau5, SolvesSlidingStepsWithTheModelsStiffPartAloneAtTheSameSteps) {
  // With the viscous top's stiff part (J = U V + O(motion), rank 2), every sliding attempt's
  // Newton uses U V alone (Woodbury, radau.hpp): no Jacobian by differences, no n x n LU. The
  // neglected part makes it contract at about h |J_motion| (h ~ 3e-4 s, |J_motion| ~ 225 1/s:
  // ~0.07), like the full-Jacobian Newton's, so the controller, which reads the iteration count,
  // takes the same steps, and the step's answer is the same collocation solution to within
  // Newton's tolerance. Measured over 1 s at 1e-12: see the output.
  for (const double k : {0.5, 1e5}) {
    const Viscous model = slipping_top(k);
    AdaptiveDriver<Viscous, Radau> low_rank(1e-12);
    low_rank.reset(model, 0.0, model.initial_state());
    ASSERT_EQ(low_rank.advance_to(model, 1.0), Event::kNone);
    const ViscousByDifferences same = slipping_top<ViscousByDifferences>(k);
    AdaptiveDriver<ViscousByDifferences, RadauIIA5<ViscousByDifferences>> by_differences(1e-12);
    by_differences.reset(same, 0.0, same.initial_state());
    ASSERT_EQ(by_differences.advance_to(same, 1.0), Event::kNone);
    const RadauStatistics& s = low_rank.stepper().method().statistics();
    const double attitude = core_test::attitude_difference(attitude_of(low_rank.state()), attitude_of(by_differences.state()));
    std::printf("[ measured ] k = %g: %ld steps (%ld by differences), %ld rejected, %ld low-rank attempts of %ld, "
                "%ld Jacobians, %.2f Newton iterations per attempt, %.3g rad apart\n",
                k, low_rank.steps(), by_differences.steps(), low_rank.rejected_steps(), s.low_rank_attempts,
                s.attempts, s.jacobians, static_cast<double>(s.newton_iterations) / s.attempts, attitude);
    // (The first attempt at k = 0.5 starts from a zero guess, fails and falls back on J.)
    EXPECT_GE(s.low_rank_attempts, s.attempts - s.attempts / 100);
    EXPECT_LE(s.jacobians, s.attempts / 100);
    EXPECT_LT(std::abs(low_rank.steps() - by_differences.steps()), by_differences.steps() / 50);
    EXPECT_LT(low_rank.rejected_steps(), low_rank.steps() / 20);
    EXPECT_LT(attitude, 1e-10);  // both at 1e-12 over 1 s: apart by less than either's error
  }
}

TEST(Radau5, LowRankNewtonAddsNoDriftOverTheManyStepsOfAFastSpin) {
  // The low-rank Newton contracts at ~0.05 and leaves a remainder of one sign step after step
  // (radau.hpp, kLowRankNewtonTightening). A 2000 rad/s top takes ~84,000 steps a second at
  // 1e-14, so a remainder of ~1e-16 per step shows in the attitude. Both Newtons solve the same
  // collocation equations, so their errors against dop853 at 1e-14 should match. Measured over
  // 0.5 s: the low-rank Newton 4.0e-13 rad, the per-stage one 4.1e-13; with the low-rank Newton
  // stopped at 1/100 of Newton's tolerance instead of 1/1000, 3.9e-12 (so the bound discriminates).
  TopParameters top;
  top.friction = 5e3;
  InitialConditions start;
  start.tilt = 0.3;
  start.spin = 2000.0;
  const Viscous model(top, start);
  AdaptiveDriver<Viscous, Radau> low_rank(1e-14);
  low_rank.reset(model, 0.0, model.initial_state());
  ASSERT_EQ(low_rank.advance_to(model, 0.5), Event::kNone);
  const ViscousByDifferences same(top, start);
  AdaptiveDriver<ViscousByDifferences, RadauIIA5<ViscousByDifferences>> by_differences(1e-14);
  by_differences.reset(same, 0.0, same.initial_state());
  ASSERT_EQ(by_differences.advance_to(same, 0.5), Event::kNone);
  const Quaternion reference = attitude_of(dop853_reference(model, 0.5));
  const double low_rank_error = core_test::attitude_difference(attitude_of(low_rank.state()), reference);
  const double per_stage_error = core_test::attitude_difference(attitude_of(by_differences.state()), reference);
  const RadauStatistics& s = low_rank.stepper().method().statistics();
  std::printf("[ measured ] 2000 rad/s, k = 5e3, 0.5 s at 1e-14: %ld steps, %ld low-rank attempts of %ld; attitude "
              "error %.3g rad (per-stage Newton: %.3g rad, %ld steps)\n",
              low_rank.steps(), s.low_rank_attempts, s.attempts, low_rank_error, per_stage_error, by_differences.steps());
  EXPECT_GE(s.low_rank_attempts, s.attempts - s.attempts / 100);
  EXPECT_LT(low_rank_error, 2.0 * per_stage_error + 2e-13);
}

}  // namespace
}  // namespace spinning_top
