// Attitude kinematics shared by every scene: the unit quaternion q (body -> world),
// the world vertical seen from the body, and the initial state from z-x-z Euler angles.
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <cmath>

#include "spinning_top/parameters.hpp"

namespace spinning_top {

using Vector2 = Eigen::Vector2d;
using Vector3 = Eigen::Vector3d;
using Quaternion = Eigen::Quaterniond;

/// Every scene's state begins with the attitude (qw, qx, qy, qz) and the transverse body
/// rates (omega_X, omega_Y); omega_Z is a constant of motion and lives in the model.
namespace state_index {
constexpr int kQw = 0, kQx = 1, kQy = 2, kQz = 3, kOmegaX = 4, kOmegaY = 5;
constexpr int kAttitudeAndRatesSize = 6;
}  // namespace state_index

/// Quaternion stored at the head of a state vector.
template <class State>
Quaternion attitude_of(const State& y) {
  return Quaternion(y[state_index::kQw], y[state_index::kQx], y[state_index::kQy],
                    y[state_index::kQz]);
}

/// Gamma = R^T e_z: the world vertical in body components (e_zX, e_zY, e_zZ); the third
/// row of the rotation matrix of a unit quaternion. Gamma_Z = e_Zz = cos(theta).
template <class State>
Vector3 vertical_in_body(const State& y) {
  const double w = y[0], x = y[1], yy = y[2], z = y[3];
  return Vector3(2.0 * (x * z - w * yy), 2.0 * (yy * z + w * x), 1.0 - 2.0 * (x * x + yy * yy));
}

/// qdot = 1/2 q (x) (0, omega) (PHYSICS.md, attitude), written into dq[0..3].
template <class State, class Derivative>
void attitude_rate(const State& y, const Vector3& omega, Derivative& dq) {
  const double w = y[0], x = y[1], yy = y[2], z = y[3];
  dq[0] = 0.5 * (-x * omega.x() - yy * omega.y() - z * omega.z());
  dq[1] = 0.5 * (w * omega.x() + yy * omega.z() - z * omega.y());
  dq[2] = 0.5 * (w * omega.y() + z * omega.x() - x * omega.z());
  dq[3] = 0.5 * (w * omega.z() + x * omega.y() - yy * omega.x());
}

/// Projects the attitude back onto the unit sphere. One-step methods conserve |q| only to
/// their local error; the projection changes q by the same order, so it keeps the method's
/// order (Hairer, Lubich, Wanner, Geometric Numerical Integration, sec. IV.4) while every
/// rotation built from q stays orthogonal to round-off.
template <class State>
void normalize_attitude(State& y) {
  const double norm = std::sqrt(y[0] * y[0] + y[1] * y[1] + y[2] * y[2] + y[3] * y[3]);
  for (int i = 0; i < 4; ++i) y[i] /= norm;
}

/// exp of a rotation vector (angle |v| about v / |v|) as a unit quaternion.
inline Quaternion rotation_by_vector(const Vector3& v) {
  const double angle = v.norm();
  const double half = 0.5 * angle;
  // sin(half)/angle -> 1/2 as angle -> 0 (series to keep full precision near zero).
  const double s = angle > 1e-4 ? std::sin(half) / angle : 0.5 - angle * angle / 48.0;
  return Quaternion(std::cos(half), s * v.x(), s * v.y(), s * v.z());
}

/// q0 = Rz(heading) Rx(tilt) Rz(spin_angle), body -> world (PHYSICS.md, initial state).
inline Quaternion initial_attitude(const InitialConditions& ic) {
  return Quaternion(Eigen::AngleAxisd(ic.heading, Vector3::UnitZ())) *
         Quaternion(Eigen::AngleAxisd(ic.tilt, Vector3::UnitX())) *
         Quaternion(Eigen::AngleAxisd(ic.spin_angle, Vector3::UnitZ()));
}

/// Body rates from the Euler-angle rates: omega_X = phidot sin(theta) sin(psi) + thetadot
/// cos(psi), omega_Y = phidot sin(theta) cos(psi) - thetadot sin(psi), omega_Z = spin.
inline Vector3 initial_body_rates(const InitialConditions& ic) {
  const double st = std::sin(ic.tilt), sp = std::sin(ic.spin_angle), cp = std::cos(ic.spin_angle);
  return Vector3(ic.precession_rate * st * sp + ic.nutation_rate * cp,
                 ic.precession_rate * st * cp - ic.nutation_rate * sp, ic.spin);
}

/// The Euler angles of an attitude (q = Rz(heading) Rx(tilt) Rz(spin_angle), as in
/// initial_attitude) and their rates from the body rates (inverting initial_body_rates:
/// phidot sin(theta) = omega_X sin(psi) + omega_Y cos(psi), thetadot = omega_X cos(psi) -
/// omega_Y sin(psi)). Upright (sin(theta) < 1e-12) heading and spin angle are one angle and
/// the precession rate is undefined: it is 0, and the spin angle points the nutation rate
/// along the horizontal body rate. tilt lies in [0, pi], the angles in (-pi, pi].
struct EulerState {
  double heading = 0.0, tilt = 0.0, spin_angle = 0.0;                 ///< phi, theta, psi [rad]
  double precession_rate = 0.0, nutation_rate = 0.0, spin = 0.0;     ///< phidot, thetadot, omega_Z [rad/s]
};

inline EulerState euler_state(const Quaternion& attitude, const Vector3& body_rates) {
  const Eigen::Matrix3d r = attitude.normalized().toRotationMatrix();
  EulerState e;
  const double sin_tilt = std::hypot(r(0, 2), r(1, 2));
  e.tilt = std::atan2(sin_tilt, r(2, 2));
  e.spin = body_rates.z();
  if (sin_tilt < 1e-12) {
    // Upright the attitude is Rz(phi + psi): a horizontal body rate tilts the axis at thetadot
    // = its size, in the direction psi = atan2(-omega_Y, omega_X) sets; phi takes the rest.
    e.nutation_rate = std::hypot(body_rates.x(), body_rates.y());
    e.spin_angle = e.nutation_rate > 0.0 ? std::atan2(-body_rates.y(), body_rates.x()) : 0.0;
    e.heading = std::remainder(std::atan2(r(1, 0), r(0, 0)) - e.spin_angle, 2.0 * M_PI);
    return e;
  }
  e.heading = std::atan2(r(0, 2), -r(1, 2));     // e_Z = (sin t sin phi, -sin t cos phi, cos t)
  e.spin_angle = std::atan2(r(2, 0), r(2, 1));   // row 3 of Rz Rx Rz: (sin t sin psi, sin t cos psi, cos t)
  const double sp = std::sin(e.spin_angle), cp = std::cos(e.spin_angle);
  e.precession_rate = (body_rates.x() * sp + body_rates.y() * cp) / sin_tilt;
  e.nutation_rate = body_rates.x() * cp - body_rates.y() * sp;
  return e;
}

/// Writes an attitude and the transverse body rates (omega_X, omega_Y of body_rates) into y[0..5].
template <class State>
void set_attitude_and_rates(const Quaternion& q, const Vector3& body_rates, State& y) {
  y[state_index::kQw] = q.w();
  y[state_index::kQx] = q.x();
  y[state_index::kQy] = q.y();
  y[state_index::kQz] = q.z();
  y[state_index::kOmegaX] = body_rates.x();
  y[state_index::kOmegaY] = body_rates.y();
}

/// Writes the attitude and transverse rates of the initial conditions into y[0..5].
template <class State>
void set_initial_attitude_and_rates(const InitialConditions& ic, State& y) {
  set_attitude_and_rates(initial_attitude(ic), initial_body_rates(ic), y);
}

}  // namespace spinning_top
