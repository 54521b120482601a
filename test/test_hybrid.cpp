// The hybrid model (doc/spec/HYBRID.md, issue 18): flight in closed form, landing impulses,
// skimming, the rim's fall, and what the front ends see of them (the transitions' rows).
// Each test states its tolerance and why.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <random>
#include <vector>

#include "core_test_support.hpp"
#include "spinning_top/case_run.hpp"
#include "spinning_top/scenes/flight.hpp"
#include "spinning_top/scenes/impact.hpp"
#include "spinning_top/simulator.hpp"

namespace spinning_top {
namespace {

using core_test::attitude_difference;

/// The hopping top of the issue: tilted 0.8 rad and precessing at 60 rad/s, it lifts off at
/// about 9.4 ms and hops every few tens of ms (frictionless, viscous).
SceneConfig hopping_top(SceneType scene) {
  SceneConfig c;
  c.scene = scene;
  c.initial.tilt = 0.8;
  c.initial.precession_rate = 60.0;
  if (scene == SceneType::kViscous) c.top.friction = 0.01;
  return c;
}

struct Row {
  double t;
  Snapshot s;
  Event event;
};

std::vector<Row> rows_of(const SceneConfig& config, double duration, double rate) {
  std::vector<Row> rows;
  auto simulator = make_simulator(config);
  const SampleTimes times(duration, rate);
  sample_run(*simulator, times.count(), [&](long long i) { return times.at(i); }, 1e8, StateWhereStepsRunOut::kDrop,
             [&](double t, const Snapshot& s, Event e) { rows.push_back({t, s, e}); });
  return rows;
}

/// L about the tip P: L_G + (G - P) x m v_G (world).
Vector3 momentum_about_tip(const TopParameters& p, const FreeBody& s) {
  const Vector3 axis = s.attitude * Vector3::UnitZ();
  const Vector3 l_g =
      s.attitude * Vector3(p.inertia_transverse * s.body_rates.x(), p.inertia_transverse * s.body_rates.y(),
                           p.inertia_axial * s.body_rates.z());
  return l_g + (p.tip_distance * axis).cross(p.mass * s.velocity);
}

Vector3 tip_velocity_of(const TopParameters& p, const FreeBody& s) {
  const Vector3 axis = s.attitude * Vector3::UnitZ();
  return s.velocity + (s.attitude * s.body_rates).cross(-p.tip_distance * axis);
}

/// Random descending free states of the toy top (tilts up to 1.2 rad, rates up to 200 rad/s,
/// G's velocity up to 1 m/s).
std::vector<FreeBody> random_descending_states(int count) {
  std::mt19937_64 random(18);
  std::uniform_real_distribution<double> unit(-1.0, 1.0);
  const TopParameters p;
  std::vector<FreeBody> states;
  while (static_cast<int>(states.size()) < count) {
    FreeBody s;
    s.attitude = Quaternion(Eigen::AngleAxisd(3.0 * unit(random), Vector3::UnitZ())) *
                 Quaternion(Eigen::AngleAxisd(1.2 * std::abs(unit(random)), Vector3::UnitX())) *
                 Quaternion(Eigen::AngleAxisd(3.0 * unit(random), Vector3::UnitZ()));
    s.body_rates = Vector3(30.0 * unit(random), 30.0 * unit(random), 200.0 * unit(random));
    s.velocity = Vector3(unit(random), unit(random), unit(random));
    s.position = Vector3(0.0, 0.0, p.tip_distance * (s.attitude * Vector3::UnitZ()).z());
    if (tip_velocity_of(p, s).z() < -0.02) states.push_back(s);
  }
  return states;
}

// HYBRID.md: "Angular momentum about P is conserved through the impact, and kinetic energy does
// not grow"; v_Pz+ = -e v_Pz-; the tangential rule. The impulse acts at P, so L_P changes only by
// round-off: |L_P+ - L_P-| <= 1e-13 of the momenta involved (sums of a few products of terms of
// that size, each with relative error eps).
TEST(Landing, KeepsMomentumAboutTheTipLosesEnergyAndRestoresTheTipSpeedByE) {
  TopParameters p;
  double worst_momentum = 0.0, worst_speed = 0.0, worst_tangential = 0.0, least_loss = 1.0;
  for (double e : {0.0, 0.5, 0.9}) {
    p.restitution = e;
    for (TangentialImpact rule : {TangentialImpact::kStick, TangentialImpact::kNormalOnly}) {
      for (const FreeBody& before : random_descending_states(500)) {
        const Landing landing = land(p, before, rule);
        const Vector3 l0 = momentum_about_tip(p, before), l1 = momentum_about_tip(p, landing.after);
        const double scale = p.inertia_axial * std::abs(before.body_rates.z()) + p.inertia_transverse * 30.0 +
                             p.mass * p.tip_distance * before.velocity.norm();
        worst_momentum = std::max(worst_momentum, (l1 - l0).norm() / scale);
        const Vector3 v0 = tip_velocity_of(p, before), v1 = tip_velocity_of(p, landing.after);
        worst_speed = std::max(worst_speed, std::abs(v1.z() + e * v0.z()) / std::abs(v0.z()));
        if (rule == TangentialImpact::kStick) {
          worst_tangential = std::max(worst_tangential, v1.head<2>().norm() / v0.norm());
        } else {  // no horizontal impulse: G's horizontal velocity is unchanged
          worst_tangential = std::max(worst_tangential, (landing.after.velocity - before.velocity).head<2>().norm());
        }
        const double t0 = kinetic_energy(p, before);
        least_loss = std::min(least_loss, (t0 - kinetic_energy(p, landing.after)) / t0);
        EXPECT_EQ(landing.after.body_rates.z(), before.body_rates.z());  // r x J is normal to e_Z
      }
    }
  }
  std::printf("[ measured ] 3000 landings: |dL_P| / L %.3g, |v_Pz+ + e v_Pz-| / |v_Pz-| %.3g, tangential %.3g, "
              "least (T- - T+) / T- %.3g\n",
              worst_momentum, worst_speed, worst_tangential, least_loss);
  EXPECT_LT(worst_momentum, 1e-13);
  EXPECT_LT(worst_speed, 1e-12);
  EXPECT_LT(worst_tangential, 1e-12);
  EXPECT_GE(least_loss, -1e-14);  // kinetic energy never grows (round-off of T's sum)
}

TEST(Landing, SlowApproachesArePlastic) {
  TopParameters p;
  p.restitution = 0.8;
  p.restitution_speed = 0.05;
  for (const FreeBody& before : random_descending_states(200)) {
    const Landing landing = land(p, before, TangentialImpact::kNormalOnly);
    const double approach = -tip_velocity_of(p, before).z();
    EXPECT_EQ(landing.restitution, approach < 0.05 ? 0.0 : 0.8);
  }
}

// The closed form of flight against Euler's torque-free equations and the parabola integrated
// by classical RK4 at 1e-6 s over 0.2 s (its global error ~ (Omega dt)^4 Omega T ~ 1e-13 rad at
// Omega ~ 300 rad/s): agreement to 1e-10 rad and 1e-12 m, and the closed form's tip height
// (written without cancellation) against z_G - h e_Zz to 1e-15 m.
TEST(Flight, MatchesTorqueFreeEulerEquationsAndTheParabola) {
  const TopParameters p;
  FreeBody start;
  start.attitude = Quaternion(Eigen::AngleAxisd(0.7, Vector3(0.3, 1.0, 0.2).normalized()));
  start.body_rates = Vector3(25.0, -12.0, 150.0);
  start.position = Vector3(0.01, -0.02, 0.03);
  start.velocity = Vector3(0.1, 0.05, 0.4);
  const Flight flight(p, 1.0, start);
  // RK4 on (q, omega_body): A wX' = (A - C) wY wZ, A wY' = -(A - C) wZ wX, q' = q (0, w) / 2.
  using State = Eigen::Matrix<double, 7, 1>;
  auto derivative = [&](const State& y) {
    State d;
    const Quaternion q(y[0], y[1], y[2], y[3]);
    const Vector3 w(y[4], y[5], y[6]);
    const Quaternion qd = q * Quaternion(0.0, w.x(), w.y(), w.z());
    d << 0.5 * qd.w(), 0.5 * qd.x(), 0.5 * qd.y(), 0.5 * qd.z(),
        (p.inertia_transverse - p.inertia_axial) * w.y() * w.z() / p.inertia_transverse,
        -(p.inertia_transverse - p.inertia_axial) * w.z() * w.x() / p.inertia_transverse, 0.0;
    return d;
  };
  State y;
  y << start.attitude.w(), start.attitude.x(), start.attitude.y(), start.attitude.z(), start.body_rates;
  const double dt = 1e-6;
  double worst_angle = 0.0, worst_rate = 0.0, worst_position = 0.0, worst_height = 0.0;
  for (int i = 1; i <= 200000; ++i) {
    const State k1 = derivative(y), k2 = derivative(y + 0.5 * dt * k1), k3 = derivative(y + 0.5 * dt * k2),
                k4 = derivative(y + dt * k3);
    y += dt / 6.0 * (k1 + 2.0 * k2 + 2.0 * k3 + k4);
    if (i % 1000 != 0) continue;
    const double t = 1.0 + i * dt, tau = i * dt;
    const FreeBody s = flight.at(t);
    const Quaternion q = Quaternion(y[0], y[1], y[2], y[3]).normalized();
    worst_angle = std::max(worst_angle, attitude_difference(q, s.attitude));
    worst_rate = std::max(worst_rate, (s.body_rates - y.tail<3>()).norm());
    const Vector3 g = start.position + tau * start.velocity - 0.5 * p.gravity * tau * tau * Vector3::UnitZ();
    worst_position = std::max(worst_position, (s.position - g).norm());
    const double direct = s.position.z() - p.tip_distance * (s.attitude * Vector3::UnitZ()).z();
    worst_height = std::max(worst_height, std::abs(flight.tip_height(t) - direct));
  }
  std::printf("[ measured ] flight vs RK4 (1e-6 s, 0.2 s): attitude %.3g rad, rates %.3g rad/s, G %.3g m, "
              "tip height vs z_G - h e_Zz %.3g m\n",
              worst_angle, worst_rate, worst_position, worst_height);
  EXPECT_LT(worst_angle, 1e-10);
  EXPECT_LT(worst_rate, 1e-8);
  EXPECT_LT(worst_position, 1e-15);
  EXPECT_LT(worst_height, 1e-15);
}

// The transitions are located to round-off: R >= 0 in every contact row, at each landing the tip
// height of the flight that ends there (its closed form from its start row) is 0 to 1e-15 m
// (0.05 ulp of z_G), descending, and at a
// landing whose R is negative at once the lift_off follows at the same time (two rows), never an
// endless loop (the run reaches its end).
TEST(HybridRun, HopsWithTransitionsLocatedToRoundOff) {
  for (SceneType scene : {SceneType::kFrictionless, SceneType::kViscous}) {
    const SceneConfig c = hopping_top(scene);
    const std::vector<Row> rows = rows_of(c, 1.0, 100.0);
    int lift_offs = 0, landings = 0, take_offs = 0, at_once = 0;
    Row flight_start{};
    double worst_height = 0.0, worst_force = 0.0;
    for (std::size_t i = 0; i < rows.size(); ++i) {
      const Row& r = rows[i];
      if (r.event == Event::kLiftOff) {
        ++lift_offs;
        EXPECT_NE(r.s.phase, Phase::kContact);
        if (i > 0 && rows[i - 1].event == Event::kLanding && rows[i - 1].t == r.t) ++at_once;
      }
      if (r.event == Event::kTakeOff) ++take_offs;
      if (r.s.phase == Phase::kFlight && (r.event == Event::kLiftOff || r.event == Event::kTakeOff)) {
        flight_start = r;
      }
      if (r.event == Event::kLanding) {
        ++landings;
        // The flight that ends here, from its start row: the tip at the floor, descending.
        FreeBody body;
        body.attitude = flight_start.s.attitude;
        body.body_rates = flight_start.s.body_rates;
        body.position = flight_start.s.outputs.center_of_mass;
        body.velocity = flight_start.s.outputs.center_of_mass_velocity;
        const Flight flight(c.top, flight_start.t, body, TipStart{});
        worst_height = std::max(worst_height, std::abs(flight.tip_height(r.t)));
        EXPECT_LT(flight.tip_velocity(r.t), 0.0);
      }
      if (r.s.phase == Phase::kFlight) {
        EXPECT_EQ(r.s.outputs.normal_force, 0.0);
        EXPECT_GE(r.s.outputs.contact_point.z(), 0.0);
      } else {
        EXPECT_EQ(r.s.outputs.contact_point.z(), 0.0);
        worst_force = std::min(worst_force, r.s.outputs.normal_force);
      }
      if (i > 0) {
        EXPECT_GE(r.t, rows[i - 1].t);
      }
    }
    std::printf("[ measured ] %s hopping top, 1 s: %d lift-offs (%d at a landing's instant), %d take-offs, %d landings, "
                "worst |z_P| at a landing %.3g m, least R in contact %.3g N, last row t = %.17g, event '%s'\n",
                to_string(scene), lift_offs, at_once, take_offs, landings, worst_height, worst_force, rows.back().t,
                to_string(rows.back().event));
    EXPECT_GE(lift_offs, 10);
    EXPECT_GE(landings, 10);
    // Viscous: friction holds R down at the lift-off (R0 > 0 > R1): the tip skims, then takes off.
    if (scene == SceneType::kViscous) {
      EXPECT_GE(take_offs, 10);
    }
    EXPECT_GE(at_once, 1);
    EXPECT_LT(worst_height, 1e-15);
    EXPECT_GE(worst_force, 0.0);
    EXPECT_EQ(rows.back().t, 1.0);  // the run went on to its end
  }
}

// Energy: the frictionless top's E is constant within each phase (exact closed forms) and drops
// only at landings, by the impact's loss; E + W + losses (the snapshot's dissipated_energy
// counts both) stays E(0) to 1e-12 of m g h over the hops.
TEST(HybridRun, EnergyDropsOnlyAtLandingsByTheImpactLoss) {
  for (SceneType scene : {SceneType::kFrictionless, SceneType::kViscous}) {
    const SceneConfig c = hopping_top(scene);
    const std::vector<Row> rows = rows_of(c, 1.0, 1000.0);
    const double scale = c.top.mass * c.top.gravity * c.top.tip_distance;
    const double balance0 = rows.front().s.outputs.energy + rows.front().s.outputs.dissipated_energy;
    double worst = 0.0, previous_energy = rows.front().s.outputs.energy;
    for (const Row& r : rows) {
      worst = std::max(worst, std::abs(r.s.outputs.energy + r.s.outputs.dissipated_energy - balance0) / scale);
      EXPECT_LE(r.s.outputs.energy, previous_energy + 1e-12 * scale) << r.t;  // kinetic energy never grows
      previous_energy = r.s.outputs.energy;
    }
    std::printf("[ measured ] %s: |E + W + impact losses - E0| / (m g h) <= %.3g over 1 s of hops\n", to_string(scene), worst);
    EXPECT_LT(worst, scene == SceneType::kFrictionless ? 1e-12 : 1e-9);
  }
}

bool same_state(const Snapshot& a, const Snapshot& b) {
  return a.attitude.coeffs() == b.attitude.coeffs() && a.body_rates == b.body_rates &&
         a.outputs.center_of_mass == b.outputs.center_of_mass && a.outputs.contact_point == b.outputs.contact_point &&
         a.outputs.normal_force == b.outputs.normal_force && a.phase == b.phase;
}

// Rows are identical at every output rate: the transitions (times and states) bit for bit, and
// the rows at the instants the rates share. Exact (frictionless auto) and dop853 (viscous auto).
TEST(HybridRun, RowsAreIdenticalAtEveryOutputRate) {
  for (SceneType scene : {SceneType::kFrictionless, SceneType::kViscous}) {
    const SceneConfig c = hopping_top(scene);
    const std::vector<Row> slow = rows_of(c, 0.5, 50.0), fast = rows_of(c, 0.5, 1000.0);
    std::vector<const Row*> slow_events, fast_events;
    for (const Row& r : slow)
      if (r.event != Event::kNone) slow_events.push_back(&r);
    for (const Row& r : fast)
      if (r.event != Event::kNone) fast_events.push_back(&r);
    ASSERT_EQ(slow_events.size(), fast_events.size()) << to_string(scene);
    for (std::size_t i = 0; i < slow_events.size(); ++i) {
      EXPECT_EQ(slow_events[i]->t, fast_events[i]->t);
      EXPECT_EQ(slow_events[i]->event, fast_events[i]->event);
      EXPECT_TRUE(same_state(slow_events[i]->s, fast_events[i]->s)) << to_string(scene) << " transition " << i;
    }
    int shared = 0;
    for (const Row& r : slow) {
      if (r.event != Event::kNone) continue;
      for (const Row& f : fast) {
        if (f.event != Event::kNone || f.t != r.t) continue;
        EXPECT_TRUE(same_state(r.s, f.s)) << to_string(scene) << " t = " << r.t;
        ++shared;
      }
    }
    std::printf("[ measured ] %s: %zu transitions and %d shared rows identical at 50 Hz and 1 kHz\n", to_string(scene),
                slow_events.size(), shared);
    EXPECT_GE(shared, 25);
  }
}

// after_lift_off: stop is today's run: the contact phase alone. Up to the first lift-off, the
// flying run's rows are those of the stopping run, bit for bit, and the stopping run ends with
// lift_off at that time.
TEST(HybridRun, StopAfterLiftOffIsTheContactModelAlone) {
  for (SceneType scene : {SceneType::kFixedTip, SceneType::kFrictionless, SceneType::kViscous}) {
    SceneConfig fly = hopping_top(scene);
    SceneConfig stop = fly;
    stop.after_lift_off = AfterLiftOff::kStop;
    const std::vector<Row> a = rows_of(fly, 0.1, 1000.0), b = rows_of(stop, 0.1, 1000.0);
    ASSERT_FALSE(b.empty());
    EXPECT_EQ(b.back().event, Event::kLiftOff) << to_string(scene);
    ASSERT_GE(a.size(), b.size());
    for (std::size_t i = 0; i < b.size(); ++i) {
      EXPECT_EQ(a[i].t, b[i].t);
      EXPECT_TRUE(same_state(a[i].s, b[i].s) || i + 1 == b.size()) << to_string(scene) << " row " << i;
    }
    EXPECT_EQ(a[b.size() - 1].t, b.back().t);
    EXPECT_EQ(a[b.size() - 1].event, Event::kLiftOff);
  }
}

// The fixed tip at a lift-off whose free tip would dive (a_f <= 0): a pivot that can neither push
// nor let go ends the run with lift_off, as before (HYBRID.md).
TEST(HybridRun, FixedTipThatWouldDiveEndsWithLiftOff) {
  const std::vector<Row> rows = rows_of(hopping_top(SceneType::kFixedTip), 0.1, 1000.0);
  EXPECT_EQ(rows.back().event, Event::kLiftOff);
  const Snapshot& s = rows.back().s;
  EXPECT_LE(free_tip_vertical_acceleration(TopParameters(), s.attitude, s.body_rates), 0.0);
}

// A bounce: with e = 0.5 the tip leaves the floor again at -e times its approach speed, and the
// flight goes on (no contact phase between).
TEST(HybridRun, ElasticLandingsBounce) {
  SceneConfig c = hopping_top(SceneType::kFrictionless);
  c.top.restitution = 0.5;
  c.top.restitution_speed = 0.0;
  auto simulator = make_simulator(c);
  int bounces = 0;
  for (int i = 1; i <= 2000 && bounces < 3; ++i) {
    simulator->advance_to(i * 1e-3);
    for (const Transition& tr : simulator->take_transitions()) {
      if (tr.event != Event::kLanding) continue;
      EXPECT_EQ(tr.state.phase, Phase::kFlight);
      EXPECT_EQ(tr.state.outputs.contact_point.z(), 0.0);
      ++bounces;
    }
  }
  EXPECT_GE(bounces, 3);
}

// The rim (HYBRID.md, "fallen"): a spinless top released at 0.3 rad falls; with a rim (a, b) it
// has fallen where the rim's lowest point reaches the floor, e_Zz = b / sqrt(a^2 + b^2), before
// the needle's e_Zz = 0. Located to round-off: the lowest point at the event within 1e-12 m.
TEST(HybridRun, ATopFallsOntoItsRim) {
  for (SceneType scene : {SceneType::kFixedTip, SceneType::kFrictionless}) {
    SceneConfig c;
    c.scene = scene;
    c.initial.tilt = 0.3;
    c.initial.spin = 0.0;
    c.top.rim_distance = 4.0 * c.top.tip_distance / 3.0;
    c.top.rim_radius = 0.0231;
    SceneConfig needle = c;
    needle.top.rim_radius = needle.top.rim_distance = 0.0;
    auto rim_run = make_simulator(c), needle_run = make_simulator(needle);
    EXPECT_EQ(rim_run->advance_to(10.0), Event::kFallen);
    EXPECT_EQ(needle_run->advance_to(10.0), Event::kFallen);
    const Snapshot s = rim_run->snapshot();
    const double u = (s.attitude * Vector3::UnitZ()).z();
    const double lowest = s.outputs.contact_point.z() + c.top.rim_distance * u - c.top.rim_radius * std::sqrt(1.0 - u * u);
    std::printf("[ measured ] %s: falls onto its rim at %.6f s (needle %.6f s), rim's lowest point %.3g m\n",
                to_string(scene), rim_run->time(), needle_run->time(), lowest);
    EXPECT_LT(rim_run->time(), needle_run->time());
    EXPECT_LT(std::abs(lowest), 1e-12);
  }
}

// Ten hops and more on the frictionless floor stay closed form piecewise: every contact phase is
// exact's (auto), and each phase costs one step.
TEST(HybridRun, FrictionlessHopsStayClosedFormPiecewise) {
  auto simulator = make_simulator(hopping_top(SceneType::kFrictionless));
  simulator->advance_to(1.0);
  const HopSummary hops = simulator->hops();
  const IntegratorChoice choice = simulator->integrator_choice();
  std::printf("[ measured ] 1 s: %ld lift-offs, %ld landings, %ld steps, highest hop %.3g m, impact losses %.3g J (%s)\n",
              hops.lift_offs, hops.landings, simulator->steps(), hops.max_hop_height, hops.impact_loss,
              simulator->integrator_description().c_str());
  EXPECT_GE(hops.landings, 10);
  EXPECT_EQ(choice.method, IntegratorType::kExact);
  EXPECT_FALSE(choice.fallback);
  // One step per exact contact phase and per transition, and the flights' search for their touch
  // (a few tens of its bounded steps per hop).
  EXPECT_LE(simulator->steps(), 100 * hops.landings);
  EXPECT_GT(hops.max_hop_height, 0.0);
  EXPECT_NEAR(hops.first_lift_off_time, 0.00935, 1e-4);
}

}  // namespace
}  // namespace spinning_top
