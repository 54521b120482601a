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

namespace spinning_top {

/// df/dy by forward differences from a known f(y): n evaluations of f, error ~ sqrt(eps) of
/// |J| at delta = sqrt(eps max(1e-5, |y_j|)) (radau5.f's increment). Enough where J only
/// drives Newton's iteration and filters an error estimate (RADAU5), not the order (RODAS).
template <class Model>
void forward_difference_jacobian(const Model& model, const typename Model::State& y, const typename Model::State& f,
                                 Eigen::Matrix<double, Model::kStateSize, Model::kStateSize>& jacobian) {
  using State = typename Model::State;
  const double eps = std::numeric_limits<double>::epsilon();
  State shifted = y, f_shifted;
  for (int c = 0; c < Model::kStateSize; ++c) {
    const double delta = std::sqrt(eps * std::max(1e-5, std::abs(y[c])));
    shifted[c] = y[c] + delta;
    model.derivative(shifted, f_shifted);
    jacobian.col(c) = (f_shifted - f) / (shifted[c] - y[c]);
    shifted[c] = y[c];
  }
}

}  // namespace spinning_top
