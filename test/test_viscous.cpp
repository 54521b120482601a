// Viscous friction F = -k v_P (PHYSICS.md, "Viscous"): the energy balance dE/dt = -k |v_P|^2
// (which catches erratum 3, the dropped v_Gz in v_P), k = 0 is the frictionless top, and
// growing k approaches the fixed tip.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

#include "core_test_support.hpp"

namespace spinning_top {
namespace {
using namespace core_test;

/// A nutating top (thetadot0 = 5 rad/s, so that v_Gz = h thetadot sin(theta) is at times larger
/// than the tip's speed) whose G also slides at 5 cm/s, against k = 1 N s/m (m/k = 0.1 s).
/// R stays above 0.29 N over 0.5 s (at thetadot0 = 8 rad/s the tip lifts off at 0.02 s).
SceneConfig nutating_viscous_top(double tolerance) {
  InitialConditions ic;
  ic.tilt = 0.4;
  ic.spin = 150.0;
  ic.precession_rate = 5.0;
  ic.nutation_rate = 5.0;
  ic.velocity_x = 0.05;
  TopParameters top = toy_top();
  top.friction = 1.0;
  return adaptive(SceneType::kViscous, ic, tolerance, top);
}

TEST(ViscousEnergyBalance, EnergyPlusDissipatedWorkIsTheInitialEnergy) {
  auto sim = make_simulator(nutating_viscous_top(1e-12));
  const double e0 = sim->snapshot().outputs.energy;
  double imbalance = 0.0, dissipated = 0.0;
  for (int i = 1; i <= 100; ++i) {
    ASSERT_EQ(sim->advance_to(0.005 * i), Event::kNone);
    const Snapshot s = sim->snapshot();
    imbalance = std::max(imbalance, std::abs(s.outputs.energy + s.outputs.dissipated_energy - e0));
    dissipated = s.outputs.dissipated_energy;
  }
  report("viscous: dissipated work W(0.5 s) [J]", dissipated);
  report("viscous: max |E + W - E(0)| [J]", imbalance);
  // W is integrated with the state, so the balance holds to the integration error: measured
  // 8.9e-15 J (a few ulps of E ~ 0.7 J) against W = 6.7e-4 J; 1e-12 J leaves 100x.
  EXPECT_GT(dissipated, 1e-4);  // friction does real work in this case
  EXPECT_LT(imbalance, 1e-12);
}

// dE/dt from the energy output alone (5-point central differences on dense output) against
// -k |v_P|^2, with v_P = v_G - h w x e_Z rebuilt here from the snapshot (G's velocity,
// attitude and body rates), not taken from the model. Erratum 3's model would dissipate
// -k (|v_P|^2 + v_Gz^2); the test checks that this case tells the two apart by far more than
// the tolerance, so a core with the erratum fails it.
TEST(ViscousEnergyBalance, EnergyDecaysAtKTimesTipSpeedSquaredNotTheErratumRate) {
  const SceneConfig config = nutating_viscous_top(1e-13);
  const double k = config.top.friction, h = config.top.tip_distance;
  auto sim = make_simulator(config);
  const double delta = 2e-4;  // (delta w)^4 / 30 ~ 1e-8 relative at the nutation's w ~ 230 rad/s
  double largest_error = 0.0, erratum_gap = 0.0, largest_rate = 0.0, vertical_tip_speed = 0.0;
  for (int i = 1; i <= 100; ++i) {
    const double t = 0.005 * i;
    double e[5];
    Snapshot centre;
    for (int j = 0; j < 5; ++j) {
      ASSERT_EQ(sim->advance_to(t + (j - 2) * delta), Event::kNone);
      const Snapshot s = sim->snapshot();
      e[j] = s.outputs.energy;
      if (j == 2) centre = s;
    }
    const double measured_rate = (e[0] - 8.0 * e[1] + 8.0 * e[3] - e[4]) / (12.0 * delta);
    const Vector3 v_p = tip_velocity(centre, h);
    const double v_gz = centre.outputs.center_of_mass_velocity.z();
    const double balance_rate = -k * v_p.squaredNorm();
    const double erratum_rate = -k * (v_p.squaredNorm() + v_gz * v_gz);
    largest_error = std::max(largest_error, std::abs(measured_rate - balance_rate));
    largest_rate = std::max(largest_rate, std::abs(balance_rate));
    erratum_gap = std::max(erratum_gap, std::abs(erratum_rate - balance_rate));
    vertical_tip_speed = std::max(vertical_tip_speed, std::abs(v_p.z()));
  }
  report("viscous: largest -dE/dt [W]", largest_rate);
  report("viscous: max |dE/dt + k |v_P|^2| [W]", largest_error);
  report("viscous: largest |erratum rate - true rate| [W]", erratum_gap);
  report("viscous: max |v_Pz| [m/s]", vertical_tip_speed);
  // The difference quotient's error: truncation ~1e-8 relative plus the dense output's
  // 1e-13-level error divided by delta (~1e-9 W); measured 2.1e-9 W against rates up to
  // 1.5e-2 W. 1e-7 W (50x) is 1e-5 of the rate; the erratum's rate differs by 1.3e-3 W.
  EXPECT_LT(largest_error, 1e-7);
  EXPECT_GT(erratum_gap, 1e3 * 1e-7);  // the case does discriminate erratum 3
  EXPECT_LT(vertical_tip_speed, 1e-15);          // the constraint keeps v_P horizontal (round-off)
}

TEST(ViscousLimits, ZeroFrictionReproducesTheFrictionlessTop) {
  InitialConditions ic;
  ic.tilt = 0.4;
  ic.spin = 150.0;
  ic.precession_rate = 5.0;
  ic.nutation_rate = 5.0;
  auto viscous = make_simulator(adaptive(SceneType::kViscous, ic, 1e-12));
  auto frictionless = make_simulator(adaptive(SceneType::kFrictionless, ic, 1e-12));
  double attitude = 0.0, rates = 0.0, normal_force = 0.0, centre_of_mass = 0.0;
  for (int i = 1; i <= 100; ++i) {
    ASSERT_EQ(viscous->advance_to(0.005 * i), Event::kNone);
    ASSERT_EQ(frictionless->advance_to(0.005 * i), Event::kNone);
    const Snapshot a = viscous->snapshot(), b = frictionless->snapshot();
    attitude = std::max(attitude, attitude_difference(a.attitude, b.attitude));
    rates = std::max(rates, (a.body_rates - b.body_rates).norm());
    normal_force = std::max(normal_force, std::abs(a.outputs.normal_force - b.outputs.normal_force));
    centre_of_mass = std::max(centre_of_mass, (a.outputs.center_of_mass - b.outputs.center_of_mass).norm());
  }
  report("viscous k = 0 vs frictionless: max attitude difference [rad]", attitude);
  report("viscous k = 0 vs frictionless: max |body rate difference| [rad/s]", rates);
  report("viscous k = 0 vs frictionless: max |R difference| [N]", normal_force);
  report("viscous k = 0 vs frictionless: max |G difference| [m]", centre_of_mass);
  // Same equations, different state vectors and step sequences: the difference is the two
  // runs' integration errors, measured 5e-13 rad / 3.1e-11 rad/s / 4e-12 N / 1.9e-15 m;
  // bounds ~100x above.
  EXPECT_LT(attitude, 1e-10);
  EXPECT_LT(rates, 3e-9);
  EXPECT_LT(normal_force, 1e-10);
  EXPECT_LT(centre_of_mass, 1e-13);
}

/// Largest angle between the axes of a viscous top with friction k and of the fixed tip,
/// started with G's velocity equal to the fixed tip's (so that v_P(0) = 0), over 0.1 s.
double deviation_from_fixed_tip(double k) {
  InitialConditions ic;
  ic.tilt = 0.3;
  ic.spin = 150.0;
  ic.precession_rate = 5.0;
  ic.nutation_rate = 2.0;
  auto fixed = make_simulator(adaptive(SceneType::kFixedTip, ic, 1e-11));
  const Vector3 v_g = fixed->snapshot().outputs.center_of_mass_velocity;
  ic.velocity_x = v_g.x();
  ic.velocity_y = v_g.y();
  TopParameters top = toy_top();
  top.friction = k;
  auto viscous = make_simulator(adaptive(SceneType::kViscous, ic, 1e-11, top));
  double deviation = 0.0;
  for (int i = 1; i <= 50; ++i) {
    EXPECT_EQ(fixed->advance_to(0.002 * i), Event::kNone);
    EXPECT_EQ(viscous->advance_to(0.002 * i), Event::kNone);
    deviation = std::max(deviation, std::acos(std::min(1.0, axis_of(fixed->snapshot()).dot(axis_of(viscous->snapshot())))));
  }
  return deviation;
}

// PHYSICS.md erratum 9: the fixed tip is the k -> infinity limit; v_P relaxes at the rate
// lambda = k (1/m + h^2/A), so the tip slips at O(1/k) and the axis drifts away from the fixed
// tip's at a rate first order in m/k. dopri5 follows the stiff relaxation with steps ~3/lambda
// (m/k = 1e-5 s: lambda = 2e5 1/s, ~3e4 steps over 0.1 s, cheap).
TEST(ViscousLimits, LargeFrictionApproachesTheFixedTipAtFirstOrderInMOverK) {
  const double d3 = deviation_from_fixed_tip(1e2), d4 = deviation_from_fixed_tip(1e3),
               d5 = deviation_from_fixed_tip(1e4);
  std::printf("[ measured ] viscous vs fixed tip, max axis angle over 0.1 s [rad]: m/k = 1e-3 s %.4g, "
              "1e-4 s %.4g, 1e-5 s %.4g\n", d3, d4, d5);
  // Measured deviations 9.0e-3, 1.16e-3, 1.19e-4 rad: ratios per decade of k 7.8 (not yet
  // asymptotic: lambda = 2e3 1/s is only 18x the nutation rate) and 9.7. First order means ~10 once lambda is far
  // above the nutation; 8 to 12 excludes order 0 (no convergence) and order 2 (100).
  EXPECT_GT(d3 / d4, 4.0);
  EXPECT_GT(d4 / d5, 8.0);
  EXPECT_LT(d4 / d5, 12.0);
}

}  // namespace
}  // namespace spinning_top
