// Shared by the test_core gtests: configurations of the toy top, geometry read off a
// Snapshot, and the closed forms of doc/spec/PHYSICS.md ("Invariants and balances")
// that the tests compare against: the steady-precession quadratic, the turning-point cubic
// in u = cos(theta), and one-dimensional quadratures.
#pragma once

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <functional>
#include <memory>
#include <utility>
#include <vector>

#include "spinning_top/scenes/viscous.hpp"
#include "spinning_top/simulator.hpp"

namespace spinning_top {
namespace core_test {

/// The slipping top's start: tilted 0.3 rad with some precession and nutation, spinning at
/// `spin`, G sliding at 5 cm/s.
inline InitialConditions slipping_start(double spin = 150.0) {
  InitialConditions ic;
  ic.tilt = 0.3;
  ic.spin = spin;
  ic.precession_rate = 5.0;
  ic.nutation_rate = 2.0;
  ic.velocity_x = 0.05;
  return ic;
}

/// The toy top from slipping_start() against friction k: every term of the viscous equations is
/// exercised (Model: Viscous, or a wrapper of it constructed the same way).
template <class Model = Viscous>
Model slipping_top(double friction) {
  TopParameters top;
  top.friction = friction;
  return Model(top, slipping_start());
}

/// The viscous top without its stiff part (kStiffRank 0): RADAU5 takes its Jacobians by
/// differences, as for a model that has none (its simplified and per-stage Newtons).
struct ViscousByDifferences : Viscous {
  using Viscous::Viscous;
  static constexpr int kStiffRank = 0;
};

/// Prints a measured figure next to the test's output (the numbers doc/physics_tests.md quotes).
inline void report(const char* what, double value) { std::printf("[ measured ] %s = %.6g\n", what, value); }

/// The toy top of config/*.yaml: m 0.1 kg, A 4e-5, C 6e-5 kg m^2, h 0.02 m, g 9.80665.
inline TopParameters toy_top() { return TopParameters(); }

inline SceneConfig adaptive(SceneType scene, const InitialConditions& initial, double tolerance,
                            const TopParameters& top = toy_top()) {
  SceneConfig config;
  config.scene = scene;
  // The seed's contact model and its validity events: a lift-off ends the run (the hybrid model's
  // flights and landings have their own tests, test_hybrid.cpp).
  config.after_lift_off = AfterLiftOff::kStop;
  config.top = top;
  config.initial = initial;
  config.integrator.type = IntegratorType::kDopri5;
  config.integrator.tolerance = tolerance;
  return config;
}

inline SceneConfig fixed_step(SceneType scene, const InitialConditions& initial, double step,
                              const TopParameters& top = toy_top()) {
  SceneConfig config = adaptive(scene, initial, 1e-10, top);
  config.integrator.type = IntegratorType::kRk4;
  config.integrator.step = step;
  return config;
}

/// e_Z in world components.
inline Vector3 axis_of(const Snapshot& s) { return s.attitude * Vector3::UnitZ(); }
/// e_Zz = cos(theta).
inline double cos_tilt(const Snapshot& s) { return axis_of(s).z(); }
/// theta, from atan2 (accurate also near 0).
inline double tilt(const Snapshot& s) {
  const Vector3 e = axis_of(s);
  return std::atan2(std::hypot(e.x(), e.y()), e.z());
}
/// phi from e_Z = (sin(theta) sin(phi), -sin(theta) cos(phi), cos(theta)) (PHYSICS.md, z-x-z).
inline double heading(const Snapshot& s) {
  const Vector3 e = axis_of(s);
  return std::atan2(e.x(), -e.y());
}
/// Rotation angle between two attitudes [rad] (q and -q are the same attitude).
inline double attitude_difference(const Quaternion& a, const Quaternion& b) {
  return 2.0 * std::asin(std::min(1.0, (a.conjugate() * b).vec().norm()));
}

/// The world-frame angular velocity and the tip velocity v_P = v_G - h w x e_Z (PHYSICS.md,
/// contact constraint), rebuilt from a snapshot's outputs independently of the models.
inline Vector3 world_rates(const Snapshot& s) { return s.attitude * s.body_rates; }
inline Vector3 tip_velocity(const Snapshot& s, double h) {
  return s.outputs.center_of_mass_velocity - h * world_rates(s).cross(axis_of(s));
}

/// Roots of A' W^2 cos(theta) - C wZ W + m g h = 0 (PHYSICS.md, steady precession), A' = A0
/// for the fixed tip, A for the frictionless top: {slow, fast}. The slow root is written
/// 2 m g h / (C wZ + sqrt(D)) so that it does not cancel.
inline std::pair<double, double> steady_precession_rates(double transverse, const TopParameters& p, double theta,
                                                         double spin) {
  const double a = transverse * std::cos(theta), b = p.inertia_axial * spin;
  const double c = p.mass * p.gravity * p.tip_distance;
  const double root = std::sqrt(b * b - 4.0 * a * c);
  return {2.0 * c / (b + root), (b + root) / (2.0 * a)};
}

/// f(u) = (2/A')(E' - m g h u)(1 - u^2) - ((L_z - C wZ u)/A')^2, E' = E - C wZ^2 / 2
/// (PHYSICS.md, integrable cases): u' ^2 = f(u) for the fixed tip (A' = A0); for the
/// frictionless top u'^2 = f(u) / (1 + (m h^2/A)(1 - u^2)) with A' = A, same roots.
struct TurningPointCubic {
  double transverse, reduced_energy, vertical_momentum, axial_momentum, weight_moment;
  double operator()(double u) const {
    const double p = vertical_momentum - axial_momentum * u;
    return 2.0 / transverse * (reduced_energy - weight_moment * u) * (1.0 - u * u) -
           p * p / (transverse * transverse);
  }
};

inline TurningPointCubic turning_point_cubic(double transverse, const TopParameters& p, double spin,
                                             const Snapshot& initial) {
  return {transverse, initial.outputs.energy - 0.5 * p.inertia_axial * spin * spin,
          initial.outputs.vertical_angular_momentum, p.inertia_axial * spin,
          p.mass * p.gravity * p.tip_distance};
}

/// The roots of f in [lo, hi]: sign changes on a fine grid, refined by bisection to round-off.
inline std::vector<double> roots_in(const std::function<double(double)>& f, double lo, double hi, int grid = 20000) {
  std::vector<double> roots;
  double a = lo, fa = f(lo);
  for (int i = 1; i <= grid; ++i) {
    const double b = lo + (hi - lo) * i / grid, fb = f(b);
    if (fa == 0.0) roots.push_back(a);
    else if (fa * fb < 0.0) {
      double x0 = a, x1 = b, f0 = fa;
      for (int k = 0; k < 200 && x1 - x0 > 1e-16; ++k) {
        const double xm = 0.5 * (x0 + x1), fm = f(xm);
        if (fm * f0 > 0.0) { x0 = xm; f0 = fm; } else { x1 = xm; }
      }
      roots.push_back(0.5 * (x0 + x1));
    }
    a = b;
    fa = fb;
  }
  return roots;
}

/// Adaptive Simpson quadrature (Lyness), to an absolute tolerance.
inline double simpson_step(const std::function<double(double)>& f, double a, double b, double fa, double fm,
                           double fb, double whole, double tolerance, int depth) {
  const double m = 0.5 * (a + b), lm = 0.5 * (a + m), rm = 0.5 * (m + b);
  const double flm = f(lm), frm = f(rm);
  const double left = (m - a) / 6.0 * (fa + 4.0 * flm + fm), right = (b - m) / 6.0 * (fm + 4.0 * frm + fb);
  if (depth <= 0 || std::abs(left + right - whole) <= 15.0 * tolerance)
    return left + right + (left + right - whole) / 15.0;
  return simpson_step(f, a, m, fa, flm, fm, left, 0.5 * tolerance, depth - 1) +
         simpson_step(f, m, b, fm, frm, fb, right, 0.5 * tolerance, depth - 1);
}
inline double integrate(const std::function<double(double)>& f, double a, double b, double tolerance) {
  const double fa = f(a), fm = f(0.5 * (a + b)), fb = f(b);
  return simpson_step(f, a, b, fa, fm, fb, (b - a) / 6.0 * (fa + 4.0 * fm + fb), tolerance, 50);
}

/// A run to its first event (or the horizon): which event, when, and the last state.
struct EventRun {
  Event event = Event::kNone;
  double time = 0.0;
  Snapshot last;
};

inline EventRun run_until_event(const SceneConfig& config, double duration) {
  auto sim = make_simulator(config);
  EventRun run;
  run.event = sim->advance_to(duration);
  run.time = sim->time();
  run.last = sim->snapshot();
  EXPECT_EQ(sim->event(), run.event);
  return run;
}

/// The spinless top falls in a vertical plane: with c = m g h / A' (A' = A0 fixed tip, A
/// frictionless) and alpha = m h^2 / A for the sliding tip (0 for the fixed one), energy gives
///   thetadot^2 (1 + alpha sin^2 theta) = thetadot0^2 + 2 c (cos theta0 - cos theta)
/// (PHYSICS.md: the sliding top's kinetic energy gains 1/2 m h^2 sin^2 theta thetadot^2).
struct PlanarFall {
  double c, alpha, theta0, thetadot0;
  /// thetadot at theta = theta0 + offset; cos theta0 - cos theta = 2 sin(theta0 + offset/2)
  /// sin(offset/2) is free of cancellation (and of rounding theta0 + offset for tiny offsets).
  double rate_at_offset(double offset) const {
    const double drop = 2.0 * std::sin(theta0 + 0.5 * offset) * std::sin(0.5 * offset);
    const double sine = std::sin(theta0 + offset);
    return std::sqrt((thetadot0 * thetadot0 + 2.0 * c * drop) / (1.0 + alpha * sine * sine));
  }
  double rate(double theta) const { return rate_at_offset(theta - theta0); }
  /// t(theta1) = integral from theta0 to theta1 of dtheta / thetadot. From rest the integrand
  /// has an inverse square root at theta0: offset = s^2 makes it smooth.
  double time_to(double theta1) const {
    if (thetadot0 > 0.0) return integrate([&](double th) { return 1.0 / rate(th); }, theta0, theta1, 1e-15);
    return integrate(
        [&](double s) {
          if (s == 0.0)  // limit of 2 s / rate: 2 / sqrt(c sin(theta0) / (1 + alpha sin^2 theta0))
            return 2.0 * std::sqrt((1.0 + alpha * std::sin(theta0) * std::sin(theta0)) / (c * std::sin(theta0)));
          return 2.0 * s / rate_at_offset(s * s);
        },
        0.0, std::sqrt(theta1 - theta0), 1e-15);
  }
};

/// Local extrema of uniformly sampled values, each refined by the vertex of the parabola
/// through it and its two neighbours (error O(dt^4) of the sampled curve's scale).
struct Extrema {
  std::vector<double> maxima, minima;
};
inline Extrema sampled_extrema(const std::vector<double>& u) {
  Extrema e;
  for (size_t i = 1; i + 1 < u.size(); ++i) {
    const double curvature = u[i + 1] - 2.0 * u[i] + u[i - 1];
    if (curvature == 0.0) continue;
    const double vertex = u[i] - (u[i + 1] - u[i - 1]) * (u[i + 1] - u[i - 1]) / (8.0 * curvature);
    if (u[i] >= u[i - 1] && u[i] > u[i + 1]) e.maxima.push_back(vertex);
    if (u[i] <= u[i - 1] && u[i] < u[i + 1]) e.minima.push_back(vertex);
  }
  return e;
}

/// cos(theta) sampled every dt up to duration (dense output for adaptive methods).
inline std::vector<double> sample_cos_tilt(Simulator& sim, double dt, double duration) {
  std::vector<double> u;
  const int n = static_cast<int>(std::lround(duration / dt));
  for (int i = 0; i <= n; ++i) {
    EXPECT_EQ(sim.advance_to(i * dt), Event::kNone);
    u.push_back(cos_tilt(sim.snapshot()));
  }
  return u;
}

}  // namespace core_test
}  // namespace spinning_top
