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
    bool out_of_budget = false;  ///< the search stopped at its work budget, before t
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
    jerk_bound_ = p.tip_distance * rate_ * rate_ * rate_ * std::hypot(c1_, s1_);
    if (!(p.rim_radius > 0.0)) needle_fall_ = first_horizontal_axis();
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
  /// d^2 z_P / dt^2 at t.
  double tip_acceleration(double t) const {
    const double x = rate_ * (t - t0_);
    return p_.tip_distance * rate_ * rate_ * (s1_ * std::sin(x) + c1_ * std::cos(x)) - p_.gravity;
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
  /// allows_step() is asked before each step of the search (a work budget); where it says no, the
  /// search returns out_of_budget and goes on from the same point at the next call. The points the
  /// search visits do not depend on t or on where a budget ran out, so neither does the touch.
  template <class AllowsStep>
  Touch search_until(double t, AllowsStep&& allows_step) {
    if (touch_.event != Event::kNone) return touch_.time <= t ? touch_ : Touch{};
    double end = t - t0_;
    // A needle falls where its axis reaches the horizontal (the seed's rule, in flight too), unless
    // the tip lands first: search up to there.
    const bool needle_falls = needle_fall_ <= end;
    if (needle_falls) end = needle_fall_;
    const Touch touch = search(scanned_, end, t0_ + end, allows_step);
    if (touch.event != Event::kNone || touch.out_of_budget || !needle_falls) return touch;
    return found(Event::kFallen, needle_fall_);
  }
  Touch search_until(double t) {
    return search_until(t, [] { return true; });
  }
  /// The time up to which the search has shown the flight free of the floor.
  double searched_until() const { return t0_ + scanned_; }

 private:
  template <class AllowsStep>
  Touch search(double tau, double end, double t, AllowsStep& allows_step) {
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
      scanned_ = last_tau_ = tau;  // where every later search goes on
      if (tau >= end) return Touch{};
    }
    const double rim_step = rim_ && rate_ > 0.0 ? (2.0 * M_PI / rate_) / 32.0 : std::numeric_limits<double>::infinity();
    for (;;) {
      if (!allows_step()) {
        scanned_ = tau;
        Touch none;
        none.out_of_budget = true;
        return none;
      }
      if (!rim_) {
        // Jump over what can hold neither a touch nor the apex (a fast spin's wobble makes M
        // large and the bounded steps short): see skip_from().
        const double next = skip_from(tau);
        if (next > tau) {
          if (next >= end) {
            scanned_ = tau;
            max_tip_height_ = std::max(max_tip_height_, tip_height(t));  // a flight still rising at t
            return Touch{};
          }
          tau = next;
        }
      }
      const double z = tip_height(t0_ + tau), zp = tip_velocity(t0_ + tau);
      max_tip_height_ = std::max(max_tip_height_, z);
      if (rim_ && rim_height(t0_ + tau) <= 0.0) return found(Event::kFallen, locate_rim(last_tau_, tau));
      if (z <= 0.0 && tau > 0.0) return found(Event::kLanding, tau);
      double d = curvature_bound_ > 0.0 ? (zp + std::sqrt(std::max(0.0, zp * zp + 2.0 * curvature_bound_ * z))) / curvature_bound_
                                        : (zp < 0.0 ? z / -zp : std::numeric_limits<double>::infinity());
      if (zp > 0.0) {
        // While the tip rises it cannot touch: z_P' >= z' + z'' d - J d^2 / 2 > 0 over the step,
        // J = h rho Omega^3 >= |z_P'''|. Near a lift-off (z, z' ~ 0 while M >> z'') this step grows
        // with tau where the curvature bound's would stay at ~z' / M.
        const double zpp = tip_acceleration(t0_ + tau);
        const double rising = jerk_bound_ > 0.0 ? (zpp + std::sqrt(std::max(0.0, zpp * zpp + 2.0 * jerk_bound_ * zp))) / jerk_bound_
                                                : (zpp < 0.0 ? zp / -zpp : std::numeric_limits<double>::infinity());
        d = std::max(d, rising);
      }
      d = std::min(d, rim_step);
      const double next = tau + d;
      if (!(next > tau)) return found(Event::kLanding, tau);  // converged onto the root from its safe side
      if (next >= end) {
        scanned_ = tau;
        if (rim_ && rim_height(t) <= 0.0) return found(Event::kFallen, locate_rim(tau, end));
        return Touch{};
      }
      if (zp > 0.0 && tip_velocity(t0_ + next) <= 0.0) apex(tau, next);
      last_tau_ = tau;
      tau = next;
    }
  }


 public:
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
  /// The tip height is a parabola less a sinusoid, z_P = Q(tau) - h rho cos(Omega tau - delta) with
  ///   Q(tau) = z_P0 + h c1 + (v_P0 + h s1 Omega) tau - g tau^2 / 2,  rho = sqrt(c1^2 + s1^2),
  /// so Q - h rho <= z_P <= Q + h rho. Where Q - h rho > 0 no touch can be; the highest point lies
  /// where Q >= max Q - 2 h rho (outside, z_P < max Q - h rho <= z_P at Q's vertex). Returns the
  /// tau to go on from: past a stretch that holds neither (the next place either can be), or tau.
  double skip_from(double tau) const {
    const double wobble = p_.tip_distance * std::hypot(c1_, s1_);
    const double a = tip_.height + p_.tip_distance * c1_, b = tip_.velocity + p_.tip_distance * s1_ * rate_;
    const double g = p_.gravity;
    const double q = a + b * tau - 0.5 * g * tau * tau;
    // A margin for the rounding of Q against tip_height's own (both are sums of terms below a few
    // times |a| + |b tau| + g tau^2 / 2 + h).
    const double margin = 1e-12 * (std::abs(a) + std::abs(b * tau) + 0.5 * g * tau * tau + p_.tip_distance);
    if (!(q - wobble > 2.0 * margin)) return tau;
    if (g == 0.0) {
      if (b >= 0.0) return std::numeric_limits<double>::infinity();  // rises for ever: no touch, highest at the end
      return tau + (q - wobble - margin) / -b;
    }
    const double vertex = b / g, half_window = std::sqrt(4.0 * wobble / g);
    if (tau < vertex - half_window) return vertex - half_window;  // up to the apex's window
    if (tau <= vertex + half_window) return tau;                   // in it: step
    // Past it: to where Q - h rho comes down to the margin, the larger root of Q = h rho + margin.
    const double c = a - wobble - margin;
    return (b + std::sqrt(std::max(0.0, b * b + 2.0 * g * c))) / g;
  }

  /// The first tau at which e_Zz = (u0 - c1) + rho cos(Omega tau - delta) comes down to 0, its
  /// last tau with e_Zz > 0 in the state at() reports (backed off by ulps), or infinity.
  double first_horizontal_axis() const {
    const double rho = std::hypot(c1_, s1_), middle = u0_ - c1_;
    if (!(rho > 0.0 && rate_ > 0.0) || middle - rho > 0.0) return std::numeric_limits<double>::infinity();
    double x = std::atan2(s1_, c1_) + std::acos(std::clamp(-middle / rho, -1.0, 1.0));  // the falling branch
    x = std::fmod(x, 2.0 * M_PI);
    if (x < 0.0) x += 2.0 * M_PI;
    double tau = x / rate_, back = std::max(tau, 1e-300) * 2.2e-16;
    // e_Zz as the contact models compute it (vertical_in_body), so that no front end reads it <= 0.
    auto vertical = [&](double at) {
      const Quaternion q = this->at(t0_ + at).attitude;
      return 1.0 - 2.0 * (q.x() * q.x() + q.y() * q.y());
    };
    for (int i = 0; i < 64 && tau > 0.0 && !(vertical(tau) > 0.0); ++i, back *= 2.0) tau = std::max(0.0, tau - back);
    return tau;
  }

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
  double curvature_bound_ = 0.0, jerk_bound_ = 0.0;  ///< M >= |z_P''|, J >= |z_P'''|
  bool rim_ = false;
  double scanned_ = 0.0, last_tau_ = 0.0;
  Touch touch_;
  bool cannot_rise_ = false;
  double max_tip_height_ = 0.0;
  double needle_fall_ = std::numeric_limits<double>::infinity();  ///< tau where a needle's axis is horizontal
};

}  // namespace spinning_top
