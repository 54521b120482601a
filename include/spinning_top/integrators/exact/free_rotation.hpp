// The torque-free symmetric top of the exact integrator (../exact.hpp): no torque about G and
// G fixed (m g h = 0 and alpha_D = 0), a rotation in closed form.
#pragma once

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <limits>

#include "spinning_top/events.hpp"
#include "spinning_top/integrators/exact/common.hpp"
#include "spinning_top/kinematics.hpp"

namespace spinning_top {
namespace exact_detail {

/// Torque-free symmetric top (transverse moment A'): L is fixed in the world, the body turns
/// about it at w = |L|/A' and about its own axis at nu = (A' - C) wZ / A' (Landau & Lifshitz,
/// sec. 33): q(t) = exp(t L_world / A') q0 exp(t nu e_Z); omega_perp turns by -nu t in the body.
/// The axis moves on its cone: e_Zz(t) = a + b cos(w t) + c sin(w t) = a + rho cos(w t - delta)
/// (Rodrigues' rotation of e_Z about L). It falls through the floor first at
/// w t = delta + acos(-a / rho) (mod 2 pi). This case runs where the torque m g h vanishes in
/// floating point (h = 0, g = 0, or m or g so small that 2 m g h / A' underflows), but the floor
/// force R = m (g + z_G'') = m (g - h w^2 rho cos(w t - delta)) can still turn negative: a
/// lift-off (found by the fuzz test: missed for g = 0 and for g = 1e-320, and states with R < 0
/// published).
class FreeRotation {
 public:
  explicit FreeRotation(const Start& from)
      : t0_(from.t0), transverse_(from.transverse), gravity_(from.gravity), tip_distance_(from.tip_distance),
        q0_(from.q0), wx0_(from.wx0), wy0_(from.wy0) {
    momentum_world_ = q0_ * Vector3(transverse_ * wx0_, transverse_ * wy0_, from.axial * from.spin);
    body_rate_ = (transverse_ - from.axial) * from.spin / transverse_;
    one_minus_a_ = 2.0 * (q0_.x() * q0_.x() + q0_.y() * q0_.y());  // 1 - e_Zz while nothing moves
    const double momentum = momentum_world_.norm();
    if (!(momentum > 0.0)) return;  // at rest: nothing moves
    const double rate = momentum / transverse_;
    const Vector3 n = momentum_world_ / momentum, axis = q0_ * Vector3::UnitZ();
    const double a = axis.dot(n) * n.z(), b = axis.z() - a, c = n.cross(axis).z();
    const double rho = std::hypot(b, c);
    if (rho == 0.0) return;  // the axis along L, or L vertical: e_Zz and R stay constant
    const double two_pi = 2.0 * kPi, delta = std::atan2(c, b);
    rate_ = rate, rho_ = rho, delta_ = delta, one_minus_a_ = 1.0 - a;
    auto ahead = [&](double phase) {  // the first w t >= 0 at that phase (mod 2 pi)
      phase = std::fmod(phase, two_pi);
      return phase < 0.0 ? phase + two_pi : phase;
    };
    double first = std::numeric_limits<double>::infinity();
    if (a - rho <= from.fallen_vertical) {
      first = ahead(delta + std::acos(std::clamp((from.fallen_vertical - a) / rho, -1.0, 1.0)));
      event_ = Event::kFallen;
    }
    // R = m (g + z_G'') with z_G = h e_Zz, so R < 0 while cos(w t - delta) > g / (h w^2 rho): from
    // w t - delta = -acos(g / (h w^2 rho)) (mod 2 pi) on.
    const double swing = tip_distance_ * rate * rate * rho;  // the largest downward z_G''
    if (swing > gravity_) {
      const double lift_off = ahead(delta - std::acos(gravity_ / swing));
      if (lift_off < first) {
        first = lift_off;
        event_ = Event::kLiftOff;
      }
    }
    if (std::isfinite(first)) event_time_ = t0_ + first / rate;
  }

  Motion motion(double t) const {
    const double dt = t - t0_;
    const Vector3 turn = dt / transverse_ * momentum_world_;
    const double angle = turn.norm();
    const Quaternion world_turn =
        angle > 0.0 ? Quaternion(Eigen::AngleAxisd(angle, turn / angle)) : Quaternion::Identity();
    const double body_angle = body_rate_ * dt;
    const Quaternion q = world_turn * q0_ * Quaternion(std::cos(0.5 * body_angle), 0.0, 0.0, std::sin(0.5 * body_angle));
    const double c = std::cos(body_angle), s = std::sin(body_angle);
    return {Complex(q.w(), q.z()), Complex(q.x(), q.y()), Complex(c * wx0_ + s * wy0_, -s * wx0_ + c * wy0_)};
  }

  /// The extremes over [t0, t] (ExactSolution::range_until): where the phase passes 0 or pi
  /// (mod 2 pi), else at the ends.
  Range range_until(double t) const {
    Range range;
    // e_Zz = a + rho cos(phi), R / m = g - h w^2 rho cos(phi), phi = w (t - t0) - delta.
    const double phi0 = -delta_, phi1 = rate_ * (t - t0_) - delta_;
    const double two_pi = 2.0 * kPi;
    auto passes = [&](double phase) {  // phi0 <= phase + 2 pi n <= phi1 for some n
      return std::floor((phi1 - phase) / two_pi) >= std::ceil((phi0 - phase) / two_pi);
    };
    const double cos_max = passes(0.0) ? 1.0 : std::max(std::cos(phi0), std::cos(phi1));
    const double cos_min = passes(kPi) ? -1.0 : std::min(std::cos(phi0), std::cos(phi1));
    range.one_minus_u_max = rho_ == 0.0 ? one_minus_a_ : one_minus_a_ - rho_ * cos_min;
    range.least_normal_force_per_mass = gravity_ - tip_distance_ * rate_ * rate_ * rho_ * cos_max;
    return range;
  }

  Event first_event() const { return event_; }
  double first_event_time() const { return event_time_; }
  double start_time() const { return t0_; }

 private:
  double t0_ = 0.0, transverse_ = 0.0, gravity_ = 0.0, tip_distance_ = 0.0;
  Quaternion q0_ = Quaternion::Identity();
  double wx0_ = 0.0, wy0_ = 0.0;
  Vector3 momentum_world_ = Vector3::Zero();
  double body_rate_ = 0.0;
  double rate_ = 0.0, rho_ = 0.0, delta_ = 0.0, one_minus_a_ = 0.0;  // e_Zz = a + rho cos(rate t - delta)
  Event event_ = Event::kNone;
  double event_time_ = std::numeric_limits<double>::infinity();
};

}  // namespace exact_detail
}  // namespace spinning_top
