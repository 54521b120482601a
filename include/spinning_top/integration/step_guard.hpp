// The StepGuard: what every state a time-stepper reports must satisfy, whatever the method.
//  - On the unit sphere: the attitude is projected after every step (a Runge-Kutta step leaves
//    |q| = 1 at the local error; projection keeps the order, Hairer, Lubich & Wanner, Geometric
//    Numerical Integration, sec. IV.4).
//  - Finite: a step that produced inf or NaN ends the run with non_finite, never published.
//  - The energy balance: B = E - C wZ^2 / 2 + W may not move by more than kEnergyBalanceTolerance
//    (|B(0)| + m g h) (events.hpp). A step, an interpolated answer or a located event's state
//    that breaks it ends the run with energy_drift at the last state that kept it.
// A closed form needs none of this: its states are exact to round-off (exact_stepper.hpp).
#pragma once

#include <cmath>

#include "spinning_top/events.hpp"
#include "spinning_top/kinematics.hpp"

namespace spinning_top {

template <class Model>
class StepGuard {
 public:
  using State = typename Model::State;

  /// (Re)starts the run's balance at y (projected and finite).
  void start(const Model& model, const State& y) {
    const TopParameters& top = model.parameters();
    balance_ = model.energy_balance(y);
    allowed_drift_ = kEnergyBalanceTolerance * (std::abs(balance_) + top.mass * top.gravity * top.tip_distance);
  }

  /// Puts the attitude back on the unit sphere (in place); false if the state is not finite.
  static bool project(State& y) {
    normalize_attitude(y);
    return all_finite(y);
  }

  /// Whether a state keeps the energy balance of the run.
  bool keeps_balance(const Model& model, const State& y) const {
    return std::abs(model.energy_balance(y) - balance_) <= allowed_drift_;
  }

 private:
  double balance_ = 0.0, allowed_drift_ = 0.0;  // B(0) of the run and the drift it may take
};

}  // namespace spinning_top
