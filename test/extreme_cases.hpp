// Shared by test/test_extreme_cases.cpp (assertions, short runs) and bench/extreme_cases.cpp
// (the table, long runs): loading a scene file the way the batch simulator does, running it at
// the node's output rate, and the closed forms the stiff and extreme cases are checked against
// (issue 4, "Stiff and extreme cases"; doc/spec/PHYSICS.md, "Invariants and balances").
#pragma once

#include <cmath>
#include <complex>
#include <ctime>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

#include "spinning_top/config.hpp"
#include "spinning_top/scene_file.hpp"
#include "spinning_top/simulator.hpp"

namespace spinning_top {
namespace extreme {

/// The node's default publication period [s] (its `step` default): the cases advance by it.
constexpr double kNodeStep = 1e-3;

// ---------------------------------------------------------------------------------------------
// Scene files: the batch simulator's path (read_scene_file, then
// parse_scene_config(values, require_all = true)).

inline SceneConfig load_scene(const std::string& path) { return parse_scene_config(read_scene_file(path), true); }

// ---------------------------------------------------------------------------------------------
// A run at the node's rate.

inline double cpu_seconds() {
  timespec ts;
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &ts);
  return static_cast<double>(ts.tv_sec) + 1e-9 * static_cast<double>(ts.tv_nsec);
}

inline bool is_finite(const Snapshot& s) {
  const ModelOutputs& o = s.outputs;
  return std::isfinite(s.time) && s.attitude.coeffs().allFinite() && s.body_rates.allFinite() &&
         std::isfinite(o.normal_force) && o.contact_force.allFinite() && o.center_of_mass.allFinite() &&
         o.center_of_mass_velocity.allFinite() && o.contact_point.allFinite() && std::isfinite(o.energy) &&
         std::isfinite(o.vertical_angular_momentum) && std::isfinite(o.dissipated_energy);
}

struct CaseRun {
  std::vector<Snapshot> samples;  ///< t = 0, kNodeStep, 2 kNodeStep, ... and the event instant
  Event event = Event::kNone;
  double event_time = NAN;
  std::string integrator;      ///< Simulator::integrator_description(): what `auto` picked
  double cpu_seconds = 0.0;    ///< CPU time of the stepping (sampling included, cheap)
  bool all_finite = true;      ///< every snapshot finite
  bool out_of_budget = false;  ///< stopped early because the CPU budget ran out
  double end_time() const { return samples.empty() ? 0.0 : samples.back().time; }
};

/// Advances to k * output_step for k = 1 .. duration / output_step, as the node does, and keeps
/// every snapshot. Stops at the first event, or after cpu_budget seconds of CPU time.
inline CaseRun run_at_node_rate(const SceneConfig& config, double duration, double output_step = kNodeStep,
                            double cpu_budget = INFINITY) {
  CaseRun run;
  const double start = cpu_seconds();
  std::unique_ptr<Simulator> simulator = make_simulator(config);
  run.integrator = simulator->integrator_description();
  run.samples.push_back(simulator->snapshot());
  const long n = std::lround(duration / output_step);
  for (long k = 1; k <= n; ++k) {
    const Event event = simulator->advance_to(static_cast<double>(k) * output_step);
    run.samples.push_back(simulator->snapshot());
    run.all_finite = run.all_finite && is_finite(run.samples.back());
    if (event != Event::kNone) {
      run.event = event;
      run.event_time = simulator->time();
      break;
    }
    if (cpu_seconds() - start > cpu_budget) {
      run.out_of_budget = true;
      break;
    }
  }
  run.all_finite = run.all_finite && is_finite(run.samples.front());
  run.cpu_seconds = cpu_seconds() - start;
  return run;
}

// ---------------------------------------------------------------------------------------------
// Geometry of a snapshot.

inline Vector3 axis_of(const Snapshot& s) { return s.attitude * Vector3::UnitZ(); }

/// Angle of the axis from the vertical, accurate for tiny tilts (atan2 of sin and cos, not acos).
inline double tilt_of(const Snapshot& s) {
  const Vector3 e = axis_of(s);
  return std::atan2(std::hypot(e.x(), e.y()), e.z());
}

inline double angle_between(const Vector3& a, const Vector3& b) {
  return std::atan2(a.cross(b).norm(), a.dot(b));
}

inline double max_abs_energy_change(const CaseRun& run) {
  double worst = 0.0;
  for (const Snapshot& s : run.samples)
    worst = std::max(worst, std::abs(s.outputs.energy - run.samples.front().outputs.energy));
  return worst;
}

/// |E + W - E0|: the viscous energy balance (PHYSICS.md: dE/dt = -k |v_P|^2 = -dW/dt).
inline double max_energy_balance_error(const CaseRun& run) {
  double worst = 0.0;
  for (const Snapshot& s : run.samples)
    worst = std::max(worst, std::abs(s.outputs.energy + s.outputs.dissipated_energy -
                                     run.samples.front().outputs.energy));
  return worst;
}

inline double max_abs_lz_change(const CaseRun& run) {
  double worst = 0.0;
  for (const Snapshot& s : run.samples)
    worst = std::max(worst, std::abs(s.outputs.vertical_angular_momentum -
                                     run.samples.front().outputs.vertical_angular_momentum));
  return worst;
}

// ---------------------------------------------------------------------------------------------
// The integrable reduction (PHYSICS.md, "Fixed tip and frictionless are integrable"). With
// u = cos(theta), energy and the two momenta give u'^2 = N(u) / D(u) with the cubic
//   N(u) = (1 - u^2)(alpha - beta u) - (lambda - a u)^2     (Goldstein, sec. 5.7)
//   alpha = 2 E' / I, beta = 2 m g h / I, lambda = L_z / I, a = C omega_Z / I,
// I = A0 for the fixed tip and A for the frictionless floor, where D(u) = 1 + (m h^2 / A)(1 - u^2)
// (G's vertical kinetic energy; D = 1 for the fixed tip). In both scenes z_G = h u, so the normal
// force is R = m (g + h u'') = m (g + h F'(u) / 2) with F = N / D.
class ReducedTop {
 public:
  explicit ReducedTop(const SceneConfig& c) {
    const TopParameters& p = c.top;
    const InitialConditions& ic = c.initial;
    const bool fixed = c.scene == SceneType::kFixedTip;
    inertia_ = fixed ? p.inertia_about_tip() : p.inertia_transverse;
    kappa_ = fixed ? 0.0 : p.mass * p.tip_distance * p.tip_distance / p.inertia_transverse;
    m_ = p.mass;
    g_ = p.gravity;
    h_ = p.tip_distance;
    u0_ = std::cos(ic.tilt);
    const double s0 = std::sin(ic.tilt);
    // E' excludes the constant spin energy and, for the frictionless floor, keeps G's vertical
    // kinetic energy 1/2 m h^2 sin^2(theta) thetadot^2 (folded into D below).
    const double e_prime = 0.5 * inertia_ * (ic.nutation_rate * ic.nutation_rate * (1.0 + kappa_ * s0 * s0) +
                                             ic.precession_rate * ic.precession_rate * s0 * s0) +
                           m_ * g_ * h_ * u0_;
    const double lz = inertia_ * ic.precession_rate * s0 * s0 + p.inertia_axial * ic.spin * u0_;
    alpha_ = 2.0 * e_prime / inertia_;
    beta_ = 2.0 * m_ * g_ * h_ / inertia_;
    lambda_ = lz / inertia_;
    a_ = p.inertia_axial * ic.spin / inertia_;
    // N(u) = beta u^3 + c2 u^2 + c1 u + c0.
    c2_ = -alpha_ - a_ * a_;
    c1_ = 2.0 * a_ * lambda_ - beta_;
    c0_ = alpha_ - lambda_ * lambda_;
  }

  double u0() const { return u0_; }
  double cubic(double u) const { return ((beta_ * u + c2_) * u + c1_) * u + c0_; }
  double cubic_slope(double u) const { return (3.0 * beta_ * u + 2.0 * c2_) * u + c1_; }
  double d(double u) const { return 1.0 + kappa_ * (1.0 - u * u); }
  /// F(u) = u'^2.
  double rate_squared(double u) const { return cubic(u) / d(u); }
  /// R(u) = m (g + h F'(u) / 2).
  double normal_force(double u) const {
    const double dd = -2.0 * kappa_ * u;
    const double slope = (cubic_slope(u) * d(u) - cubic(u) * dd) / (d(u) * d(u));
    return m_ * (g_ + 0.5 * h_ * slope);
  }

  /// Started with thetadot0 = 0, u0 is a root of N: N(u) = (u - u0) Q(u), Q(u) = beta u^2 + q1 u + q0
  /// (synthetic division, exact in u0 up to round-off). Returns the other two roots, ascending.
  /// (Requires beta > 0.)
  std::pair<double, double> other_roots() const {
    const double q1 = c2_ + beta_ * u0_, q0 = c1_ + q1 * u0_;
    const double disc = std::sqrt(std::max(0.0, q1 * q1 - 4.0 * beta_ * q0));
    // Citardauq-free stable pair: r1 r2 = q0 / beta.
    const double big = (-q1 - std::copysign(disc, q1)) / (2.0 * beta_);
    const double small = (big != 0.0) ? q0 / (beta_ * big) : 0.0;
    return {std::min(big, small), std::max(big, small)};
  }
  double quotient(double u) const {
    const double q1 = c2_ + beta_ * u0_, q0 = c1_ + q1 * u0_;
    return (beta_ * u + q1) * u + q0;
  }

  /// Time for u to go from the turning point u0 (thetadot0 = 0) to u_end, monotonically:
  /// t = integral du / sqrt(F(u)); with u = u0 + sigma s^2 the root's singularity cancels:
  /// t = integral_0^sqrt|u_end - u0| 2 sqrt(D(u)) / sqrt(sigma Q(u)) ds (smooth), composite Simpson.
  double time_from_turning_point(double u_end, int intervals = 20000) const {
    const double sigma = (u_end < u0_) ? -1.0 : 1.0;
    const double s_end = std::sqrt(std::abs(u_end - u0_));
    auto integrand = [&](double s) {
      const double u = u0_ + sigma * s * s;
      return 2.0 * std::sqrt(d(u)) / std::sqrt(sigma * quotient(u));
    };
    return simpson(integrand, 0.0, s_end, intervals);
  }

  /// Period of the nutation between u1 = other_roots().second < u0 (or above) and u0:
  /// with u = c + r cos(psi) between the two roots and u2 the third root,
  /// T = 2 integral_0^pi sqrt(D(u)) / sqrt(beta |u2 - u|) dpsi.
  double nutation_period(int intervals = 2000) const {
    const auto [low, high] = other_roots();
    // The partner root of u0 is the one of the two closest to it; the other is u2.
    const bool high_is_partner = std::abs(high - u0_) < std::abs(low - u0_);
    const double u1 = high_is_partner ? high : low, u2 = high_is_partner ? low : high;
    const double c = 0.5 * (u0_ + u1), r = 0.5 * (u0_ - u1);
    auto integrand = [&](double psi) {
      const double u = c + r * std::cos(psi);
      return std::sqrt(d(u)) / std::sqrt(beta_ * std::abs(u2 - u));
    };
    return 2.0 * simpson(integrand, 0.0, M_PI, intervals);
  }

  /// First u between u0 and `toward` (a turning point) where R(u) = 0, by bisection; NAN if none.
  double lift_off_height(double toward) const {
    const int n = 4000;
    double previous = u0_;
    for (int i = 1; i <= n; ++i) {
      const double u = u0_ + (toward - u0_) * i / n;
      if (normal_force(u) < 0.0) {
        double lo = previous, hi = u;
        for (int k = 0; k < 200; ++k) {
          const double mid = 0.5 * (lo + hi);
          (normal_force(mid) < 0.0 ? hi : lo) = mid;
        }
        return 0.5 * (lo + hi);
      }
      previous = u;
    }
    return NAN;
  }

  template <class F>
  static double simpson(const F& f, double a, double b, int n) {
    n += n % 2;
    const double step = (b - a) / n;
    double sum = f(a) + f(b);
    for (int i = 1; i < n; ++i) sum += (i % 2 ? 4.0 : 2.0) * f(a + i * step);
    return sum * step / 3.0;
  }

 private:
  double inertia_, kappa_, m_, g_, h_, u0_;
  double alpha_, beta_, lambda_, a_, c2_, c1_, c0_;
};

/// Sleeping top linearised about the upright (fixed tip, thetadot0 = phidot0 = 0, omega_perp = 0):
/// the complex horizontal axis sigma = e_Zx + i e_Zy obeys A0 sigma'' - i C wZ sigma' - m g h sigma = 0,
/// so sigma = sigma0 (w- e^{i w+ t} - w+ e^{i w- t}) / (w- - w+), w+- = (C wZ +- sqrt(C^2 wZ^2 - 4 A0 m g h)) / (2 A0).
/// |sigma| stays in [theta0, theta0 (w+ + w-) / (w+ - w-)] = [theta0, theta0 C wZ / sqrt(C^2 wZ^2 - 4 A0 m g h)].
struct SleepingTopLinear {
  double w_plus, w_minus;
  std::complex<double> sigma0;
  explicit SleepingTopLinear(const SceneConfig& c) {
    const double a0 = c.top.inertia_about_tip(), cw = c.top.inertia_axial * c.initial.spin;
    const double mgh = c.top.mass * c.top.gravity * c.top.tip_distance;
    const double root = std::sqrt(cw * cw - 4.0 * a0 * mgh);
    w_plus = (cw + root) / (2.0 * a0);
    w_minus = (cw - root) / (2.0 * a0);
    const Vector3 e = initial_attitude(c.initial) * Vector3::UnitZ();
    sigma0 = {e.x(), e.y()};
  }
  std::complex<double> sigma(double t) const {
    const std::complex<double> i(0.0, 1.0);
    return sigma0 * (w_minus * std::exp(i * w_plus * t) - w_plus * std::exp(i * w_minus * t)) / (w_minus - w_plus);
  }
  double max_tilt() const { return std::abs(sigma0) * (w_plus + w_minus) / (w_plus - w_minus); }
};

/// Torque-free symmetric top (h = 0, PHYSICS.md): L is fixed in the world and the axis turns
/// about it at |L| / A: e_Z(t) = Rot(L / |L|, |L| t / A) e_Z(0).
struct FreePrecession {
  Vector3 momentum, axis0;
  double inertia;
  explicit FreePrecession(const SceneConfig& c) {
    const Quaternion q0 = initial_attitude(c.initial);
    const Vector3 w = initial_body_rates(c.initial);
    inertia = c.top.inertia_transverse;
    momentum = q0 * Vector3(inertia * w.x(), inertia * w.y(), c.top.inertia_axial * w.z());
    axis0 = q0 * Vector3::UnitZ();
  }
  double rate() const { return momentum.norm() / inertia; }
  Vector3 axis(double t) const { return Eigen::AngleAxisd(rate() * t, momentum.normalized()) * axis0; }
};

/// Dominant angular frequency of a uniformly sampled, nearly sinusoidal signal, from the
/// three-term recurrence x[k+1] + x[k-1] - 2 c = 2 cos(w dt) (x[k] - c) fitted by least squares
/// (an exact identity for c + a cos(w t + phi)). Valid while w dt < pi (no aliasing).
inline double dominant_frequency(const std::vector<double>& x, double dt) {
  // y = p x + q with y = x[k+1] + x[k-1]: p = 2 cos(w dt). Centred first: the oscillation can
  // be 1e-4 of the mean, and the normal equations would lose it to cancellation.
  double mean = 0.0;
  for (double v : x) mean += v / static_cast<double>(x.size());
  double sx = 0, sy = 0, sxx = 0, sxy = 0;
  int n = 0;
  for (size_t k = 1; k + 1 < x.size(); ++k, ++n) {
    const double xi = x[k] - mean, yi = x[k + 1] + x[k - 1] - 2.0 * mean;
    sx += xi;
    sy += yi;
    sxx += xi * xi;
    sxy += xi * yi;
  }
  const double p = (n * sxy - sx * sy) / (n * sxx - sx * sx);
  return std::acos(std::max(-1.0, std::min(1.0, 0.5 * p))) / dt;
}

}  // namespace extreme
}  // namespace spinning_top
