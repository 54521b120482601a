// The general motion of the exact integrator (../exact.hpp): the nutation in closed form by
// Jacobi's elliptic functions, the attitude by Fourier series in its phase, and the events.
//
// 1. The nutation. With u = cos(theta) = e_Zz, energy and the two conserved momenta give
// (PHYSICS.md, "Invariants"; Goldstein, Classical Mechanics, 3rd ed., sec. 5.7)
//   udot^2 D(u) = f(u) = (2/A')(E' - m g h u)(1 - u^2) - p(u)^2,   p(u) = (L_z - C wZ u) / A',
// A' = A0, D = 1 (fixed tip); A' = A, D = 1 + (m h^2/A)(1 - u^2) (frictionless); f is the cubic
// kappa (u - u1)(u2 - u)(u3 - u), kappa = 2 m g h / A', u1 <= u <= u2 <= 1 <= u3. Jacobi's
// substitution u = u1 + (u2 - u1) sn^2(w, k), k^2 = (u2 - u1)/(u3 - u1), turns it into
//   dt/dw = 2 sqrt(D(u)) / mu,   mu^2 = kappa (u3 - u1)
// (Whittaker, Analytical Dynamics, sec. 72; constant for the fixed tip, so there t is linear in w).
// w is the uniformizing variable of the motion: every quantity below is analytic in a strip of
// half-width K' about the real w axis whatever the state, in particular near the separatrix
// (k -> 1: a slow top released near the vertical, an unstable sleeping top), where the
// trigonometric parameter u = u2 - (u2 - u1) sin^2(s) of the earlier version had a branch point
// at distance sqrt((u3 - u2)/(u2 - u1)) from the real s axis.
//
// 2. The attitude, without Euler angles. Write q = (w, x, y, z) as the Cayley-Klein pair
// alpha = w + i z, beta = x + i y (|alpha|^2 = (1 + u)/2, |beta|^2 = (1 - u)/2). The kinematics
// qdot = q (0, omega)/2 read (Omega = omega_X + i omega_Y)
//   alphadot = (i wZ alpha - beta conj(Omega))/2,   betadot = (alpha Omega - i wZ beta)/2,
// and with the z-x-z angles alpha = cos(theta/2) e^{i a}, beta = sin(theta/2) e^{i b},
// a = (phi + psi)/2, b = (phi - psi)/2:
//   adot = (wZ + p/(1 + u))/2,   bdot = (p/(1 - u) - wZ)/2.
// bdot has a pole where u = 1 (a zero of 1 - u(w) at complex w, near the real axis when the axis
// passes near the vertical): that is the Euler-angle singularity, and why the Fourier series
// of phi and psi need arbitrarily many terms there. It is removed in closed form: on the real
// axis 1 - u = (1 - u1) cn^2 + (1 - u2) sn^2 = |F(w)|^2 with the entire function
//   F(w) = sqrt(1 - u1) cn(w) + i s+ sqrt(1 - u2) sn(w),   s+ = sign(p(1)),
// whose phase has exactly the pole part of b (its residue is that of b, i/2, at the zero of
// F; matching it fixes s+), so that
//   beta = e^{i b_r(w)} F(w) / sqrt(2),   db_r/dw = db/dw - d arg F/dw = analytic,
// and the same at u = -1 with G(w) = sqrt(1 + u1) cn + i s- sqrt(1 + u2) sn for alpha. The
// analytic remainders, written without cancellation (p(u) - p(1) = c (1 - u), D - 1 = alpha_D
// (1 - u^2), dn = sqrt((u3 - u)/(u3 - u1))):
//   db_r/dw = [p alpha_D (1 + u)/(sqrt D + 1) + c]/mu - s+ sqrt((1-u1)(1-u2)) kappa /
//             (mu (sqrt(kappa (u3 - 1)) + mu dn)) - wZ sqrt(D)/mu,
//   da_r/dw = [p alpha_D (1 - u)/(sqrt D + 1) - c]/mu + s- sqrt((1+u1)(1+u2)) kappa /
//             (mu (sqrt(kappa (u3 + 1)) + mu dn)) + wZ sqrt(D)/mu,           c = C wZ / A'.
// They depend on w only through u, so t(w), a_r(w), b_r(w) are a secular term plus a sine series
// in x = pi w / K (K = K(k)), whose coefficients come from a DCT-I of samples on [0, K],
// doubled until the upper half of the coefficients is at round-off. No state is refused for
// passing near or through the vertical, and none for starting there while moving.
// The body rates follow from the kinematics: Omega = (2 betadot + i wZ beta) / alpha (or, where
// |alpha| < |beta|, from alphadot), with betadot = e^{i b_r} (i b_r' F + F') wdot / sqrt(2).
//
// (3. Serving requests: ../exact.hpp and exact_driver.hpp.)
//
// 4. Events in closed form. R and e_Zz are functions of u alone: z_G = h u, so R = m (g + h
// udd) with udd = (f' D - f D')/(2 D^2) (fixed tip: f'/2): the sign of R is that of the quartic
// (fixed tip: quadratic) P(u) = 2 g D^2 + h (f' D - f D'). Its roots in [u1, u2] (by isolating
// intervals from the roots of its derivatives) and u = 0 give the phases w where the motion
// enters R < 0 or e_Zz <= 0; the first one after the start, converted by t(w), is the event.
// Nothing is sampled, so no dip of R, however short, is missed.
//
// Steady precession (u1 = u2) needs no special case (k = 0). The frictionless top without
// gravity (kappa = 0, f quadratic: u3 -> infinity) is the limit k -> 0 with mu^2 = -f''/2.
// Refused with MethodRefusal("exact", why, "dop853") (method_refusal.hpp): a motion exactly on the separatrix (k = 1:
// it approaches the unstable vertical for ever, the period is infinite), series that do not
// converge within kMaxSamples samples, and starts whose cubic has no usable turning points.
#pragma once

#include <algorithm>
#include <array>
#include <cmath>
#include <complex>
#include <limits>
#include <string>
#include <vector>

#include "spinning_top/events.hpp"
#include "spinning_top/integrators/elliptic.hpp"
#include "spinning_top/integrators/exact/common.hpp"
#include "spinning_top/integrators/exact/polynomial.hpp"
#include "spinning_top/integrators/exact/series.hpp"
#include "spinning_top/kinematics.hpp"
#include "spinning_top/method_refusal.hpp"
#include "spinning_top/parameters.hpp"

namespace spinning_top {
namespace exact_detail {

/// The quadrature from one start (items 1, 2 and 4): the turning points, the series in the
/// nutation phase w, the phase w0 of the start, the period factors and the first event.
class Quadrature {
 public:
  /// Largest number of samples per half period of the series (beyond: refused).
  static constexpr int kMaxSamples = 1 << 14;

  /// gamma = Gamma at the start, sin2 = Gamma_X^2 + Gamma_Y^2.
  Quadrature(const Start& from, const Vector3& gamma, double sin2)
      : t0_(from.t0), alpha_d_(from.alpha_d), kappa_(from.kappa), gravity_(from.gravity),
        tip_distance_(from.tip_distance), spin_(from.spin) {
    fallen_vertical_ = from.fallen_vertical;
    const double wx0 = from.wx0, wy0 = from.wy0;
    const double qx = from.q0.x(), qy = from.q0.y();
    u0_ = gamma.z();
    d0_ = 2.0 * (qx * qx + qy * qy);  // 1 - u0 without cancellation
    c_ = from.axial * spin_ / from.transverse;
    // From the state (Gamma_perp = sin(theta) e^{i(pi/2 - psi)}): udot = omega_Y Gamma_X -
    // omega_X Gamma_Y, p = sin^2(theta) phidot = omega . Gamma_perp.
    const double u_dot0 = wy0 * gamma.x() - wx0 * gamma.y();
    p0_ = wx0 * gamma.x() + wy0 * gamma.y();
    // A planar motion (phidot = 0) computed from rotated components leaves p at round-off.
    if (std::abs(p0_) <= 8.0 * kEpsilon * std::hypot(wx0, wy0) * std::sqrt(sin2)) p0_ = 0.0;
    const double d_start = 1.0 + alpha_d_ * sin2;
    // K = 2 (E' - m g h u0) / A' = omega_perp^2 + alpha_D udot0^2 (kinetic energy without spin).
    const double k_energy = wx0 * wx0 + wy0 * wy0 + alpha_d_ * u_dot0 * u_dot0;
    // Taylor coefficients of f(u0 + v) = f0 + f1 v + f2 v^2 + kappa v^3.
    f0_ = u_dot0 * u_dot0 * d_start;
    f1_ = -kappa_ * sin2 - 2.0 * u0_ * k_energy + 2.0 * c_ * p0_;
    f2_ = 2.0 * kappa_ * u0_ - k_energy - c_ * c_;
    find_turning_points();
    delta_ = v2_ - v1_;
    // The distances of the turning points from the vertical, 1 - u1, 1 - u2, u3 - 1, and from the
    // downward vertical, 1 + u1, 1 + u2, to full relative precision (end_roots()).
    const double p_up = p0_ - c_ * d0_, p_down = p0_ + c_ * (2.0 - d0_);  // p(1), p(-1)
    end_roots(p_up, p_down, k_energy);
    // mu^2 = kappa (u3 - u1); for kappa = 0 (u3 -> infinity) its limit -f2 (Vieta).
    mu2_ = kappa_ > 0.0 ? kappa_ * (one_minus_u1_ - one_minus_u3_) : -f2_;  // (u3 - 1) + (1 - u1)
    if (!(mu2_ > 0.0) || !std::isfinite(mu2_))
      throw MethodRefusal("exact", "nothing drives the nutation (no gravity torque, no spin and no "
                                           "transverse motion: the cubic vanishes, kappa (u3 - u1) = " +
                                               format(mu2_) + ", and the phase is undefined)", "dop853");
    mu_ = std::sqrt(mu2_);
    // k'^2 = (u3 - u2)/(u3 - u1): near the separatrix both u3 - 1 and 1 - u2 are small.
    const double complement =
        kappa_ > 0.0 ? std::sqrt((one_minus_u2_ - one_minus_u3_) / (one_minus_u1_ - one_minus_u3_)) : 1.0;
    if (!(complement > 0.0))
      throw MethodRefusal("exact", "the motion lies on the separatrix (k = 1: it approaches the unstable vertical "
                             "for ever and its period is infinite)", "dop853");
    modulus_ = elliptic::JacobiModulus(std::min(1.0, complement));
    kappa_u3_minus_1_ = kappa_ > 0.0 ? -kappa_ * one_minus_u3_ : mu2_;
    kappa_u3_plus_1_ = mu2_ + kappa_ * one_plus_u1_;
    // Signs of the pole parts: p(1) = p0 - c (1 - u0), p(-1) = p0 + c (1 + u0).
    sign_up_ = p_up >= 0.0 ? 1.0 : -1.0;
    sign_down_ = p_down >= 0.0 ? 1.0 : -1.0;
    pole_up_ = sign_up_ * std::sqrt(one_minus_u1_ * one_minus_u2_);
    pole_down_ = sign_down_ * std::sqrt(one_plus_u1_ * one_plus_u2_);
    // |omega| bounds |Omega| (K(u1) = omega_perp^2 + alpha_D udot^2 at the lowest point) and sets
    // the round-off of Omega = (2 betadot + i wZ beta)/alpha, whose terms are ~ |omega| each.
    rate_scale_ = std::sqrt(std::max(k_energy - kappa_ * v1_, 0.0) + spin_ * spin_) + 1e-300;
    build_series();
    // The start's phase w0 in [0, 2K): sn^2 = (u0 - u1)/(u2 - u1), cn^2 = (u2 - u0)/(u2 - u1),
    // dn^2 = (u3 - u0)/(u3 - u1), from the roots without cancellation; u rises on (0, K).
    const double quarter = modulus_.quarter_period();
    if (delta_ > 0.0) {
      const double sn2 = -v1_ / delta_, cn2 = v2_ / delta_;
      const double dn2 = kappa_ > 0.0 ? (d0_ - one_minus_u3_) / (one_minus_u1_ - one_minus_u3_) : 1.0;
      const double w = elliptic::inverse_sn(std::sqrt(sn2), cn2, dn2);
      w0_ = u_dot0 >= 0.0 ? w : 2.0 * quarter - w;
      if (u_dot0 == 0.0 && v2_ == 0.0) w0_ = quarter;  // at the upper turning point exactly
    } else {
      w0_ = 0.0;  // steady precession: every phase is the same state
    }
    time_of_w0_ = time_of_phase(w0_);
    period_ = 2.0 * quarter * mean_[0];
    alpha_turn_ = -std::polar(1.0, 2.0 * quarter * mean_[1]);
    beta_turn_ = -std::polar(1.0, 2.0 * quarter * mean_[2]);
    // Offsets: alpha(w0) = alpha0 fixes e^{i a}; beta's from beta0 and betadot0 together, which
    // stays well posed when the start is at the vertical (beta0 = 0).
    alpha_offset_ = beta_offset_ = Complex(1.0, 0.0);
    const Complex alpha0(from.q0.w(), from.q0.z()), beta0(from.q0.x(), from.q0.y()), omega0(wx0, wy0);
    Complex beta_rate_free(0.0, 0.0);
    const Motion start = motion_at_phase(w0_, &beta_rate_free);
    alpha_offset_ = unit(alpha0 / start.alpha);
    const Complex beta_rate0 = 0.5 * (alpha0 * omega0 - Complex(0.0, spin_) * beta0);
    const double rate2 = spin_ * spin_ + std::norm(omega0) + 0.25 * mu2_ / d_start + 1e-300;
    beta_offset_ = unit(beta0 * std::conj(start.beta) + beta_rate0 * std::conj(beta_rate_free) / rate2);
    find_first_event();
  }

  /// Nutation period T [s], turning points u1 <= u2.
  double period() const { return period_; }
  double turning_point_low() const { return u0_ + v1_; }
  double turning_point_high() const { return u0_ + v2_; }
  /// Fourier terms per series in w (what the start computed; requests do not sum them).
  int terms() const { return static_cast<int>(std::max(angle_sine_.size(), time_sine_.size())); }
  /// Samples per half period the series needed (a cost measure).
  int samples() const { return samples_; }
  /// The first time after the start at which the motion leaves the model's validity, and
  /// which way (kNone and infinity if it never does).
  Event first_event() const { return event_; }
  double first_event_time() const { return event_time_; }
  double start_time() const { return t0_; }
  /// Period factors of the quadrature: alpha(t + T) = alpha_turn * alpha(t), beta likewise.
  Complex alpha_turn() const { return alpha_turn_; }
  Complex beta_turn() const { return beta_turn_; }
  /// The angle the interpolated functions (alpha, beta, Omega) turn through in one period: their
  /// secular phases plus 2 pi per significant harmonic of the nutation (a coefficient above 1e-3
  /// of the largest). Sets the pieces of the request interpolation.
  double phase_per_period() const {
    const double quarter = modulus_.quarter_period();
    const double a = std::abs(2.0 * quarter * mean_[1]) + kPi;  // G turns by pi per period
    const double b = std::abs(2.0 * quarter * mean_[2]) + kPi;
    double largest = 0.0;
    for (const auto& c : angle_sine_) largest = std::max({largest, std::abs(c[0]), std::abs(c[1])});
    for (const auto& c : time_sine_) largest = std::max(largest, std::abs(c[0]) / std::max(mean_[0], 1e-300));
    int harmonics = 1;  // the nutation itself, through u
    for (std::size_t k = 0; k < std::max(angle_sine_.size(), time_sine_.size()); ++k) {
      const double size = std::max(k < angle_sine_.size() ? std::max(std::abs(angle_sine_[k][0]), std::abs(angle_sine_[k][1])) : 0.0,
                                   k < time_sine_.size() ? std::abs(time_sine_[k][0]) / std::max(mean_[0], 1e-300) : 0.0);
      if (size > 1e-3 * largest) harmonics = static_cast<int>(k) + 1;
    }
    return std::max({a, b, a + b}) + 2.0 * kPi * harmonics;
  }
  /// A bound of |omega| over the motion (the scale of the body rates and of their round-off).
  double rate_scale() const { return rate_scale_; }

  Motion motion(double t) const { return motion_at_phase(phase_of_time(t)); }

  /// The extremes of the motion over [t0, t] (t >= t0): the largest 1 - u (u = e_Zz = cos tilt),
  /// and the least R / m. Both depend on the state through u alone (z_G = h u, R = m (g + z_G''),
  /// header comment, item 4), so over [t0, t] they are extremes of functions of u over the range
  /// u covers: [u1, u2] once the phase w has passed a turning point of each kind (u = u1 at
  /// w = 0 mod 2K, u2 at w = K mod 2K), else the values between the ends. R / m = P(v) / (2 D^2),
  /// least at an end of that range or where d(P / D^2)/dv = (P' D - 2 P D') / D^3 changes sign.
  /// Nothing is sampled: no peak between two samples is missed.
  Range range_until(double t) const {
    Range range;
    const double quarter = modulus_.quarter_period(), period_w = 2.0 * quarter;
    const double w1 = std::max(w0_, phase_of_time(t));
    auto passes = [&](double phase) {  // w0 <= phase + 2K n <= w1 for some n
      return std::floor((w1 - phase) / period_w) >= std::ceil((w0_ - phase) / period_w);
    };
    const bool low = delta_ > 0.0 && passes(0.0), high = delta_ > 0.0 && passes(quarter);
    // u and 1 - u at the end (1 - u from the Jacobi functions, without cancellation).
    const double turns = std::floor(w1 / period_w);
    const Phase end = phase_values(modulus_.at(std::fma(-turns, period_w, w1)));
    const double v_end = delta_ > 0.0 ? end.v : 0.0;
    const double v_low = low ? v1_ : std::min(0.0, v_end), v_high = high ? v2_ : std::max(0.0, v_end);
    range.one_minus_u_max = low ? one_minus_u1_ : std::max(d0_, delta_ > 0.0 ? end.one_minus_u : d0_);
    const Polynomial p = normal_force_sign(), d = inertia_factor();
    auto per_mass = [&](double v) {
      const double dv = evaluate(d, v);
      return evaluate(p, v) / (2.0 * dv * dv);
    };
    double least = std::min(per_mass(v_low), per_mass(v_high));
    const Polynomial slope = subtract(multiply(derivative(p), d), multiply({2.0}, multiply(p, derivative(d))));
    for (double v : sign_changes(slope, v_low, v_high)) least = std::min(least, per_mass(v));
    range.least_normal_force_per_mass = least;
    return range;
  }

 private:
  static Complex unit(Complex z) {
    const double r = std::abs(z);
    return r > 0.0 && std::isfinite(r) ? z / r : Complex(1.0, 0.0);
  }

  /// 1 - u_i and 1 + u_i to full relative precision. They enter where the axis passes near the
  /// vertical (1 - u2 small: the amplitude of beta there is sqrt((1 - u2)/2)) and near the
  /// separatrix (u3 - 1 small too: k'), and 1 + u1 for a top swinging through the bottom; from
  /// the roots in v = u - u0 they would keep only an absolute precision ~ eps. Expanded about
  /// u = 1 and u = -1 the cubic's constant terms are exact invariants, f(+-1) = -p(+-1)^2, so its
  /// small roots come out with relative precision: the root of largest magnitude (from the
  /// v-roots, polished) is divided out from the low end (which keeps the small roots' relative
  /// accuracy; Wilkinson, Rounding Errors in Algebraic Processes, ch. 2) and the quadratic left is
  /// solved without cancellation.
  ///   f(1 - z) = -p(1)^2 + (2 K(1) - 2 c p(1)) z + (2 kappa - K(1) - c^2) z^2 - kappa z^3,
  ///   f(-1 + y) = -p(-1)^2 + (2 K(-1) + 2 c p(-1)) y - (2 kappa + K(-1) + c^2) y^2 + kappa y^3,
  /// K(u) = 2 (E' - m g h u)/A' = K(u0) - kappa (u - u0); roots z3 <= 0 <= z2 <= z1, y1 <= y2 <= y3.
  void end_roots(double p_up, double p_down, double k_energy) {
    auto polish = [](const Polynomial& g, double x) {
      const Polynomial dg = derivative(g);
      for (int i = 0; i < 4; ++i) {
        const double slope = evaluate(dg, x);
        if (slope == 0.0) break;
        const double next = x - evaluate(g, x) / slope;
        if (!(std::abs(evaluate(g, next)) < std::abs(evaluate(g, x)))) break;
        x = next;
      }
      return x;
    };
    // Roots of q0 + q1 x + q2 x^2 in increasing order, without cancellation.
    auto quadratic = [](double q0, double q1, double q2) {
      const double disc = std::sqrt(std::max(0.0, q1 * q1 - 4.0 * q2 * q0));
      const double s = -0.5 * (q1 + std::copysign(disc, q1));
      double a = s / q2, b = s != 0.0 ? q0 / s : 0.0;
      if (a > b) std::swap(a, b);
      return std::array<double, 2>{a, b};
    };
    // Divides g by (x - r) from the constant term up: the quotient's coefficients.
    auto deflate = [](const Polynomial& g, double r) {
      const double q0 = -g[0] / r, q1 = (q0 - g[1]) / r;
      return std::array<double, 2>{q0, q1};
    };
    const double k_up = k_energy - kappa_ * d0_, k_down = k_energy + kappa_ * (2.0 - d0_);
    const Polynomial g = {-p_up * p_up, 2.0 * k_up - 2.0 * c_ * p_up, 2.0 * kappa_ - k_up - c_ * c_, -kappa_};
    const Polynomial h = {-p_down * p_down, 2.0 * k_down + 2.0 * c_ * p_down, -2.0 * kappa_ - k_down - c_ * c_, kappa_};
    double z1 = d0_ - v1_, z2 = d0_ - v2_, z3 = -std::numeric_limits<double>::infinity();
    double y1 = 2.0 - d0_ + v1_, y2 = 2.0 - d0_ + v2_;
    if (kappa_ > 0.0) {
      z3 = d0_ - v3_;
      if (-z3 > z1) {  // u3 is the farthest from 1: z1, z2 from the quotient
        const double big = polish(g, z3);
        const std::array<double, 2> q = deflate(g, big);
        const std::array<double, 2> r = quadratic(q[0], q[1], g[3]);
        z3 = big, z2 = polish(g, r[0]), z1 = polish(g, r[1]);
      } else {  // u1 is: z2, z3 from the quotient
        const double big = polish(g, z1);
        const std::array<double, 2> q = deflate(g, big);
        const std::array<double, 2> r = quadratic(q[0], q[1], g[3]);
        z1 = big, z3 = polish(g, r[0]), z2 = polish(g, r[1]);
      }
      const double big = polish(h, 2.0 - d0_ + v3_);  // y3 = 1 + u3 >= 2 - ... is the largest
      const std::array<double, 2> q = deflate(h, big);
      const std::array<double, 2> r = quadratic(q[0], q[1], h[3]);
      y1 = polish(h, r[0]), y2 = polish(h, r[1]);
    } else if (g[2] != 0.0) {
      const std::array<double, 2> r = quadratic(g[0], g[1], g[2]);
      z2 = polish(g, r[0]), z1 = polish(g, r[1]);
      const std::array<double, 2> s = quadratic(h[0], h[1], h[2]);
      y1 = polish(h, s[0]), y2 = polish(h, s[1]);
    }
    // Each distance from its better source: from the v-roots where that is a sum of positive
    // terms (1 - u1 = d0 - v1, 1 + u2), or where it does not cancel; from the end expansions
    // where the v-roots would cancel (the turning point much nearer the vertical than the start).
    // The end roots come in pairs that may be close to each other (steady precession: z1 ~ z2),
    // but a root used here is then far from the other two, hence well conditioned.
    (void)y2;
    one_minus_u1_ = d0_ - v1_;
    const double from_v2 = d0_ - v2_;
    one_minus_u2_ = std::clamp(from_v2 < 0.5 * d0_ ? z2 : from_v2, 0.0, one_minus_u1_);
    const double from_v3 = d0_ - v3_;  // 1 - u3 <= 0
    one_minus_u3_ = std::min(0.0, -from_v3 < 0.5 * (v3_ + 1.0) ? z3 : from_v3);
    const double from_v1 = 2.0 - d0_ + v1_;
    one_plus_u1_ = std::max(0.0, from_v1 < 0.5 * (2.0 - d0_) ? y1 : from_v1);
    one_plus_u2_ = 2.0 - d0_ + v2_;
  }

  /// Roots v1 <= 0 <= v2 <= v3 of f(u0 + v) (v3 = infinity for kappa = 0).
  void find_turning_points() {
    const double f0 = f0_, f1 = f1_, f2 = f2_, kappa = kappa_;
    auto f = [&](double v) { return f0 + v * (f1 + v * (f2 + v * kappa)); };
    auto df = [&](double v) { return f1 + v * (2.0 * f2 + 3.0 * kappa * v); };
    auto polish = [&](double v) {  // Newton steps on the full cubic while they reduce |f|
      for (int i = 0; i < 3; ++i) {
        const double slope = df(v);
        if (slope == 0.0) break;
        const double next = v - f(v) / slope;
        if (!(std::abs(f(next)) < std::abs(f(v)))) break;
        v = next;
      }
      return v;
    };
    v3_ = std::numeric_limits<double>::infinity();
    if (kappa == 0.0) {
      // f = f0 + f1 v + f2 v^2 with f2 = -K - c^2 < 0 (or f identically 0: nothing moves).
      if (f2 == 0.0) {
        v1_ = v2_ = 0.0;
      } else {
        const double disc = std::sqrt(std::max(0.0, f1 * f1 - 4.0 * f2 * f0));
        const double qq = -0.5 * (f1 + std::copysign(disc, f1));
        const double a = qq / f2, b = qq != 0.0 ? f0 / qq : 0.0;
        v1_ = std::min(a, b);
        v2_ = std::max(a, b);
        if (f0 == 0.0) (std::abs(v1_) < std::abs(v2_) ? v1_ : v2_) = 0.0;
        v1_ = std::min(v1_, 0.0);
        v2_ = std::max(v2_, 0.0);
      }
    } else if (f0 == 0.0) {
      // A turning point: v = 0 is a root exactly; deflate to kappa v^2 + f2 v + f1 = kappa (v - a)
      // (v - b). f = kappa v (v - a)(v - b) is >= 0 between u1 and u2, so: a < 0 < b (f1 < 0)
      // puts the start at the upper turning point (v1 = a, v2 = 0, v3 = b); 0 < a <= b (f1 > 0)
      // at the lower one (v1 = 0, v2 = a, v3 = b); f1 = 0 is a double root at the start, a
      // steady precession (v1 = v2 = 0) if the third root lies above.
      const double disc = std::sqrt(std::max(0.0, f2 * f2 - 4.0 * kappa * f1));
      const double qq = -0.5 * (f2 + std::copysign(disc, f2));
      double a = polish(qq / kappa), b = qq != 0.0 ? polish(f1 / qq) : 0.0;
      if (a > b) std::swap(a, b);
      if (f1 < 0.0) {
        v1_ = std::min(a, 0.0), v2_ = 0.0, v3_ = std::max(b, 0.0);
      } else if (f1 > 0.0 && a > 0.0) {
        v1_ = 0.0, v2_ = a, v3_ = b;
      } else if (f1 == 0.0 && -f2 / kappa >= 0.0) {
        v1_ = v2_ = 0.0, v3_ = -f2 / kappa;
      } else {
        throw MethodRefusal("exact", "the start is a turning point of the nutation with no motion "
                                             "towards either side (f'(u0) = " + format(f1) +
                                             ")", "dop853");
      }
    } else {
      // f(0) > 0 >= f(u = -1) = -p(-1)^2 brackets u1 (= -1 when p(-1) = 0: the spinless top
      // swings through the bottom). u2 lies between 0 and the local minimum of f, the larger
      // root of f', where f <= 0 (u2 <= 1 <= u3 are both roots beyond 0).
      const double lo = -1.0 - u0_;
      v1_ = f(lo) < 0.0 ? bracketed_root(f, df, lo, 0.0) : lo;
      const double disc = std::sqrt(std::max(0.0, f2 * f2 - 3.0 * kappa * f1));
      const double minimum = f2 < 0.0 ? (disc - f2) / (3.0 * kappa) : -f1 / (f2 + disc);  // cancellation-free
      if (!(minimum > 0.0 && f(minimum) <= 0.0))
        throw MethodRefusal("exact", "the turning points of the nutation cannot be separated "
                                             "(no root of the cubic above the current tilt)", "dop853");
      v2_ = bracketed_root(f, df, 0.0, minimum);
      v3_ = polish(-f2 / kappa - v1_ - v2_);  // Vieta: v1 + v2 + v3 = -f2 / kappa
      if (v3_ < v2_) v3_ = v2_;
    }
    if (!(v1_ <= 0.0 && 0.0 <= v2_ && v2_ <= v3_ && std::isfinite(v1_) && std::isfinite(v2_)))
      throw MethodRefusal("exact", "the turning points of the nutation cannot be separated "
                                           "(u - u0 roots " + format(v1_) + ", " +
                                           format(v2_) + ", " + format(v3_) +
                                           ")", "dop853");
  }

  /// What depends on the phase w only through u: sn, cn, dn, 1 -+ u, sqrt(D).
  struct Phase {
    double sn, cn, dn, v, one_minus_u, one_plus_u, sqrt_d;
  };
  Phase phase_values(const elliptic::JacobiValues& j) const {
    Phase ph;
    ph.sn = j.sn;
    ph.cn = j.cn;
    ph.dn = j.dn;
    const double sn2 = j.sn * j.sn, cn2 = j.cn * j.cn;
    ph.v = v1_ + delta_ * sn2;
    ph.one_minus_u = one_minus_u1_ * cn2 + one_minus_u2_ * sn2;
    ph.one_plus_u = one_plus_u1_ * cn2 + one_plus_u2_ * sn2;
    ph.sqrt_d = std::sqrt(1.0 + alpha_d_ * ph.one_minus_u * ph.one_plus_u);
    return ph;
  }

  /// dt/dw, da_r/dw, db_r/dw at a phase (header comment, eqs. for the analytic remainders).
  std::array<double, 3> integrands(const Phase& ph) const {
    const double p = p0_ - c_ * ph.v;
    const double rd = ph.sqrt_d;
    const double dt_dw = 2.0 * rd / mu_;
    const double spin_part = spin_ * rd / mu_;
    const double up = kappa_ == 0.0 ? 0.0 : pole_up_ * kappa_ / (mu_ * (std::sqrt(kappa_u3_minus_1_) + mu_ * ph.dn));
    const double down = kappa_ == 0.0 ? 0.0 : pole_down_ * kappa_ / (mu_ * (std::sqrt(kappa_u3_plus_1_) + mu_ * ph.dn));
    const double db = (p * alpha_d_ * ph.one_plus_u / (rd + 1.0) + c_) / mu_ - up - spin_part;
    const double da = (p * alpha_d_ * ph.one_minus_u / (rd + 1.0) - c_) / mu_ + down + spin_part;
    return {dt_dw, da, db};
  }

  /// Series of t, a_r, b_r in x = pi w / K: cosine series of the integrands by a DCT-I of n + 1
  /// samples on [0, K] (they are even about 0 and K), n doubled until converged (the samples of
  /// the coarser grid are reused), integrated term by term.
  void build_series() {
    const double quarter = modulus_.quarter_period();
    std::vector<std::array<double, 3>> samples;
    for (int n = 16;; n *= 2) {
      if (n > kMaxSamples) refuse_series();
      std::vector<std::array<double, 3>> grid(n + 1);
      for (int j = 0; j <= n; ++j) {
        if (!samples.empty() && j % 2 == 0) {
          grid[j] = samples[j / 2];
        } else {
          grid[j] = integrands(phase_values(modulus_.at(quarter * j / n)));
        }
      }
      samples = grid;
      std::array<std::vector<double>, 3> a;
      std::array<double, 3> scale = {0.0, 0.0, 0.0};
      bool converged = true;
      std::array<std::vector<double>, 3> columns;
      for (int i = 0; i < 3; ++i) {
        columns[i].resize(n + 1);
        for (int j = 0; j <= n; ++j) columns[i][j] = grid[j][i];
      }
      // The two angle rates share one FFT (their sizes are alike), the time rate has its own.
      const auto angles = cosine_coefficients(columns[1], columns[2]);
      a[0] = cosine_coefficients(columns[0], columns[0])[0];
      a[1] = angles[0], a[2] = angles[1];
      // An angle rate's coefficients matter to an absolute eps / K (the angle per half period
      // K), even where the rate itself vanishes (a spinless top's a_r).
      scale[1] = scale[2] = 1.0 / quarter;
      for (int i = 0; i < 3; ++i) {
        double tail = 0.0;
        for (int k = 0; k <= n; ++k) {
          if (!std::isfinite(a[i][k])) refuse_series();
          scale[i] = std::max(scale[i], std::abs(a[i][k]));
          if (k > n / 2) tail = std::max(tail, std::abs(a[i][k]));
        }
        converged = converged && tail <= 64.0 * kEpsilon * scale[i];
      }
      if (!converged) continue;
      samples_ = n;
      for (int i = 0; i < 3; ++i) mean_[i] = a[i][0];
      if (alpha_d_ == 0.0) {
        mean_[0] = 2.0 / mu_;  // fixed tip: dt/dw = 2/mu exactly
        for (int k = 1; k <= n; ++k) a[0][k] = 0.0;
      }
      // Drop the trailing coefficients below round-off: the time's series apart from the
      // angles' (Newton's method on t(w) sums only the former).
      int last_time = n, last_angle = n;
      while (last_time > 0 && std::abs(a[0][last_time]) <= 0.5 * kEpsilon * scale[0]) --last_time;
      while (last_angle > 0 && std::abs(a[1][last_angle]) <= 0.5 * kEpsilon * scale[1] &&
             std::abs(a[2][last_angle]) <= 0.5 * kEpsilon * scale[2])
        --last_angle;
      time_sine_.assign(last_time, {0.0});
      periodic_bound_ = 0.0;
      time_rate_cosine_.assign(last_time, 0.0);
      angle_sine_.assign(last_angle, {0.0, 0.0});
      for (int k = 1; k <= n; ++k) {
        const double integral = quarter / (kPi * k);
        if (k <= last_time) {
          time_sine_[k - 1][0] = a[0][k] * integral, time_rate_cosine_[k - 1] = a[0][k];
          periodic_bound_ += std::abs(time_sine_[k - 1][0]);
        }
        if (k <= last_angle) angle_sine_[k - 1] = {a[1][k] * integral, a[2][k] * integral};
      }
      return;
    }
  }

  [[noreturn]] void refuse_series() const {
    throw MethodRefusal("exact", "the series in the nutation phase need more than " +
                                             std::to_string(kMaxSamples) + " samples (k' = " +
                                             format(modulus_.complement()) + ")", "dop853");
  }

  double time_of_phase(double w) const {
    if (alpha_d_ == 0.0) return mean_[0] * w;
    const double quarter = modulus_.quarter_period();
    const double turns = std::floor(w / (2.0 * quarter));
    const double x = kPi * std::fma(-turns, 2.0 * quarter, w) / quarter;
    return mean_[0] * w + sine_sums(time_sine_, std::cos(x), std::sin(x))[0];
  }

  /// The phase w at time t: t(w) = t0 + T(w) - T(w0), linear for the fixed tip, else Newton's
  /// method on the series (dt/dw > 0 is bounded away from 0, so it converges from the secular
  /// guess in a few iterations).
  double phase_of_time(double t) const {
    const double elapsed = t - t0_;
    double w = w0_ + elapsed / mean_[0];
    if (alpha_d_ == 0.0) return w;
    const double quarter = modulus_.quarter_period();
    const double target = time_of_w0_ + elapsed;
    // t(w) = mean w + periodic(w) increases with w and |periodic| <= periodic_bound_, so the root
    // lies in [lo, hi]. Newton's step is kept inside the bracket (bisection otherwise): where dt/dw
    // varies by orders of magnitude over a period (a frictionless top passing the vertical with
    // m h^2 / A = 1e4) pure Newton jumped to another branch and gave e_Zz = -0.7 for 0.84 (found
    // by the fuzz test).
    double lo = (target - periodic_bound_) / mean_[0], hi = (target + periodic_bound_) / mean_[0];
    w = std::clamp(w, lo, hi);
    for (int iteration = 0; iteration < 200; ++iteration) {
      const double turns = std::floor(w / (2.0 * quarter));
      const double r = std::fma(-turns, 2.0 * quarter, w);
      const double x = kPi * r / quarter;
      const double cos_x = std::cos(x), sin_x = std::sin(x);
      const double periodic = sine_sums(time_sine_, cos_x, sin_x)[0];
      const double rate = mean_[0] + cosine_sum(time_rate_cosine_, cos_x);
      const double residual = mean_[0] * w + periodic - target;
      if (residual < 0.0) lo = w;
      if (residual > 0.0) hi = w;
      double next = w - residual / rate;
      if (!(next > lo && next < hi)) next = 0.5 * (lo + hi);
      const double step = next - w;
      w = next;
      if (std::abs(step) <= 2.0 * kEpsilon * std::max(1.0, std::abs(w)) || residual == 0.0) break;
    }
    return w;
  }

  /// alpha, beta and Omega at phase w. With beta_rate_free set, also betadot without the
  /// offset (for the start).
  Motion motion_at_phase(double w, Complex* beta_rate_free = nullptr) const {
    const double quarter = modulus_.quarter_period();
    const double turns = std::floor(w / (2.0 * quarter));
    const double r = std::fma(-turns, 2.0 * quarter, w);
    elliptic::JacobiValues j = modulus_.at(r);
    if (std::fmod(turns, 2.0) != 0.0) j.sn = -j.sn, j.cn = -j.cn;  // sn, cn have period 4K
    const Phase ph = phase_values(j);
    const std::array<double, 3> rates = integrands(ph);
    const double x = kPi * r / quarter;
    const std::array<double, 2> periodic = sine_sums(angle_sine_, std::cos(x), std::sin(x));
    const double a = mean_[1] * w + periodic[0], b = mean_[2] * w + periodic[1];
    const double root_down1 = std::sqrt(one_plus_u1_), root_down2 = std::sqrt(one_plus_u2_);
    const double root_up1 = std::sqrt(one_minus_u1_), root_up2 = std::sqrt(one_minus_u2_);
    const Complex g(root_down1 * ph.cn, sign_down_ * root_down2 * ph.sn);
    const Complex f(root_up1 * ph.cn, sign_up_ * root_up2 * ph.sn);
    const Complex dg(-root_down1 * ph.sn * ph.dn, sign_down_ * root_down2 * ph.cn * ph.dn);
    const Complex df(-root_up1 * ph.sn * ph.dn, sign_up_ * root_up2 * ph.cn * ph.dn);
    const double w_dot = 1.0 / rates[0];
    constexpr double kRootHalf = 0.70710678118654752440;
    const Complex turn_a = std::polar(kRootHalf, a), turn_b = std::polar(kRootHalf, b);
    const Complex i(0.0, 1.0);
    Motion m;
    m.alpha = alpha_offset_ * turn_a * g;
    m.beta = beta_offset_ * turn_b * f;
    const Complex alpha_dot = alpha_offset_ * turn_a * (i * rates[1] * g + dg) * w_dot;
    const Complex beta_dot = beta_offset_ * turn_b * (i * rates[2] * f + df) * w_dot;
    if (beta_rate_free) *beta_rate_free = turn_b * (i * rates[2] * f + df) * w_dot;
    // Omega from betadot = (alpha Omega - i wZ beta)/2, or from alphadot = (i wZ alpha - beta
    // conj(Omega))/2 where beta is the larger (|alpha|^2 = (1 + u)/2).
    if (ph.one_plus_u >= ph.one_minus_u)
      m.omega = (2.0 * beta_dot + i * spin_ * m.beta) / m.alpha;
    else
      m.omega = std::conj((i * spin_ * m.alpha - 2.0 * alpha_dot) / m.beta);
    return m;
  }

  /// D(u0 + v) = 1 + alpha_D (1 - u^2) as a polynomial in v = u - u0 (1 for the fixed tip).
  Polynomial inertia_factor() const {
    const double sin2 = (2.0 - d0_) * d0_;
    return {1.0 + alpha_d_ * sin2, -2.0 * alpha_d_ * u0_, -alpha_d_};
  }

  /// The polynomial with the sign of R: P(v) = 2 g D^2 + h (f' D - f D') in v = u - u0
  /// (R = m P / (2 D^2), header comment).
  Polynomial normal_force_sign() const {
    const Polynomial f = {f0_, f1_, f2_, kappa_};
    const Polynomial d = inertia_factor();
    const Polynomial df = derivative(f), dd = derivative(d);
    Polynomial p = multiply({2.0 * gravity_}, multiply(d, d));
    const Polynomial force = subtract(multiply(df, d), multiply(f, dd));
    p.resize(std::max(p.size(), force.size()), 0.0);
    for (std::size_t k = 0; k < force.size(); ++k) p[k] += tip_distance_ * force[k];
    return p;
  }

  /// The first phase after w0 where R < 0 or e_Zz <= 0 begins (R and e_Zz depend on u only, and
  /// u(w) = u1 + (u2 - u1) sn^2 rises on (0, K) and falls on (K, 2K)), and its time.
  void find_first_event() {
    if (!(delta_ > 0.0)) return;  // u is constant: the start's validity is for ever
    const double quarter = modulus_.quarter_period(), period_w = 2.0 * quarter;
    double best = std::numeric_limits<double>::infinity();
    Event which = Event::kNone;
    // The phase in [0, K] of v, and the candidate phase after w0 on the rising or falling branch.
    auto phase_of_v = [&](double v) {
      const double sn2 = std::clamp((v - v1_) / delta_, 0.0, 1.0), cn2 = std::clamp((v2_ - v) / delta_, 0.0, 1.0);
      const double dn2 = (mu2_ - kappa_ * (v - v1_)) / mu2_;
      return elliptic::inverse_sn(std::sqrt(sn2), cn2, dn2);
    };
    auto consider = [&](double w, Event event) {
      double ahead = std::fmod(w - w0_, period_w);
      if (ahead < 0.0) ahead += period_w;
      if (ahead > period_w - 8.0 * kEpsilon * period_w) ahead = 0.0;  // at the start, up to round-off
      if (ahead < best) best = ahead, which = event;
    };
    // Fall: u crosses u_fall (0 for a needle, TopParameters::fallen_vertical) downwards (u1 <= u_fall),
    // on the falling branch.
    if (u0_ + v1_ <= fallen_vertical_) consider(period_w - phase_of_v(fallen_vertical_ - u0_), Event::kFallen);
    // Lift-off: R turns negative where P changes sign in (u1, u2); rising branch if P falls
    // with u there, falling branch if it rises.
    const Polynomial p = normal_force_sign(), dp = derivative(p);
    for (double v : sign_changes(p, v1_, v2_)) {
      const double slope = evaluate(dp, v);
      if (slope < 0.0) consider(phase_of_v(v), Event::kLiftOff);
      if (slope > 0.0) consider(period_w - phase_of_v(v), Event::kLiftOff);
    }
    if (which == Event::kNone) return;
    event_ = which;
    event_time_ = t0_ + (time_of_phase(w0_ + best) - time_of_w0_);
  }

  // From the start (Start): what the phase functions and the events read.
  double t0_ = 0.0;
  double alpha_d_ = 0.0, kappa_ = 0.0, gravity_ = 0.0, tip_distance_ = 0.0, spin_ = 0.0;
  double rate_scale_ = 0.0;
  double fallen_vertical_ = 0.0;
  // u0, 1 - u0, the cubic's Taylor coefficients about u0 and roots in v = u - u0.
  double u0_ = 1.0, d0_ = 0.0, c_ = 0.0, p0_ = 0.0, f0_ = 0.0, f1_ = 0.0, f2_ = 0.0;
  double v1_ = 0.0, v2_ = 0.0, v3_ = 0.0, delta_ = 0.0;
  double one_minus_u1_ = 0.0, one_minus_u2_ = 0.0, one_minus_u3_ = 0.0, one_plus_u1_ = 0.0, one_plus_u2_ = 0.0;
  double mu2_ = 0.0, mu_ = 0.0, kappa_u3_minus_1_ = 0.0, kappa_u3_plus_1_ = 0.0;
  double sign_up_ = 1.0, sign_down_ = 1.0, pole_up_ = 0.0, pole_down_ = 0.0;
  elliptic::JacobiModulus modulus_;
  std::array<double, 3> mean_ = {0.0, 0.0, 0.0};
  std::vector<std::array<double, 1>> time_sine_;   // t(w): sine coefficients (frictionless only)
  double periodic_bound_ = 0.0;                     // sum of |time_sine_|: bounds t(w) - mean w
  std::vector<double> time_rate_cosine_;            // dt/dw: cosine coefficients
  std::vector<std::array<double, 2>> angle_sine_;   // a_r(w), b_r(w)
  int samples_ = 0;
  double w0_ = 0.0, time_of_w0_ = 0.0, period_ = 0.0;
  Complex alpha_turn_{1.0, 0.0}, beta_turn_{1.0, 0.0};
  Complex alpha_offset_{1.0, 0.0}, beta_offset_{1.0, 0.0};
  Event event_ = Event::kNone;
  double event_time_ = std::numeric_limits<double>::infinity();
};

}  // namespace exact_detail
}  // namespace spinning_top
