// Dormand-Prince 5(4) embedded pair with its fourth-order continuous extension
// (Dormand & Prince 1980; coefficients and dense output as in Hairer's DOPRI5,
// Hairer, Norsett, Wanner, Solving ODEs I, Tables II.5.2 and II.6.2).
#pragma once

#include <Eigen/Core>
#include <algorithm>
#include <cmath>

#include "spinning_top/hot_path.hpp"
#include "spinning_top/integration/controllers.hpp"

namespace spinning_top {

template <class Model>
class DormandPrince54 {
 public:
  using State = typename Model::State;
  static constexpr int kOrder = 5;          // order of the propagated solution
  static constexpr int kEmbeddedOrder = 4;  // order of the error estimate
  using Controller = PiController<kEmbeddedOrder + 1>;  // the estimate is O(dt^(kEmbeddedOrder + 1))
  static constexpr int kStagesPerStep = 6;  // FSAL: the seventh stage is the next step's first
  static constexpr const char* kName = "dopri5";

  /// Result of one attempted step from (y0, f0 = f(y0)) of size dt.
  struct Attempt {
    State y1;     // fifth-order solution
    State f1;     // f(y1): the next step's first stage (FSAL)
    State error;  // y1 - y1_hat (fifth minus fourth order)
  };

  /// Coefficients of the dense output on the last attempted step (see dense()).
  struct DenseStep {
    State r1, r2, r3, r4, r5;
    double t0 = 0.0, dt = 0.0;
  };

  /// Nothing is kept from step to step.
  void restart() {}

  SPINNING_TOP_FLATTEN void attempt(const Model& model, const State& y0, const State& f0, double dt, Attempt& out) {
    work_ += kStagesPerStep;
    model.derivative(y0 + dt * (a21 * f0), k2_);
    model.derivative(y0 + dt * (a31 * f0 + a32 * k2_), k3_);
    model.derivative(y0 + dt * (a41 * f0 + a42 * k2_ + a43 * k3_), k4_);
    model.derivative(y0 + dt * (a51 * f0 + a52 * k2_ + a53 * k3_ + a54 * k4_), k5_);
    model.derivative(y0 + dt * (a61 * f0 + a62 * k2_ + a63 * k3_ + a64 * k4_ + a65 * k5_), k6_);
    out.y1 = y0 + dt * (a71 * f0 + a73 * k3_ + a74 * k4_ + a75 * k5_ + a76 * k6_);
    model.derivative(out.y1, out.f1);
    out.error = dt * (e1 * f0 + e3 * k3_ + e4 * k4_ + e5 * k5_ + e6 * k6_ + e7 * out.f1);
  }

  /// Prepares the continuous extension of the step just attempted (call after attempt()).
  SPINNING_TOP_FLATTEN void prepare_dense(const State& y0, const State& f0, const Attempt& a, double t0, double dt, DenseStep& d) const {
    const State ydiff = a.y1 - y0;
    const State bspl = dt * f0 - ydiff;
    d.r1 = y0;
    d.r2 = ydiff;
    d.r3 = bspl;
    d.r4 = ydiff - dt * a.f1 - bspl;
    d.r5 = dt * (d1 * f0 + d3 * k3_ + d4 * k4_ + d5 * k5_ + d6 * k6_ + d7 * a.f1);
    d.t0 = t0;
    d.dt = dt;
  }

  /// The continuous extension needs nothing beyond prepare_dense().
  void complete_dense(const Model& /*model*/, DenseStep& /*d*/) {}

  /// Work units spent (work_budget.hpp): the evaluations of f of its attempts (its dense output
  /// needs none).
  long work() const { return work_; }

  /// y(t0 + theta dt), fourth order, theta in [0, 1].
  SPINNING_TOP_FLATTEN static State dense(const DenseStep& d, double t) {
    const double theta = (t - d.t0) / d.dt, theta1 = 1.0 - theta;
    return d.r1 + theta * (d.r2 + theta1 * (d.r3 + theta * (d.r4 + theta1 * d.r5)));
  }

 private:
  State k2_, k3_, k4_, k5_, k6_;
  long work_ = 0;

  static constexpr double a21 = 1.0 / 5.0;
  static constexpr double a31 = 3.0 / 40.0, a32 = 9.0 / 40.0;
  static constexpr double a41 = 44.0 / 45.0, a42 = -56.0 / 15.0, a43 = 32.0 / 9.0;
  static constexpr double a51 = 19372.0 / 6561.0, a52 = -25360.0 / 2187.0, a53 = 64448.0 / 6561.0,
                          a54 = -212.0 / 729.0;
  static constexpr double a61 = 9017.0 / 3168.0, a62 = -355.0 / 33.0, a63 = 46732.0 / 5247.0,
                          a64 = 49.0 / 176.0, a65 = -5103.0 / 18656.0;
  static constexpr double a71 = 35.0 / 384.0, a73 = 500.0 / 1113.0, a74 = 125.0 / 192.0,
                          a75 = -2187.0 / 6784.0, a76 = 11.0 / 84.0;
  static constexpr double e1 = 71.0 / 57600.0, e3 = -71.0 / 16695.0, e4 = 71.0 / 1920.0,
                          e5 = -17253.0 / 339200.0, e6 = 22.0 / 525.0, e7 = -1.0 / 40.0;
  static constexpr double d1 = -12715105075.0 / 11282082432.0, d3 = 87487479700.0 / 32700410799.0,
                          d4 = -10690763975.0 / 1880347072.0, d5 = 701980252875.0 / 199316789632.0,
                          d6 = -1453857185.0 / 822651844.0, d7 = 69997945.0 / 29380423.0;
};

}  // namespace spinning_top
