// RADAU9: the 5-stage Radau IIA method of order 9 (fully implicit, L-stable, stiffly accurate
// collocation; Hairer & Wanner, Solving ODEs II, sec. IV.5 and IV.8, and Hairer's radau.f, which
// runs it as its middle order). Why a second Radau: on stiff friction radau5 is accurate enough
// only at ~1e-4 s steps (order 5 at 1e-14), while the motion allows ~1e-3 s at order 9: the same
// error (~1e-12 rad over 10 s) for several times less work (doc/integrators.md, "radau9").
//
// An embedded method of the EmbeddedStepper (integration/steppers.hpp), as RadauIIA5 is:
//  - Newton on the stage equations G(Z) = Z - h (A x I) F(Z) = 0. For a model with a stiff part
//    (J = U V + O(fastest motion), the viscous top while sliding) by the low-rank Newton of
//    radau.hpp: Woodbury's identity with U_i V_i at each stage, a 10 x 10 LU; the factors are
//    taken again at the current iterate when it contracts slowly (the stiff direction turns with
//    the body). Otherwise (no stiff part, a skim, or a failure) by Newton with a Jacobian by
//    differences per stage and one LU of the 5n x 5n matrix I - h (A x I) diag(J_i).
//  - The error estimate of radau.f for 5 stages: the difference to the embedded order-5 solution
//    gamma0 h f(y0) + sum (bhat_i - b_i) h f_i, gamma0 = 1/gamma (gamma: A^-1's real eigenvalue),
//    written with the stages (h F = A^-1 Z) and filtered by (gamma/h I - J)^-1 so that stiff
//    components do not count; O(h^6), mapped to the tolerance as radau.f does (rtol' = 0.1
//    rtol^(3/5)), so that the controller's 1/10 on the mapped norm is radau.f's 1/6 on it.
//  - Requests inside a step: collocation steps from the step's start, as RadauIIA5::dense() (the
//    collocation polynomial is only O(h^6) between the nodes).
#pragma once

#include <Eigen/Core>
#include <Eigen/LU>
#include <algorithm>
#include <cmath>
#include <limits>

#include "spinning_top/hot_path.hpp"
#include "spinning_top/integration/controllers.hpp"
#include "spinning_top/integrators/jacobian.hpp"
#include "spinning_top/integrators/radau.hpp"
#include "spinning_top/integrators/small_lu.hpp"

namespace spinning_top {

/// radau.f's tolerance map for 5 stages (radau.hpp's RadauToleranceMap: rtol' = 0.1 rtol^(3/5)).
using Radau9ToleranceMap = RadauToleranceMap<10, 6>;
using Radau9Controller = PiController<10, Radau9ToleranceMap>;

template <class Model>
class RadauIIA9 {
 public:
  using State = typename Model::State;
  static constexpr int kN = Model::kStateSize;
  static constexpr int kStages = 5;
  static constexpr int kOrder = 9;
  static constexpr const char* kName = "radau9";
  using Controller = Radau9Controller;
  using Stages = Eigen::Matrix<double, kN, kStages>;
  static constexpr int kStiffRank = StiffRankOf<Model>::value;

  struct Attempt {
    State y1;     // y0 + Z_5 (stiffly accurate)
    State f1;     // f(y1)
    State error;  // the filtered difference to the embedded solution, O(h^6)
  };

  struct DenseStep {
    State y0, y1;
    Stages polynomial;  // y(t0 + x dt) = y0 + sum_k polynomial.col(k) x^(k+1)
    double t0 = 0.0, dt = 0.0;
    const Model* model = nullptr;
    RadauStatistics* statistics = nullptr;
  };

  void restart() {
    earlier_work_ += statistics_.work;
    statistics_ = RadauStatistics();
    have_predictor_ = attempt_pending_ = false;
    first_step_ = true;
  }

  const RadauStatistics& statistics() const { return statistics_; }
  long work() const { return earlier_work_ + statistics_.work; }

  void attempt(const Model& model, const State& y0, const State& f0, double dt, Attempt& out) {
    ++statistics_.attempts;
    const bool after_rejection = attempt_pending_;
    attempt_pending_ = true;
    Stages guess;
    starting_guess(dt, guess);
    Stages z = guess;
    Filter filter;
    if (!solve_stages(model, y0, dt, guess, z, filter, statistics_)) {
      // Non-finite error: the driver rejects the step and shrinks it.
      out.y1 = y0;
      out.f1 = f0;
      out.error.setConstant(std::numeric_limits<double>::quiet_NaN());
      return;
    }
    if (filter.low_rank) ++statistics_.low_rank_attempts;  // (solved by it: else the filter is J's)
    z_ = z;
    out.y1 = y0 + z.col(kStages - 1);
    model.derivative(out.y1, out.f1);
    const bool improve = first_step_ || after_rejection;
    estimate_error(model, y0, f0, out.y1, dt, z, filter, improve, out.error);
    statistics_.work += 1 + (improve ? 2 : 1) * filter.work + (improve ? 1 : 0);
  }

  void prepare_dense(const State& y0, const State& /*f0*/, const Attempt& a, double t0, double dt, DenseStep& d) {
    attempt_pending_ = false;
    first_step_ = false;
    d.y0 = y0;
    d.y1 = a.y1;
    d.polynomial = z_ * dense_polynomial().transpose();
    d.t0 = t0;
    d.dt = dt;
    d.model = nullptr;
    previous_polynomial_ = d.polynomial;
    previous_step_ = dt;
    have_predictor_ = true;
  }

  void complete_dense(const Model& model, DenseStep& d) {
    d.model = &model;
    d.statistics = &statistics_;
  }

  /// y(t0 + tau), 0 < tau <= dt: the collocation step of length 3 tau / 4 from y0, then one of
  /// tau / 4 (RadauIIA5::dense(): the last, short step sets the slip velocity that R reads times
  /// k), Newton started from the step's collocation polynomial. The step's end as computed.
  static State dense(const DenseStep& d, double t) {
    const double tau = t - d.t0;
    if (!(tau > 0.0)) return d.y0;
    if (tau >= d.dt) return d.y1;
    const double x = tau / d.dt;
    if (d.model == nullptr) return d.y0 + polynomial_at(d.polynomial, x);
    const double x_split = 0.75 * x;
    State y_split, y;
    if (!partial_step(d, d.y0, 0.0, x_split, y_split) || !partial_step(d, y_split, x_split, x, y))
      return d.y0 + polynomial_at(d.polynomial, x);  // (the whole step converged: not expected)
    return y;
  }

  // Radau IIA, s = 5: nodes, A, A^-1 (computed to 50 digits from the collocation conditions,
  // rounded), A^-1's real eigenvalue gamma, the error estimate's weights d_i = gamma e_i (ESTRAD
  // of radau.f: err = (gamma/h I - J)^-1 (f0 + sum d_i Z_i / h)) and the collocation polynomial's
  // coefficients of x, ..., x^5 in terms of Z_1..Z_5.
  static constexpr double kC[kStages] = {0.05710419611451768219312, 0.27684301363812382768, 0.5835904323689168200567,
                                         0.8602401356562194478479, 1.0};
  static constexpr double kA[kStages][kStages] = {
      {0.07299886431790332430557, -0.0267353311079455718777, 0.01867692976398435441225, -0.01287910609330643985365,
       0.00504283923388201520665},
      {0.1537752314791824686681, 0.1462148678474935066497, -0.03644456890512808952665, 0.02123306311930471942151,
       -0.007935579902728777532622},
      {0.1400630456848098715138, 0.2989671294912834793983, 0.1675850701352489634421, -0.03396910168661774657192,
       0.0109442887441922522745},
      {0.1448943081095347575366, 0.2765000687601592275559, 0.3257979229104210299849, 0.1287567532549097611582,
       -0.01570891737880532838779},
      {0.1437135607912259413234, 0.2813560151494620601922, 0.3118265229757412540819, 0.2231039010835707444026, 0.04},
  };
  static constexpr double kGamma = 6.286704751729276645173;
  static constexpr double kErrorWeights[kStages] = {-27.78093394406463730479, 3.641478498049213152712,
                                                    -1.252547721169118720491, 0.5920031671845428725662, -0.2};
  static constexpr double kDensePolynomial[kStages][kStages] = {
      {27.78093394406463730479, -3.641478498049213152712, 1.252547721169118720491, -0.5920031671845428725662, 0.2},
      {-208.0278573009013363819, 77.88337605511782785356, -29.16741431782969682998, 14.11189556361320535827, -4.8},
      {524.1878839694918316622, -264.8949135682263519042, 137.9029044041347843974, -72.39587480540026415533, 25.2},
      {-543.8283560361324920544, 317.6758690799527338257, -202.090870943607426426, 123.0433578997871846547, -44.8},
      {199.8873954234773594693, -127.0228530687949966223, 92.10283313613322013809, -64.16737549081558298507, 25.2},
  };

 private:
  using Jacobian = Eigen::Matrix<double, kN, kN>;
  static constexpr int kRank = kStiffRank > 0 ? kStiffRank : 1;  // (sizes only)
  using StiffColumns = Eigen::Matrix<double, kN, kRank>;
  using StiffRows = Eigen::Matrix<double, kRank, kN>;
  using Coupling = Eigen::Matrix<double, kStages * kRank, kStages * kRank>;
  using CouplingVector = Eigen::Matrix<double, kStages * kRank, 1>;
  // The fallback's 5n x 5n system: dynamic (a fixed 55 x 55 LU costs the compiler minutes). The
  // Newton solvers stay out of line (SPINNING_TOP_NOINLINE): the EmbeddedStepper's flattened
  // attempt() would otherwise inline Eigen's dynamic LU and products into every step (GCC took
  // minutes and GBs at -O1).
  using Big = Eigen::MatrixXd;
  using BigVector = Eigen::VectorXd;

  /// The error estimate's (gamma/h I - J)^-1: J's stiff part at y0 (low-rank Newton) or J at
  /// y0 by differences (the other Newton), and its work in evaluations per application.
  struct Filter {
    bool low_rank = false;
    StiffColumns u = StiffColumns::Zero();
    StiffRows v = StiffRows::Zero();
    Eigen::PartialPivLU<Jacobian> lu;
    long work = 0;
  };

  static constexpr int kMaxLowRankIterations = 12;
  static constexpr int kMaxIterations = 10;
  static constexpr int kLowRankRefactorizations = 2;  // factors taken again at slow contraction
  static constexpr double kSlowContraction = 0.3;
  // Newton's ends as RadauIIA5's: the estimated remaining error below kNewtonTolerance (its low-rank
  // tightening included: the low-rank Newton leaves a remainder of one sign step after step), or
  // corrections that stop contracting at round-off.
  static constexpr double kNewtonTolerance = 1e-18;
  // dense()'s collocation solves (requests, the event locator's samples and located events, the
  // range tracker) end sooner: their remainders do not accumulate from step to step as the
  // steps' do (a located event state that starts the next phase carries one, once), and at
  // 1e-17 the answers move by round-off alone (R by <= 7.5e-11 m g at k = 1e7, where changing
  // the LU's rounding alone moves it by 7.2e-11; 1e-16 moved it by 4.1e-10). 17 % fewer Newton
  // iterations at 1 kHz.
  static constexpr double kAnswerNewtonTolerance = 1e-17;
  static constexpr double kRoundOffFloor = 1e-14;

  static const Eigen::Matrix<double, kStages, kStages>& dense_polynomial() {
    static const Eigen::Matrix<double, kStages, kStages> p = [] {
      Eigen::Matrix<double, kStages, kStages> m;
      for (int k = 0; k < kStages; ++k)
        for (int i = 0; i < kStages; ++i) m(k, i) = kDensePolynomial[k][i];
      return m;
    }();
    return p;
  }

  static State polynomial_at(const Stages& q, double x) {
    State out = q.col(kStages - 1);
    for (int k = kStages - 2; k >= 0; --k) out = q.col(k) + x * out;
    return x * out;
  }

  void starting_guess(double dt, Stages& z) const {
    if (!have_predictor_) {
      z.setZero();
      return;
    }
    const State end = polynomial_at(previous_polynomial_, 1.0);
    for (int i = 0; i < kStages; ++i)
      z.col(i) = polynomial_at(previous_polynomial_, 1.0 + kC[i] * dt / previous_step_) - end;
  }

  /// h (A x I) X: column i is h sum_j a_ij X_j.
  static Stages times_a(double h, const Stages& x) {
    Stages out;
    for (int i = 0; i < kStages; ++i) {
      State s = kA[i][0] * x.col(0);
      for (int j = 1; j < kStages; ++j) s += kA[i][j] * x.col(j);
      out.col(i) = h * s;
    }
    return out;
  }

  static double rms(const Stages& dz, const State& scale) {
    double sum = 0.0;
    for (int i = 0; i < kStages; ++i) sum += dz.col(i).cwiseQuotient(scale).squaredNorm();
    return std::sqrt(sum / (kStages * kN));
  }

  /// The residual G(Z) = Z - h (A x I) F(Z); false if F is not finite.
  static bool residual(const Model& model, const State& y0, double h, const Stages& z, Stages& g) {
    Stages f;
    State fi;
    for (int i = 0; i < kStages; ++i) {
      model.derivative(State(y0 + z.col(i)), fi);
      f.col(i) = fi;
    }
    if (!f.allFinite()) return false;
    g = z - times_a(h, f);
    return true;
  }

  /// Newton's stopping rule (RadauIIA5's): +1 converged, -1 failed, 0 go on.
  static int verdict(int iteration, int max_iterations, double norm, double& previous_norm, double& theta,
                     double tolerance) {
    double faccon = 1.0;
    if (iteration > 1) {
      theta = norm / previous_norm;
      if (theta < 0.99)
        faccon = theta / (1.0 - theta);
      else if (norm > kRoundOffFloor)
        return -1;
    }
    const bool at_round_off = norm <= kRoundOffFloor && (theta >= 0.5 || iteration == max_iterations);
    if (faccon * norm <= tolerance || norm == 0.0 || at_round_off) return +1;
    previous_norm = std::max(norm, std::numeric_limits<double>::min());
    return iteration == max_iterations ? -1 : 0;
  }

  /// Solves the stage equations from z (the guess); the filter for the error estimate comes with
  /// it. Counts its work in `statistics`.
  static bool solve_stages(const Model& model, const State& y0, double h, const Stages& guess, Stages& z,
                           Filter& filter, RadauStatistics& statistics, double tolerance = kNewtonTolerance) {
    const State scale = (1.0 + y0.cwiseAbs().array()).matrix();
    if constexpr (kStiffRank > 0) {
      if (model.stiff_part(y0, filter.u, filter.v)) {
        filter.low_rank = true;
        filter.work = 1;
        if (solve_low_rank(model, y0, h, scale, z, statistics, tolerance)) return true;
        ++statistics.newton_failures;
        z = guess;
      }
    }
    filter.low_rank = false;
    return solve_dense(model, y0, h, scale, z, filter, statistics, tolerance);
  }

  /// The low-rank Newton (header comment): Woodbury with U_i V_i at y0 + Z_i.
  SPINNING_TOP_NOINLINE static bool solve_low_rank(const Model& model, const State& y0, double h, const State& scale, Stages& z,
                             RadauStatistics& statistics, double tolerance) {
    StiffColumns u[kStages];
    StiffRows v[kStages];
    SmallLu<kStages * kRank> lu;
    const auto factor = [&] {
      for (int i = 0; i < kStages; ++i) model.stiff_part(State(y0 + z.col(i)), u[i], v[i]);
      Coupling s;
      for (int i = 0; i < kStages; ++i)
        for (int j = 0; j < kStages; ++j)
          s.template block<kRank, kRank>(i * kRank, j * kRank) = (-h * kA[i][j]) * (v[i] * u[j]);
      s += Coupling::Identity();
      lu.compute(s);
      ++statistics.decompositions;
      statistics.work += kStages + radau_work::low_rank_decomposition(kN) * 3;
    };
    factor();
    int refactorizations = 0;
    double previous_norm = 0.0, theta = 0.0;
    for (int iteration = 1; iteration <= kMaxLowRankIterations; ++iteration) {
      ++statistics.newton_iterations;
      statistics.work += kStages + 2 * radau_work::low_rank_solve(kN);
      Stages g;
      if (!residual(model, y0, h, z, g)) return false;
      // (I - h (A x I) diag(U_i V_i)) dZ = -G: dZ = -G + h (A x I) (U_j w_j), where
      // (I - h a_ij V_i U_j) w = -V_i G_i.
      CouplingVector rhs;
      for (int i = 0; i < kStages; ++i) rhs.template segment<kRank>(i * kRank) = -(v[i] * g.col(i));
      const CouplingVector w = lu.solve(rhs);
      Stages uw;
      for (int j = 0; j < kStages; ++j) uw.col(j) = u[j] * w.template segment<kRank>(j * kRank);
      const Stages dz = times_a(h, uw) - g;
      if (!dz.allFinite()) return false;
      const double norm = rms(dz, scale);
      z += dz;
      const int outcome = verdict(iteration, kMaxLowRankIterations, norm, previous_norm, theta, tolerance);
      if (outcome > 0) return true;
      if (outcome < 0 && refactorizations == kLowRankRefactorizations) return false;
      if ((outcome < 0 || theta > kSlowContraction) && refactorizations < kLowRankRefactorizations) {
        // The stiff direction has turned from where the factors were taken: take them again here.
        ++refactorizations;
        factor();
        previous_norm = 0.0;
        theta = 0.0;
        iteration = 0;  // a new count (bounded by the refactorizations)
      }
    }
    return false;
  }

  /// Newton with J_i by differences at the stages and one LU of I - h (A x I) diag(J_i); J at the
  /// starting guess, then at the last iterate if that fails.
  SPINNING_TOP_NOINLINE static bool solve_dense(const Model& model, const State& y0, double h, const State& scale, Stages& z,
                          Filter& filter, RadauStatistics& statistics, double tolerance) {
    for (int pass = 0; pass < 2; ++pass) {
      Jacobian j[kStages];
      State fi;
      for (int i = 0; i < kStages; ++i) {
        const State yi = y0 + z.col(i);
        model.derivative(yi, fi);
        forward_difference_jacobian(model, yi, fi, j[i]);
      }
      statistics.jacobians += kStages;
      if (pass == 0) {
        filter.lu.compute(Jacobian::Identity() * (kGamma / h) - j[0]);
        filter.work = radau_work::real_solve(kN);
      }
      Big m = Big::Identity(kStages * kN, kStages * kN);
      for (int i = 0; i < kStages; ++i)
        for (int k = 0; k < kStages; ++k) m.block(i * kN, k * kN, kN, kN) -= (h * kA[i][k]) * j[k];
      const Eigen::PartialPivLU<Big> lu(m);
      ++statistics.decompositions;
      // (A 5n x 5n LU: ~125 n x n LUs' operations.)
      statistics.work += kStages * (1 + kN) + radau_work::real_decomposition(kN) * 125 / 3;
      double previous_norm = 0.0, theta = 0.0;
      for (int iteration = 1; iteration <= kMaxIterations; ++iteration) {
        ++statistics.newton_iterations;
        statistics.work += kStages + radau_work::real_solve(kN) * 25;
        Stages g;
        if (!residual(model, y0, h, z, g)) return false;
        const BigVector dz_flat = lu.solve(-Eigen::Map<const BigVector>(g.data(), kStages * kN));
        const Stages dz = Eigen::Map<const Stages>(dz_flat.data());
        if (!dz.allFinite()) return false;
        const double norm = rms(dz, scale);
        z += dz;
        const int outcome = verdict(iteration, kMaxIterations, norm, previous_norm, theta, tolerance);
        if (outcome > 0) return true;
        if (outcome < 0) break;
      }
      ++statistics.newton_failures;
    }
    return false;
  }

  static State apply_filter(const Filter& filter, double h, const State& b) {
    if constexpr (kStiffRank > 0) {
      if (filter.low_rank) {
        const double c = kGamma / h;
        const Eigen::Matrix<double, kRank, kRank> small =
            c * Eigen::Matrix<double, kRank, kRank>::Identity() - filter.v * filter.u;
        return (b + filter.u * small.partialPivLu().solve(filter.v * b)) / c;
      }
    }
    return filter.lu.solve(b);
  }

  /// ESTRAD for 5 stages (header comment); at the first step and after a rejection the filter
  /// once more, on f(y0 + err) (as RadauIIA5::estimate_error), the smaller of the two kept.
  void estimate_error(const Model& model, const State& y0, const State& f0, const State& y1, double dt,
                      const Stages& z, const Filter& filter, bool improve, State& error) const {
    State combination = kErrorWeights[0] * z.col(0);
    for (int i = 1; i < kStages; ++i) combination += kErrorWeights[i] * z.col(i);
    combination /= dt;
    State err = apply_filter(filter, dt, f0 + combination);
    if (improve) {
      const State scale = (1.0 + y0.cwiseAbs().cwiseMax(y1.cwiseAbs()).array()).matrix();
      const double n = static_cast<double>(kN);
      const double norm = std::sqrt(err.cwiseQuotient(scale).squaredNorm() / n);
      State f_err;
      model.derivative(State(y0 + err), f_err);
      const State second = apply_filter(filter, dt, f_err + combination);
      const double second_norm = std::sqrt(second.cwiseQuotient(scale).squaredNorm() / n);
      if (second_norm < norm || !std::isfinite(norm)) err = second;
    }
    error = err;
  }

  /// The collocation step from y_start at t0 + x_start dt to t0 + x_end dt, Newton started from
  /// the step's polynomial. False if Newton does not converge.
  SPINNING_TOP_NOINLINE static bool partial_step(const DenseStep& d, const State& y_start, double x_start, double x_end, State& y_end) {
    const double tau = (x_end - x_start) * d.dt;
    Stages guess;
    const State start = polynomial_at(d.polynomial, x_start);
    for (int i = 0; i < kStages; ++i)
      guess.col(i) = polynomial_at(d.polynomial, x_start + kC[i] * (x_end - x_start)) - start;
    Stages z = guess;
    Filter filter;
    RadauStatistics scratch;
    RadauStatistics& statistics = d.statistics != nullptr ? *d.statistics : scratch;
    ++statistics.dense_solves;
    const bool converged = solve_stages(*d.model, y_start, tau, guess, z, filter, statistics, kAnswerNewtonTolerance);
    y_end = y_start + z.col(kStages - 1);
    return converged;
  }

  Stages z_ = Stages::Zero(), previous_polynomial_ = Stages::Zero();
  double previous_step_ = 0.0;
  bool have_predictor_ = false, attempt_pending_ = false, first_step_ = true;
  RadauStatistics statistics_;
  long earlier_work_ = 0;
};

}  // namespace spinning_top
