// The two conservative scenes, fixed tip and frictionless (PHYSICS.md, "Invariants and
// balances"): steady precession from the quadratic, nutation turning points from the cubic in
// u = cos(theta), conservation of E, L_z and omega_Z with an error that shrinks at the method's
// order, and (frictionless) G's horizontal position at rest.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

#include "core_test_support.hpp"

namespace spinning_top {
namespace {
using namespace core_test;

/// Starts exactly on a steady precession (theta0, Omega a root of the quadratic, thetadot0 = 0)
/// and returns {max |theta - theta0|, max |phi - Omega t|} over the run.
std::pair<double, double> steady_precession_deviation(SceneType scene, double transverse_inertia, bool fast) {
  const TopParameters p = toy_top();
  InitialConditions ic;
  ic.tilt = 0.3;
  ic.spin = 150.0;
  const auto rates = steady_precession_rates(transverse_inertia, p, ic.tilt, ic.spin);
  ic.precession_rate = fast ? rates.second : rates.first;
  auto sim = make_simulator(adaptive(scene, ic, 1e-12));
  double tilt_error = 0.0, heading_error = 0.0, unwrapped = 0.0, previous = heading(sim->snapshot());
  const double dt = 5e-4;  // < 0.06 rad of the fast precession per sample: unwrapping is safe
  for (int i = 1; i <= 2000; ++i) {
    EXPECT_EQ(sim->advance_to(i * dt), Event::kNone);
    const Snapshot s = sim->snapshot();
    const double phi = heading(s);
    unwrapped += std::remainder(phi - previous, 2.0 * M_PI);
    previous = phi;
    tilt_error = std::max(tilt_error, std::abs(tilt(s) - ic.tilt));
    heading_error = std::max(heading_error, std::abs(unwrapped - ic.precession_rate * s.time));
  }
  return {tilt_error, heading_error};
}

// dopri5 at tolerance 1e-12 over 1 s: the steady state is an exact solution, so what remains is
// the integration error. Measured (both scenes, both roots): tilt <= 4e-12 rad, heading <= 1.5e-11
// rad. Bounds 1e-10 / 1e-9 rad keep a 25x margin and still fail for a precession rate off the root
// by 1e-8 (slow: measured tilt deviation 1.2e-10) or 2e-10 (fast: 5.7e-9 per 1e-8) relative.
TEST(FixedTipSteadyPrecession, SlowRootOfTheQuadraticStaysSteady) {
  const auto [tilt_error, heading_error] =
      steady_precession_deviation(SceneType::kFixedTip, toy_top().inertia_about_tip(), false);
  report("fixed tip slow precession: max |theta - theta0| [rad]", tilt_error);
  report("fixed tip slow precession: max |phi - Omega t| [rad]", heading_error);
  EXPECT_LT(tilt_error, 1e-10);
  EXPECT_LT(heading_error, 1e-9);
}

TEST(FixedTipSteadyPrecession, FastRootOfTheQuadraticStaysSteady) {
  const auto [tilt_error, heading_error] =
      steady_precession_deviation(SceneType::kFixedTip, toy_top().inertia_about_tip(), true);
  report("fixed tip fast precession: max |theta - theta0| [rad]", tilt_error);
  report("fixed tip fast precession: max |phi - Omega t| [rad]", heading_error);
  EXPECT_LT(tilt_error, 1e-10);
  EXPECT_LT(heading_error, 1e-9);
}

/// The extremes of cos(theta) over a run from thetadot0 = 0 against the two roots of the
/// cubic in [-1, 1]: returns the largest deviation of any maximum from the upper root and of
/// any minimum from the lower one.
double turning_point_error(SceneType scene, double transverse_inertia, const InitialConditions& ic,
                           double duration) {
  const TopParameters p = toy_top();
  auto sim = make_simulator(adaptive(scene, ic, 1e-12));
  const TurningPointCubic f = turning_point_cubic(transverse_inertia, p, ic.spin, sim->snapshot());
  const std::vector<double> roots = roots_in(f, -1.0, 1.0);
  EXPECT_EQ(roots.size(), 2u) << "a nutating top has exactly two turning points in [-1, 1]";
  if (roots.size() != 2u) return INFINITY;
  const double lower = roots[0], upper = roots[1];
  report("turning points: upper root - lower root (cos theta)", upper - lower);
  // Samples every 1e-4 s: ~300 per nutation period; the parabola's vertex error (dt w)^4 u_amp
  // <= (1e-2)^4 * 2e-3 ~ 2e-11 in u (a bound: the measured total is 5e-13).
  const Extrema e = sampled_extrema(sample_cos_tilt(*sim, 1e-4, duration));
  EXPECT_GE(e.maxima.size(), 3u);
  EXPECT_GE(e.minima.size(), 3u);
  double error = 0.0;
  for (double u : e.maxima) error = std::max(error, std::abs(u - upper));
  for (double u : e.minima) error = std::max(error, std::abs(u - lower));
  return error;
}

// Nutation amplitude (upper - lower root) is 2e-3 in u; measured deviation 5e-13 (fixed tip),
// 2e-12 (frictionless). 1e-10 keeps a 50x margin; A in place of A0 moves the lower root by 1e-3.
TEST(FixedTipNutation, ExtremesOfCosThetaAreTheRootsOfTheCubic) {
  InitialConditions ic;
  ic.tilt = 0.3;
  ic.spin = 150.0;
  ic.precession_rate = 1.0;  // off the steady roots (2.2 and 115 rad/s): the top nutates
  const double error = turning_point_error(SceneType::kFixedTip, toy_top().inertia_about_tip(), ic, 0.3);
  report("fixed tip: max |extreme of cos theta - root of cubic|", error);
  EXPECT_LT(error, 1e-10);
}

/// Relative errors of E and L_z (against t = 0) after `duration` with rk4 at `step`, and
/// the largest deviation of omega_Z from the initial spin.
struct InvariantErrors {
  double energy = 0.0, vertical_momentum = 0.0, spin = 0.0;
};
InvariantErrors rk4_invariant_errors(SceneType scene, double step, double duration) {
  InitialConditions ic;
  ic.tilt = 0.3;
  ic.spin = 150.0;
  ic.precession_rate = 5.0;
  ic.nutation_rate = 2.0;
  auto sim = make_simulator(fixed_step(scene, ic, step));
  const Snapshot s0 = sim->snapshot();
  InvariantErrors e;
  for (int i = 1; i <= 100; ++i) {
    EXPECT_EQ(sim->advance_to(duration * i / 100), Event::kNone);
    const Snapshot s = sim->snapshot();
    e.energy = std::max(e.energy, std::abs(s.outputs.energy - s0.outputs.energy) / s0.outputs.energy);
    e.vertical_momentum = std::max(e.vertical_momentum, std::abs(s.outputs.vertical_angular_momentum -
                                                                 s0.outputs.vertical_angular_momentum) /
                                                            std::abs(s0.outputs.vertical_angular_momentum));
    e.spin = std::max(e.spin, std::abs(s.body_rates.z() - ic.spin));
  }
  return e;
}

void expect_fourth_order_conservation(SceneType scene, const char* name) {
  const InvariantErrors coarse = rk4_invariant_errors(scene, 2e-3, 1.0);
  const InvariantErrors fine = rk4_invariant_errors(scene, 1e-3, 1.0);
  const double energy_ratio = coarse.energy / fine.energy;
  const double momentum_ratio = coarse.vertical_momentum / fine.vertical_momentum;
  std::printf("[ measured ] %s rk4 relative errors: E %.3g -> %.3g (ratio %.3g), L_z %.3g -> %.3g (ratio %.3g)\n",
              name, coarse.energy, fine.energy, energy_ratio, coarse.vertical_momentum, fine.vertical_momentum,
              momentum_ratio);
  // rk4's global error is O(dt^4), but its error in the invariants is one order higher: on
  // the oscillatory motion it is dissipative, |R(i y)|^2 = 1 - y^6/72 per step (Hairer, Norsett,
  // Wanner, Solving ODEs I, sec. IV.2), summed over 1/dt steps: O(dt^5), ratio 2^5 = 32 when dt
  // halves. Measured orders 4.95-4.99 for dt = 4e-3 ... 2.5e-4 in both scenes; +-0.3 rejects
  // both order 4 (the state's) and order 6.
  EXPECT_NEAR(std::log2(energy_ratio), 5.0, 0.3);
  EXPECT_NEAR(std::log2(momentum_ratio), 5.0, 0.3);
  // The constant in C dt^5 (a scale check): measured E 2.2e-9 (fixed tip) and 1.1e-9
  // (frictionless), L_z 7.7e-8 and 2.7e-8 at dt = 1 ms; 3x above the larger is a genuine bound.
  EXPECT_LT(fine.energy, 7e-9);
  EXPECT_LT(fine.vertical_momentum, 2.5e-7);
  // omega_Z is a constant of the model (a parameter, not a state): exactly conserved.
  EXPECT_EQ(coarse.spin, 0.0);
  EXPECT_EQ(fine.spin, 0.0);
}

TEST(FixedTipInvariants, EnergyVerticalMomentumAndSpinConservedToFourthOrderWithRk4) {
  expect_fourth_order_conservation(SceneType::kFixedTip, "fixed tip");
}

// The frictionless top conserves the same invariants (L_z about the vertical through G).
TEST(FrictionlessInvariants, EnergyVerticalMomentumAndSpinConservedToFourthOrderWithRk4) {
  expect_fourth_order_conservation(SceneType::kFrictionless, "frictionless");
}

// Frictionless: G stays put horizontally, so the quadratic holds with A in place of A0.
TEST(FrictionlessSteadyPrecession, SlowRootOfTheQuadraticWithAStaysSteady) {
  const auto [tilt_error, heading_error] =
      steady_precession_deviation(SceneType::kFrictionless, toy_top().inertia_transverse, false);
  report("frictionless slow precession: max |theta - theta0| [rad]", tilt_error);
  report("frictionless slow precession: max |phi - Omega t| [rad]", heading_error);
  EXPECT_LT(tilt_error, 1e-10);  // as for the fixed tip
  EXPECT_LT(heading_error, 1e-9);
}

TEST(FrictionlessSteadyPrecession, FastRootOfTheQuadraticWithAStaysSteady) {
  const auto [tilt_error, heading_error] =
      steady_precession_deviation(SceneType::kFrictionless, toy_top().inertia_transverse, true);
  report("frictionless fast precession: max |theta - theta0| [rad]", tilt_error);
  report("frictionless fast precession: max |phi - Omega t| [rad]", heading_error);
  EXPECT_LT(tilt_error, 1e-10);  // as for the fixed tip
  EXPECT_LT(heading_error, 1e-9);
}

// The frictionless u'^2 is the cubic with A divided by 1 + (m h^2/A)(1 - u^2) > 0: same roots.
TEST(FrictionlessNutation, ExtremesOfCosThetaAreTheRootsOfTheCubicWithA) {
  InitialConditions ic;
  ic.tilt = 0.3;
  ic.spin = 150.0;
  ic.precession_rate = 1.0;
  const double error = turning_point_error(SceneType::kFrictionless, toy_top().inertia_transverse, ic, 0.3);
  report("frictionless: max |extreme of cos theta - root of cubic|", error);
  EXPECT_LT(error, 1e-10);  // as for the fixed tip
}

// No horizontal force: G's horizontal momentum stays zero and its position stays where the
// tip at the origin put it, h e_Z(0) horizontally, while the tip slides.
TEST(FrictionlessCentreOfMass, HorizontalPositionOfGIsConstantWhileTheTipSlides) {
  InitialConditions ic;
  ic.tilt = 0.4;
  ic.spin = 150.0;
  ic.precession_rate = 5.0;
  ic.nutation_rate = 2.0;
  auto sim = make_simulator(adaptive(SceneType::kFrictionless, ic, 1e-11));
  const Snapshot s0 = sim->snapshot();
  const Vector3 g0 = s0.outputs.center_of_mass;
  EXPECT_NEAR(g0.x(), toy_top().tip_distance * axis_of(s0).x(), 1e-15);  // tip at the origin
  EXPECT_NEAR(g0.y(), toy_top().tip_distance * axis_of(s0).y(), 1e-15);
  double g_drift = 0.0, tip_travel = 0.0, height_error = 0.0, tip_on_line = 0.0;
  for (int i = 1; i <= 200; ++i) {
    EXPECT_EQ(sim->advance_to(0.005 * i), Event::kNone);
    const Snapshot s = sim->snapshot();
    const Vector3 g = s.outputs.center_of_mass, e = axis_of(s);
    g_drift = std::max(g_drift, std::hypot(g.x() - g0.x(), g.y() - g0.y()) + std::abs(s.outputs.center_of_mass_velocity.x()) +
                                    std::abs(s.outputs.center_of_mass_velocity.y()));
    tip_travel = std::max(tip_travel, s.outputs.contact_point.head<2>().norm());
    height_error = std::max(height_error, std::abs(g.z() - toy_top().tip_distance * e.z()));
    // r_G = r_P + h e_Z with the tip on the floor.
    tip_on_line = std::max(tip_on_line, (s.outputs.contact_point + toy_top().tip_distance * e - g).norm());
  }
  report("frictionless: max horizontal drift of G [m]", g_drift);
  report("frictionless: tip's largest distance from its start [m]", tip_travel);
  EXPECT_EQ(g_drift, 0.0);        // G's horizontal position is a constant of the scene's state
  EXPECT_GT(tip_travel, 1e-3);    // ...while the tip really slides (a millimetre or more)
  EXPECT_LT(height_error, 1e-15);  // z_G = h e_Zz to round-off
  EXPECT_LT(tip_on_line, 1e-15);
}

}  // namespace
}  // namespace spinning_top
