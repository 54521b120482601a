// Radau IIA of order 5 (3 stages): the fully implicit, L-stable, stiffly accurate collocation
// method of Hairer's RADAU5 (Hairer & Wanner, Solving ODEs II, 2nd ed. 1996, sec. IV.5,
// Table 5.6 and sec. IV.8), here at a fixed step with Newton's method on the stage equations
//   Z = dt (A x I) F(Z),  F(Z)_i = f(y0 + Z_i),  y1 = y0 + Z_3.
// Why not only a Rosenbrock method for the viscous top: friction relaxes v_P at the rate
// lambda = k (1/m + h^2/A), but the stiff direction in the state (q, omega_X, omega_Y, v_G)
// turns with the body at the spin rate (v_P = v_G - h (omega_Y e_X - omega_X e_Y)): over a
// 1 ms step at 150 rad/s by 0.15 rad. A linearly implicit method freezes J at the step's start
// and takes the mismatch, 0.15 lambda, explicitly: RODAS4 blows up for lambda dt >~ 1e2
// (measured). Newton's iteration instead converges to the implicit solution, whose stability
// function is that of Radau IIA (R(inf) = 0): the friction transient is damped in one step
// and the solution lies on the slow manifold (the fixed-tip limit as k -> inf).
#pragma once

#include <Eigen/Core>
#include <Eigen/LU>
#include <cmath>
#include <limits>

#include "spinning_top/integrators/jacobian.hpp"

namespace spinning_top {

template <class Model>
class RadauIIA5 {
 public:
  using State = typename Model::State;
  static constexpr int kN = Model::kStateSize;
  static constexpr int kStages = 3;
  static constexpr int kOrder = 5;
  static constexpr const char* kName = "radau5";

  /// One step; a step whose Newton iteration does not converge is taken as two half steps
  /// (at most kMaxHalvings deep), and as NaN beyond (the driver reports non_finite).
  void step(const Model& model, State& y, double dt) { step_recursive(model, y, dt, 0); }

  /// Newton iterations of the last step (diagnostics and tests).
  int last_iterations() const { return iterations_; }

 private:
  using Stages = Eigen::Matrix<double, kStages * kN, 1>;
  using NewtonMatrix = Eigen::Matrix<double, kStages * kN, kStages * kN>;
  using Jacobian = Eigen::Matrix<double, kN, kN>;
  static constexpr int kMaxIterations = 12, kMaxHalvings = 6;
  static constexpr double kTolerance = 1e-13;

  void step_recursive(const Model& model, State& y, double dt, int depth) {
    State y1 = y;
    if (solve_stages(model, y, dt, y1)) {
      y = y1;
      return;
    }
    if (depth >= kMaxHalvings) {
      y.setConstant(std::numeric_limits<double>::quiet_NaN());
      return;
    }
    step_recursive(model, y, 0.5 * dt, depth + 1);
    step_recursive(model, y, 0.5 * dt, depth + 1);
  }

  /// Newton's method on G(Z) = Z - dt (A x I) F(Z) = 0 from Z = 0. The matrix
  /// I - dt (A x I) diag(J_i) starts with J_i = J(y0) (simplified Newton); if the iteration
  /// contracts slowly (the stiff direction turned within the step), it is rebuilt with the
  /// Jacobians at the current stage values, which restores Newton's fast convergence.
  bool solve_stages(const Model& model, const State& y0, double dt, State& y1) {
    Stages z = Stages::Zero(), f_stages, residual;
    Jacobian j0;
    finite_difference_jacobian(model, y0, j0);
    const double stiffness = dt * j0.cwiseAbs().rowwise().sum().maxCoeff();  // dt |J|_inf
    NewtonMatrix matrix;
    build_matrix(dt, {j0, j0, j0}, matrix);
    Eigen::PartialPivLU<NewtonMatrix> lu(matrix);
    double previous_norm = 0.0;
    State scale = (1.0 + y0.cwiseAbs().array()).matrix();
    for (iterations_ = 1; iterations_ <= kMaxIterations; ++iterations_) {
      evaluate_stages(model, y0, z, f_stages);
      residual = z;
      for (int i = 0; i < kStages; ++i)
        for (int j = 0; j < kStages; ++j) residual.template segment<kN>(i * kN) -= dt * kA[i][j] * f_stages.template segment<kN>(j * kN);
      const Stages correction = lu.solve(-residual);
      if (!correction.allFinite()) return false;
      z += correction;
      double norm = 0.0;
      for (int i = 0; i < kStages; ++i)
        norm = std::max(norm, correction.template segment<kN>(i * kN).cwiseQuotient(scale).cwiseAbs().maxCoeff());
      // Converged when the remaining error, estimated from the contraction rate, is at
      // round-off of the state (far below the method's own truncation error), or when the
      // corrections stop shrinking at round-off level.
      const double contraction = previous_norm > 0.0 ? norm / previous_norm : 1.0;
      if (norm <= kTolerance) break;
      if (iterations_ >= 2 && contraction < 1.0 && contraction / (1.0 - contraction) * norm <= kTolerance) break;
      if (iterations_ >= 3 && contraction >= 1.0 && norm <= 1e3 * kTolerance) break;
      // Stiff (|J| dt >> 1): the first iteration has put the stage attitudes in place (they
      // are not stiff), so the stiff directions are now known at the stages; refactor there
      // once rather than let J(y0)'s turned stiff subspace push the iterate far away.
      const bool stiff_first_iteration = iterations_ == 1 && stiffness > 10.0;
      if (stiff_first_iteration || (iterations_ >= 2 && contraction > 0.3)) {
        Jacobian j1, j2, j3;
        finite_difference_jacobian(model, State(y0 + z.template segment<kN>(0)), j1);
        finite_difference_jacobian(model, State(y0 + z.template segment<kN>(kN)), j2);
        finite_difference_jacobian(model, State(y0 + z.template segment<kN>(2 * kN)), j3);
        build_matrix(dt, {j1, j2, j3}, matrix);
        lu.compute(matrix);
      }
      previous_norm = norm;
      if (iterations_ == kMaxIterations) return false;
    }
    y1 = y0 + z.template segment<kN>(2 * kN);  // stiffly accurate: y1 = Y_3
    return y1.allFinite();
  }

  void evaluate_stages(const Model& model, const State& y0, const Stages& z, Stages& f) const {
    State fi;
    for (int i = 0; i < kStages; ++i) {
      model.derivative(State(y0 + z.template segment<kN>(i * kN)), fi);
      f.template segment<kN>(i * kN) = fi;
    }
  }

  static void build_matrix(double dt, const Jacobian (&j)[kStages], NewtonMatrix& m) {
    m.setIdentity();
    for (int i = 0; i < kStages; ++i)
      for (int k = 0; k < kStages; ++k) m.template block<kN, kN>(i * kN, k * kN) -= dt * kA[i][k] * j[k];
  }

  int iterations_ = 0;

  // Radau IIA, s = 3 (Hairer & Wanner, Table IV.5.6), with sqrt(6) written out.
  static constexpr double kSqrt6 = 2.449489742783178098197284;
  static constexpr double kA[kStages][kStages] = {
      {(88.0 - 7.0 * kSqrt6) / 360.0, (296.0 - 169.0 * kSqrt6) / 1800.0, (-2.0 + 3.0 * kSqrt6) / 225.0},
      {(296.0 + 169.0 * kSqrt6) / 1800.0, (88.0 + 7.0 * kSqrt6) / 360.0, (-2.0 - 3.0 * kSqrt6) / 225.0},
      {(16.0 - kSqrt6) / 36.0, (16.0 + kSqrt6) / 36.0, 1.0 / 9.0},
  };
};

}  // namespace spinning_top
