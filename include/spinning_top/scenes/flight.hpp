// Phase "flight" (doc/spec/HYBRID.md, "Phases"): the tip is off the floor and nothing but gravity
// acts. G moves on a parabola, and the body turns torque-free about G: a symmetric top's regular
// precession about its fixed angular momentum L_G. Both in closed form, exact to round-off; the
// first touch of the floor (the tip landing, or the rim touching first: fallen) is searched for
// along the closed form with a bound on the tip height's curvature, so that none is missed.
#pragma once

#include <algorithm>
#include <cmath>
#include <limits>

#include "spinning_top/events.hpp"
#include "spinning_top/kinematics.hpp"
#include "spinning_top/parameters.hpp"

namespace spinning_top {

/// The state of the free top: attitude (body -> world), body rates (omega_X, omega_Y, omega_Z),
/// G and its velocity (world).
struct FreeBody {
  Quaternion attitude = Quaternion::Identity();
  Vector3 body_rates = Vector3::Zero();
  Vector3 position = Vector3::Zero();
  Vector3 velocity = Vector3::Zero();
};

/// How the tip leaves the floor at the start of a flight: the tip's height and vertical velocity
/// there are 0 by the contact constraint (a lift-off: they are set to 0, not computed, so that
/// round-off cannot put the tip under the floor at once), or it rebounds at v_Pz = speed > 0.
struct TipStart {
  double height = 0.0;    ///< z_P at the start [m]
  double velocity = 0.0;  ///< dz_P/dt at the start [m/s]
};

/// The free top's closed form from (t0, start):
///   G(t) = G0 + v0 tau - g tau^2 / 2 e_z,  tau = t - t0,
///   q(t) = exp(tau L / A) q0 exp(tau nu e_Z / 2 ...),  nu = (A - C) wZ / A  (L = L_G, world),
/// the same composition as FixedTip::free_rotation with A about G in place of A0: the axis
/// precesses about L at Omega = |L| / A, and omega_perp turns in the body by -nu tau.
/// e_Zz(tau) = u0 + c1 (cos Omega tau - 1) + s1 sin Omega tau (Rodrigues' formula about L / |L|), so
///   z_P(tau) = z_P0 + v_P0 tau + h s1 (Omega tau - sin Omega tau) + 2 h c1 sin^2(Omega tau / 2)
///              - g tau^2 / 2,
/// written so that each term is small where tau is (no cancellation near the start).
class Flight {
 public:
  struct Touch {
    Event event = Event::kNone;  ///< kLanding (the tip) or kFallen (the rim first)
    double time = std::numeric_limits<double>::infinity();
  };

  Flight() = default;

  /// From any free state: the tip's height and vertical velocity from the state.
  Flight(const TopParameters& p, double t0, const FreeBody& start) : Flight(p, t0, start, tip_of(p, start)) {}

  /// From the floor: the tip's height and vertical velocity as given (TipStart).
  Flight(const TopParameters& p, double t0, const FreeBody& start, const TipStart& tip)
      : p_(p), t0_(t0), start_(start), tip_(tip) {
    a_ = p.inertia_transverse;
    spin_ = start.body_rates.z();
    const Vector3& w = start.body_rates;
    momentum_ = start.attitude * Vector3(a_ * w.x(), a_ * w.y(), p.inertia_axial * spin_);
    body_rate_ = (a_ - p.inertia_axial) * spin_ / a_;
    const Vector3 axis = start.attitude * Vector3::UnitZ();
    u0_ = axis.z();
    const double momentum = momentum_.norm();
    if (momentum > 0.0) {
      rate_ = momentum / a_;
      const Vector3 n = momentum_ / momentum;
      c1_ = (axis - axis.dot(n) * n).z();
      s1_ = n.cross(axis).z();
    }
    curvature_bound_ = p.gravity + p.tip_distance * rate_ * rate_ * std::hypot(c1_, s1_);
    // The rim can touch first only where it is below the tip: e_Zz < u_fall (a e_Zz - b sin < 0).
    rim_ = (p.rim_radius > 0.0 || p.rim_distance > 0.0) && u0_ - 2.0 * std::hypot(c1_, s1_) < p.fallen_vertical();
    scanned_ = 0.0;
    max_tip_height_ = tip.height;
  }

  double start_time() const { return t0_; }
  const FreeBody& start() const { return start_; }

  FreeBody at(double t) const {
    const double tau = t - t0_;
    FreeBody s;
    const Quaternion world_turn = rotation_by_vector((tau / a_) * momentum_);
    const double half = 0.5 * tau * body_rate_;
    s.attitude = (world_turn * start_.attitude * Quaternion(std::cos(half), 0.0, 0.0, std::sin(half))).normalized();
    const double c = std::cos(tau * body_rate_), sn = std::sin(tau * body_rate_);
    const Vector3& w = start_.body_rates;
    s.body_rates = Vector3(c * w.x() + sn * w.y(), -sn * w.x() + c * w.y(), spin_);
    s.position = start_.position + tau * start_.velocity;
    s.position.z() -= 0.5 * p_.gravity * tau * tau;
    s.velocity = start_.velocity;
    s.velocity.z() -= p_.gravity * tau;
    return s;
  }

  /// e_Zz at t.
  double axis_vertical(double t) const {
    const double x = rate_ * (t - t0_);
    const double half = std::sin(0.5 * x);
    return u0_ - 2.0 * c1_ * half * half + s1_ * std::sin(x);
  }
  /// z_P at t (formula in the class comment).
  double tip_height(double t) const {
    const double tau = t - t0_, x = rate_ * tau;
    const double half = std::sin(0.5 * x);
    return tip_.height + tip_.velocity * tau + p_.tip_distance * (s1_ * x_minus_sin(x) + 2.0 * c1_ * half * half) -
           0.5 * p_.gravity * tau * tau;
  }
  /// dz_P/dt at t.
  double tip_velocity(double t) const {
    const double tau = t - t0_, x = rate_ * tau;
    const double half = std::sin(0.5 * x);
    return tip_.velocity + p_.tip_distance * rate_ * (2.0 * s1_ * half * half + c1_ * std::sin(x)) - p_.gravity * tau;
  }
  /// The height of the body's lowest point on the rim (HYBRID.md): z_P + a e_Zz - b sqrt(1 - e_Zz^2).
  double rim_height(double t) const {
    const double u = axis_vertical(t);
    return tip_height(t) + p_.rim_distance * u - p_.rim_radius * std::sqrt(std::max(0.0, 1.0 - u * u));
  }

  /// Searches (start, t] for the first touch of the floor, going on from where the last search
  /// ended. Steps along tau with the bound |z_P''| <= M = g + h Omega^2 sqrt(c1^2 + s1^2): from
  /// tau with z = z_P(tau) >= 0 and z' = z_P'(tau), z_P stays >= z + z' d - M d^2 / 2 > 0 for
  /// d < (z' + sqrt(z'^2 + 2 M z)) / M, so the step cannot pass a root. Near a root the steps are
  /// Newton's from the safe side and converge to it. Returns the touch at or before t, or none.
  Touch search_until(double t) {
    if (touch_.event != Event::kNone) return touch_.time <= t ? touch_ : Touch{};
    double tau = scanned_;
    const double end = t - t0_;
    if (!(end > tau)) return Touch{};
    if (tau == 0.0 && tip_.height <= 0.0 && tip_.velocity <= 0.0) {
      // A lift-off: z_P = z_P' = 0 at the start, and z_P rises as a_f tau^2 / 2 or, on the
      // frictionless floor (a_f = 0 there), as j tau^3 / 6 (the lift-off rule has checked its
      // sign). Start the bounded steps where it has risen clear of round-off.
      tau = 1e-12;
      while (!(tip_height(t0_ + tau) > 0.0 && tip_velocity(t0_ + tau) > 0.0) && tau < 1e-3) tau *= 2.0;
      if (!(tip_height(t0_ + tau) > 0.0)) {
        cannot_rise_ = true;
        touch_ = {Event::kLanding, t0_};
        return touch_;
      }
      if (tau >= end) {
        scanned_ = std::min(tau, end);
        return Touch{};
      }
    }
    const double rim_step = rim_ && rate_ > 0.0 ? (2.0 * M_PI / rate_) / 32.0 : std::numeric_limits<double>::infinity();
    for (int iteration = 0; iteration < 100000000; ++iteration) {
      const double z = tip_height(t0_ + tau), zp = tip_velocity(t0_ + tau);
      max_tip_height_ = std::max(max_tip_height_, z);
      if (rim_ && rim_height(t0_ + tau) <= 0.0) return found(Event::kFallen, locate_rim(last_tau_, tau));
      if (z <= 0.0 && tau > 0.0) return found(Event::kLanding, tau);
      double d = curvature_bound_ > 0.0 ? (zp + std::sqrt(std::max(0.0, zp * zp + 2.0 * curvature_bound_ * z))) / curvature_bound_
                                        : (zp < 0.0 ? z / -zp : std::numeric_limits<double>::infinity());
      d = std::min(d, rim_step);
      const double next = tau + d;
      if (!(next > tau)) return found(Event::kLanding, tau);  // converged onto the root from its safe side
      if (zp > 0.0 && tip_velocity(t0_ + std::min(next, end)) <= 0.0) apex(tau, std::min(next, end));
      if (next >= end) {
        last_tau_ = tau;
        scanned_ = end;
        if (rim_ && rim_height(t) <= 0.0) return found(Event::kFallen, locate_rim(tau, end));
        return Touch{};
      }
      last_tau_ = tau;
      tau = next;
    }
    return Touch{};
  }

  /// True if the search found that the tip cannot rise off the floor (a lift-off whose free tip
  /// does not move up within 1 ms): the flight is not a motion.
  bool cannot_rise() const { return cannot_rise_; }
  /// The highest the tip has been over the searched span [m].
  double max_tip_height() const { return max_tip_height_; }
  /// The least e_Zz over [start, t] (the largest tilt), in closed form: e_Zz = centre + rho
  /// cos(Omega tau - delta).
  double least_axis_vertical(double t) const {
    const double tau = std::max(0.0, t - t0_);
    const double rho = std::hypot(c1_, s1_);
    double least = std::min(u0_, axis_vertical(t));
    if (rho > 0.0 && rate_ > 0.0) {
      const double delta = std::atan2(s1_, c1_);
      // Omega tau - delta passes pi (mod 2 pi) within [-delta, Omega tau - delta]?
      const double first = std::remainder(M_PI + delta, 2.0 * M_PI);
      const double at = first < 0.0 ? first + 2.0 * M_PI : first;
      if (at <= rate_ * tau) least = std::min(least, u0_ - c1_ - rho);
    }
    return least;
  }

 private:
  static TipStart tip_of(const TopParameters& p, const FreeBody& s) {
    const Vector3 axis = s.attitude * Vector3::UnitZ();
    const Vector3 r = -p.tip_distance * axis;
    return {s.position.z() + r.z(), (s.velocity + (s.attitude * s.body_rates).cross(r)).z()};
  }

  /// x - sin x without cancellation: its Taylor series below 0.5 (terms to x^15, the rest below
  /// 1e-20 relative).
  static double x_minus_sin(double x) {
    if (std::abs(x) >= 0.5) return x - std::sin(x);
    const double x2 = x * x;
    double term = x * x2 / 6.0, sum = term;
    for (int k = 4; k <= 14; k += 2) {
      term *= -x2 / (k * (k + 1));
      sum += term;
    }
    return sum;
  }

  Touch found(Event event, double tau) {
    touch_ = {event, t0_ + tau};
    scanned_ = tau;
    return touch_;
  }

  void apex(double lo, double hi) {
    for (int i = 0; i < 80 && hi - lo > 1e-15 * std::max(1.0, hi); ++i) {
      const double mid = 0.5 * (lo + hi);
      (tip_velocity(t0_ + mid) > 0.0 ? lo : hi) = mid;
    }
    max_tip_height_ = std::max(max_tip_height_, tip_height(t0_ + lo));
  }

  /// The rim's touch in (lo, hi], rim_height(lo) > 0 >= rim_height(hi), by bisection (its last
  /// valid tau).
  double locate_rim(double lo, double hi) const {
    for (int i = 0; i < 200 && hi - lo > 4e-16 * std::max(1.0, hi); ++i) {
      const double mid = 0.5 * (lo + hi);
      (rim_height(t0_ + mid) > 0.0 ? lo : hi) = mid;
    }
    return lo;
  }

  TopParameters p_;
  double t0_ = 0.0;
  FreeBody start_;
  TipStart tip_;
  double a_ = 1.0, spin_ = 0.0, body_rate_ = 0.0;
  Vector3 momentum_ = Vector3::Zero();
  double rate_ = 0.0, u0_ = 1.0, c1_ = 0.0, s1_ = 0.0;
  double curvature_bound_ = 0.0;
  bool rim_ = false;
  double scanned_ = 0.0, last_tau_ = 0.0;
  Touch touch_;
  bool cannot_rise_ = false;
  double max_tip_height_ = 0.0;
};

}  // namespace spinning_top
