// Exact solution of the integrable scenes (fixed tip, frictionless) by quadrature, the
// benchmark's reference for the attitude and the normal force (doc/benchmark.md).
//
// With u = cos(theta), energy and the two conserved momenta give (PHYSICS.md, invariants)
//   udot^2 = f(u) / D(u),  f(u) = (2/A')(E' - m g h u)(1 - u^2) - ((L_z - C wZ u)/A')^2,
// a cubic f = k (u - u1)(u2 - u)(u3 - u) with k = 2 m g h / A', u1 <= u <= u2 <= 1 <= u3;
// A' = A0, D = 1 for the fixed tip; A' = A, D = 1 + (m h^2/A)(1 - u^2) for the frictionless top.
// The substitution u = u2 - (u2 - u1) sin^2(s) removes both endpoint singularities:
//   dt/ds = 2 sqrt(D(u) / (k (u3 - u))),   dphi/ds = phidot(u) dt/ds,
//   phidot = (L_z - C wZ u) / (A' (1 - u^2)),
// smooth and periodic in s with period pi (one nutation period T = t(pi)). t(s) and phi(s) are
// tabulated by 16-point Gauss-Legendre on 64 panels (machine precision for these analytic,
// slowly varying integrands), and t(s) = t is inverted by Newton's method inside the panel.
#pragma once

#include <algorithm>
#include <array>
#include <cmath>
#include <stdexcept>
#include <vector>

#include "spinning_top/parameters.hpp"

namespace spinning_top::bench {

/// 16-point Gauss-Legendre nodes and weights on [-1, 1] (positive half; symmetric).
inline const std::array<std::pair<double, double>, 8>& gauss_legendre16() {
  static const std::array<std::pair<double, double>, 8> table = {{
      {0.0950125098376374401853193, 0.1894506104550684962853967},
      {0.2816035507792589132304605, 0.1826034150449235888667637},
      {0.4580167776572273863424194, 0.1691565193950025381893121},
      {0.6178762444026437484466718, 0.1495959888165767320815017},
      {0.7554044083550030338951012, 0.1246289712555338720524763},
      {0.8656312023878317438804679, 0.0951585116824927848099251},
      {0.9445750230732325760779884, 0.0622535239386478928628438},
      {0.9894009349916499325961542, 0.0271524594117540948517806},
  }};
  return table;
}

class QuadratureReference {
 public:
  struct Sample {
    double theta, phi, theta_dot, phi_dot;
  };

  /// frictionless = false: fixed tip (A' = A0, D = 1).
  QuadratureReference(const TopParameters& p, const InitialConditions& ic, bool frictionless) {
    const double m = p.mass, g = p.gravity, h = p.tip_distance;
    a_ = frictionless ? p.inertia_transverse : p.inertia_about_tip();
    alpha_ = frictionless ? m * h * h / p.inertia_transverse : 0.0;
    c_spin_ = p.inertia_axial * ic.spin;
    mgh_ = m * g * h;
    const double u0 = std::cos(ic.tilt), s2 = 1.0 - u0 * u0;
    // E' = E - C wZ^2/2 (constant) and L_z from the initial Euler-angle rates.
    const double kinetic = 0.5 * a_ * (ic.nutation_rate * ic.nutation_rate + s2 * ic.precession_rate * ic.precession_rate) +
                           0.5 * m * h * h * (frictionless ? s2 * ic.nutation_rate * ic.nutation_rate : 0.0);
    energy_ = kinetic + mgh_ * u0;
    lz_ = a_ * s2 * ic.precession_rate + c_spin_ * u0;
    // f(u) = c3 u^3 + c2 u^2 + c1 u + c0.
    const double e2 = 2.0 * energy_ / a_, k = 2.0 * mgh_ / a_, l = lz_ / a_, cw = c_spin_ / a_;
    const double c3 = k, c2 = -e2 - cw * cw, c1 = -k + 2.0 * l * cw, c0 = e2 - l * l;
    k_ = k;
    std::array<double, 3> roots = cubic_roots(c3, c2, c1, c0);
    if (ic.nutation_rate == 0.0) {
      // The start is a turning point: u0 is a root exactly. Deflating f by (u - u0) gives
      // the other two from a quadratic; a numerical root a few ulp from u0 would instead
      // shift the phase by sqrt(ulp / (u2 - u1)) ~ 1e-7 (the sqrt-singularity at a turning point).
      const double b1 = c2 + c3 * u0, b0 = c1 + b1 * u0;
      const double disc = std::sqrt(std::max(0.0, b1 * b1 - 4.0 * c3 * b0));
      const double qq = -0.5 * (b1 + std::copysign(disc, b1));
      roots = {u0, qq / c3, b0 / qq};
    }
    std::sort(roots.begin(), roots.end());
    u1_ = roots[0];
    u2_ = roots[1];
    u3_ = roots[2];
    if (!(u1_ < u2_) || u2_ > 1.0 + 1e-12 || u1_ < -1.0) throw std::runtime_error("reference: degenerate nutation");
    // Initial phase s0 in [0, pi]: u decreases (theta grows) on (0, pi/2).
    const double ratio = std::clamp((u2_ - u0) / (u2_ - u1_), 0.0, 1.0);
    s0_ = std::asin(std::sqrt(ratio));
    if (ic.nutation_rate < 0.0) s0_ = kPi - s0_;
    phi0_ = ic.heading;
    // Tables of t(s) and phi(s) at the panel edges of [0, pi].
    t_edges_.assign(kPanels + 1, 0.0);
    phi_edges_.assign(kPanels + 1, 0.0);
    for (int i = 0; i < kPanels; ++i) {
      const double a = i * panel_width(), b = a + panel_width();
      t_edges_[i + 1] = t_edges_[i] + integrate(a, b, false);
      phi_edges_[i + 1] = phi_edges_[i] + integrate(a, b, true);
    }
    period_ = t_edges_.back();
    phi_per_period_ = phi_edges_.back();
    t_at_s0_ = t_of_s(s0_);
    phi_at_s0_ = phi_of_s(s0_);
  }

  double period() const { return period_; }
  double turning_point_low() const { return u1_; }   ///< cos(theta_max)
  double turning_point_high() const { return u2_; }  ///< cos(theta_min)
  /// Mean precession rate over a nutation period.
  double mean_precession_rate() const { return phi_per_period_ / period_; }

  Sample at(double t) const {
    const double tau = t + t_at_s0_;
    const double n = std::floor(tau / period_);
    const double r = tau - n * period_;
    // Panel containing r, then Newton on t(s) = r (t' = dt/ds > 0, smooth).
    int i = static_cast<int>(std::upper_bound(t_edges_.begin(), t_edges_.end(), r) - t_edges_.begin()) - 1;
    i = std::clamp(i, 0, kPanels - 1);
    const double a = i * panel_width();
    double s = a + panel_width() * (r - t_edges_[i]) / (t_edges_[i + 1] - t_edges_[i]);
    for (int iter = 0; iter < 30; ++iter) {
      const double residual = t_edges_[i] + integrate(a, s, false) - r;
      const double ds = residual / dt_ds(s);
      s -= ds;
      if (std::abs(ds) < 1e-15) break;
    }
    const double phi = phi0_ + n * phi_per_period_ + phi_edges_[i] + integrate(a, s, true) - phi_at_s0_;
    const double u = u_of(s);
    const double sin_theta = std::sqrt(std::max(0.0, 1.0 - u * u));
    // udot = (du/ds) / (dt/ds), thetadot = -udot / sin(theta).
    const double du_ds = -(u2_ - u1_) * std::sin(2.0 * s);
    const double theta_dot = -(du_ds / dt_ds(s)) / sin_theta;
    return Sample{std::acos(std::clamp(u, -1.0, 1.0)), phi, theta_dot, phi_dot(u)};
  }

 private:
  static constexpr double kPi = 3.14159265358979323846;
  static constexpr int kPanels = 64;
  static double panel_width() { return kPi / kPanels; }

  double u_of(double s) const {
    const double sn = std::sin(s);
    return u2_ - (u2_ - u1_) * sn * sn;
  }
  double dt_ds(double s) const {
    const double u = u_of(s);
    return 2.0 * std::sqrt((1.0 + alpha_ * (1.0 - u * u)) / (k_ * (u3_ - u)));
  }
  double phi_dot(double u) const { return (lz_ - c_spin_ * u) / (a_ * (1.0 - u * u)); }

  double integrate(double a, double b, bool phi) const {
    const double mid = 0.5 * (a + b), half = 0.5 * (b - a);
    double sum = 0.0;
    for (const auto& [x, w] : gauss_legendre16()) {
      for (const double s : {mid - half * x, mid + half * x}) {
        const double v = dt_ds(s);
        sum += w * (phi ? v * phi_dot(u_of(s)) : v);
      }
    }
    return sum * half;
  }
  double t_of_s(double s) const {
    const int i = std::clamp(static_cast<int>(s / panel_width()), 0, kPanels - 1);
    return t_edges_[i] + integrate(i * panel_width(), s, false);
  }
  double phi_of_s(double s) const {
    const int i = std::clamp(static_cast<int>(s / panel_width()), 0, kPanels - 1);
    return phi_edges_[i] + integrate(i * panel_width(), s, true);
  }

  /// Real roots of c3 u^3 + c2 u^2 + c1 u + c0 (three expected), trigonometric method,
  /// each polished by Newton's method.
  static std::array<double, 3> cubic_roots(double c3, double c2, double c1, double c0) {
    const double a = c2 / c3, b = c1 / c3, c = c0 / c3;
    const double q = (a * a - 3.0 * b) / 9.0, r = (2.0 * a * a * a - 9.0 * a * b + 27.0 * c) / 54.0;
    if (!(r * r < q * q * q)) throw std::runtime_error("reference: cubic without three real roots");
    const double theta = std::acos(std::clamp(r / std::sqrt(q * q * q), -1.0, 1.0));
    std::array<double, 3> roots;
    for (int j = 0; j < 3; ++j) {
      double x = -2.0 * std::sqrt(q) * std::cos((theta + 2.0 * kPi * (j - 1)) / 3.0) - a / 3.0;
      for (int it = 0; it < 5; ++it) {
        const double f = ((x + a) * x + b) * x + c, df = (3.0 * x + 2.0 * a) * x + b;
        if (df != 0.0) x -= f / df;
      }
      roots[j] = x;
    }
    return roots;
  }

  double a_, alpha_, c_spin_, mgh_, energy_, lz_, k_;
  double u1_, u2_, u3_, s0_, phi0_;
  double period_, phi_per_period_, t_at_s0_, phi_at_s0_;
  std::vector<double> t_edges_, phi_edges_;
};

}  // namespace spinning_top::bench
