// Geometric integrator for the frictionless top (and, for comparison, the fixed tip):
// Gauss-Legendre collocation of order 6 (3 stages) on the reduced variables
//   u = (q, Gamma, omega_X, omega_Y),  q' = q (0, omega) / 2,  Gamma' = Gamma x omega,
//   omega_perp' = the scene's law (Model::transverse_acceleration), which depends on the
//   attitude only through Gamma,
// followed by the smallest body rotation of q that makes its vertical R(q)^T e_z equal the
// collocation's Gamma (an O(dt^7) correction).
// Why: the frictionless kinetic energy has the attitude-dependent term 1/2 m v_Gz^2, so the
// free-rotation + kick splitting of the fixed tip does not apply. Gauss methods conserve
// every quadratic invariant exactly (Hairer, Lubich, Wanner, Geometric Numerical
// Integration, 2nd ed. 2006, Thm. IV.2.2); in the reduced variables
//   L_z = A (omega_X Gamma_X + omega_Y Gamma_Y) + C omega_Z Gamma_Z   and   |Gamma|^2
// are quadratic (omega_Z is a constant of the model), so both are conserved to round-off,
// and after the correction so is L_z computed from the reported (q, omega). The reduced
// system (Gamma, omega_perp) is closed, integrable and reversible, and the method is
// symmetric, so the energy (a function of Gamma and omega_perp only) has a bounded error with
// no drift (GNI, ch. XI, reversible perturbation theory); measured over 1e6 steps in
// doc/integrators.md. The heading (rotation about the vertical) follows from q's own
// collocation, accurate to order 6.
#pragma once

#include <Eigen/Core>
#include <cmath>
#include <limits>

#include "spinning_top/hot_path.hpp"
#include "spinning_top/kinematics.hpp"

namespace spinning_top {

template <class Model>
class ReducedGauss6 {
 public:
  using State = typename Model::State;
  static constexpr int kOrder = 6;
  static constexpr const char* kName = "gauss6";

  /// One step; if the fixed-point iteration does not converge (a step far beyond the
  /// motion's time scales, which validate() refuses anyway) it takes two half steps.
  void step(const Model& model, State& y, double dt) const { step_recursive(model, y, dt, 0); }

  /// Work units spent (work_budget.hpp): evaluations of the reduced rate (one per stage of each
  /// fixed-point sweep, one at the start of each collocation) and one for each final correction.
  /// A step costs 1 + 3 x sweeps + 1: 29 at 1 ms on the toy top (9 sweeps), a step taken
  /// in two halves twice that and more.
  long work() const { return work_; }

 private:
  static constexpr int kStages = 3, kDim = 9;  // u = (q: 4, Gamma: 3, omega_perp: 2)
  static constexpr int kMaxIterations = 60, kMaxHalvings = 6;
  using Reduced = Eigen::Matrix<double, kDim, 1>;

  void step_recursive(const Model& model, State& y, double dt, int depth) const {
    if (collocate(model, y, dt)) return;
    if (depth >= kMaxHalvings) {
      y.setConstant(std::numeric_limits<double>::quiet_NaN());
      return;
    }
    step_recursive(model, y, 0.5 * dt, depth + 1);
    step_recursive(model, y, 0.5 * dt, depth + 1);
  }

  static Reduced rate(const Model& model, double spin, const Reduced& u) {
    const Vector3 omega(u[7], u[8], spin);
    const Vector3 gamma = u.template segment<3>(4);
    Reduced du;
    attitude_rate(u, omega, du);  // reads u[0..3] = q, writes du[0..3]
    du.template segment<3>(4) = gamma.cross(omega);
    du.template segment<2>(7) = model.transverse_acceleration(gamma, u[7], u[8]);
    return du;
  }

  /// Solves the collocation equations K_i = f(u0 + dt sum_j a_ij K_j) by fixed-point
  /// iteration (the problem is not stiff: contraction ~ dt |omega| / 2 per sweep).
  /// Flattened (hot_path.hpp): rate() and its attitude_rate() were left as calls. Out of line
  /// (hot_path.hpp), as it was before the one driver loop flattened its step.
  SPINNING_TOP_FLATTEN SPINNING_TOP_NOINLINE bool collocate(const Model& model, State& y, double dt) const {
    const double spin = model.spin();
    Reduced u0;
    u0.template head<4>() = y.template head<4>();
    u0.template segment<3>(4) = vertical_in_body(y);
    u0[7] = y[state_index::kOmegaX];
    u0[8] = y[state_index::kOmegaY];
    Reduced k[kStages];
    const Reduced f0 = rate(model, spin, u0);
    for (auto& ki : k) ki = f0;
    const double scale = 1.0 + u0.cwiseAbs().maxCoeff();
    bool converged = false;
    int sweeps = 0;
    for (int iteration = 0; iteration < kMaxIterations && !converged; ++iteration) {
      ++sweeps;
      double change = 0.0;
      for (int i = 0; i < kStages; ++i) {
        Reduced stage = u0;
        for (int j = 0; j < kStages; ++j) stage += (dt * kA[i][j]) * k[j];
        const Reduced updated = rate(model, spin, stage);
        change = std::max(change, dt * (updated - k[i]).cwiseAbs().maxCoeff());
        k[i] = updated;
      }
      if (!std::isfinite(change)) break;
      // Converged when a sweep changes the stages by round-off of the state.
      converged = change <= 16.0 * std::numeric_limits<double>::epsilon() * scale;
    }
    work_ += 2 + kStages * sweeps;
    if (!converged) return false;
    Reduced u1 = u0;
    for (int i = 0; i < kStages; ++i) u1 += (dt * kB[i]) * k[i];

    // Turn q by the smallest body rotation r with R(q r)^T e_z = Gamma_1, i.e. r takes
    // Gamma_1 to Gamma(q_1): r = normalize(1 + g.c, g x c) for unit vectors g -> c.
    Quaternion q1(u1[0], u1[1], u1[2], u1[3]);
    q1.normalize();
    const Vector3 target = u1.template segment<3>(4).normalized();
    State trial = y;
    trial.template head<4>() << q1.w(), q1.x(), q1.y(), q1.z();
    const Vector3 current = vertical_in_body(trial);
    const Vector3 axis = target.cross(current);
    Quaternion r(1.0 + target.dot(current), axis.x(), axis.y(), axis.z());
    r.normalize();
    q1 = q1 * r;
    y[state_index::kQw] = q1.w();
    y[state_index::kQx] = q1.x();
    y[state_index::kQy] = q1.y();
    y[state_index::kQz] = q1.z();
    y[state_index::kOmegaX] = u1[7];
    y[state_index::kOmegaY] = u1[8];
    return y.allFinite();
  }

  // Gauss-Legendre, s = 3 (Hairer, Norsett, Wanner, Solving ODEs I, Table II.7.4).
  static constexpr double kSqrt15 = 3.872983346207416885179265;
  static constexpr double kA[kStages][kStages] = {
      {5.0 / 36.0, 2.0 / 9.0 - kSqrt15 / 15.0, 5.0 / 36.0 - kSqrt15 / 30.0},
      {5.0 / 36.0 + kSqrt15 / 24.0, 2.0 / 9.0, 5.0 / 36.0 - kSqrt15 / 24.0},
      {5.0 / 36.0 + kSqrt15 / 30.0, 2.0 / 9.0 + kSqrt15 / 15.0, 5.0 / 36.0},
  };
  static constexpr double kB[kStages] = {5.0 / 18.0, 4.0 / 9.0, 5.0 / 18.0};

  mutable long work_ = 0;  // step() is const: the count is not the method's state
};

}  // namespace spinning_top
