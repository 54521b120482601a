// Classical fourth-order Runge-Kutta (Hairer, Norsett, Wanner, Solving ODEs I, Table II.1.2).
#pragma once

#include "spinning_top/hot_path.hpp"

namespace spinning_top {

/// One-step method: step() advances y by dt in place. Any Model with State and
/// derivative(y, dydt) will do.
template <class Model>
class ClassicalRk4 {
 public:
  using State = typename Model::State;
  static constexpr int kOrder = 4;
  static constexpr int kStagesPerStep = 4;
  /// Work units per step (work_budget.hpp): its evaluations of f.
  static constexpr long kWorkPerStep = kStagesPerStep;
  static constexpr const char* kName = "rk4";

  SPINNING_TOP_FLATTEN void step(const Model& model, State& y, double dt) const {
    State k1, k2, k3, k4;
    model.derivative(y, k1);
    model.derivative(y + (0.5 * dt) * k1, k2);
    model.derivative(y + (0.5 * dt) * k2, k3);
    model.derivative(y + dt * k3, k4);
    y += (dt / 6.0) * (k1 + 2.0 * (k2 + k3) + k4);
  }
};

}  // namespace spinning_top
