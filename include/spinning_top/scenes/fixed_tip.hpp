// Scene "fixed tip": the tip P is a pivot at the origin (PHYSICS.md, v_P = 0).
// State y = (qw, qx, qy, qz, omega_X, omega_Y); omega_Z is a constant of motion.
#pragma once

#include <Eigen/Core>

#include "spinning_top/kinematics.hpp"
#include "spinning_top/model_outputs.hpp"
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
    const Vector3 force = q * pivot_force_in_body(y);
    out.normal_force = force.z();
    out.contact_force = Vector3(force.x(), force.y(), 0.0);
    out.center_of_mass = h * (q * Vector3::UnitZ());
    out.center_of_mass_velocity = h * (q * Vector3(wy, -wx, 0.0));  // v_G = h w x e_Z
    out.contact_point = Vector3::Zero();
    // E = 1/2 A0 w_perp^2 + 1/2 C wZ^2 + m g h e_Zz (|v_G|^2 = h^2 w_perp^2 folded into A0).
    out.energy = 0.5 * a0 * (wx * wx + wy * wy) + 0.5 * c * spin_ * spin_ +
                 parameters_.mass * parameters_.gravity * h * gamma.z();
    // L_z about the pivot: L = (A0 wX, A0 wY, C wZ) in body components, projected on e_z.
    out.vertical_angular_momentum = a0 * (wx * gamma.x() + wy * gamma.y()) + c * spin_ * gamma.z();
    return out;
  }

  const TopParameters& parameters() const { return parameters_; }
  const InitialConditions& initial_conditions() const { return initial_; }
  double spin() const { return spin_; }

 private:
  TopParameters parameters_;
  InitialConditions initial_;
  double spin_;
  double gyroscopic_rate_;             // (A0 - C) wZ / A0
  double gravity_torque_per_inertia_;  // m g h / A0
};

}  // namespace spinning_top
