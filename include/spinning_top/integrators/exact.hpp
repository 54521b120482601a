// "Integrator" exact: the closed-form solution of the two integrable scenes (fixed tip =
// Lagrange top, frictionless top), evaluated at any requested time from constants of motion
// computed once per (re)start. No time step: the cost of a request does not depend on how far
// it lies from the previous one.
//
// With u = cos(theta) and the z-x-z Euler angles of PHYSICS.md (q = Rz(phi) Rx(theta) Rz(psi)),
// the energy and the two conserved momenta give (PHYSICS.md, "Invariants"; Goldstein, Classical
// Mechanics, 3rd ed., sec. 5.7; Landau & Lifshitz, Mechanics, sec. 35, problem 1)
//   udot^2 D(u) = f(u) = (2/A')(E' - m g h u)(1 - u^2) - ((L_z - C wZ u)/A')^2,
//   phidot = (L_z - C wZ u) / (A' (1 - u^2)),   psidot = wZ - phidot u,
// A' = A0, D = 1 (fixed tip); A' = A, D = 1 + (m h^2/A)(1 - u^2) (frictionless), and
// f = kappa (u - u1)(u2 - u)(u3 - u), kappa = 2 m g h / A', u1 <= u <= u2 <= 1 <= u3.
// The substitution u = u2 - (u2 - u1) sin^2(s) (as in bench/reference_solution.hpp) gives
//   dt/ds = 2 sqrt(D(u) / (kappa (u3 - u))),  dphi/ds = phidot dt/ds,  dpsi/ds = psidot dt/ds,
// analytic, even and pi-periodic in s. Their cosine series (trapezoidal rule = DCT-I, exact to
// round-off once the coefficients have decayed) give t(s), phi(s), psi(s) as secular term plus
// sine series; inverting t(s) on a grid gives s, phi, psi as functions of time, again secular
// term plus sine series in 2 pi t / T (T the nutation period). One evaluation is then one
// Clenshaw sum of three series and four sin/cos pairs; theta, thetadot, phidot, psidot and the
// body rates follow in closed form:
//   omega_X = phidot sin(theta) sin(psi) + thetadot cos(psi),
//   omega_Y = phidot sin(theta) cos(psi) - thetadot sin(psi)      (PHYSICS.md, initial state).
//
// The cubic is written about the current state, v = u - u0 (Taylor coefficients from the state,
// f(0) = udot0^2 D(u0) >= 0), so a start at a turning point deflates exactly (udot0 = 0 gives
// f(0) = 0: a numerical root a few ulp off would shift the phase by sqrt(ulp / (u2 - u1))), and
// the phase s0 comes from both u0 and udot0 by atan2, well conditioned everywhere.
//
// Handled exactly: torque-free tops (m g h = 0: the free symmetric top, in closed form, with
// A' = A0 for the fixed tip) and the sleeping top (axis vertical and omega_perp = 0: an
// equilibrium). Steady precession (u1 = u2) needs no special case: the nutation amplitude
// multiplies every periodic term, and the state error is that of the roots (~1e-16).
// Refused with InvalidParameter("integrator", why): the viscous scene (not integrable), the
// frictionless top without gravity (g = 0, h > 0: the cubic degenerates), an axis that is
// vertical while it moves, and motions whose series do not converge within kMaxTerms
// coefficients (the axis passes so near the vertical that the Euler angles are singular).
#pragma once

#include <Eigen/Core>
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <limits>
#include <string>
#include <type_traits>
#include <vector>

#include "spinning_top/drivers.hpp"
#include "spinning_top/events.hpp"
#include "spinning_top/kinematics.hpp"
#include "spinning_top/parameters.hpp"
#include "spinning_top/scenes/fixed_tip.hpp"
#include "spinning_top/scenes/frictionless.hpp"

namespace spinning_top {

namespace exact_detail {

constexpr double kPi = 3.14159265358979323846;
constexpr double kEpsilon = std::numeric_limits<double>::epsilon();
/// Largest number of Fourier coefficients per series (beyond: refused, see above).
constexpr int kMaxTerms = 4096;

/// Three series sharing the argument x: sum_k c[k][i] sin(k x), k = 1..n, by Clenshaw's
/// recurrence b_k = c_k + 2 cos(x) b_{k+1} - b_{k+2}, sum = b_1 sin(x).
inline std::array<double, 3> sine_sums(const std::vector<std::array<double, 3>>& c, double cos_x, double sin_x) {
  double b1[3] = {0.0, 0.0, 0.0}, b2[3] = {0.0, 0.0, 0.0};
  const double two_cos = 2.0 * cos_x;
  for (std::size_t k = c.size(); k-- > 0;) {
    for (int i = 0; i < 3; ++i) {
      const double b0 = c[k][i] + two_cos * b1[i] - b2[i];
      b2[i] = b1[i];
      b1[i] = b0;
    }
  }
  return {b1[0] * sin_x, b1[1] * sin_x, b1[2] * sin_x};
}

/// Whether a series has converged on an n-point grid: its upper half of coefficients is at
/// round-off relative to scale (aliasing then leaves the lower half exact to round-off and the
/// neglected tail is smaller still, the coefficients of an analytic function decaying
/// geometrically).
inline bool converged(const std::vector<std::array<double, 3>>& c, int i, double scale) {
  double tail = 0.0;
  for (std::size_t k = 0; k < c.size(); ++k) {
    if (!std::isfinite(c[k][i])) return false;
    if (k >= c.size() / 2) tail = std::max(tail, std::abs(c[k][i]));
  }
  return tail <= 64.0 * kEpsilon * scale;
}

/// Drops trailing coefficients that are below round-off of every series (each changes a sum
/// by less than half an ulp of its scale; they are the samples' rounding, not the function's).
inline void trim(std::vector<std::array<double, 3>>& c, const std::array<double, 3>& scale) {
  while (!c.empty()) {
    const auto& last = c.back();
    bool negligible = true;
    for (int i = 0; i < 3; ++i) negligible = negligible && std::abs(last[i]) <= 0.5 * kEpsilon * scale[i];
    if (!negligible) break;
    c.pop_back();
  }
}

/// Root of the polynomial f in [lo, hi], where f(lo) and f(hi) differ in sign: Newton's
/// method safeguarded by bisection (Numerical Recipes' rtsafe), to round-off.
template <class F, class DF>
double bracketed_root(const F& f, const DF& df, double lo, double hi) {
  double f_lo = f(lo);
  if (f_lo == 0.0) return lo;
  if (f(hi) == 0.0) return hi;
  double x = 0.5 * (lo + hi);
  for (int iteration = 0; iteration < 200; ++iteration) {
    const double fx = f(x);
    if (fx == 0.0) return x;
    if ((fx < 0.0) == (f_lo < 0.0)) {
      lo = x;
      f_lo = fx;
    } else {
      hi = x;
    }
    const double slope = df(x);
    double next = slope != 0.0 ? x - fx / slope : 0.5 * (lo + hi);
    if (!(next > lo && next < hi)) next = 0.5 * (lo + hi);
    const bool done = std::abs(next - x) <= 2.0 * kEpsilon * std::abs(x) || hi - lo <= 2.0 * kEpsilon * std::abs(x);
    x = next;
    if (done) break;
  }
  return x;
}

}  // namespace exact_detail

/// The exact motion from one state (t0, y0). Throws InvalidParameter("integrator", why) for the
/// cases it refuses (header comment).
template <class Model>
class ExactSolution {
 public:
  using State = typename Model::State;
  static_assert(std::is_same_v<Model, FixedTip> || std::is_same_v<Model, Frictionless>,
                "exact: only the integrable scenes (fixed tip, frictionless)");
  enum class Kind { kQuadrature, kFreeRotation, kSleeping };

  ExactSolution() = default;

  ExactSolution(const Model& model, double t0, const State& y0) : t0_(t0) {
    using exact_detail::kPi;
    const TopParameters& p = model.parameters();
    constexpr bool sliding = std::is_same_v<Model, Frictionless>;
    const double h = p.tip_distance;
    transverse_ = sliding ? p.inertia_transverse : p.inertia_about_tip();  // A'
    alpha_ = sliding ? p.mass * h * h / p.inertia_transverse : 0.0;
    kappa_ = 2.0 * p.mass * p.gravity * h / transverse_;
    spin_ = model.spin();
    axial_ = p.inertia_axial;
    q0_ = attitude_of(y0).normalized();
    wx0_ = y0[state_index::kOmegaX];
    wy0_ = y0[state_index::kOmegaY];
    State unit = y0;
    normalize_attitude(unit);
    const Vector3 gamma = vertical_in_body(unit);
    if (kappa_ == 0.0) {
      if (alpha_ != 0.0)
        throw InvalidParameter("integrator",
                               "exact: a frictionless top without gravity (g = 0, h > 0) makes the quadrature's cubic "
                               "degenerate, which is not implemented; use gauss6 or dop853");
      init_free_rotation();
      return;
    }
    const double sin2 = gamma.x() * gamma.x() + gamma.y() * gamma.y();
    if (sin2 == 0.0) {
      if (wx0_ != 0.0 || wy0_ != 0.0)
        throw InvalidParameter("integrator",
                               "exact: the axis is vertical while it moves (theta = 0, omega_perp != 0): the Euler "
                               "angles of the quadrature are singular there; use auto or dop853");
      kind_ = Kind::kSleeping;  // an equilibrium: Gamma = e_Z, no torque, omega_perp stays 0
      return;
    }
    init_quadrature(unit, gamma, sin2);
  }

  Kind kind() const { return kind_; }
  /// The event functions (R, e_Zz) are periodic with this period [s]; infinite for an
  /// equilibrium (sleeping top, top at rest without torque).
  double event_period() const { return event_period_; }
  /// Nutation period T [s] of the quadrature (0 otherwise), turning points u1 <= u2.
  double nutation_period() const { return kind_ == Kind::kQuadrature ? period_ : 0.0; }
  double turning_point_low() const { return u0_ + v1_; }
  double turning_point_high() const { return u0_ + v2_; }
  /// Fourier coefficients per series, in s (the quadrature) and in time (what one evaluation sums).
  int terms_in_s() const { return terms_in_s_; }
  int terms() const { return static_cast<int>(series_.size()); }

  /// Quadrature only: the state at nutation phase s with phi = psi = 0 (the event functions R and
  /// e_Zz depend on theta, thetadot and phidot only, by the top's symmetry).
  State at_phase(double s) const {
    const double sin_s = std::sin(s), cos_s = std::cos(s);
    const double v = v2_ - (v2_ - v1_) * sin_s * sin_s;
    const double one_minus_u = d0_ - v, sin2 = one_minus_u * (2.0 - one_minus_u), sin_theta = std::sqrt(sin2);
    const double dt_ds = 2.0 * std::sqrt((1.0 + alpha_ * sin2) / (kappa_ * (v3_ - v)));
    const double u_dot = -(v2_ - v1_) * 2.0 * sin_s * cos_s / dt_ds;
    State y;
    write(y, Quaternion(std::sqrt(0.5 * (2.0 - one_minus_u)), std::sqrt(0.5 * one_minus_u), 0.0, 0.0), -u_dot / sin_theta,
          (p0_ - c_ * v) / sin_theta);
    return y;
  }

  /// The state at time t.
  State at(double t) const {
    State y;
    const double dt = t - t0_;
    if (kind_ == Kind::kSleeping) {
      const Quaternion q = q0_ * Quaternion(std::cos(0.5 * spin_ * dt), 0.0, 0.0, std::sin(0.5 * spin_ * dt));
      write(y, q, 0.0, 0.0);
      return y;
    }
    if (kind_ == Kind::kFreeRotation) return free_rotation(dt);
    using exact_detail::kPi;
    // tau: time since the upper turning point s = 0; n whole periods plus r in [0, T).
    const double tau = dt + tau0_;
    const double n = std::floor(tau / period_);
    const double r = std::fma(-n, period_, tau);
    const double x = 2.0 * kPi * r / period_;
    const std::array<double, 3> periodic = exact_detail::sine_sums(series_, std::cos(x), std::sin(x));
    // s - n pi (sin^2 s and sin 2s have period pi), phi and psi.
    const double s = kPi * r / period_ + periodic[0];
    const double phi = phi_offset_ + n * phi_per_period_ + phi_rate_ * r + periodic[1];
    const double psi = psi_offset_ + n * psi_per_period_ + psi_rate_ * r + periodic[2];
    const double sin_s = std::sin(s), cos_s = std::cos(s);
    const double v = v2_ - (v2_ - v1_) * sin_s * sin_s;  // u - u0
    const double one_minus_u = d0_ - v, one_plus_u = 2.0 - one_minus_u;
    const double sin2 = one_minus_u * one_plus_u, sin_theta = std::sqrt(sin2);
    const double dt_ds = 2.0 * std::sqrt((1.0 + alpha_ * sin2) / (kappa_ * (v3_ - v)));
    const double u_dot = -(v2_ - v1_) * 2.0 * sin_s * cos_s / dt_ds;
    const double p = p0_ - c_ * v;  // sin^2(theta) phidot = (L_z - C wZ u) / A'
    // q = qz(phi) qx(theta) qz(psi) = (ch cos a, sh cos b, sh sin b, ch sin a), a = (phi+psi)/2,
    // b = (phi-psi)/2, ch = cos(theta/2) = sqrt((1+u)/2), sh = sin(theta/2) = sqrt((1-u)/2).
    const double a = 0.5 * (phi + psi), b = 0.5 * (phi - psi);
    const double ca = std::cos(a), sa = std::sin(a), cb = std::cos(b), sb = std::sin(b);
    const double ch = std::sqrt(0.5 * one_plus_u), sh = std::sqrt(0.5 * one_minus_u);
    const Quaternion q(sign_ * ch * ca, sign_ * sh * cb, sign_ * sh * sb, sign_ * ch * sa);
    const double cos_psi = ca * cb + sa * sb, sin_psi = sa * cb - ca * sb;  // psi = a - b
    // omega_X = phidot sin(theta) sin(psi) + thetadot cos(psi), thetadot = -udot / sin(theta).
    write(y, q, (p * sin_psi - u_dot * cos_psi) / sin_theta, (p * cos_psi + u_dot * sin_psi) / sin_theta);
    return y;
  }

 private:
  static void write(State& y, const Quaternion& q, double wx, double wy) {
    y[state_index::kQw] = q.w();
    y[state_index::kQx] = q.x();
    y[state_index::kQy] = q.y();
    y[state_index::kQz] = q.z();
    y[state_index::kOmegaX] = wx;
    y[state_index::kOmegaY] = wy;
  }

  /// Torque-free symmetric top (transverse moment A'): L is fixed in the world, the body turns
  /// about it at |L|/A' and about its own axis at nu = (A' - C) wZ / A' (Landau & Lifshitz,
  /// sec. 33): q(t) = exp(t L_world / A') q0 exp(t nu e_Z); omega_perp turns by -nu t in the body.
  void init_free_rotation() {
    kind_ = Kind::kFreeRotation;
    momentum_world_ = q0_ * Vector3(transverse_ * wx0_, transverse_ * wy0_, axial_ * spin_);
    body_rate_ = (transverse_ - axial_) * spin_ / transverse_;
    const double rate = momentum_world_.norm() / transverse_;
    // (R, e_Zz) depend on the axis' angle to the vertical, periodic with the cone's period.
    event_period_ = rate > 0.0 ? 2.0 * exact_detail::kPi / rate : std::numeric_limits<double>::infinity();
  }

  State free_rotation(double dt) const {
    const Vector3 turn = dt / transverse_ * momentum_world_;
    const double angle = turn.norm();
    const Quaternion world_turn =
        angle > 0.0 ? Quaternion(Eigen::AngleAxisd(angle, turn / angle)) : Quaternion::Identity();
    const double body_angle = body_rate_ * dt;
    const Quaternion q = world_turn * q0_ * Quaternion(std::cos(0.5 * body_angle), 0.0, 0.0, std::sin(0.5 * body_angle));
    const double c = std::cos(body_angle), s = std::sin(body_angle);
    State y;
    write(y, q, c * wx0_ + s * wy0_, -s * wx0_ + c * wy0_);
    return y;
  }

  void init_quadrature(const State& y0, const Vector3& gamma, double sin2) {
    using exact_detail::kPi;
    kind_ = Kind::kQuadrature;
    const double qx = y0[state_index::kQx], qy = y0[state_index::kQy];
    u0_ = gamma.z();
    d0_ = 2.0 * (qx * qx + qy * qy);  // 1 - u0 without cancellation
    c_ = axial_ * spin_ / transverse_;
    // From the state (Gamma = (sin(theta) sin(psi), sin(theta) cos(psi), cos(theta))):
    // udot = omega_Y Gamma_X - omega_X Gamma_Y, p = sin^2(theta) phidot = omega . Gamma_perp.
    const double u_dot0 = wy0_ * gamma.x() - wx0_ * gamma.y();
    p0_ = wx0_ * gamma.x() + wy0_ * gamma.y();
    // A planar motion (phidot = 0) computed from rotated components leaves p at round-off:
    // make it exact, or the spinless top's period, which runs through theta = pi after its
    // fall, would divide round-off by sin(theta) = 0 there.
    if (std::abs(p0_) <= 8.0 * exact_detail::kEpsilon * std::hypot(wx0_, wy0_) * std::sqrt(sin2)) p0_ = 0.0;
    const double d_0 = 1.0 + alpha_ * sin2;
    // K = 2 (E' - m g h u0) / A' = omega_perp^2 + alpha udot0^2 (kinetic energy without spin).
    const double k_energy = wx0_ * wx0_ + wy0_ * wy0_ + alpha_ * u_dot0 * u_dot0;
    // Taylor coefficients of f(u0 + v) = f0 + f1 v + f2 v^2 + kappa v^3.
    const double f0 = u_dot0 * u_dot0 * d_0;
    const double f1 = -kappa_ * sin2 - 2.0 * u0_ * k_energy + 2.0 * c_ * p0_;
    const double f2 = 2.0 * kappa_ * u0_ - k_energy - c_ * c_;
    const double kappa = kappa_;
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
    if (f0 == 0.0) {
      // A turning point: v = 0 is a root exactly; deflate to kappa v^2 + f2 v + f1.
      const double disc = std::sqrt(std::max(0.0, f2 * f2 - 4.0 * kappa * f1));
      const double qq = -0.5 * (f2 + std::copysign(disc, f2));
      std::array<double, 3> roots = {0.0, polish(qq / kappa), qq != 0.0 ? polish(f1 / qq) : 0.0};
      std::sort(roots.begin(), roots.end());
      v1_ = roots[0];
      v2_ = roots[1];
      v3_ = roots[2];
    } else {
      // f(0) > 0 >= f(u = -1) = -((L_z + C wZ)/A')^2 (PHYSICS.md) brackets u1 (= -1 when that
      // vanishes: the spinless top swings through the bottom). u2 lies between 0 and the local
      // minimum of f, the larger root of f', where f <= 0 (u2 <= 1 <= u3 are both roots
      // beyond 0, and u3 = 1 for the spinless top).
      const double lo = -1.0 - u0_;
      v1_ = f(lo) < 0.0 ? exact_detail::bracketed_root(f, df, lo, 0.0) : lo;
      const double disc = std::sqrt(std::max(0.0, f2 * f2 - 3.0 * kappa * f1));
      const double minimum = f2 < 0.0 ? (disc - f2) / (3.0 * kappa) : -f1 / (f2 + disc);  // cancellation-free
      if (!(minimum > 0.0 && f(minimum) <= 0.0))
        throw InvalidParameter("integrator", "exact: the turning points of the nutation cannot be separated "
                                             "(no root of the cubic above the current tilt); use auto or dop853");
      v2_ = exact_detail::bracketed_root(f, df, 0.0, minimum);
      if (!(v2_ < d0_ - 4.0 * exact_detail::kEpsilon))
        throw InvalidParameter("integrator",
                               "exact: the axis reaches the vertical (L_z = C omega_Z), where the Euler angles of "
                               "the quadrature are singular; use auto or dop853");
      v3_ = polish(-f2 / kappa - v1_ - v2_);  // Vieta: v1 + v2 + v3 = -f2 / kappa
    }
    if (!(v1_ <= 0.0 && 0.0 <= v2_ && v2_ <= v3_ && v3_ > 0.0 && std::isfinite(v3_)))
      throw InvalidParameter("integrator", "exact: the turning points of the nutation cannot be separated "
                                           "(u - u0 roots " + format(v1_) + ", " + format(v2_) + ", " + format(v3_) +
                                           "); use auto or dop853");
    // Phase: sin(2 s0) = -udot0 (dt/ds)(s0) / (u2 - u1), cos(2 s0) = (-v1 - v2) / (u2 - u1).
    const double sin_part = -u_dot0 * 2.0 * std::sqrt(d_0 / (kappa_ * v3_)), cos_part = -v1_ - v2_;
    double s0 = (sin_part == 0.0 && cos_part == 0.0) ? 0.0 : 0.5 * std::atan2(sin_part, cos_part);
    if (s0 < 0.0) s0 += kPi;

    build_series_in_s();
    build_series_in_time();

    // Offsets: the series start at s = 0 (u = u2); the start is at tau0 = t(s0).
    tau0_ = time_of_s(s0);
    const Quaternion q_in = q0_;
    const Vector3 axis = q_in * Vector3::UnitZ();
    const double phi0 = std::atan2(axis.x(), -axis.y());  // e_Z = (s sin(phi), -s cos(phi), u)
    const double psi0 = std::atan2(gamma.x(), gamma.y());
    const double x0 = 2.0 * kPi * tau0_ / period_;
    const std::array<double, 3> periodic = exact_detail::sine_sums(series_, std::cos(x0), std::sin(x0));
    phi_offset_ = phi0 - (phi_rate_ * tau0_ + periodic[1]);
    psi_offset_ = psi0 - (psi_rate_ * tau0_ + periodic[2]);
    // q and -q are one attitude: keep the sign of the given quaternion.
    sign_ = 1.0;
    const State y_start = at(t0_);
    if (attitude_of(y_start).coeffs().dot(q0_.coeffs()) < 0.0) sign_ = -1.0;
  }

  /// u - u0 and the integrands dt/ds, dphi/ds, dpsi/ds at s.
  std::array<double, 3> integrands(double s) const {
    const double sin_s = std::sin(s);
    const double v = v2_ - (v2_ - v1_) * sin_s * sin_s;
    const double one_minus_u = d0_ - v, sin2 = one_minus_u * (2.0 - one_minus_u);
    const double dt_ds = 2.0 * std::sqrt((1.0 + alpha_ * sin2) / (kappa_ * (v3_ - v)));
    // phidot = p / (1 - u^2) with p = (L_z - C wZ u) / A' linear in u; when p vanishes at
    // u = -1 (e.g. the spinless top, whose period runs through theta = pi after the fall),
    // phidot = p(1) / (2 (1 - u)) exactly, without 0/0 there.
    const double p_down = p0_ + c_ * (2.0 - d0_);
    const double phi_dot = p_down == 0.0 ? (p0_ - c_ * d0_) / (2.0 * one_minus_u) : (p0_ - c_ * v) / sin2;
    const double psi_dot = spin_ - phi_dot * (u0_ + v);
    return {dt_ds, phi_dot * dt_ds, psi_dot * dt_ds};
  }

  /// Cosine series of the three integrands in x = 2s by DCT-I on n + 1 points of s in [0, pi/2],
  /// n doubled until converged. t(s) = mean_t s + sum_k (a_k / 2k) sin(2ks), etc.
  void build_series_in_s() {
    using exact_detail::kPi;
    for (int n = 16;; n *= 2) {
      if (n > exact_detail::kMaxTerms) refuse_series("t(s), phi(s), psi(s)");
      std::vector<std::array<double, 3>> samples(n + 1);
      for (int j = 0; j <= n; ++j) samples[j] = integrands(0.5 * kPi * j / n);
      std::vector<double> cosine(2 * n);
      for (int m = 0; m < 2 * n; ++m) cosine[m] = std::cos(kPi * m / n);
      std::vector<std::array<double, 3>> a(n + 1);
      for (int k = 0; k <= n; ++k) {
        std::array<double, 3> sum = {0.0, 0.0, 0.0};
        for (int j = 0; j <= n; ++j) {
          const double w = (j == 0 || j == n) ? 0.5 : 1.0;
          const double c = w * cosine[(static_cast<long>(j) * k) % (2 * n)];
          for (int i = 0; i < 3; ++i) sum[i] += c * samples[j][i];
        }
        for (int i = 0; i < 3; ++i) a[k][i] = 2.0 * sum[i] / n;
      }
      for (int i = 0; i < 3; ++i) a[0][i] *= 0.5, a[n][i] *= 0.5;  // mean and last of DCT-I
      std::array<double, 3> scale = {0.0, 0.0, 0.0};
      for (const auto& ak : a)
        for (int i = 0; i < 3; ++i) scale[i] = std::max(scale[i], std::abs(ak[i]));
      std::vector<std::array<double, 3>> tail(a.begin() + 1, a.end());
      if (!(exact_detail::converged(tail, 0, scale[0]) && exact_detail::converged(tail, 1, scale[1]) &&
            exact_detail::converged(tail, 2, scale[2])))
        continue;
      mean_in_s_ = a[0];
      integral_series_.assign(a.begin() + 1, a.end());  // cosine coefficients of 2ks ...
      exact_detail::trim(integral_series_, scale);
      terms_in_s_ = static_cast<int>(integral_series_.size());
      for (std::size_t k = 0; k < integral_series_.size(); ++k)
        for (int i = 0; i < 3; ++i) integral_series_[k][i] /= 2.0 * static_cast<double>(k + 1);  // ... integrated
      period_ = kPi * mean_in_s_[0];
      phi_per_period_ = kPi * mean_in_s_[1];
      psi_per_period_ = kPi * mean_in_s_[2];
      phi_rate_ = mean_in_s_[1] / mean_in_s_[0];
      psi_rate_ = mean_in_s_[2] / mean_in_s_[0];
      event_period_ = period_;
      return;
    }
  }

  /// t(s), phi(s) - phi(0), psi(s) - psi(0) from the series in s.
  std::array<double, 3> integrals_of_s(double s) const {
    const std::array<double, 3> periodic = exact_detail::sine_sums(integral_series_, std::cos(2.0 * s), std::sin(2.0 * s));
    return {mean_in_s_[0] * s + periodic[0], mean_in_s_[1] * s + periodic[1], mean_in_s_[2] * s + periodic[2]};
  }
  double time_of_s(double s) const { return integrals_of_s(s)[0]; }

  /// s(tau) - pi tau / T, phi - phi_rate tau, psi - psi_rate tau: odd and T-periodic in tau,
  /// sine series in 2 pi tau / T by DST-I on a grid of tau in [0, T/2], s found by Newton's
  /// method on t(s) = tau.
  void build_series_in_time() {
    using exact_detail::kPi;
    const std::array<double, 3> secular = {kPi, phi_per_period_, psi_per_period_};
    for (int n = 16;; n *= 2) {
      if (n > exact_detail::kMaxTerms) refuse_series("s(t)");
      std::vector<std::array<double, 3>> samples(n + 1, {0.0, 0.0, 0.0});
      for (int j = 1; j < n; ++j) {
        const double tau = 0.5 * period_ * j / n;
        double s = kPi * tau / period_;
        for (int iteration = 0; iteration < 50; ++iteration) {
          const double ds = (time_of_s(s) - tau) / integrands(s)[0];
          s -= ds;
          if (std::abs(ds) <= 2.0 * exact_detail::kEpsilon * std::max(1.0, s)) break;
        }
        const std::array<double, 3> angles = integrals_of_s(s);
        samples[j] = {s - kPi * tau / period_, angles[1] - phi_rate_ * tau, angles[2] - psi_rate_ * tau};
      }
      std::vector<double> sine(2 * n);
      for (int m = 0; m < 2 * n; ++m) sine[m] = std::sin(kPi * m / n);
      std::vector<std::array<double, 3>> b(n - 1);
      for (int k = 1; k < n; ++k) {
        std::array<double, 3> sum = {0.0, 0.0, 0.0};
        for (int j = 1; j < n; ++j) {
          const double s = sine[(static_cast<long>(j) * k) % (2 * n)];
          for (int i = 0; i < 3; ++i) sum[i] += s * samples[j][i];
        }
        for (int i = 0; i < 3; ++i) b[k - 1][i] = 2.0 * sum[i] / n;
      }
      std::array<double, 3> scale = {std::abs(secular[0]), std::abs(secular[1]), std::abs(secular[2])};
      for (const auto& bk : b)
        for (int i = 0; i < 3; ++i) scale[i] = std::max(scale[i], std::abs(bk[i]));
      if (!(exact_detail::converged(b, 0, scale[0]) && exact_detail::converged(b, 1, scale[1]) &&
            exact_detail::converged(b, 2, scale[2])))
        continue;
      series_ = std::move(b);
      exact_detail::trim(series_, scale);
      return;
    }
  }

  [[noreturn]] void refuse_series(const char* what) const {
    throw InvalidParameter("integrator", std::string("exact: the series of ") + what + " need more than " +
                                             std::to_string(exact_detail::kMaxTerms) +
                                             " terms: the axis passes " + format(std::acos(std::min(1.0, u0_ + v2_))) +
                                             " rad from the vertical" +
                                             (u0_ + v1_ < -0.5 ? " and, after its fall, would pass " +
                                                                     format(std::acos(std::min(1.0, -(u0_ + v1_)))) +
                                                                     " rad from the downward vertical"
                                                               : std::string()) +
                                             ", where the Euler angles are singular; use auto or dop853");
  }
  static std::string format(double value) {
    char buffer[32];
    std::snprintf(buffer, sizeof buffer, "%.3g", value);
    return buffer;
  }

  Kind kind_ = Kind::kSleeping;
  double t0_ = 0.0;
  double transverse_ = 0.0, alpha_ = 0.0, kappa_ = 0.0, spin_ = 0.0, axial_ = 0.0;
  Quaternion q0_ = Quaternion::Identity();
  double wx0_ = 0.0, wy0_ = 0.0;
  double event_period_ = std::numeric_limits<double>::infinity();
  // Free rotation.
  Vector3 momentum_world_ = Vector3::Zero();
  double body_rate_ = 0.0;
  // Quadrature: u0, 1 - u0, roots of f in v = u - u0, C wZ / A', p(u0).
  double u0_ = 1.0, d0_ = 0.0, v1_ = 0.0, v2_ = 0.0, v3_ = 0.0, c_ = 0.0, p0_ = 0.0;
  std::array<double, 3> mean_in_s_ = {0.0, 0.0, 0.0};
  std::vector<std::array<double, 3>> integral_series_;  // in s
  std::vector<std::array<double, 3>> series_;                          // in time
  int terms_in_s_ = 0;
  double period_ = 0.0, phi_per_period_ = 0.0, psi_per_period_ = 0.0, phi_rate_ = 0.0, psi_rate_ = 0.0;
  double tau0_ = 0.0, phi_offset_ = 0.0, psi_offset_ = 0.0, sign_ = 1.0;
};

/// Driver of the exact solution, with the interface of the stepping drivers (drivers.hpp): a
/// request evaluates the closed form; the first validity event is found once per (re)start.
/// steps() counts evaluations of the closed form made for requests.
template <class Model>
class ExactDriver : public DriverBase<Model> {
 public:
  using State = typename Model::State;
  static constexpr bool kAdaptive = false;
  static constexpr bool kClosedForm = true;
  static constexpr const char* kName = "exact";

  /// Starts at (t, y): constants of motion, series, and the first event. Throws
  /// InvalidParameter("integrator", why) for a refused case.
  void reset(const Model& model, double t, const State& y) {
    this->start(model, t, y);
    pending_ = Event::kNone;
    event_time_ = std::numeric_limits<double>::infinity();
    if (this->event_ == Event::kNonFinite) return;
    // Built (or refused) even when the start itself is an event, so that a refusal depends on
    // the parameters and the state, not on the sign of R there.
    solution_ = ExactSolution<Model>(model, t, this->y_out_);
    if (this->event_ == Event::kNone) find_first_event(model);
  }

  std::string description() const {
    char buffer[128];
    switch (solution_.kind()) {
      case ExactSolution<Model>::Kind::kQuadrature:
        std::snprintf(buffer, sizeof buffer, "exact: quadrature, nutation period %.6g s, %d Fourier terms",
                      solution_.nutation_period(), solution_.terms());
        return buffer;
      case ExactSolution<Model>::Kind::kFreeRotation: return "exact: torque-free rotation";
      case ExactSolution<Model>::Kind::kSleeping: return "exact: sleeping top";
    }
    return "exact";
  }
  const ExactSolution<Model>& solution() const { return solution_; }

  Event advance_to(const Model& /*model*/, double t_target) {
    if (this->event_ != Event::kNone || t_target <= this->t_out_) return this->event_;
    if (pending_ != Event::kNone && t_target >= event_time_) {
      this->t_out_ = event_time_;
      this->y_out_ = event_state_;
      return this->event_ = pending_;
    }
    State y = solution_.at(t_target);
    ++this->steps_;
    if (!all_finite(y)) return this->event_ = Event::kNonFinite;
    this->t_out_ = t_target;
    this->y_out_ = y;
    return Event::kNone;
  }

 private:
  static constexpr int kSamplesPerPeriod = 128;

  /// The event functions depend only on the nutation phase, so they repeat with
  /// event_period(): the first event, if any, lies within one period of the start. Sampled at
  /// 128 points per period; a sampled minimum close enough to zero that the function could dip
  /// below it between samples is refined by golden-section search (a tangential crossing).
  /// The crossing is located by the drivers' locate_event (Illinois) on the closed form.
  void find_first_event(const Model& model) {
    const double period = solution_.event_period();
    if (!std::isfinite(period)) return;  // an equilibrium: the state's (R, e_Zz) stay as they are
    if (solution_.kind() == ExactSolution<Model>::Kind::kQuadrature && solution_.turning_point_low() > 0.0 &&
        !normal_force_may_vanish(model))
      return;  // the axis never reaches the floor (u1 > 0) and R > 0 over a whole nutation period
    const double t0 = this->t_out_;
    auto state_at = [&](double t) { return solution_.at(t); };
    auto g_at = [&](double t) { return event_functions(model, solution_.at(t)); };
    double t_before = t0, t_prev = t0;
    Eigen::Vector2d g_before = event_functions(model, this->y_out_), g_prev = g_before;
    for (int j = 1; j <= kSamplesPerPeriod + 1; ++j) {
      const double t = t0 + period * j / kSamplesPerPeriod;
      const Eigen::Vector2d g = g_at(t);
      if (triggered_event(g) != Event::kNone) return locate(model, t_prev, g_prev, t, g, state_at);
      if (j >= 2) {
        for (int i = 0; i < 2; ++i) {
          const double drop = std::max(g_before[i] - g_prev[i], g[i] - g_prev[i]);
          if (!(g_prev[i] < g_before[i] && g_prev[i] < g[i] && g_prev[i] < 2.0 * drop)) continue;
          // Golden-section search for the minimum of g_i on [t_before, t].
          const double ratio = 0.5 * (std::sqrt(5.0) - 1.0);
          double a = t_before, b = t;
          double c = b - ratio * (b - a), d = a + ratio * (b - a);
          double gc = g_at(c)[i], gd = g_at(d)[i];
          for (int iteration = 0; iteration < 60 && b - a > 1e-15 * std::max(1.0, std::abs(t)); ++iteration) {
            if (gc < gd) {
              b = d, d = c, gd = gc, c = b - ratio * (b - a), gc = g_at(c)[i];
            } else {
              a = c, c = d, gc = gd, d = a + ratio * (b - a), gd = g_at(d)[i];
            }
          }
          const double t_min = gc < gd ? c : d;
          const Eigen::Vector2d g_min = g_at(t_min);
          if (triggered_event(g_min) != Event::kNone) return locate(model, t_before, g_before, t_min, g_min, state_at);
        }
      }
      t_before = t_prev, g_before = g_prev;
      t_prev = t, g_prev = g;
    }
  }

  /// R over one nutation period, sampled in the phase s (cheaper than in time: no series), with
  /// the same golden-section refinement of sampled minima as in time.
  bool normal_force_may_vanish(const Model& model) const {
    constexpr double kPi = exact_detail::kPi;
    auto r_at = [&](double s) { return model.normal_force(solution_.at_phase(s)); };
    double before = r_at(-kPi / kSamplesPerPeriod), previous = r_at(0.0);
    for (int j = 1; j <= kSamplesPerPeriod; ++j) {
      const double s = kPi * j / kSamplesPerPeriod, r = r_at(s);
      if (!(r >= 0.0) || !(previous >= 0.0)) return true;
      const double drop = std::max(before - previous, r - previous);
      if (previous < before && previous < r && previous < 2.0 * drop) {
        const double ratio = 0.5 * (std::sqrt(5.0) - 1.0);
        double a = s - 2.0 * kPi / kSamplesPerPeriod, b = s;
        double c = b - ratio * (b - a), d = a + ratio * (b - a), rc = r_at(c), rd = r_at(d);
        for (int iteration = 0; iteration < 60 && b - a > 1e-15; ++iteration) {
          if (rc < rd) {
            b = d, d = c, rd = rc, c = b - ratio * (b - a), rc = r_at(c);
          } else {
            a = c, c = d, rc = rd, d = a + ratio * (b - a), rd = r_at(d);
          }
        }
        if (!(std::min(rc, rd) >= 0.0)) return true;
      }
      before = previous;
      previous = r;
    }
    return false;
  }

  template <class StateAt>
  void locate(const Model& model, double t_lo, const Eigen::Vector2d& g_lo, double t_hi, const Eigen::Vector2d& g_hi,
              const StateAt& state_at) {
    Event which = Event::kNone;
    const double t_event = locate_event(model, t_lo, g_lo, t_hi, g_hi, state_at, which);
    if (which == Event::kNone) return;
    pending_ = which;
    event_time_ = t_event;
    event_state_ = t_event > this->t_out_ ? state_at(t_event) : this->y_out_;
  }

  ExactSolution<Model> solution_;
  Event pending_ = Event::kNone;
  double event_time_ = std::numeric_limits<double>::infinity();
  State event_state_ = State::Zero();
};

}  // namespace spinning_top
