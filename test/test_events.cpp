// Validity events (PHYSICS.md, "Validity of the model"): a run stops at the first of e_Zz = 0
// (`fallen`) and R = 0 (`lift_off`), located within the step. Event times are compared with
// quadratures of the energy integral for the spinless top, and between integrators.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

#include "core_test_support.hpp"

namespace spinning_top {
namespace {
using namespace core_test;

InitialConditions spinless(double tilt, double nutation_rate) {
  InitialConditions ic;
  ic.tilt = tilt;
  ic.spin = 0.0;
  ic.nutation_rate = nutation_rate;
  return ic;
}

void expect_fall_at_quadrature_time(SceneType scene) {
  const TopParameters p = toy_top();
  const bool fixed = scene == SceneType::kFixedTip;
  const double transverse = fixed ? p.inertia_about_tip() : p.inertia_transverse;
  const PlanarFall fall{p.mass * p.gravity * p.tip_distance / transverse,
                        fixed ? 0.0 : p.mass * p.tip_distance * p.tip_distance / p.inertia_transverse, 0.3, 0.0};
  const double expected = fall.time_to(0.5 * M_PI);
  const InitialConditions ic = spinless(0.3, 0.0);
  const EventRun adaptive_run = run_until_event(adaptive(scene, ic, 1e-12), 2.0);
  const EventRun rk4_run = run_until_event(fixed_step(scene, ic, 1e-4), 2.0);
  std::printf("[ measured ] %s fall: quadrature %.15g s, dopri5 1e-12 %+.3g s, rk4 1e-4 s %+.3g s\n", to_string(scene),
              expected, adaptive_run.time - expected, rk4_run.time - expected);
  for (const EventRun* run : {&adaptive_run, &rk4_run}) {
    EXPECT_EQ(run->event, Event::kFallen) << to_string(scene);
    EXPECT_GE(cos_tilt(run->last), 0.0);   // the reported state is the last valid one...
    EXPECT_LT(cos_tilt(run->last), 1e-12);  // ...at the floor (e_Zz falls at ~10/s: 1e-12 ~ 1e-13 s)
    EXPECT_GT(run->last.outputs.normal_force, 0.0);  // R stayed positive all the way down
  }
  // Measured: dopri5 within 3.2e-14 s, rk4 within 8e-15 s of the quadrature (Simpson to 1e-15).
  // 1e-12 s (30x) is ~1e-11 of the fall time: a misplaced event (e.g. reported after the step,
  // up to 1e-4 s late) or an error in A0 / the frictionless alpha (percent) fails it.
  EXPECT_NEAR(adaptive_run.time, expected, 1e-12);
  EXPECT_NEAR(rk4_run.time, expected, 1e-12);
}

TEST(FallenEvent, SpinlessFixedTipFallsAtTheQuadratureTime) { expect_fall_at_quadrature_time(SceneType::kFixedTip); }

TEST(FallenEvent, SpinlessFrictionlessTopFallsAtTheQuadratureTime) {
  expect_fall_at_quadrature_time(SceneType::kFrictionless);
}

// The fixed tip swung down from 0.3 rad at thetadot0 = 20 rad/s: R/m = g + a_Gz with
// a_Gz = -h (cos theta thetadot^2 + sin theta thetaddot), thetaddot = c sin theta, starts at
// 1.7 m/s^2 and falls through 0 as the top speeds up: the pivot would have to pull the tip down.
TEST(LiftOffEvent, SpinlessFixedTipLiftsOffWhereTheNormalForceOfTheEnergyIntegralVanishes) {
  const TopParameters p = toy_top();
  const PlanarFall swing{p.mass * p.gravity * p.tip_distance / p.inertia_about_tip(), 0.0, 0.3, 20.0};
  auto normal_force = [&](double theta) {
    const double thetadot = swing.rate(theta);
    return p.mass * (p.gravity - p.tip_distance * (std::cos(theta) * thetadot * thetadot +
                                                  std::sin(theta) * swing.c * std::sin(theta)));
  };
  ASSERT_GT(normal_force(0.3), 0.0);
  const std::vector<double> zeros = roots_in(normal_force, 0.3, 0.5 * M_PI, 1000);
  ASSERT_FALSE(zeros.empty());
  const double expected = swing.time_to(zeros.front());
  const InitialConditions ic = spinless(0.3, 20.0);
  const EventRun adaptive_run = run_until_event(adaptive(SceneType::kFixedTip, ic, 1e-12), 1.0);
  const EventRun rk4_run = run_until_event(fixed_step(SceneType::kFixedTip, ic, 1e-4), 1.0);
  std::printf("[ measured ] fixed tip lift-off at theta %.6f: quadrature %.15g s, dopri5 %+.3g s, rk4 %+.3g s, "
              "R at the event %.3g / %.3g N\n", zeros.front(), expected, adaptive_run.time - expected,
              rk4_run.time - expected, adaptive_run.last.outputs.normal_force, rk4_run.last.outputs.normal_force);
  for (const EventRun* run : {&adaptive_run, &rk4_run}) {
    EXPECT_EQ(run->event, Event::kLiftOff);
    // The event is located to a few ulps of t before the root and R falls at ~1e2 N/s there,
    // so R just before the event is 0+ (measured <= 1.6e-15 N); 1e-12 N is ~1e-11 of m g.
    EXPECT_GE(run->last.outputs.normal_force, 0.0);
    EXPECT_LT(run->last.outputs.normal_force, 1e-12);
    EXPECT_GT(cos_tilt(run->last), 0.0);  // lifted off before falling
  }
  // As for the fall: measured dopri5 +1.5e-13 s, rk4 -1.3e-16 s; 1e-12 s bounds both.
  EXPECT_NEAR(adaptive_run.time, expected, 1e-12);
  EXPECT_NEAR(rk4_run.time, expected, 1e-12);
}

// With spin (no closed form): a fast top kicked at thetadot0 = 15 rad/s (R(0) = 0.51 N) nutates
// with thetaddot ~ 1e3 rad/s^2, and h sin(theta) thetaddot pulls R below 0 at ~0.043 s (at 10
// rad/s it does not within 1 s). The adaptive run's event time is checked against rk4 at 2e-5 s.
TEST(LiftOffEvent, SpinningFixedTipLiftOffTimeAgreesBetweenIntegrators) {
  InitialConditions ic = spinless(0.3, 15.0);
  ic.spin = 150.0;
  const EventRun adaptive_run = run_until_event(adaptive(SceneType::kFixedTip, ic, 1e-12), 1.0);
  const EventRun rk4_run = run_until_event(fixed_step(SceneType::kFixedTip, ic, 2e-5), 1.0);
  std::printf("[ measured ] spinning lift-off: dopri5 %.15g s, rk4 %+.3g s from it, R %.3g / %.3g N\n",
              adaptive_run.time, rk4_run.time - adaptive_run.time, adaptive_run.last.outputs.normal_force,
              rk4_run.last.outputs.normal_force);
  EXPECT_EQ(adaptive_run.event, Event::kLiftOff);
  EXPECT_EQ(rk4_run.event, Event::kLiftOff);
  EXPECT_GT(adaptive_run.time, 0.0);  // R(0) > 0: a crossing, not a refusal of the initial state
  EXPECT_GE(adaptive_run.last.outputs.normal_force, 0.0);
  EXPECT_LT(adaptive_run.last.outputs.normal_force, 1e-12);  // as for the spinless case
  EXPECT_NEAR(rk4_run.time, adaptive_run.time, 1e-12);       // measured 2.5e-14 s apart
}

}  // namespace
}  // namespace spinning_top
