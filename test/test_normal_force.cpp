// The normal force in the two cases where it is m g exactly (PHYSICS.md, "Invariants and
// balances"): a sleeping top (theta = 0, G at rest at height h) and h = 0 (the tip is G: no
// torque, the three scenes coincide and the free symmetric top precesses in closed form).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <complex>

#include "core_test_support.hpp"

namespace spinning_top {
namespace {
using namespace core_test;

constexpr SceneType kAllScenes[] = {SceneType::kFixedTip, SceneType::kFrictionless, SceneType::kViscous};

TopParameters with_friction_in(SceneType scene, TopParameters top, double k) {
  top.friction = scene == SceneType::kViscous ? k : 0.0;
  return top;
}

// Stable sleeping (C^2 wZ^2 = 8.1e-5 > 4 A0 m g h = 6.3e-6): upright, at rest but for the spin,
// so a_G = 0 and R = m g. Run with each scene's default integrator (auto) and with dopri5.
TEST(SleepingTop, NormalForceIsWeightInEveryScene) {
  for (SceneType scene : kAllScenes) {
    for (IntegratorType integrator : {IntegratorType::kAuto, IntegratorType::kDopri5}) {
      InitialConditions ic;
      ic.tilt = 0.0;
      ic.spin = 150.0;
      SceneConfig config = adaptive(scene, ic, 1e-10, with_friction_in(scene, toy_top(), 1.0));
      config.integrator.type = integrator;
      auto sim = make_simulator(config);
      const double weight = config.top.mass * config.top.gravity;
      double force_error = std::abs(sim->snapshot().outputs.normal_force - weight), tilt_reached = 0.0;
      for (int i = 1; i <= 100; ++i) {
        ASSERT_EQ(sim->advance_to(0.01 * i), Event::kNone);
        const Snapshot s = sim->snapshot();
        force_error = std::max(force_error, std::abs(s.outputs.normal_force - weight));
        tilt_reached = std::max(tilt_reached, tilt(s));
      }
      std::printf("[ measured ] sleeping top, %s, %s: max |R - m g| %.3g N, max tilt %.3g rad\n", to_string(scene),
                  sim->integrator_description().c_str(), force_error, tilt_reached);
      // Upright exactly: Gamma = (0, 0, 1), w_perp = 0 are kept exactly by every method, so R is
      // m g to round-off; 1e-14 N is ~10 ulps of m g.
      EXPECT_LT(force_error, 1e-14) << to_string(scene) << " " << sim->integrator_description();
      EXPECT_LT(tilt_reached, 1e-14) << to_string(scene) << " " << sim->integrator_description();
    }
  }
}

// h = 0: no gravity torque, so A wX' = (A - C) wY wZ, A wY' = -(A - C) wZ wX: w_perp turns in
// the body at the rate (A - C) wZ / A, i.e. wX + i wY = (wX0 + i wY0) exp(-i (A - C) wZ t / A),
// and the angular momentum L = q (A wX, A wY, C wZ) is fixed in the world.
TEST(ZeroTipDistance, NormalForceIsWeightAndTheMotionIsTorqueFreeInEveryScene) {
  TopParameters top = toy_top();
  top.tip_distance = 0.0;
  InitialConditions ic;
  ic.tilt = 0.3;
  ic.spin = 150.0;
  ic.precession_rate = 5.0;
  ic.nutation_rate = 2.0;
  const double a = top.inertia_transverse, c = top.inertia_axial, weight = top.mass * top.gravity;
  const double body_rate = (a - c) * ic.spin / a;
  for (SceneType scene : kAllScenes) {
    auto sim = make_simulator(adaptive(scene, ic, 1e-12, with_friction_in(scene, top, 1.0)));
    const Snapshot s0 = sim->snapshot();
    const std::complex<double> w0(s0.body_rates.x(), s0.body_rates.y());
    const Vector3 l0 = s0.attitude * Vector3(a * s0.body_rates.x(), a * s0.body_rates.y(), c * ic.spin);
    double force_error = 0.0, rate_error = 0.0, momentum_error = 0.0;
    for (int i = 1; i <= 100; ++i) {
      ASSERT_EQ(sim->advance_to(0.005 * i), Event::kNone);
      const Snapshot s = sim->snapshot();
      const std::complex<double> expected = w0 * std::exp(std::complex<double>(0.0, -body_rate * s.time));
      const Vector3 l = s.attitude * Vector3(a * s.body_rates.x(), a * s.body_rates.y(), c * ic.spin);
      force_error = std::max(force_error, std::abs(s.outputs.normal_force - weight));
      rate_error = std::max(rate_error, std::abs(std::complex<double>(s.body_rates.x(), s.body_rates.y()) - expected));
      momentum_error = std::max(momentum_error, (l - l0).norm() / l0.norm());
    }
    std::printf("[ measured ] h = 0, %s: max |R - m g| %.3g N, max |w_perp - closed form| %.3g rad/s, "
                "max |L - L0|/|L0| %.3g\n", to_string(scene), force_error, rate_error, momentum_error);
    // R = m g holds identically for h = 0 (a_Gz = h (...) = 0): measured at round-off, 1e-14 N.
    EXPECT_LT(force_error, 1e-14) << to_string(scene);
    // dopri5 at 1e-12 over 0.5 s (12 turns of w_perp at 150 rad/s): measured rate error <= 3.2e-11
    // rad/s of |w_perp| ~ 2.5 rad/s and L drift <= 6e-14; bounds ~100x above.
    EXPECT_LT(rate_error, 3e-9) << to_string(scene);
    EXPECT_LT(momentum_error, 1e-11) << to_string(scene);
  }
}

// Steady precession at the fixed tip: G circles horizontally at radius h sin(theta) with rate
// Omega, so a_Gz = 0 (R = m g) and the pivot supplies the centripetal force -m Omega^2 r_G,xy.
TEST(SteadyPrecession, PivotForceIsWeightPlusCentripetalForceOfG) {
  for (bool fast : {false, true}) {
    const TopParameters top = toy_top();
    InitialConditions ic;
    ic.tilt = 0.3;
    ic.spin = 150.0;
    const auto rates = steady_precession_rates(top.inertia_about_tip(), top, ic.tilt, ic.spin);
    ic.precession_rate = fast ? rates.second : rates.first;
    auto sim = make_simulator(adaptive(SceneType::kFixedTip, ic, 1e-12));
    const double weight = top.mass * top.gravity;
    const double centripetal = top.mass * ic.precession_rate * ic.precession_rate;
    double normal_error = 0.0, horizontal_error = 0.0, horizontal = 0.0;
    for (int i = 0; i <= 100; ++i) {
      ASSERT_EQ(sim->advance_to(0.005 * i), Event::kNone);
      const Snapshot s = sim->snapshot();
      const Vector3 g = s.outputs.center_of_mass;
      const Vector3 expected(-centripetal * g.x(), -centripetal * g.y(), 0.0);
      normal_error = std::max(normal_error, std::abs(s.outputs.normal_force - weight));
      horizontal_error = std::max(horizontal_error, (s.outputs.contact_force - expected).norm());
      horizontal = std::max(horizontal, expected.norm());
    }
    std::printf("[ measured ] fixed tip %s steady precession: max |R - m g| %.3g N, centripetal force %.3g N, "
                "max |F_h - expected| %.3g N\n", fast ? "fast" : "slow", normal_error, horizontal, horizontal_error);
    // The state stays on the steady solution to ~1e-11 (test_conservative_scenes), and R and F
    // are smooth functions of it with O(m h Omega^2) ~ 1e2 N per unit state error at the fast
    // root: measured |R - m g| <= 1.0e-12 N, |F_h - expected| <= 5.1e-12 N (F_h = 7.9 N at the
    // fast root); 1e-9 N leaves 200x and is ~1e-9 of the forces.
    EXPECT_LT(normal_error, 1e-9);
    EXPECT_LT(horizontal_error, 1e-9);
  }
}

}  // namespace
}  // namespace spinning_top
