// Scene "fixed tip": the tip P is a pivot at the origin (PHYSICS.md, v_P = 0).
// State y = (qw, qx, qy, qz, omega_X, omega_Y); omega_Z is a constant of motion.
#pragma once

#include <Eigen/Core>
#include <cmath>

#include "spinning_top/kinematics.hpp"
#include "spinning_top/model_outputs.hpp"
#include "spinning_top/motion_rates.hpp"
#include "spinning_top/parameters.hpp"

namespace spinning_top {

class FixedTip {
 public:
  static constexpr int kStateSize = state_index::kAttitudeAndRatesSize;
  static constexpr bool kConservesEnergy = true;
  static constexpr bool kConservesVerticalAngularMomentum = true;  // about the pivot
  static constexpr const char* kName = "fixed_tip";
  using State = Eigen::Matrix<double, kStateSize, 1>;

  FixedTip(const TopParameters& parameters, const InitialConditions& initial)
      : parameters_(parameters), initial_(initial), spin_(initial.spin) {
    const double a0 = parameters.inertia_about_tip();
    a0_ = a0;
    inverse_a0_ = 1.0 / a0;
    axial_momentum_ = parameters.inertia_axial * spin_;
    gyroscopic_rate_ = (a0 - parameters.inertia_axial) * spin_ / a0;
    gravity_torque_per_inertia_ = parameters.mass * parameters.gravity * parameters.tip_distance / a0;
  }

  State initial_state() const {
    State y;
    set_initial_attitude_and_rates(initial_, y);
    return y;
  }

  /// Euler's equations about the pivot (PHYSICS.md, fixed tip):
  ///   A0 wX' = (A0 - C) wY wZ + m g h e_zY,   A0 wY' = -(A0 - C) wZ wX - m g h e_zX.
  void derivative(const State& y, State& dydt) const {
    const Vector3 gamma = vertical_in_body(y);
    const double wx = y[state_index::kOmegaX], wy = y[state_index::kOmegaY];
    attitude_rate(y, Vector3(wx, wy, spin_), dydt);
    const Vector2 rates = transverse_acceleration(gamma, wx, wy);
    dydt[state_index::kOmegaX] = rates.x();
    dydt[state_index::kOmegaY] = rates.y();
  }

  /// (wX', wY') of Euler's equations above.
  Vector2 transverse_acceleration(const Vector3& gamma, double wx, double wy) const {
    return Vector2(gyroscopic_rate_ * wy + gravity_torque_per_inertia_ * gamma.y(),
                   -gyroscopic_rate_ * wx - gravity_torque_per_inertia_ * gamma.x());
  }

  // The exact flows of the two parts of the energy about the pivot, H = T + V with
  //   T = (L_X^2 + L_Y^2) / (2 A0) + L_Z^2 / (2 C)  (free symmetric top),  V = m g h e_Zz,
  // which the splitting integrators compose (integrators/splitting.hpp). Their sum of vector
  // fields is Euler's equations above.

  /// Free symmetric top for a time tau (the flow of T). L is fixed in the world; the body
  /// turns about it at |L|/A0 and about its own axis at (1/C - 1/A0) L_Z = (A0 - C) wZ / A0:
  ///   q(tau) = exp(tau L_world / A0) q(0) exp(tau nu e_Z),  nu = (A0 - C) wZ / A0,
  /// and L in the body turns by -nu tau about Z: omega_perp rotates by the same angle.
  void free_rotation(double tau, State& y) const {
    const Quaternion q = attitude_of(y);
    const double wx = y[state_index::kOmegaX], wy = y[state_index::kOmegaY];
    const Vector3 momentum_world = q * Vector3(a0_ * wx, a0_ * wy, axial_momentum_);
    const Quaternion world_turn = rotation_by_vector(tau * inverse_a0_ * momentum_world);
    const double half_body_angle = 0.5 * tau * gyroscopic_rate_;
    const double ch = std::cos(half_body_angle), sh = std::sin(half_body_angle);
    const Quaternion q1 = world_turn * q * Quaternion(ch, 0.0, 0.0, sh);
    y[state_index::kQw] = q1.w();
    y[state_index::kQx] = q1.x();
    y[state_index::kQy] = q1.y();
    y[state_index::kQz] = q1.z();
    // cos and sin of the full angle by the double-angle formulas (two fewer calls).
    const double c = 1.0 - 2.0 * sh * sh, s = 2.0 * sh * ch;
    y[state_index::kOmegaX] = c * wx + s * wy;
    y[state_index::kOmegaY] = -s * wx + c * wy;
  }

  /// Gravity for a time tau at fixed attitude (the flow of V): the torque about the pivot
  /// m g h (e_zY, -e_zX, 0) is constant, so the body rates change linearly (the gravity terms
  /// of transverse_acceleration). The kick is horizontal (orthogonal to e_z), so L_z does not
  /// change; it has no Z part, so omega_Z does not either.
  void gravity_kick(double tau, State& y) const {
    const Vector3 gamma = vertical_in_body(y);
    y[state_index::kOmegaX] += tau * gravity_torque_per_inertia_ * gamma.y();
    y[state_index::kOmegaY] -= tau * gravity_torque_per_inertia_ * gamma.x();
  }

  /// Floor force on the tip in body components: N = m (a_G + g e_z), with
  /// a_G = h (w' x e_Z + w x (w x e_Z)) = h (wY' + wZ wX, -wX' + wZ wY, -w_perp^2).
  /// Only (wX', wY') are needed, not the whole derivative (this is an event function,
  /// evaluated after every step).
  Vector3 pivot_force_in_body(const State& y) const {
    const Vector3 gamma = vertical_in_body(y);
    const double wx = y[state_index::kOmegaX], wy = y[state_index::kOmegaY];
    const Vector2 rates = transverse_acceleration(gamma, wx, wy);
    const double h = parameters_.tip_distance, m = parameters_.mass;
    const Vector3 acceleration_of_g(h * (rates.y() + spin_ * wx),
                                    h * (-rates.x() + spin_ * wy),
                                    -h * (wx * wx + wy * wy));
    return m * (acceleration_of_g + parameters_.gravity * gamma);
  }

  /// R = N . e_z (vertical part of the pivot force).
  double normal_force(const State& y) const { return pivot_force_in_body(y).dot(vertical_in_body(y)); }

  ModelOutputs outputs(const State& y) const {
    const Quaternion q = attitude_of(y);
    const Vector3 gamma = vertical_in_body(y);
    const double wx = y[state_index::kOmegaX], wy = y[state_index::kOmegaY];
    const double h = parameters_.tip_distance, a0 = parameters_.inertia_about_tip();
    const double c = parameters_.inertia_axial;
    ModelOutputs out;
    const Vector3 force_in_body = pivot_force_in_body(y);
    const Vector3 force = q * force_in_body;
    // R as the event function computes it (normal_force()), so that the two never disagree in
    // sign by round-off: q * F gave R = -5.7e-14 N at a located lift-off (found by the fuzz test).
    out.normal_force = force_in_body.dot(gamma);
    out.contact_force = Vector3(force.x(), force.y(), 0.0);
    out.center_of_mass = h * (q * Vector3::UnitZ());
    out.center_of_mass_velocity = h * (q * Vector3(wy, -wx, 0.0));  // v_G = h w x e_Z
    out.contact_point = Vector3::Zero();
    out.energy = energy_without_spin(y) + 0.5 * c * spin_ * spin_;
    // L_z about the pivot: L = (A0 wX, A0 wY, C wZ) in body components, projected on e_z.
    out.vertical_angular_momentum = a0 * (wx * gamma.x() + wy * gamma.y()) + c * spin_ * gamma.z();
    return out;
  }

  /// E - C wZ^2 / 2 = 1/2 A0 w_perp^2 + m g h e_Zz (|v_G|^2 = h^2 w_perp^2 folded into A0): the
  /// part of the energy that moves (C wZ^2 / 2 is a constant of the model).
  double energy_without_spin(const State& y) const {
    const double wx = y[state_index::kOmegaX], wy = y[state_index::kOmegaY];
    return 0.5 * parameters_.inertia_about_tip() * (wx * wx + wy * wy) +
           parameters_.mass * parameters_.gravity * parameters_.tip_distance * vertical_in_body(y).z();
  }
  /// What the energy balance watches (StepGuard): E - C wZ^2 / 2, conserved.
  double energy_balance(const State& y) const { return energy_without_spin(y); }

  const TopParameters& parameters() const { return parameters_; }
  /// The largest step that resolves this top's fastest oscillation (motion_rates.hpp): the
  /// adaptive controllers' cap.
  double largest_resolving_step() const { return spinning_top::largest_resolving_step(SceneType::kFixedTip, parameters_, initial_); }
  const InitialConditions& initial_conditions() const { return initial_; }
  double spin() const { return spin_; }

 private:
  TopParameters parameters_;
  InitialConditions initial_;
  double spin_;
  double a0_, inverse_a0_;             // A0 = A + m h^2 and 1 / A0
  double axial_momentum_;              // L_Z = C wZ
  double gyroscopic_rate_;             // (A0 - C) wZ / A0
  double gravity_torque_per_inertia_;  // m g h / A0
};

}  // namespace spinning_top
