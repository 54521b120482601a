// The transitions between the contact and flight phases (doc/spec/HYBRID.md, "Transitions"): the
// landing impulse, and the free tip's vertical acceleration that decides what follows a lift-off.
#pragma once

#include <Eigen/Dense>
#include <cmath>

#include "spinning_top/kinematics.hpp"
#include "spinning_top/parameters.hpp"
#include "spinning_top/scenes/flight.hpp"

namespace spinning_top {

/// The tip's rule at a landing: it sticks where it lands (fixed tip: v_P+ horizontal = 0), or
/// the floor gives a normal impulse only (frictionless, viscous: finite friction gives none).
enum class TangentialImpact { kStick, kNormalOnly };

struct Landing {
  FreeBody after;             ///< the state just after the impulse
  double restitution = 0.0;   ///< the e applied: 0 (plastic) below restitution_speed
  double tip_speed_before = 0.0;  ///< v_Pz- [m/s] (negative: descending)
  double tip_speed_after = 0.0;   ///< v_Pz+ = -e v_Pz-
  double kinetic_energy_loss = 0.0;  ///< T- - T+ >= 0 [J]
};

/// World-frame inverse inertia about G: I^-1 = 1/A + (1/C - 1/A) e_Z e_Z^T.
inline Eigen::Matrix3d inverse_inertia_world(const TopParameters& p, const Vector3& axis) {
  const double a = p.inertia_transverse, c = p.inertia_axial;
  return Eigen::Matrix3d::Identity() / a + (1.0 / c - 1.0 / a) * axis * axis.transpose();
}

inline double kinetic_energy(const TopParameters& p, const FreeBody& s) {
  const Vector3& w = s.body_rates;
  return 0.5 * p.mass * s.velocity.squaredNorm() +
         0.5 * (p.inertia_transverse * (w.x() * w.x() + w.y() * w.y()) + p.inertia_axial * w.z() * w.z());
}

/// The impulse J at the tip P (r = P - G = -h e_Z), HYBRID.md "landing":
///   m (v_G+ - v_G-) = J,  I (omega+ - omega-) = r x J,  so  v_P+ = v_P- + K J,
///   K = 1/m - [r]x I^-1 [r]x  (symmetric positive definite: the tip's inverse effective mass).
/// Normal: v_Pz+ = -e v_Pz- (e = 0 below restitution_speed); tangential: kStick solves K J for
/// v_P+ = (0, 0, -e v_Pz-), kNormalOnly takes J = j e_z. omega_Z is unchanged (r x J is normal to
/// e_Z), and kept exactly.
inline Landing land(const TopParameters& p, const FreeBody& before, TangentialImpact rule) {
  const Vector3 axis = before.attitude * Vector3::UnitZ();
  const Vector3 r = -p.tip_distance * axis;
  const Vector3 omega = before.attitude * before.body_rates;
  const Vector3 tip_velocity = before.velocity + omega.cross(r);
  Eigen::Matrix3d rx;
  rx << 0.0, -r.z(), r.y(), r.z(), 0.0, -r.x(), -r.y(), r.x(), 0.0;
  const Eigen::Matrix3d inverse_inertia = inverse_inertia_world(p, axis);
  const Eigen::Matrix3d k = Eigen::Matrix3d::Identity() / p.mass - rx * inverse_inertia * rx;

  Landing landing;
  landing.tip_speed_before = tip_velocity.z();
  landing.restitution = std::abs(tip_velocity.z()) < p.restitution_speed ? 0.0 : p.restitution;
  landing.tip_speed_after = -landing.restitution * tip_velocity.z();
  Vector3 impulse;
  if (rule == TangentialImpact::kStick) {
    const Vector3 change = Vector3(0.0, 0.0, landing.tip_speed_after) - tip_velocity;
    impulse = k.ldlt().solve(change);
  } else {
    impulse = Vector3(0.0, 0.0, (landing.tip_speed_after - tip_velocity.z()) / k(2, 2));
  }
  landing.after = before;
  landing.after.velocity = before.velocity + impulse / p.mass;
  const Vector3 omega_after = omega + inverse_inertia * r.cross(impulse);
  const Vector3 body = before.attitude.conjugate() * omega_after;
  landing.after.body_rates = Vector3(body.x(), body.y(), before.body_rates.z());
  // T- - T+ as the impulse's work, -J . (v_P- + v_P+) / 2 (Kelvin's theorem for impulsive
  // motion; Routh, Dynamics of a System of Rigid Bodies, sec. 331): the difference of the two
  // kinetic energies would cancel the spin's C wZ^2 / 2, often 1e10 times the loss.
  const Vector3 tip_after = landing.after.velocity + omega_after.cross(r);
  landing.kinetic_energy_loss = std::max(0.0, -0.5 * impulse.dot(tip_velocity + tip_after));
  return landing;
}

/// The vertical acceleration of the tip with no floor force at all (HYBRID.md, "lift_off": a_f):
/// a_P = -g e_z + omega' x r + omega x (omega x r), r = -h e_Z, omega' from Euler's torque-free
/// equations about G (A wX' = (A - C) wY wZ, A wY' = -(A - C) wZ wX). In body components.
inline double free_tip_vertical_acceleration(const TopParameters& p, const Quaternion& attitude,
                                              const Vector3& body_rates) {
  const double a = p.inertia_transverse, c = p.inertia_axial, h = p.tip_distance;
  const Vector3& w = body_rates;
  const Vector3 angular_acceleration((a - c) * w.y() * w.z() / a, -(a - c) * w.z() * w.x() / a, 0.0);
  const Vector3 r(0.0, 0.0, -h);
  const Vector3 relative = angular_acceleration.cross(r) + w.cross(w.cross(r));
  const Vector3 vertical = attitude.conjugate() * Vector3::UnitZ();
  return relative.dot(vertical) - p.gravity;
}

}  // namespace spinning_top
