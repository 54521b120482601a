// Euler's equations about G for a tip that slides on the floor, with the normal force R
// eliminated through the contact constraint (shared by the frictionless and viscous scenes).
#pragma once

#include "spinning_top/kinematics.hpp"
#include "spinning_top/parameters.hpp"

namespace spinning_top {

/// Solves, for the floor force N = R e_z + F on the tip (F horizontal, known):
///   A wX' - (A - C) wY wZ = h N_Y,  A wY' + (A - C) wZ wX = -h N_X       (Euler about G)
///   R = m g + m a_Gz,  a_Gz = h (s - n . w_perp'),                          (vertical constraint)
///   s = wZ (e_zX wX + e_zY wY) - e_zZ w_perp^2,  n = (e_zY, -e_zX).
/// Writing w_perp' = b + (h/A)(R n + f) with b the gyroscopic term and f = (F_Y, -F_X):
///   R (1 + alpha |n|^2) = m (g + h (s - n . b)) - alpha n . f,   alpha = m h^2 / A,
/// where 1 + alpha |n|^2 = 1 + alpha_XX + alpha_YY is det T of the notes.
class SlidingContact {
 public:
  struct Result {
    double normal_force;          ///< R [N]
    Vector2 transverse_acceleration;  ///< (wX', wY') [rad/s^2]
  };

  SlidingContact(const TopParameters& p, double spin)
      : spin_(spin),
        gyroscopic_rate_((p.inertia_transverse - p.inertia_axial) * spin / p.inertia_transverse),
        alpha_(p.mass * p.tip_distance * p.tip_distance / p.inertia_transverse),
        h_over_a_(p.tip_distance / p.inertia_transverse),
        mass_(p.mass),
        gravity_(p.gravity),
        h_(p.tip_distance) {}

  /// friction_body = (F_X, F_Y): the horizontal floor force in body components.
  Result solve(const Vector3& gamma, double wx, double wy, const Vector2& friction_body) const {
    const Vector2 b(gyroscopic_rate_ * wy, -gyroscopic_rate_ * wx);
    const Vector2 n(gamma.y(), -gamma.x());
    const Vector2 f(friction_body.y(), -friction_body.x());
    const double s = spin_ * (gamma.x() * wx + gamma.y() * wy) - gamma.z() * (wx * wx + wy * wy);
    const double det_t = 1.0 + alpha_ * n.squaredNorm();
    const double r = (mass_ * (gravity_ + h_ * (s - n.dot(b))) - alpha_ * n.dot(f)) / det_t;
    return {r, b + h_over_a_ * (r * n + f)};
  }

  Result solve(const Vector3& gamma, double wx, double wy) const {
    return solve(gamma, wx, wy, Vector2::Zero());
  }

 private:
  double spin_;
  double gyroscopic_rate_;  // (A - C) wZ / A
  double alpha_;            // m h^2 / A
  double h_over_a_;         // h / A
  double mass_, gravity_, h_;
};

/// Vertical velocity of G forced by the constraint: v_Gz = h (w x e_Z) . e_z
/// = h (wY e_zX - wX e_zY).
inline double constrained_vertical_velocity(double h, const Vector3& gamma, double wx, double wy) {
  return h * (wy * gamma.x() - wx * gamma.y());
}

}  // namespace spinning_top
