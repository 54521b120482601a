// RODAS4: the L-stable, stiffly accurate Rosenbrock method of order 4 with 6 stages
// (Hairer & Wanner, Solving ODEs II, 2nd ed. 1996, sec. IV.7, method RODAS; coefficients
// of Hairer's rodas.f, METH = 1). A linearly implicit method: each step solves six linear
// systems with the one matrix (I / (gamma dt) - J), J = df/dy at the step's start, so it
// needs no Newton iteration and no step-size control to stay stable on stiff problems.
// Why for the viscous top: friction is linear in the velocities, v_P relaxes at the rate
// lambda = k (1/m + h^2/A) (PHYSICS.md erratum 9), and with m/k = 1e-8 s at the node's 1 kHz
// step lambda dt ~ 1e5: an explicit method needs dt < 3/lambda. L-stability (R(inf) = 0)
// damps the relaxation in one step as the physics does, and stiff accuracy (y1 is the last
// stage) keeps the order on the slow manifold (the fixed-tip limit k -> inf).
#pragma once

#include <Eigen/Core>
#include <Eigen/LU>

#include "spinning_top/integrators/jacobian.hpp"

namespace spinning_top {

template <class Model>
class Rodas4 {
 public:
  using State = typename Model::State;
  static constexpr int kN = Model::kStateSize;
  using Matrix = Eigen::Matrix<double, kN, kN>;
  static constexpr int kOrder = 4;
  static constexpr int kStages = 6;
  static constexpr const char* kName = "rodas4";
  /// Work units per step (work_budget.hpp): the central-difference Jacobian (2n evaluations of
  /// f), the 6 stages' evaluations, and the linear algebra at its measured cost in evaluations of
  /// the viscous top's f (bench/budget_time.cpp): one n x n LU (10) and 6 solves (5 each).
  static constexpr long kWorkPerStep = 2 * kN + kStages + 10 + kStages * 5;

  void step(const Model& model, State& y, double dt) {
    finite_difference_jacobian(model, y, jacobian_);
    const Matrix iteration_matrix = Matrix::Identity() * (1.0 / (kGamma * dt)) - jacobian_;
    const Eigen::PartialPivLU<Matrix> lu(iteration_matrix);
    State k[kStages];
    State f, stage;
    for (int i = 0; i < kStages; ++i) {
      stage = y;
      State rhs_correction = State::Zero();
      for (int j = 0; j < i; ++j) {
        stage += kA[i][j] * k[j];
        rhs_correction += (kC[i][j] / dt) * k[j];
      }
      model.derivative(stage, f);
      k[i] = lu.solve(f + rhs_correction);
    }
    // Stiffly accurate: y1 = Y_6 + K_6 with Y_6 = y + sum a_6j K_j (m_j = a_6j, m_6 = 1).
    for (int j = 0; j < kStages - 1; ++j) y += kA[kStages - 1][j] * k[j];
    y += k[kStages - 1];
  }

 private:
  Matrix jacobian_;

  static constexpr double kGamma = 0.25;
  // a_ij and c_ij of rodas.f (Hairer's "Rosenbrock form with transformed stages").
  static constexpr double kA[kStages][kStages] = {
      {0, 0, 0, 0, 0, 0},
      {1.544, 0, 0, 0, 0, 0},
      {0.9466785280815826, 0.2557011698983284, 0, 0, 0, 0},
      {3.314825187068521, 2.896124015972201, 0.9986419139977817, 0, 0, 0},
      {1.221224509226641, 6.019134481288629, 12.53708332932087, -0.6878860361058950, 0, 0},
      {1.221224509226641, 6.019134481288629, 12.53708332932087, -0.6878860361058950, 1.0, 0},
  };
  static constexpr double kC[kStages][kStages] = {
      {0, 0, 0, 0, 0, 0},
      {-5.6688, 0, 0, 0, 0, 0},
      {-2.430093356833875, -0.2063599157091915, 0, 0, 0, 0},
      {-0.1073529058151375, -9.594562251023355, -20.47028614809616, 0, 0, 0},
      {7.496443313967647, -10.24680431464352, -33.99990352819905, 11.70890893206160, 0, 0},
      {8.083246795921522, -7.981132988064893, -31.52159432874371, 16.31930543123136,
       -6.058818238834054, 0},
  };
};

}  // namespace spinning_top
