// Scene "frictionless": the tip slides on a frictionless floor (PHYSICS.md, N = R e_z).
// G starts with no horizontal velocity and keeps none, so its horizontal position is a
// constant of the scene and its height follows from the attitude: the state is only
// y = (qw, qx, qy, qz, omega_X, omega_Y); omega_Z is a constant of motion.
#pragma once

#include <Eigen/Core>

#include "spinning_top/kinematics.hpp"
#include "spinning_top/model_outputs.hpp"
#include "spinning_top/motion_rates.hpp"
#include "spinning_top/parameters.hpp"
#include "spinning_top/scenes/sliding_contact.hpp"

namespace spinning_top {

class Frictionless {
 public:
  static constexpr int kStateSize = state_index::kAttitudeAndRatesSize;
  static constexpr bool kConservesEnergy = true;
  static constexpr bool kConservesVerticalAngularMomentum = true;  // about the vertical through G
  static constexpr const char* kName = "frictionless";
  using State = Eigen::Matrix<double, kStateSize, 1>;

  Frictionless(const TopParameters& parameters, const InitialConditions& initial)
      : parameters_(parameters), initial_(initial), spin_(initial.spin), contact_(parameters, initial.spin) {
    // The tip starts at the origin, so G stands at h e_Z(0) horizontally, for ever.
    const Vector3 axis = initial_attitude(initial) * Vector3::UnitZ();
    center_of_mass_xy_ = parameters.tip_distance * Vector2(axis.x(), axis.y());
  }

  State initial_state() const {
    State y;
    set_initial_attitude_and_rates(initial_, y);
    return y;
  }

  /// T w_perp' = wZ U w_perp + alpha (w_perp^2 e_Zz - g/h)(-e_zY, e_zX) of the notes,
  /// solved in closed form by SlidingContact with no friction.
  void derivative(const State& y, State& dydt) const {
    const double wx = y[state_index::kOmegaX], wy = y[state_index::kOmegaY];
    const Vector2 rates = transverse_acceleration(vertical_in_body(y), wx, wy);
    attitude_rate(y, Vector3(wx, wy, spin_), dydt);
    dydt[state_index::kOmegaX] = rates.x();
    dydt[state_index::kOmegaY] = rates.y();
  }

  /// (wX', wY') above: a function of the vertical Gamma and omega_perp only (the reduced
  /// variables of integrators/gauss.hpp).
  Vector2 transverse_acceleration(const Vector3& gamma, double wx, double wy) const {
    return contact_.solve(gamma, wx, wy).transverse_acceleration;
  }

  double normal_force(const State& y) const {
    return contact_.solve(vertical_in_body(y), y[state_index::kOmegaX], y[state_index::kOmegaY]).normal_force;
  }

  ModelOutputs outputs(const State& y) const {
    const Quaternion q = attitude_of(y);
    const Vector3 gamma = vertical_in_body(y);
    const Vector3 axis = q * Vector3::UnitZ();
    const double wx = y[state_index::kOmegaX], wy = y[state_index::kOmegaY];
    const double h = parameters_.tip_distance;
    const double a = parameters_.inertia_transverse, c = parameters_.inertia_axial;
    const double vz = constrained_vertical_velocity(h, gamma, wx, wy);
    ModelOutputs out;
    out.normal_force = contact_.solve(gamma, wx, wy).normal_force;
    out.center_of_mass = Vector3(center_of_mass_xy_.x(), center_of_mass_xy_.y(), h * gamma.z());
    out.center_of_mass_velocity = Vector3(0.0, 0.0, vz);
    out.contact_point = Vector3(center_of_mass_xy_.x() - h * axis.x(), center_of_mass_xy_.y() - h * axis.y(), 0.0);
    out.energy = energy_without_spin(y) + 0.5 * c * spin_ * spin_;
    // L_z about the vertical through G: L_G = (A wX, A wY, C wZ) in body components.
    out.vertical_angular_momentum = a * (wx * gamma.x() + wy * gamma.y()) + c * spin_ * gamma.z();
    return out;
  }

  /// E - C wZ^2 / 2 = 1/2 m vz_G^2 + 1/2 A w_perp^2 + m g z_G: the part of the energy that moves
  /// (C wZ^2 / 2 is a constant of the model).
  double energy_without_spin(const State& y) const {
    const Vector3 gamma = vertical_in_body(y);
    const double wx = y[state_index::kOmegaX], wy = y[state_index::kOmegaY];
    const double h = parameters_.tip_distance, m = parameters_.mass;
    const double vz = constrained_vertical_velocity(h, gamma, wx, wy);
    return 0.5 * m * vz * vz + 0.5 * parameters_.inertia_transverse * (wx * wx + wy * wy) +
           m * parameters_.gravity * h * gamma.z();
  }
  /// What the energy balance watches (StepGuard): E - C wZ^2 / 2, conserved.
  double energy_balance(const State& y) const { return energy_without_spin(y); }

  const TopParameters& parameters() const { return parameters_; }
  /// The largest step that resolves this top's fastest oscillation (motion_rates.hpp): the
  /// adaptive controllers' cap.
  double largest_resolving_step() const { return spinning_top::largest_resolving_step(SceneType::kFrictionless, parameters_, initial_); }
  const InitialConditions& initial_conditions() const { return initial_; }
  double spin() const { return spin_; }

 private:
  TopParameters parameters_;
  InitialConditions initial_;
  double spin_;
  SlidingContact contact_;
  Vector2 center_of_mass_xy_;
};

}  // namespace spinning_top
