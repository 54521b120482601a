// Scene "viscous": the tip slides on the floor against viscous friction F = -k v_P
// (PHYSICS.md). State y = (qw, qx, qy, qz, omega_X, omega_Y, x_G, y_G, vx_G, vy_G, W):
// attitude, transverse rates, G's horizontal position and velocity, and the work W done
// against friction (so that the energy balance E(t) + W(t) = E(0) can be checked).
#pragma once

#include <Eigen/Core>
#include <algorithm>

#include "spinning_top/kinematics.hpp"
#include "spinning_top/model_outputs.hpp"
#include "spinning_top/motion_rates.hpp"
#include "spinning_top/parameters.hpp"
#include "spinning_top/scenes/sliding_contact.hpp"

namespace spinning_top {

class Viscous {
 public:
  static constexpr int kX = 6, kY = 7, kVx = 8, kVy = 9, kWork = 10;
  static constexpr int kStateSize = 11;
  static constexpr bool kConservesEnergy = false;
  static constexpr bool kConservesVerticalAngularMomentum = false;
  static constexpr const char* kName = "viscous";
  using State = Eigen::Matrix<double, kStateSize, 1>;

  /// skimming: the tip skims the floor (HYBRID.md, "lift_off", viscous): R = 0 and the friction is
  /// scaled by the lambda in [0, 1] that keeps R at 0.
  Viscous(const TopParameters& parameters, const InitialConditions& initial, bool skimming = false)
      : parameters_(parameters), initial_(initial), spin_(initial.spin), contact_(parameters, initial.spin),
        skimming_(skimming) {}

  bool skimming() const { return skimming_; }

  /// What bounds the floor phase (events.hpp: event_functions): R while sliding; while skimming,
  /// min(eps - R1, R0) with R1 = R under full friction and R0 = R without friction. The skim ends
  /// where R1 rises above eps = kSkimReturn m g (the floor pushes again: back to sliding) or R0
  /// turns negative (the free tip rises: take-off). eps keeps the skim that begins at a located
  /// lift-off, where R1 is 0 up to the locator's ulps, from ending at once.
  double contact_validity(const State& y) const {
    if (!skimming_) return normal_force(y);
    const Evaluation e = evaluate(y);
    return std::min(kSkimReturn * parameters_.mass * parameters_.gravity - e.full_friction_normal_force,
                    e.frictionless_normal_force);
  }
  static constexpr double kSkimReturn = 1e-9;

  /// R without friction and with full friction at y (the lift-off rule and the skim's ends).
  Vector2 normal_force_range(const State& y) const {
    const Viscous skimming(parameters_, initial_, true);  // evaluate() finds both only while skimming
    const Evaluation e = skimming.evaluate(y);
    return Vector2(e.frictionless_normal_force, e.full_friction_normal_force);
  }

  State initial_state() const {
    State y;
    set_initial_attitude_and_rates(initial_, y);
    const Vector3 axis = initial_attitude(initial_) * Vector3::UnitZ();
    y[kX] = parameters_.tip_distance * axis.x();  // the tip starts at the origin
    y[kY] = parameters_.tip_distance * axis.y();
    y[kVx] = initial_.velocity_x;
    y[kVy] = initial_.velocity_y;
    y[kWork] = 0.0;
    return y;
  }

  void derivative(const State& y, State& dydt) const {
    const Evaluation e = evaluate(y);
    attitude_rate(y, Vector3(y[state_index::kOmegaX], y[state_index::kOmegaY], spin_), dydt);
    dydt[state_index::kOmegaX] = e.dynamics.transverse_acceleration.x();
    dydt[state_index::kOmegaY] = e.dynamics.transverse_acceleration.y();
    dydt[kX] = y[kVx];
    dydt[kY] = y[kVy];
    dydt[kVx] = e.friction.x() / parameters_.mass;  // m vx_G' = F_x
    dydt[kVy] = e.friction.y() / parameters_.mass;
    dydt[kWork] = -e.friction.dot(e.tip_velocity);  // W' = -F . v_P = k |v_P|^2 >= 0
  }

  /// The stiff part of df/dy while sliding, of rank 2: J_stiff = U V with V = dF/dy = -k dv_P/dy
  /// and U = df/dF (F enters (wX', wY') through Euler's equations and R, vx_G', vy_G' as F/m,
  /// and W' = k |v_P|^2 as -2 v_P . F's rows). Everything else in J is O(fastest motion), k times
  /// smaller at stiff friction: RADAU5 solves its Newton systems with this part alone, by
  /// Woodbury's identity (radau.hpp, "low-rank Newton"). False while skimming (F is then scaled
  /// by a lambda that depends on y).
  static constexpr int kStiffRank = 2;
  using StiffColumns = Eigen::Matrix<double, kStateSize, kStiffRank>;
  using StiffRows = Eigen::Matrix<double, kStiffRank, kStateSize>;
  bool stiff_part(const State& y, StiffColumns& u, StiffRows& v) const {
    if (skimming_) return false;
    const double w = y[0], x = y[1], yy = y[2], z = y[3];
    const double wx = y[state_index::kOmegaX], wy = y[state_index::kOmegaY];
    const double h = parameters_.tip_distance, k = parameters_.friction;
    // The horizontal parts of e_X and e_Y (evaluate()) and their derivatives in (w, x, y, z).
    const Vector2 ex(1.0 - 2.0 * (yy * yy + z * z), 2.0 * (x * yy + w * z));
    const Vector2 ey(2.0 * (x * yy - w * z), 1.0 - 2.0 * (x * x + z * z));
    const Eigen::Matrix<double, 2, 4> d_ex = (Eigen::Matrix<double, 2, 4>() << 0.0, 0.0, -4.0 * yy, -4.0 * z,  //
                                              2.0 * z, 2.0 * yy, 2.0 * x, 2.0 * w)
                                                 .finished();
    const Eigen::Matrix<double, 2, 4> d_ey = (Eigen::Matrix<double, 2, 4>() << -2.0 * z, 2.0 * yy, 2.0 * x, -2.0 * w,  //
                                              0.0, -4.0 * x, 0.0, -4.0 * z)
                                                 .finished();
    // v_P = v_G - h (wY e_X - wX e_Y) (evaluate()); V = -k dv_P/dy.
    v.setZero();
    v.template leftCols<4>() = (k * h) * (wy * d_ex - wx * d_ey);
    v.col(state_index::kOmegaX) = (-k * h) * ey;
    v.col(state_index::kOmegaY) = (k * h) * ex;
    v(0, kVx) = v(1, kVy) = -k;
    // U: (wX', wY') = b + (h/A) (R n + f), f = (F . e_Y, -F . e_X), R affine in n . f with slope
    // -alpha / det T (SlidingContact::solve), so d(wX', wY')/dF = (h/A) (I - alpha n n^T / det T) S.
    const Vector3 gamma = vertical_in_body(y);
    const Vector2 n(gamma.y(), -gamma.x());
    const double a = parameters_.inertia_transverse, m = parameters_.mass;
    const double alpha = m * h * h / a;
    const Eigen::Matrix2d projection = Eigen::Matrix2d::Identity() - (alpha / (1.0 + alpha * n.squaredNorm())) * n * n.transpose();
    Eigen::Matrix2d s;
    s.row(0) = ey.transpose();
    s.row(1) = -ex.transpose();
    u.setZero();
    u.template middleRows<2>(state_index::kOmegaX) = (h / a) * projection * s;
    u(kVx, 0) = u(kVy, 1) = 1.0 / m;
    const Vector2 tip_velocity(y[kVx] - h * (wy * ex.x() - wx * ey.x()), y[kVy] - h * (wy * ex.y() - wx * ey.y()));
    u.row(kWork) = -2.0 * tip_velocity.transpose();
    return true;
  }

  double normal_force(const State& y) const { return evaluate(y).dynamics.normal_force; }

  ModelOutputs outputs(const State& y) const {
    const Evaluation e = evaluate(y);
    const Vector3 gamma = vertical_in_body(y);
    const double wx = y[state_index::kOmegaX], wy = y[state_index::kOmegaY];
    const double h = parameters_.tip_distance;
    const double a = parameters_.inertia_transverse, c = parameters_.inertia_axial;
    const Vector3 velocity(y[kVx], y[kVy], constrained_vertical_velocity(h, gamma, wx, wy));
    ModelOutputs out;
    out.normal_force = e.dynamics.normal_force;
    out.contact_force = Vector3(e.friction.x(), e.friction.y(), 0.0);
    out.center_of_mass = Vector3(y[kX], y[kY], h * gamma.z());
    out.center_of_mass_velocity = velocity;
    out.contact_point = Vector3(y[kX] - h * e.axis.x(), y[kY] - h * e.axis.y(), 0.0);
    out.energy = energy_without_spin(y) + 0.5 * c * spin_ * spin_;
    out.vertical_angular_momentum = a * (wx * gamma.x() + wy * gamma.y()) + c * spin_ * gamma.z();
    out.dissipated_energy = y[kWork];
    return out;
  }

  /// E - C wZ^2 / 2 = 1/2 m |v_G|^2 + 1/2 A w_perp^2 + m g z_G: the part of the energy that moves
  /// (friction acts at the tip, on the axis, so it leaves wZ and C wZ^2 / 2 constant).
  double energy_without_spin(const State& y) const {
    const Vector3 gamma = vertical_in_body(y);
    const double wx = y[state_index::kOmegaX], wy = y[state_index::kOmegaY];
    const double h = parameters_.tip_distance, m = parameters_.mass;
    const Vector3 velocity(y[kVx], y[kVy], constrained_vertical_velocity(h, gamma, wx, wy));
    return 0.5 * m * velocity.squaredNorm() + 0.5 * parameters_.inertia_transverse * (wx * wx + wy * wy) +
           m * parameters_.gravity * h * gamma.z();
  }
  /// What the energy balance watches (StepGuard): E - C wZ^2 / 2 + W, conserved (W' = k |v_P|^2).
  double energy_balance(const State& y) const { return energy_without_spin(y) + y[kWork]; }

  const TopParameters& parameters() const { return parameters_; }
  /// The largest step that resolves this top's fastest oscillation (motion_rates.hpp): the
  /// adaptive controllers' cap.
  double largest_resolving_step() const { return spinning_top::largest_resolving_step(SceneType::kViscous, parameters_, initial_); }
  const InitialConditions& initial_conditions() const { return initial_; }
  double spin() const { return spin_; }

 private:
  struct Evaluation {
    Vector2 tip_velocity;  // v_P, horizontal world components
    Vector2 friction;      // F = -k v_P, horizontal world components
    Vector3 axis;          // e_Z in world components
    SlidingContact::Result dynamics;
    double frictionless_normal_force = 0.0, full_friction_normal_force = 0.0;  // skimming only
  };

  /// v_P = v_G - h w x e_Z in world components (PHYSICS.md erratum 3: the vertical part
  /// cancels by the constraint, the horizontal part must not drop v_Gz's projection),
  /// then F = -k v_P projected on the body axes for Euler's equations.
  Evaluation evaluate(const State& y) const {
    const double w = y[0], x = y[1], yy = y[2], z = y[3];
    const double wx = y[state_index::kOmegaX], wy = y[state_index::kOmegaY];
    const double h = parameters_.tip_distance;
    // Columns e_X, e_Y, e_Z of the rotation matrix of q.
    const Vector3 ex(1.0 - 2.0 * (yy * yy + z * z), 2.0 * (x * yy + w * z), 2.0 * (x * z - w * yy));
    const Vector3 ey(2.0 * (x * yy - w * z), 1.0 - 2.0 * (x * x + z * z), 2.0 * (yy * z + w * x));
    const Vector3 ez(2.0 * (x * z + w * yy), 2.0 * (yy * z - w * x), 1.0 - 2.0 * (x * x + yy * yy));
    const Vector3 gamma(ex.z(), ey.z(), ez.z());
    // h w x e_Z = h (wY e_X - wX e_Y).
    Evaluation e;
    e.tip_velocity = Vector2(y[kVx] - h * (wy * ex.x() - wx * ey.x()), y[kVy] - h * (wy * ex.y() - wx * ey.y()));
    e.friction = -parameters_.friction * e.tip_velocity;
    e.axis = ez;
    const Vector2 friction_body(e.friction.x() * ex.x() + e.friction.y() * ex.y(),
                                e.friction.x() * ey.x() + e.friction.y() * ey.y());
    e.dynamics = contact_.solve(gamma, wx, wy, friction_body);
    if (skimming_) {
      // R is affine in the friction's scale lambda: R(lambda) = R0 + lambda (R1 - R0) = 0 at
      // lambda = R0 / (R0 - R1) (R1 <= 0 <= R0 while skimming), and so are (wX', wY').
      const SlidingContact::Result free = contact_.solve(gamma, wx, wy);
      e.frictionless_normal_force = free.normal_force;
      e.full_friction_normal_force = e.dynamics.normal_force;
      const double span = free.normal_force - e.dynamics.normal_force;
      const double lambda = span > 0.0 ? std::clamp(free.normal_force / span, 0.0, 1.0) : 1.0;
      e.friction *= lambda;
      e.dynamics.transverse_acceleration =
          free.transverse_acceleration + lambda * (e.dynamics.transverse_acceleration - free.transverse_acceleration);
      e.dynamics.normal_force = 0.0;
    }
    return e;
  }

  TopParameters parameters_;
  InitialConditions initial_;
  double spin_;
  SlidingContact contact_;
  bool skimming_ = false;
};

}  // namespace spinning_top
