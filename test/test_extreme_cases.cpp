// Stiff and extreme cases (issue 4; doc/extreme_cases.md): one test per scene file in
// config/extreme/, loaded through the batch simulator's path (flatten the YAML, then
// parse_scene_config(values, true)) and advanced in steps of 1 ms as the node does, with the
// default integrator unless the case is about a specific one. Each test asserts a physical
// expectation derived in the scene file's comment and that every output stays finite.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <limits>
#include <string>

#include "extreme_cases.hpp"

#ifndef SPINNING_TOP_SOURCE_DIR
#error "SPINNING_TOP_SOURCE_DIR must name the package's source directory"
#endif

namespace spinning_top {
namespace extreme {
namespace {

std::string scene_file(const std::string& name) {
  return std::string(SPINNING_TOP_SOURCE_DIR) + "/config/extreme/" + name + ".yaml";
}

double mgh(const SceneConfig& c) { return c.top.mass * c.top.gravity * c.top.tip_distance; }

/// |L(0)| about the pivot (fixed tip) or G (frictionless): the scale of L_z.
double angular_momentum_scale(const SceneConfig& c) {
  const Vector3 w = initial_body_rates(c.initial);
  const double a = c.scene == SceneType::kFixedTip ? c.top.inertia_about_tip() : c.top.inertia_transverse;
  return std::hypot(a * std::hypot(w.x(), w.y()), c.top.inertia_axial * w.z());
}

/// Prints what was measured, so that a failing tolerance shows its number (and `--gtest_filter`
/// runs double as a quick table).
void report(const char* what, double value) {
  std::printf("  [measured] %-44s %.6g\n", what, value);
  ::testing::Test::RecordProperty(what, std::to_string(value));
}

/// Every case: every output finite (the core never lets a NaN out), and no kNonFinite event.
void expect_finite(const CaseRun& run) {
  EXPECT_TRUE(run.all_finite);
  EXPECT_NE(run.event, Event::kNonFinite) << "the solution could not be continued with finite values";
  std::printf("  [integrator] %s, %zu samples, t_end %.6g s\n", run.integrator.c_str(), run.samples.size(),
              run.end_time());
}

/// The conservative scenes' invariants. Tolerances are physical, not the method's: an energy
/// error of 1e-6 m g h is a height error of G of 1e-6 h (20 nm for the toy top), and an L_z error
/// of 1e-6 |L| a 1 microradian error in the direction of L; both far above round-off (1e-16 E0)
/// and far below anything visible. omega_Z is a constant of the model: exactly conserved.
void expect_invariants(const SceneConfig& c, const CaseRun& run) {
  const double de = max_abs_energy_change(run), dl = max_abs_lz_change(run);
  report("max |E - E0| / (m g h)", de / mgh(c));
  report("max |Lz - Lz0| / |L0|", dl / angular_momentum_scale(c));
  EXPECT_LE(de, 1e-6 * mgh(c));
  EXPECT_LE(dl, 1e-6 * angular_momentum_scale(c));
  for (const Snapshot& s : run.samples) ASSERT_EQ(s.body_rates.z(), c.initial.spin);
}

/// theta stays between the cubic's roots theta0 and theta1 (exact solution), to 0.1 % of the
/// nutation amplitude (the resolution at which this test claims the motion is right), and the
/// 1 ms samples, whose nutation phase is spread over many periods, come within 5 % of theta1.
void expect_tilt_band(const SceneConfig& c, const CaseRun& run) {
  const ReducedTop top(c);
  const auto [low, high] = top.other_roots();
  const double u1 = std::abs(high - top.u0()) < std::abs(low - top.u0()) ? high : low;
  const double theta0 = c.initial.tilt, theta1 = std::acos(u1);
  const double amplitude = theta1 - theta0, slack = 1e-3 * std::abs(amplitude);
  double lowest = INFINITY, highest = -INFINITY;
  for (const Snapshot& s : run.samples) {
    lowest = std::min(lowest, tilt_of(s));
    highest = std::max(highest, tilt_of(s));
  }
  report("theta1 (cubic) - theta0 [rad]", amplitude);
  report("(min theta - theta0) / amplitude", (lowest - theta0) / amplitude);
  report("(max theta - theta1) / amplitude", (highest - theta1) / amplitude);
  EXPECT_GE(lowest, std::min(theta0, theta1) - slack);
  EXPECT_LE(highest, std::max(theta0, theta1) + slack);
  EXPECT_GE(highest, theta0 + 0.95 * amplitude);
}

/// An event predicted by a quadrature: same kind, at the same time to 1e-5 s, i.e. 1 % of the
/// node's 1 ms step (the issue asks for events located within the step, not at step ends).
void expect_event_at(const CaseRun& run, Event expected, double t_expected) {
  report("expected event time [s]", t_expected);
  report("event time - expected [s]", run.event_time - t_expected);
  EXPECT_EQ(run.event, expected) << "got '" << to_string(run.event) << "'";
  EXPECT_NEAR(run.event_time, t_expected, 1e-5);
}

/// R >= 0 up to the event (the model's validity: a valid state is reported with it).
void expect_normal_force_non_negative(const CaseRun& run) {
  for (const Snapshot& s : run.samples) ASSERT_GE(s.outputs.normal_force, 0.0) << "at t = " << s.time;
}

// ---------------------------------------------------------------------------------------------

TEST(ExtremeCases, SleepingTopExactlyUprightStaysUprightWithNormalForceMg) {
  const SceneConfig c = load_scene(scene_file("sleeping_upright"));
  const CaseRun run = run_at_node_rate(c, 1.0);
  expect_finite(run);
  EXPECT_EQ(run.event, Event::kNone);
  const double weight = c.top.mass * c.top.gravity;
  double worst_tilt = 0.0, worst_force = 0.0;
  for (const Snapshot& s : run.samples) {
    worst_tilt = std::max(worst_tilt, tilt_of(s));
    worst_force = std::max(worst_force, std::abs(s.outputs.normal_force - weight));
  }
  report("max tilt [rad]", worst_tilt);
  report("max |R - m g| / (m g)", worst_force / weight);
  // The torque m g h e_Z x e_z is exactly zero on the axis, so omega_perp and the tilt stay exactly
  // 0 in floating point too; R = m g e_zZ with e_zZ = 1 - 2 (qx^2 + qy^2) = 1: allow 4 ulps of m g
  // for the rotation of the force into the world frame.
  EXPECT_LE(worst_tilt, 1e-15);
  EXPECT_LE(worst_force, 4.0 * std::numeric_limits<double>::epsilon() * weight);
}

TEST(ExtremeCases, StableSleepingTopKeepsATiltOfOrderItsInitialOne) {
  const SceneConfig c = load_scene(scene_file("sleeping_tilted"));
  // Over 0.5 s: about 9 beats (period 2 pi / (w+ - w-) = 58 ms) of the epicycles' tilt.
  const CaseRun run = run_at_node_rate(c, 0.5);
  expect_finite(run);
  EXPECT_EQ(run.event, Event::kNone);
  const SleepingTopLinear linear(c);
  const double theta0 = c.initial.tilt;
  double lowest = INFINITY, highest = 0.0, distance = 0.0;
  for (const Snapshot& s : run.samples) {
    const double tilt = tilt_of(s);
    lowest = std::min(lowest, tilt);
    highest = std::max(highest, tilt);
    const Vector3 e = axis_of(s);
    distance = std::max(distance, std::abs(std::complex<double>(e.x(), e.y()) - linear.sigma(s.time)));
  }
  report("linear-theory max tilt / theta0", linear.max_tilt() / theta0);
  report("min tilt / theta0", lowest / theta0);
  report("max tilt / theta0", highest / theta0);
  report("max |sigma - sigma_linear| / theta0", distance / theta0);
  // Bounded by the linear theory's [theta0, theta0 C wZ / sqrt(C^2 wZ^2 - 4 A0 m g h)] (exact to
  // O(theta0^2) = 1e-16 relative). 1 %: the adaptive integrators' absolute attitude tolerance,
  // ~1e-10, is 1 % of this tilt; the physical claim (bounded, of order theta0) needs no more.
  EXPECT_GE(lowest, theta0 * (1.0 - 1e-2));
  EXPECT_LE(highest, linear.max_tilt() * (1.0 + 1e-2));
  // The samples reach the top of the beat (they fall every 1 ms on a 58 ms beat).
  EXPECT_GE(highest, theta0 + 0.9 * (linear.max_tilt() - theta0));
  // And the axis follows the epicycles themselves, not just their envelope: within 1 % of theta0.
  EXPECT_LE(distance, 1e-2 * theta0);
}

TEST(ExtremeCases, VeryFastSpinConservesInvariantsAndNutatesAtTheGyroscopicPeriod) {
  const SceneConfig c = load_scene(scene_file("fast_spin"));
  const CaseRun run = run_at_node_rate(c, 0.2);  // ~48 nutation periods
  expect_finite(run);
  EXPECT_EQ(run.event, Event::kNone);
  expect_invariants(c, run);
  expect_tilt_band(c, run);
  // Gyroscopic stiffness: the nutation period is the quadrature's (4.19 ms, ~ 2 pi A0 / (C wZ)),
  // measured from the 1 ms tilt samples (about 4 per period, below Nyquist).
  std::vector<double> tilt;
  for (const Snapshot& s : run.samples) tilt.push_back(tilt_of(s));
  const double measured = 2.0 * M_PI / dominant_frequency(tilt, kNodeStep);
  const double expected = ReducedTop(c).nutation_period();
  report("nutation period, quadrature [s]", expected);
  report("nutation period, measured / quadrature - 1", measured / expected - 1.0);
  report("2 pi A0 / (C wZ) / quadrature - 1",
         2.0 * M_PI * c.top.inertia_about_tip() / (c.top.inertia_axial * c.initial.spin) / expected - 1.0);
  // 1e-3: the fit assumes a pure sinusoid; the elliptic theta(t)'s harmonics are O(amplitude /
  // theta0) = 2e-4 of it.
  EXPECT_NEAR(measured / expected, 1.0, 1e-3);
}

TEST(ExtremeCases, SpinBelowTheThresholdFallsAtTheQuadratureTime) {
  const SceneConfig c = load_scene(scene_file("slow_spin"));
  const CaseRun run = run_at_node_rate(c, 0.5);
  expect_finite(run);
  const ReducedTop top(c);
  ASSERT_LT(top.other_roots().first, 0.0) << "the cubic's lower root must be below the floor";
  expect_event_at(run, Event::kFallen, top.time_from_turning_point(0.0));
  expect_normal_force_non_negative(run);
}

TEST(ExtremeCases, NearHorizontalFastTopPrecessesWithoutFalling) {
  const SceneConfig c = load_scene(scene_file("near_horizontal"));
  const CaseRun run = run_at_node_rate(c, 0.5);  // ~9 nutation periods (56 ms)
  expect_finite(run);
  EXPECT_EQ(run.event, Event::kNone) << "the cubic's lower root, u = 0.0485, is above the floor";
  expect_invariants(c, run);
  expect_tilt_band(c, run);
  expect_normal_force_non_negative(run);
}

TEST(ExtremeCases, ZeroSpinFallsLikeTheSlidingPendulumOfTheQuadrature) {
  const SceneConfig c = load_scene(scene_file("zero_spin"));
  const CaseRun run = run_at_node_rate(c, 0.5);
  expect_finite(run);
  expect_event_at(run, Event::kFallen, ReducedTop(c).time_from_turning_point(0.0));
  expect_normal_force_non_negative(run);
  // No spin, no precession: the axis falls in its initial vertical plane (heading 0: the y-z
  // plane); e_Zx = 0 exactly in exact arithmetic, round-off only.
  double off_plane = 0.0;
  for (const Snapshot& s : run.samples) off_plane = std::max(off_plane, std::abs(axis_of(s).x()));
  report("max |e_Zx|", off_plane);
  EXPECT_LE(off_plane, 1e-12);
  // The frictionless floor: G falls straight down (its horizontal position never changes).
  const Vector3 g0 = run.samples.front().outputs.center_of_mass;
  for (const Snapshot& s : run.samples) {
    ASSERT_EQ(s.outputs.center_of_mass.x(), g0.x());
    ASSERT_EQ(s.outputs.center_of_mass.y(), g0.y());
  }
}

TEST(ExtremeCases, FastPrecessionLiftsTheTipOffAtTheQuadratureTime) {
  SceneConfig c = load_scene(scene_file("lift_off"));
  c.after_lift_off = AfterLiftOff::kStop;  // where the contact model ends (the flight after it: test_hybrid)
  const CaseRun run = run_at_node_rate(c, 0.1);
  expect_finite(run);
  const ReducedTop top(c);
  const double u_top = top.other_roots().second;  // the upper turning point (the top rises)
  ASSERT_GT(u_top, top.u0());
  const double u_lift = top.lift_off_height(u_top);
  ASSERT_TRUE(std::isfinite(u_lift)) << "R must reach 0 before the upper turning point";
  report("lift-off tilt [deg]", std::acos(u_lift) * 180.0 / M_PI);
  expect_event_at(run, Event::kLiftOff, top.time_from_turning_point(u_lift));
  // The event's state is the last valid one: R has come down to 0 (from 2.46 m g at t = 0).
  // 1e-6 m g: R falls at ~1e2 m g per second (2.46 m g to 0 in 21 ms), so ~1e-8 s of event time.
  report("R at the event / (m g)", run.samples.back().outputs.normal_force / (c.top.mass * c.top.gravity));
  EXPECT_NEAR(run.samples.back().outputs.normal_force, 0.0, 1e-6 * c.top.mass * c.top.gravity);
}

/// Viscous with a tiny m/k: stable, E + W = E0, the tip pinned to -(m/k) v_G, and the fixed-tip
/// motion recovered to O(m/k).
void check_stiff_friction(const std::string& name, double duration, double* deviation_out = nullptr) {
  const SceneConfig c = load_scene(scene_file(name));
  const double epsilon = c.top.mass / c.top.friction;
  const CaseRun run = run_at_node_rate(c, duration);
  expect_finite(run);
  EXPECT_EQ(run.event, Event::kNone);
  EXPECT_EQ(run.samples.size(), static_cast<size_t>(std::lround(duration / kNodeStep)) + 1);
  SceneConfig fixed = c;
  fixed.scene = SceneType::kFixedTip;
  fixed.top.friction = 0.0;
  const CaseRun reference = run_at_node_rate(fixed, duration);
  ASSERT_EQ(reference.event, Event::kNone);
  ASSERT_EQ(reference.samples.size(), run.samples.size());

  double balance = 0.0, pinned = 0.0, tip = 0.0, speed = 0.0, deviation = 0.0;
  const double e0 = run.samples.front().outputs.energy;
  for (size_t i = 0; i < run.samples.size(); ++i) {
    const ModelOutputs& o = run.samples[i].outputs;
    balance = std::max(balance, std::abs(o.energy + o.dissipated_energy - e0));
    const Vector3 v_horizontal(o.center_of_mass_velocity.x(), o.center_of_mass_velocity.y(), 0.0);
    pinned = std::max(pinned, (o.contact_point + epsilon * v_horizontal).norm());
    tip = std::max(tip, o.contact_point.norm());
    speed = std::max(speed, v_horizontal.norm());
    deviation = std::max(deviation, angle_between(axis_of(run.samples[i]), axis_of(reference.samples[i])));
  }
  report("max |E + W - E0| / (m g h)", balance / mgh(c));
  report("max |x_P + (m/k) v_G| [m]", pinned);
  report("max |x_P| / ((m/k) max |v_G|)", tip / (epsilon * speed));
  report("max axis angle to fixed tip [rad]", deviation);
  report("max axis angle to fixed tip / (m/k) [1/s]", deviation / epsilon);
  // The energy balance, to the same 1e-6 m g h as the conservative scenes' energy.
  EXPECT_LE(balance, 1e-6 * mgh(c));
  // x_P + (m/k) v_G = 0 exactly (momentum balance m v_G' = -k v_P, tip and G at rest at t = 0):
  // to 1e-3 of the tip's excursion (m/k) |v_G| (the integrator resolves the tip's sliding), plus
  // 1e-10 h, the position of a 1e-10 rad attitude error: x_P = x_G - h e_Z mixes two states, and
  // 1e-10 rad over the run is the accuracy asked of the integrators at the node's step (the
  // torque-free and tiny-step cases hold 1e-14). At m/k = 1e-8 s the excursion is 0.3 nm.
  EXPECT_LE(pinned, 1e-3 * epsilon * speed + 1e-10 * c.top.tip_distance);
  // The fixed-tip limit: the axis deviation is O(m/k). The tip moves by (m/k) |v_G| <= (m/k) h
  // |w_perp|, tilting the axis by (m/k) |w_perp| ~ (m/k) * 10 rad/s here; the gyroscopic response
  // (rates up to C wZ / A0 = 112 rad/s) may amplify it over the run by up to ~10. 100 (m/k) rad
  // covers both, and fails for any method that is not converging to the fixed tip as m/k -> 0.
  EXPECT_LE(deviation, 1e2 * epsilon);
  if (deviation_out != nullptr) *deviation_out = deviation;
}

TEST(ExtremeCases, StiffFrictionMicrosecondIsStableAndApproachesTheFixedTip) {
  check_stiff_friction("stiff_friction_1e-6", 0.05);
}

TEST(ExtremeCases, StiffFrictionTenNanosecondsIsStableAndApproachesTheFixedTip) {
  check_stiff_friction("stiff_friction_1e-8", 0.05);
}

TEST(ExtremeCases, StiffFrictionDeviationFromTheFixedTipIsFirstOrderInMOverK) {
  // The fixed tip is the m/k -> 0 limit with an O(m/k) correction (a regular expansion on the
  // slow manifold after the O(m/k)-long initial layer): dividing m/k by 100 must divide the
  // axis's deviation by ~100. [50, 200] accepts an observed order p = log(ratio) / log(100)
  // within 0.85..1.15, and rejects order 0 (a method that does not converge to the limit) or 2.
  double coarse = NAN, fine = NAN;
  check_stiff_friction("stiff_friction_1e-6", 0.05, &coarse);
  check_stiff_friction("stiff_friction_1e-8", 0.05, &fine);
  report("deviation ratio (m/k = 1e-6 vs 1e-8)", coarse / fine);
  EXPECT_GE(coarse / fine, 50.0);
  EXPECT_LE(coarse / fine, 200.0);
}

TEST(ExtremeCases, DiskLikeTopConservesInvariants) {
  const SceneConfig c = load_scene(scene_file("disk_like"));
  const CaseRun run = run_at_node_rate(c, 0.5);
  expect_finite(run);
  EXPECT_EQ(run.event, Event::kNone);
  expect_invariants(c, run);
  expect_tilt_band(c, run);
}

TEST(ExtremeCases, RodLikeTopSpunLikeTheToyFallsAtTheQuadratureTime) {
  const SceneConfig c = load_scene(scene_file("rod_like"));
  const CaseRun run = run_at_node_rate(c, 0.5);
  expect_finite(run);
  const ReducedTop top(c);
  ASSERT_LT(top.other_roots().first, 0.0) << "derived: wZ = 150 < 2266 rad/s, the rod must fall";
  expect_event_at(run, Event::kFallen, top.time_from_turning_point(0.0));
  expect_normal_force_non_negative(run);
}

TEST(ExtremeCases, TorqueFreeTopPrecessesExactlyAboutFixedL) {
  const SceneConfig c = load_scene(scene_file("torque_free"));
  const CaseRun run = run_at_node_rate(c, 0.5);  // ~18 precession periods (28 ms)
  expect_finite(run);
  EXPECT_EQ(run.event, Event::kNone);
  const FreePrecession exact(c);
  const double weight = c.top.mass * c.top.gravity;
  double distance = 0.0, force = 0.0, energy = 0.0;
  for (const Snapshot& s : run.samples) {
    distance = std::max(distance, angle_between(axis_of(s), exact.axis(s.time)));
    force = std::max(force, std::abs(s.outputs.normal_force - weight));
    energy = std::max(energy, std::abs(s.outputs.energy - run.samples.front().outputs.energy));
  }
  report("precession rate |L| / A [rad/s]", exact.rate());
  report("max axis angle to closed form [rad]", distance);
  report("max |R - m g| / (m g)", force / weight);
  report("max |E - E0| / E0", energy / run.samples.front().outputs.energy);
  // The closed form is exact: 1e-6 rad (a microradian, the invariants' tolerance above) after
  // 18 periods, i.e. a relative phase error of 5e-8 of the 112 rad turned.
  EXPECT_LE(distance, 1e-6);
  // h = 0: R = m g exactly (no acceleration of G); round-off of the force's rotation only.
  EXPECT_LE(force, 1e-12 * weight);
  // Energy: no m g h scale here; 1e-9 E0 (the kinetic energy is all there is).
  EXPECT_LE(energy, 1e-9 * run.samples.front().outputs.energy);
  for (const Snapshot& s : run.samples) ASSERT_EQ(s.body_rates.z(), c.initial.spin);
}

TEST(ExtremeCases, TinyTipDistanceIsTheFreePrecessionToOrderH) {
  const SceneConfig c = load_scene(scene_file("tiny_h"));
  const CaseRun run = run_at_node_rate(c, 0.5);
  expect_finite(run);
  EXPECT_EQ(run.event, Event::kNone);
  const FreePrecession free(c);  // uses A, the h = 0 closed form
  const double a0 = c.top.inertia_about_tip();
  const double weight = c.top.mass * c.top.gravity;
  double excess = -INFINITY, distance = 0.0, force = 0.0;
  for (const Snapshot& s : run.samples) {
    const double t = s.time;
    // e_Z' = (L / A0) x e_Z for every symmetric top; |L - L(0)| <= m g h t, so the axis departs
    // from the free precession by at most m g h t^2 / (2 A0), plus the rate error |L| t (1/A - 1/A0).
    const double bound = mgh(c) * t * t / (2.0 * a0) + free.momentum.norm() * t * (1.0 / free.inertia - 1.0 / a0);
    const double d = angle_between(axis_of(s), free.axis(t));
    distance = std::max(distance, d);
    excess = std::max(excess, d - bound);
    // |R - m g| = m |a_Gz| <= m h (|w_perp'| + |w_perp| |w|): O(h).
    const double w_perp = std::hypot(s.body_rates.x(), s.body_rates.y());
    const double w_perp_rate =
        std::abs(a0 - c.top.inertia_axial) / a0 * std::abs(c.initial.spin) * w_perp + mgh(c) / a0;
    const double force_bound = c.top.mass * c.top.tip_distance * (w_perp_rate + w_perp * s.body_rates.norm());
    force = std::max(force, std::abs(s.outputs.normal_force - weight) / force_bound);
  }
  report("max axis angle to h = 0 closed form [rad]", distance);
  report("O(h) bound at the end [rad]", mgh(c) * 0.25 / (2.0 * a0));
  report("max (axis angle - O(h) bound) [rad]", excess);
  report("max |R - m g| / (O(h) bound)", force);
  // The bounds are proven, not fitted; 1e-6 rad is the integrator's own allowance (the
  // torque-free case's tolerance).
  EXPECT_LE(excess, 1e-6);
  EXPECT_LE(force, 1.0);
  expect_invariants(c, run);
}

TEST(ExtremeCases, HugeGravityNutatesFasterAndConservesInvariants) {
  const SceneConfig c = load_scene(scene_file("huge_gravity"));
  const CaseRun run = run_at_node_rate(c, 0.2);  // ~22 nutation periods (9.19 ms)
  expect_finite(run);
  EXPECT_EQ(run.event, Event::kNone);
  expect_invariants(c, run);
  expect_tilt_band(c, run);
  expect_normal_force_non_negative(run);
}

TEST(ExtremeCases, TinyFixedStepMatchesTheReference) {
  const SceneConfig c = load_scene(scene_file("tiny_step"));
  ASSERT_EQ(c.integrator.step, 1e-6);
  const double duration = 0.02;  // 2e4 RK4 steps
  const CaseRun run = run_at_node_rate(c, duration);
  expect_finite(run);
  EXPECT_EQ(run.event, Event::kNone);
  ParameterMap values = read_scene_file(scene_file("tiny_step"));
  values["integrator"] = "dopri5";
  values["tolerance"] = "1e-13";
  values.erase("step");
  const CaseRun reference = run_at_node_rate(parse_scene_config(values, true), duration);
  ASSERT_EQ(reference.samples.size(), run.samples.size());
  double distance = 0.0, rates = 0.0;
  for (size_t i = 0; i < run.samples.size(); ++i) {
    distance = std::max(distance, angle_between(axis_of(run.samples[i]), axis_of(reference.samples[i])));
    rates = std::max(rates, (run.samples[i].body_rates - reference.samples[i].body_rates).norm());
  }
  report("max axis angle to reference [rad]", distance);
  report("max |w - w_ref| [rad/s]", rates);
  // RK4's truncation error at 1e-6 s is (w dt)^5 ~ 1e-20 per step: what remains is round-off,
  // ~ sqrt(2e4 steps) * 1e-16 = 1e-14 rad, and the reference's 1e-13 tolerance. 1e-10 rad and
  // 1e-8 rad/s (of |w| = 150) leave three orders of margin and still catch any blow-up.
  EXPECT_LE(distance, 1e-10);
  EXPECT_LE(rates, 1e-8);
  expect_invariants(c, run);
}

/// A step longer than the nutation period: refused with InvalidParameter("step", ...) by
/// make_simulator, or run stably (finite, no event, bounded energy error). Never NaN.
void check_huge_step(const std::string& name) {
  // Refusal may come from parsing the scene (validate) or from make_simulator: both are the
  // front ends' path, and both must name the key.
  SceneConfig c;
  try {
    c = load_scene(scene_file(name));
    make_simulator(c);
  } catch (const InvalidParameter& refused) {
    std::printf("  [refused] %s\n", refused.what());
    report("refused", 1.0);
    EXPECT_EQ(refused.parameter(), "step");
    EXPECT_NE(std::string(refused.what()).find("step"), std::string::npos);
    return;
  }
  const CaseRun run = run_at_node_rate(c, 1.0);
  expect_finite(run);
  // The physical top stays up (fast top, theta within 6.4e-5 rad of theta0), so any event is
  // the numerics' doing.
  EXPECT_EQ(run.event, Event::kNone) << "got '" << to_string(run.event) << "' at t = " << run.event_time;
  const double de = max_abs_energy_change(run);
  report("max |E - E0| / (m g h)", de / mgh(c));
  // Bounded: 1 % of m g h (G's height to 1 % of h) after 1 s: an inaccurate but stable run,
  // still the same top. An unstable method grows without bound and fails this.
  EXPECT_LE(de, 1e-2 * mgh(c));
}

TEST(ExtremeCases, HugeFixedStepRk4IsRefusedOrStable) { check_huge_step("huge_step"); }

TEST(ExtremeCases, HugeStepWithTheDefaultIntegratorIsRefusedOrStable) { check_huge_step("huge_step_default"); }

}  // namespace
}  // namespace extreme
}  // namespace spinning_top
