// The sleeping top of the exact integrator (../exact.hpp): the axis vertical and omega_perp = 0
// at the start. An equilibrium: Gamma = e_Z, no torque, omega_perp stays 0, and the body turns
// about the vertical at its spin, q(t) = q0 exp(t wZ e_Z / 2): alpha by e^{i wZ t / 2}, beta by
// its conjugate.
#pragma once

#include <cmath>
#include <limits>

#include "spinning_top/events.hpp"
#include "spinning_top/integrators/exact/common.hpp"
#include "spinning_top/kinematics.hpp"

namespace spinning_top {
namespace exact_detail {

class Sleeping {
 public:
  /// At rest, upright, at t = 0: what a default ExactSolution holds.
  Sleeping() = default;
  explicit Sleeping(const Start& from) : t0_(from.t0), spin_(from.spin), gravity_(from.gravity), q0_(from.q0) {}

  Motion motion(double t) const {
    const double dt = t - t0_;
    const double half = 0.5 * spin_ * dt;
    const Complex turn(std::cos(half), std::sin(half));
    return {Complex(q0_.w(), q0_.z()) * turn, Complex(q0_.x(), q0_.y()) * std::conj(turn), Complex(0.0, 0.0)};
  }

  /// The axis stays vertical, nothing accelerates: 1 - u = 0 and R = m g.
  Range range_until(double /*t*/) const {
    Range range;
    range.least_normal_force_per_mass = gravity_;
    return range;
  }

  /// An equilibrium leaves nothing.
  Event first_event() const { return Event::kNone; }
  double first_event_time() const { return std::numeric_limits<double>::infinity(); }
  double start_time() const { return t0_; }

 private:
  double t0_ = 0.0, spin_ = 0.0, gravity_ = 0.0;
  Quaternion q0_ = Quaternion::Identity();
};

}  // namespace exact_detail
}  // namespace spinning_top
