// The Jacobian df/dy of a scene model, for the implicit integrators.
#pragma once

#include <Eigen/Core>
#include <algorithm>
#include <cmath>
#include <limits>

namespace spinning_top {

/// df/dy by central differences: error O(delta^2) + O(eps / delta), about 1e-11 of |J| at
/// delta = eps^(1/3) max(1, |y_j|). The implicit methods need J for stability (it must
/// resolve the stiff friction rates, which it does to the same relative accuracy) and the
/// Rosenbrock method also for its order, which holds down to errors of ~1e-12 (measured in
/// test_integrators). 2n evaluations of f (22 for the viscous top).
template <class Model>
void finite_difference_jacobian(const Model& model, const typename Model::State& y,
                                Eigen::Matrix<double, Model::kStateSize, Model::kStateSize>& jacobian) {
  using State = typename Model::State;
  const double cube_root_eps = std::cbrt(std::numeric_limits<double>::epsilon());
  State plus, minus, f_plus, f_minus;
  for (int c = 0; c < Model::kStateSize; ++c) {
    const double delta = cube_root_eps * std::max(1.0, std::abs(y[c]));
    plus = y;
    minus = y;
    plus[c] += delta;
    minus[c] -= delta;
    model.derivative(plus, f_plus);
    model.derivative(minus, f_minus);
    jacobian.col(c) = (f_plus - f_minus) / (plus[c] - minus[c]);
  }
}

}  // namespace spinning_top
