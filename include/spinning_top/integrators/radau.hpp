// RADAU5: the 3-stage Radau IIA method of order 5 (fully implicit, L-stable, stiffly accurate
// collocation) with Hairer's embedded error estimate, step-size control and continuous output
// (Hairer & Wanner, Solving ODEs II, 2nd ed. 1996, sec. IV.5 Table 5.6 and sec. IV.8; the
// Fortran code radau5.f, whose structure SciPy's integrate/_ivp/radau.py follows). It is an
// embedded method of the EmbeddedStepper (integration/steppers.hpp): restart / attempt /
// prepare_dense / complete_dense / dense; a Newton failure reports a non-finite error, and the
// controller shrinks the step.
//
// Stage equations Z = h (A x I) F(Z), F(Z)_i = f(y0 + Z_i), y1 = y0 + Z_3, solved by simplified
// Newton in the eigenbasis of A^-1 (W = (T^-1 x I) Z): one real n x n system with
// (gamma/h I - J) and one complex one with ((alpha - i beta)/h I - J) per iteration, sec. IV.8.
// As in radau5.f, J and the LU decompositions are kept across steps: J is recomputed only
// when Newton contracted slowly in the last accepted step (rate > 1e-3), after a rejection or
// a Newton failure with an older J; the LUs only when h or J changed.
//
// Why the viscous top needs this: friction relaxes v_P at the rate lambda = k (1/m + h^2/A)
// (PHYSICS.md erratum 9), up to 2e8 1/s. The stiff direction (v_P = v_G - h (omega_Y e_X -
// omega_X e_Y)) turns with the body at the spin rate, so a linearly implicit method (RODAS,
// J frozen at the step's start) blows up for lambda dt >~ 1e2; Newton's iteration converges
// to the implicit solution, whose stability function is Radau IIA's (R(inf) = 0).
//
// Where this differs from radau5.f, each measured to be needed (doc/integrators.md, "Viscous"):
//  1. Per-stage Jacobians. One J for all three stages contracts only while h^2 lambda omega_Z
//     is small (the stiff direction turns between the stages): with it alone the steps were
//     limited by Newton failures to ~18 us at k = 1e7. When the simplified Newton fails with a
//     fresh J, the step is solved by Newton with a Jacobian per stage (decompose_per_stage(), by
//     block elimination), and the simplified one is tried again after 16, 32, ... 256 steps.
//  2. Newton to round-off. R = m (g + ...) - alpha n.F reads F = -k v_P: an error dv_P in the
//     state is an error k dv_P in R (k = 1e7 N s/m: 1e-15 m/s is 1e-8 N).
//  3. Requests inside a step are answered by collocation steps from the step's start (dense()),
//     not by the collocation cubic (radau5.f's CONTR5): the cubic's error is O(h^4), against
//     the steps' O(h^6), and it interpolates q, omega and v_G separately, so v_P between the
//     stages leaves the slow manifold, R off by 3e-7 m g at k = 1e5 (test_radau).
//  4. The PI controller (integration/controllers.hpp, through Radau5ToleranceMap below) replaces
//     Gustafsson's predictive one: it rejects few steps here (test_radau), and the controller
//     stays common to the adaptive methods.
#pragma once

#include <Eigen/Core>
#include <Eigen/LU>
#include <algorithm>
#include <cmath>
#include <complex>
#include <limits>
#include <type_traits>

#include "spinning_top/integration/controllers.hpp"
#include "spinning_top/integrators/jacobian.hpp"
#include "spinning_top/integrators/small_lu.hpp"

namespace spinning_top {

/// Work counters of a RadauIIA5 (for the benchmark and the tests).
struct RadauStatistics {
  long attempts = 0;           ///< step attempts (accepted or not)
  long newton_iterations = 0;  ///< in steps and dense outputs
  long newton_failures = 0;    ///< attempts whose Newton iteration did not converge
  long jacobians = 0;          ///< finite-difference Jacobians
  long decompositions = 0;     ///< Newton matrices factorized (a real + complex LU pair, or per stage)
  long dense_solves = 0;       ///< partial collocation steps for requests inside a step
  long per_stage_attempts = 0; ///< attempts solved by the per-stage Newton
  long low_rank_attempts = 0;  ///< attempts solved by the low-rank Newton (models with a stiff part)
  /// Work units (work_budget.hpp): the evaluations of f, and the linear algebra at its measured
  /// cost in evaluations (radau_work below), in attempts accepted or not and in dense outputs.
  long work = 0;
};

/// The work (work_budget.hpp) of RADAU5's linear algebra in evaluations of the model's f, for a
/// state of n components: measured for the viscous top (n = 11) by bench/budget_time.cpp (its
/// f: 0.032 us; a real 11 x 11 LU 10 evaluations, a complex one 56, their solves 5 and 13, an
/// LU with its inverse 34, a product 7), and scaled as n for smaller states (the fixed tip's
/// n = 6 measured within 2x of that).
namespace radau_work {
constexpr long scaled(long at_n11, int n) { return (at_n11 * n + 10) / 11; }
/// A real and a complex LU (the simplified Newton's matrices).
constexpr long decomposition(int n) { return scaled(66, n); }
/// The real LU alone (the error estimate's, after per-stage steps).
constexpr long real_decomposition(int n) { return scaled(10, n); }
/// The per-stage Newton's block elimination: two LUs with their inverses, two products, an LU.
constexpr long per_stage_decomposition(int n) { return scaled(95, n); }
/// A simplified Newton iteration's real and complex solves and its transforms (f apart).
constexpr long newton_solve(int n) { return scaled(18, n); }
/// A per-stage Newton iteration's six products and one solve (f apart).
constexpr long per_stage_solve(int n) { return scaled(11, n); }
/// One real solve (the error estimate).
constexpr long real_solve(int n) { return scaled(5, n); }
/// The low-rank Newton (models with a stiff part, measured by bench/budget_time.cpp for the
/// viscous top's rank 2: 8.1, 2.6 and 0.3 evaluations): its 3r x 3r matrix with the stages'
/// factors, one iteration's Woodbury solve (f apart), one filter of the error estimate.
constexpr long low_rank_decomposition(int n) { return scaled(8, n); }
constexpr long low_rank_solve(int n) { return scaled(3, n); }
constexpr long low_rank_filter(int n) { return scaled(1, n); }
}  // namespace radau_work

/// The rank of a model's stiff part (its stiff_part(y, U, V): J_stiff = U V), 0 if it has none.
template <class Model, class = void>
struct StiffRankOf : std::integral_constant<int, 0> {};
template <class Model>
struct StiffRankOf<Model, std::void_t<decltype(Model::kStiffRank)>> : std::integral_constant<int, Model::kStiffRank> {};

/// radau.f's tolerance map for an estimate err = O(h^kErrorPower) of a method whose controller
/// runs on O(h^kMappedPower): the error norm is err scaled by (|err| / 0.1)^e / 0.1 with
/// e = kMappedPower / kErrorPower - 1, |err| the RMS over 1 + max(|y0|, |y1|), the controller's
/// own scale, so the map needs no tolerance. radau5 (sec. IV.8: err O(h^4) from an embedded
/// order-3 solution): rtol' = 0.1 rtol^(2/3), e = 1/2, and the controller's exponent 1/6 on the
/// mapped norm is radau5.f's 1/4 on err. radau9 (err O(h^6)): rtol' = 0.1 rtol^(3/5), e = 2/3,
/// and 1/10 on the mapped norm is radau.f's 1/6 on err.
template <int kMappedPower, int kErrorPower>
struct RadauToleranceMap {
  template <class State>
  static State map(const State& err, const State& y0, const State& y1) {
    const State scale = (1.0 + y0.cwiseAbs().cwiseMax(y1.cwiseAbs()).array()).matrix();
    const double norm = std::sqrt(err.cwiseQuotient(scale).squaredNorm() / static_cast<double>(err.size()));
    if constexpr (2 * kMappedPower == 3 * kErrorPower) {
      return err * (std::sqrt(norm / 0.1) / 0.1);  // e = 1/2: sqrt, exact and cheaper than pow
    } else {
      constexpr double e = static_cast<double>(kMappedPower - kErrorPower) / kErrorPower;
      return err * (std::pow(norm / 0.1, e) / 0.1);
    }
  }
};
using Radau5ToleranceMap = RadauToleranceMap<6, 4>;
using Radau5Controller = PiController<6, Radau5ToleranceMap>;

template <class Model>
class RadauIIA5 {
 public:
  using State = typename Model::State;
  static constexpr int kN = Model::kStateSize;
  static constexpr int kStages = 3;
  static constexpr int kOrder = 5;
  static constexpr const char* kName = "radau5";
  using Controller = Radau5Controller;  // the PI control of radau5.f's mapped estimate

  using Jacobian = Eigen::Matrix<double, kN, kN>;
  using Stages = Eigen::Matrix<double, kN, kStages>;  // Z_1, Z_2, Z_3 as columns
  /// The rank of the model's stiff part (0: none, the low-rank Newton is not compiled in).
  static constexpr int kStiffRank = StiffRankOf<Model>::value;

  struct Attempt {
    State y1;     // y0 + Z_3 (stiffly accurate)
    State f1;     // f(y1)
    State error;  // radau5.f's err, O(h^4) (estimate_error()); Radau5ToleranceMap puts it on the controller's scale
  };

  struct DenseStep {
    State y0, y1;
    Stages polynomial;  // y(t0 + x dt) = y0 + sum_k polynomial.col(k) x^(k+1): the collocation cubic
    double t0 = 0.0, dt = 0.0;
    bool per_stage_newton = false;  // how the step's stages were solved
    bool low_rank = false;          // ... by the low-rank Newton
    // Filled by complete_dense() for the partial collocation steps of dense(): the step's J
    // (simplified Newton), or J at c = 0, c1, c2, 1 (per-stage Newton), interpolated in between.
    Jacobian jacobians[kStages + 1];
    const Model* model = nullptr;
    RadauStatistics* statistics = nullptr;
  };

  /// Starts a run (the driver's reset): no Jacobian, no starting guess, counters at zero.
  void restart() {
    earlier_work_ += statistics_.work;
    statistics_ = RadauStatistics();
    have_jacobian_ = have_predictor_ = attempt_pending_ = jacobian_is_fresh_ = false;
    per_stage_newton_ = used_per_stage_ = returned_to_simplified_ = false;
    per_stage_run_ = kPerStageNewtonSteps;
    real_step_ = complex_step_ = 0.0;
    contraction_ = kJacobianReuseRate;
    faccon_ = 1.0;
    first_step_ = true;
  }

  const RadauStatistics& statistics() const { return statistics_; }
  /// Work units spent since the method was built (work_budget.hpp): RadauStatistics::work of
  /// this run and of the runs before its restarts.
  long work() const { return earlier_work_ + statistics_.work; }

  void attempt(const Model& model, const State& y0, const State& f0, double dt, Attempt& out) {
    ++statistics_.attempts;
    // An attempt without an accepted step since the last one follows a rejection: as radau5.f,
    // do not retry with a Jacobian older than this step.
    const bool after_rejection = attempt_pending_;
    attempt_pending_ = true;
    if (after_rejection && !jacobian_is_fresh_) have_jacobian_ = false;
    const State scale = (1.0 + y0.cwiseAbs().array()).matrix();
    Stages guess;
    starting_guess(dt, guess);
    Stages z = guess;
    bool converged = false;
    used_per_stage_ = false;
    used_low_rank_ = false;
    if constexpr (kStiffRank > 0) {
      if (model.stiff_part(y0, start_factors_.u, start_factors_.v)) {
        LowRankFactorization lr;
        low_rank_factors(model, y0, guess, dt, lr);
        const NewtonOutcome outcome = solve_stages_low_rank(model, y0, lr, scale, z, faccon_);
        statistics_.newton_iterations += outcome.iterations;
        // (1: the stiff part at y0, for the error filter; the stages' are in the decomposition's.)
        statistics_.work += 1 + radau_work::low_rank_decomposition(kN) +
                            outcome.iterations * (kStages + radau_work::low_rank_solve(kN));
        if (outcome.converged) {
          used_low_rank_ = true;
          ++statistics_.low_rank_attempts;
          z_ = z;
          out.y1 = y0 + z.col(2);
          model.derivative(out.y1, out.f1);
          const bool improve = first_step_ || after_rejection;
          estimate_error(model, y0, f0, out.y1, dt, z, improve, out.error);
          statistics_.work += 1 + radau_work::low_rank_filter(kN) * (improve ? 2 : 1) + (improve ? 1 : 0);
          return;
        }
        // Should the neglected O(motion) part of J slow it down too much, the full Jacobian's.
        ++statistics_.newton_failures;
        z = guess;
      }
    }
    if (!per_stage_newton_) {
      for (;;) {
        if (!have_jacobian_) fresh_jacobian(model, y0, f0);
        if (dt != real_step_ || dt != complex_step_) {
          decompose(jacobian_, dt, lu_);
          real_step_ = complex_step_ = dt;
          ++statistics_.decompositions;
          statistics_.work += radau_work::decomposition(kN);
        }
        z = guess;
        const NewtonOutcome outcome = solve_stages(model, y0, dt, lu_, scale, z, faccon_);
        statistics_.newton_iterations += outcome.iterations;
        statistics_.work += outcome.iterations * (kStages + radau_work::newton_solve(kN));
        if (outcome.converged) {
          contraction_ = outcome.contraction;
          converged = true;
          break;
        }
        ++statistics_.newton_failures;
        if (jacobian_is_fresh_) break;
        have_jacobian_ = false;  // radau5.f: a new J at y0 before anything else
      }
      if (!converged) {  // the stiff subspace turns too much within the step (header comment)
        per_stage_newton_ = true;
        // Each failed return doubles the wait, up to kMaxPerStageRun steps: a persistently stiff
        // run pays for the simplified trial in at most 1 step in 256.
        per_stage_run_ = returned_to_simplified_ ? std::min(2 * per_stage_run_, kMaxPerStageRun) : kPerStageNewtonSteps;
        per_stage_steps_left_ = per_stage_run_;
      }
      returned_to_simplified_ = false;
    }
    if (!converged) {
      if (!have_jacobian_) fresh_jacobian(model, y0, f0);  // for the error estimate
      used_per_stage_ = true;
      ++statistics_.per_stage_attempts;
      z = guess;
      for (int pass = 0; pass < 2 && !converged; ++pass) {
        // Jacobians at the starting guess; if Newton fails from there, at its last iterate.
        Stages f;
        stage_jacobians(model, y0, z, stage_jacobians_, f);
        statistics_.jacobians += kStages;
        decompose_per_stage(stage_jacobians_, dt, per_stage_lu_);
        ++statistics_.decompositions;
        const NewtonOutcome outcome = solve_stages_per_stage(model, y0, dt, per_stage_lu_, scale, z, f, faccon_);
        statistics_.newton_iterations += outcome.iterations;
        statistics_.work += kStages * (1 + kN) + radau_work::per_stage_decomposition(kN) +
                            per_stage_newton_work(outcome.iterations);
        converged = outcome.converged;
        if (!converged) ++statistics_.newton_failures;
      }
      if (!converged) {
        // Non-finite error: the driver rejects the step and shrinks it (by its largest factor).
        out.y1 = y0;
        out.f1 = f0;
        out.error.setConstant(std::numeric_limits<double>::quiet_NaN());
        return;
      }
      if (dt != real_step_) {
        lu_.real.compute(Jacobian::Identity() * (kGamma / dt) - jacobian_);
        real_step_ = dt;
        statistics_.work += radau_work::real_decomposition(kN);
      }
    }
    z_ = z;
    out.y1 = y0 + z.col(2);
    model.derivative(out.y1, out.f1);
    const bool improve = first_step_ || after_rejection;
    estimate_error(model, y0, f0, out.y1, dt, z, improve, out.error);
    statistics_.work += 1 + radau_work::real_solve(kN) * (improve ? 2 : 1) + (improve ? 1 : 0);
  }

  /// The step just attempted is accepted: keep its stages (the next step's starting guess and
  /// the continuous output), and decide whether the next step needs a new Jacobian.
  void prepare_dense(const State& y0, const State& /*f0*/, const Attempt& a, double t0, double dt, DenseStep& d) {
    attempt_pending_ = false;
    first_step_ = false;
    jacobian_is_fresh_ = false;
    d.low_rank = used_low_rank_;
    d.per_stage_newton = used_per_stage_;
    if (used_low_rank_) {
      // The full-Jacobian machinery keeps its state for a step that needs it (a skim).
    } else if (used_per_stage_) {
      jacobian_at_start_ = jacobian_;
      // J at stage 3 is J near the next step's start, for its error estimate; after
      // kPerStageNewtonSteps steps the simplified Newton is tried again, with a fresh J.
      jacobian_ = stage_jacobians_[kStages - 1];
      real_step_ = complex_step_ = 0.0;
      if (--per_stage_steps_left_ <= 0) {
        per_stage_newton_ = false;
        returned_to_simplified_ = true;
        have_jacobian_ = false;
      }
    } else if (contraction_ > kJacobianReuseRate) {
      have_jacobian_ = false;  // radau5.f's THET
    }
    d.y0 = y0;
    d.y1 = a.y1;
    d.polynomial = z_ * kDensePolynomial;
    d.t0 = t0;
    d.dt = dt;
    previous_polynomial_ = d.polynomial;
    previous_step_ = dt;
    have_predictor_ = true;
  }

  /// Second part of the continuous output, for a step where a request falls: the step's
  /// Jacobian and the model, for dense()'s partial collocation steps. Must come before the
  /// next attempt() (which may replace the Jacobian).
  void complete_dense(const Model& model, DenseStep& d) {
    d.jacobians[0] = used_per_stage_ ? jacobian_at_start_ : jacobian_;
    if (used_per_stage_)
      for (int i = 0; i < kStages; ++i) d.jacobians[i + 1] = stage_jacobians_[i];
    d.model = &model;
    d.statistics = &statistics_;
  }

  /// y(t0 + tau), 0 < tau < dt: the Radau IIA step of length tau from y0, Newton started from
  /// the collocation cubic, solved as the step was (simplified, else per-stage Newton). The
  /// ends of the step are returned as computed.
  /// y(t0 + tau), 0 < tau <= dt: the collocation step of length 3 tau / 4 from y0, then one of
  /// tau / 4 (Newton started from the collocation cubic, solved as the step was). Why two: the
  /// slip velocity at the end of a collocation step of length s carries an O(s^3) error (stage
  /// order 3) that R reads times k, so the last, short step sets it 64x smaller, and damps the
  /// first one's by its stability function (measured: R 2e-9 -> 7e-11 m g at k = 1e5, 1e-13).
  static State dense(const DenseStep& d, double t) {
    const double tau = t - d.t0;
    if (!(tau > 0.0)) return d.y0;
    const double x = std::min(1.0, tau / d.dt);
    if (d.model == nullptr) return collocation_polynomial(d, x);
    const double x_split = x * (1.0 - kFinalSubstepFraction);
    State y_split, y;
    // The whole step from y0 converged, so shorter ones do too; should they not, the cubic is
    // the fallback (its error is O(h^4), header comment).
    if (!partial_step(d, d.y0, 0.0, x_split, y_split) || !partial_step(d, y_split, x_split, x, y))
      return collocation_polynomial(d, x);
    return y;
  }

  /// The collocation step from y_start at t0 + x_start dt to t0 + x_end dt (x in [0, 1] of the
  /// step), Newton started from the collocation cubic, solved as the step was (simplified, else
  /// per-stage Newton). False if Newton does not converge.
  static bool partial_step(const DenseStep& d, const State& y_start, double x_start, double x_end, State& y_end) {
    const double tau = (x_end - x_start) * d.dt;
    Stages guess;
    const State start = polynomial_at(d.polynomial, x_start);
    for (int i = 0; i < kStages; ++i)
      guess.col(i) = polynomial_at(d.polynomial, x_start + kC[i] * (x_end - x_start)) - start;
    const State scale = (1.0 + y_start.cwiseAbs().array()).matrix();
    double faccon = 1.0;
    Stages z = guess;
    NewtonOutcome outcome;
    long decompositions = 0, work = 0;
    if constexpr (kStiffRank > 0) {
      if (d.low_rank) {
        LowRankFactorization lr;
        low_rank_factors(*d.model, y_start, guess, tau, lr);
        ++decompositions;
        outcome = solve_stages_low_rank(*d.model, y_start, lr, scale, z, faccon);
        work += radau_work::low_rank_decomposition(kN) +
                outcome.iterations * (kStages + radau_work::low_rank_solve(kN));
      }
    }
    if (!d.per_stage_newton && !d.low_rank) {
      Factorization lu;
      decompose(d.jacobians[0], tau, lu);
      ++decompositions;
      outcome = solve_stages(*d.model, y_start, tau, lu, scale, z, faccon);
      work += radau_work::decomposition(kN) + outcome.iterations * (kStages + radau_work::newton_solve(kN));
    }
    int iterations = outcome.iterations;
    if (!outcome.converged) {
      // (After a low-rank Newton that failed: the per-stage one with Jacobians at the guess.)
      Jacobian j[kStages];
      Stages f;
      z = guess;
      if (d.per_stage_newton) {
        // J at the partial step's stages from the step's four, by cubic interpolation in time:
        // its error, O((omega h)^4), is far below what Newton's contraction needs.
        for (int i = 0; i < kStages; ++i)
          interpolate_jacobian(d.jacobians, x_start + kC[i] * (x_end - x_start), j[i]);
        State fi;
        for (int i = 0; i < kStages; ++i) {
          d.model->derivative(State(y_start + z.col(i)), fi);
          f.col(i) = fi;
        }
        work += kStages;
      } else {
        stage_jacobians(*d.model, y_start, z, j, f);
        work += kStages * (1 + kN);
      }
      PerStageFactorization lu;
      decompose_per_stage(j, tau, lu);
      ++decompositions;
      faccon = 1.0;
      outcome = solve_stages_per_stage(*d.model, y_start, tau, lu, scale, z, f, faccon);
      iterations += outcome.iterations;
      work += radau_work::per_stage_decomposition(kN) + per_stage_newton_work(outcome.iterations);
    }
    if (d.statistics != nullptr) {
      ++d.statistics->dense_solves;
      d.statistics->work += work;
      d.statistics->decompositions += decompositions;
      d.statistics->newton_iterations += iterations;
      if (!outcome.converged) ++d.statistics->newton_failures;
    }
    y_end = y_start + z.col(2);
    return outcome.converged;
  }

  /// radau5.f's CONTR5: the collocation cubic through y0 and the three stages, x in [0, 1].
  static State collocation_polynomial(const DenseStep& d, double x) { return d.y0 + polynomial_at(d.polynomial, x); }

  // ---- The low-rank Newton (models with a stiff part, e.g. the viscous top while sliding) ----
  // (Its linear algebra is public for bench/budget_time, which measures its cost in evaluations.)
  // J(y) = U(y) V(y) + O(fastest motion), with U V of rank r (the friction's rate, up to 2e8 1/s,
  // in r = 2 directions that turn with the body). Newton's matrix with J_i = U_i V_i at each
  // stage, (A^-1/h x I) - diag(U_i V_i) = D - U V (U, V block-diagonal), is inverted by
  // Woodbury's identity: (D - U V)^-1 = D^-1 + D^-1 U (I - V D^-1 U)^-1 V D^-1, with
  // D^-1 = h A x I and a 3r x 3r matrix S = I - V D^-1 U, S_ij = delta_ij I - h a_ij V_i U_j.
  // It follows the stiff subspace from stage to stage (what the per-stage Newton does with three
  // n x n Jacobians by differences and their LUs) at the cost of three evaluations of the
  // factors and a 6 x 6 LU; the neglected part of J makes the iteration contract at about
  // h |A| (fastest motion), 0.01-0.1 at the steps the tolerances give.
  static constexpr int kRank = kStiffRank > 0 ? kStiffRank : 1;  // (sizes only)
  using StiffColumns = Eigen::Matrix<double, kN, kRank>;
  using StiffRows = Eigen::Matrix<double, kRank, kN>;
  using Coupling = Eigen::Matrix<double, kStages * kRank, kStages * kRank>;
  using CouplingVector = Eigen::Matrix<double, kStages * kRank, 1>;
  struct StiffFactors {
    StiffColumns u = StiffColumns::Zero();
    StiffRows v = StiffRows::Zero();
  };
  struct LowRankFactorization {
    StiffFactors stage[kStages];
    SmallLu<kStages * kRank> s;
    double h = 0.0;
  };

  /// The stages' factors at y0 + Z_i (Z: the starting guess) and S's LU for the step h.
  static void low_rank_factors(const Model& model, const State& y0, const Stages& z, double h,
                               LowRankFactorization& lr) {
    for (int i = 0; i < kStages; ++i) model.stiff_part(State(y0 + z.col(i)), lr.stage[i].u, lr.stage[i].v);
    Coupling s;
    for (int i = 0; i < kStages; ++i)
      for (int j = 0; j < kStages; ++j)
        s.template block<kRank, kRank>(i * kRank, j * kRank) = (-h * kA[i][j]) * (lr.stage[i].v * lr.stage[j].u);
    s += Coupling::Identity();
    lr.s.compute(s);
    lr.h = h;
  }

  /// Solves (D - U V) dZ = r (block comment above).
  static Stages solve_low_rank(const LowRankFactorization& lr, const Stages& r) {
    const double h = lr.h;
    Stages x;
    for (int i = 0; i < kStages; ++i) x.col(i) = h * (kA[i][0] * r.col(0) + kA[i][1] * r.col(1) + kA[i][2] * r.col(2));
    CouplingVector projected;
    for (int i = 0; i < kStages; ++i) projected.template segment<kRank>(i * kRank) = lr.stage[i].v * x.col(i);
    const CouplingVector w = lr.s.solve(projected);
    Stages uw;
    for (int j = 0; j < kStages; ++j) uw.col(j) = lr.stage[j].u * w.template segment<kRank>(j * kRank);
    for (int i = 0; i < kStages; ++i)
      x.col(i) += h * (kA[i][0] * uw.col(0) + kA[i][1] * uw.col(1) + kA[i][2] * uw.col(2));
    return x;
  }

  /// (c I - U V)^-1 b = (b + U (c I - V U)^-1 V b) / c: the error estimate's filter.
  static State filter_low_rank(const StiffFactors& f, double c, const State& b) {
    const Eigen::Matrix<double, kRank, kRank> small = c * Eigen::Matrix<double, kRank, kRank>::Identity() - f.v * f.u;
    return (b + f.u * small.partialPivLu().solve(f.v * b)) / c;
  }

 private:
  using RealLU = Eigen::PartialPivLU<Jacobian>;
  using ComplexMatrix = Eigen::Matrix<std::complex<double>, kN, kN>;
  using ComplexState = Eigen::Matrix<std::complex<double>, kN, 1>;
  using ComplexLU = Eigen::PartialPivLU<ComplexMatrix>;
  struct Factorization {
    RealLU real;
    ComplexLU complex;
  };
  /// Newton's matrix with a Jacobian per stage, written as (A^-1/h x I) - diag(J_1, J_2, J_3):
  /// its off-diagonal blocks are multiples of I, so block elimination costs three n x n
  /// factorizations and two products instead of one 3n x 3n LU (2.5x fewer operations). The
  /// pivots' scalar parts are A^-1's leading Schur complements, 3.22, 2.07 and 9.0, all
  /// positive, so the elimination needs no pivoting between blocks.
  struct PerStageFactorization {
    double beta[kStages][kStages];  // A^-1 / h
    Jacobian first_inverse;         // (beta_11 I - J_1)^-1
    Jacobian second_inverse;        // S_22^-1 after eliminating stage 1
    Jacobian s23, s32;              // couplings of stages 2 and 3 after eliminating stage 1
    RealLU last;                    // S_33 - S_32 S_22^-1 S_23
  };
  struct NewtonOutcome {
    bool converged = false;
    int iterations = 0;
    double contraction = 0.0;
  };

  static constexpr int kMaxNewtonIterations = 7;      // radau5.f's NIT
  static constexpr double kJacobianReuseRate = 1e-3;  // radau5.f's THET
  static constexpr int kPerStageNewtonSteps = 16;     // steps before the simplified Newton is tried again
  static constexpr int kMaxPerStageRun = 256;
  static constexpr double kFinalSubstepFraction = 0.25;  // of a request's partial steps (dense())
  // Newton stops when the estimated remaining error theta/(1-theta) |dZ| (RMS over 1 + |y0|)
  // is below kNewtonTolerance, or when the corrections stop contracting below kRoundOffFloor:
  // the stage values are then exact to round-off, which R needs at large k (header comment, 1.).
  static constexpr double kNewtonTolerance = 1e-15;
  static constexpr double kRoundOffFloor = 1e-14;
  // The low-rank Newton contracts at theta ~ h |J_motion| ~ 0.05 (the per-stage one at ~1e-3)
  // and what it leaves has the same sign step after step (the neglected part of J is smooth), so
  // it accumulates over the ~1e5 steps per second of a fast spin. Stopped at kNewtonTolerance,
  // the toy top at k = 5e3 ended 1.4e-10 rad and 1.1e-11 m g h (energy balance) off after 10 s,
  // against 1.4e-11 and 4e-13 with the per-stage Newton; at a hundredth of it, a 2000 rad/s top
  // at k = 5e3 was still 1.5e-11 rad off dop853 at 1e-14 after 2 s (per-stage: 1.7e-12), and at
  // a thousandth 1.7e-12: at 1e-14, 3.3-4 iterations per attempt instead of 3.
  static constexpr double kLowRankNewtonTightening = 1e-3;

  void fresh_jacobian(const Model& model, const State& y0, const State& f0) {
    forward_difference_jacobian(model, y0, f0, jacobian_);
    ++statistics_.jacobians;
    statistics_.work += kN;
    have_jacobian_ = jacobian_is_fresh_ = true;
    real_step_ = complex_step_ = 0.0;
  }

  /// The work of a per-stage Newton solve of `iterations` iterations: f at the stages in each but
  /// the first (which starts from f at the initial Z), and the solves.
  static constexpr long per_stage_newton_work(int iterations) {
    return iterations * radau_work::per_stage_solve(kN) + (iterations > 0 ? iterations - 1 : 0) * kStages;
  }

  static void decompose(const Jacobian& j, double h, Factorization& lu) {
    lu.real.compute(Jacobian::Identity() * (kGamma / h) - j);
    const std::complex<double> shift(kAlpha / h, -kBeta / h);
    lu.complex.compute(ComplexMatrix::Identity() * shift - j.template cast<std::complex<double>>());
  }

  static State polynomial_at(const Stages& q, double x) { return x * (q.col(0) + x * (q.col(1) + x * q.col(2))); }

  /// radau5.f: zero for the first step; else the previous step's collocation cubic, extrapolated.
  void starting_guess(double dt, Stages& z) const {
    if (!have_predictor_) {
      z.setZero();
      return;
    }
    const State end = polynomial_at(previous_polynomial_, 1.0);
    for (int i = 0; i < kStages; ++i)
      z.col(i) = polynomial_at(previous_polynomial_, 1.0 + kC[i] * dt / previous_step_) - end;
  }

  /// Newton's stopping rule, common to both iterations (radau5.f's, with the round-off ends
  /// above): updates theta and faccon from the correction norms; returns +1 converged, -1 failed,
  /// 0 go on.
  static int newton_verdict(int iteration, double norm, double& previous_norm, double& previous_rate, double& theta,
                            double& faccon, double tolerance = kNewtonTolerance) {
    if (iteration > 1) {
      const double rate = norm / previous_norm;
      theta = iteration == 2 ? rate : std::sqrt(rate * previous_rate);
      previous_rate = rate;
      if (theta < 0.99) {
        faccon = theta / (1.0 - theta);
      } else if (norm > kRoundOffFloor) {
        return -1;  // diverging
      }
    }
    const bool at_round_off = norm <= kRoundOffFloor && (theta >= 0.5 || iteration == kMaxNewtonIterations);
    if (faccon * norm <= tolerance || norm == 0.0 || at_round_off) return +1;
    previous_norm = std::max(norm, std::numeric_limits<double>::min());
    return iteration == kMaxNewtonIterations ? -1 : 0;
  }

  /// Simplified Newton on the stage equations in the transformed variables W = T^-1 Z (sec.
  /// IV.8, eq. 8.16-8.19): one real and one complex n x n solve per iteration, all stages with
  /// J(y0). faccon carries theta/(1-theta) from the last solve (radau5.f).
  static NewtonOutcome solve_stages(const Model& model, const State& y0, double h, const Factorization& lu,
                                    const State& scale, Stages& z, double& faccon) {
    NewtonOutcome outcome;
    Stages w = z * kTInverse.transpose(), f;
    faccon = std::pow(std::max(faccon, std::numeric_limits<double>::epsilon()), 0.8);
    double previous_norm = 0.0, previous_rate = 0.0, theta = kJacobianReuseRate;
    State fi;
    const std::complex<double> shift(kAlpha / h, -kBeta / h), i_unit(0.0, 1.0);
    for (int iteration = 1; iteration <= kMaxNewtonIterations; ++iteration) {
      outcome.iterations = iteration;
      for (int i = 0; i < kStages; ++i) {
        model.derivative(State(y0 + z.col(i)), fi);
        f.col(i) = fi;
      }
      if (!f.allFinite()) return outcome;
      const Stages tf = f * kTInverse.transpose();  // columns: (T^-1 F)_k
      const State real_rhs = tf.col(0) - (kGamma / h) * w.col(0);
      const ComplexState complex_rhs = tf.col(1).template cast<std::complex<double>>() + i_unit * tf.col(2) -
                                       shift * (w.col(1).template cast<std::complex<double>>() + i_unit * w.col(2));
      Stages dw;
      dw.col(0) = lu.real.solve(real_rhs);
      const ComplexState dc = lu.complex.solve(complex_rhs);
      dw.col(1) = dc.real();
      dw.col(2) = dc.imag();
      if (!dw.allFinite()) return outcome;
      const double norm = rms(dw, scale);
      w += dw;
      z = w * kT.transpose();
      const int verdict = newton_verdict(iteration, norm, previous_norm, previous_rate, theta, faccon);
      if (verdict != 0) {
        outcome.converged = verdict > 0;
        outcome.contraction = theta;
        return outcome;
      }
    }
    return outcome;
  }

  /// Jacobians at the three stages y0 + Z_i (n forward differences each), and f there.
  static void stage_jacobians(const Model& model, const State& y0, const Stages& z, Jacobian (&j)[kStages], Stages& f) {
    State fi;
    for (int i = 0; i < kStages; ++i) {
      const State yi = y0 + z.col(i);
      model.derivative(yi, fi);
      f.col(i) = fi;
      forward_difference_jacobian(model, yi, fi, j[i]);
    }
  }

  /// Lagrange interpolation through J at c = 0, c1, c2, 1.
  static void interpolate_jacobian(const Jacobian (&j)[kStages + 1], double c, Jacobian& out) {
    const double nodes[kStages + 1] = {0.0, kC[0], kC[1], kC[2]};
    out.setZero();
    for (int k = 0; k <= kStages; ++k) {
      double weight = 1.0;
      for (int m = 0; m <= kStages; ++m)
        if (m != k) weight *= (c - nodes[m]) / (nodes[k] - nodes[m]);
      out += weight * j[k];
    }
  }

  static void decompose_per_stage(const Jacobian (&j)[kStages], double h, PerStageFactorization& lu) {
    auto& b = lu.beta;
    for (int r = 0; r < kStages; ++r)
      for (int c = 0; c < kStages; ++c) b[r][c] = kAInverse[r][c] / h;
    const Jacobian identity = Jacobian::Identity();
    lu.first_inverse = RealLU(identity * b[0][0] - j[0]).inverse();
    const Jacobian& p = lu.first_inverse;
    lu.s23 = identity * b[1][2] - (b[1][0] * b[0][2]) * p;
    lu.s32 = identity * b[2][1] - (b[2][0] * b[0][1]) * p;
    lu.second_inverse = RealLU(identity * b[1][1] - j[1] - (b[1][0] * b[0][1]) * p).inverse();
    const Jacobian s33 = identity * b[2][2] - j[2] - (b[2][0] * b[0][2]) * p;
    const Jacobian q_s23 = lu.second_inverse.lazyProduct(lu.s23);
    lu.last.compute(s33 - lu.s32.lazyProduct(q_s23));
  }

  /// Solves ((A^-1/h x I) - diag(J_i)) dZ = r by the block elimination of decompose_per_stage().
  static Stages solve_per_stage(const PerStageFactorization& lu, const Stages& r) {
    const auto& b = lu.beta;
    const State p_r1 = lu.first_inverse * r.col(0);
    const State r2 = r.col(1) - b[1][0] * p_r1;
    const State q_r2 = lu.second_inverse * r2;
    const State r3 = r.col(2) - b[2][0] * p_r1 - lu.s32 * q_r2;
    Stages x;
    x.col(2) = lu.last.solve(r3);
    x.col(1) = q_r2 - lu.second_inverse * (lu.s23 * x.col(2));
    x.col(0) = lu.first_inverse * (r.col(0) - b[0][1] * x.col(1) - b[0][2] * x.col(2));
    return x;
  }

  /// Newton on F(Z) - (A^-1/h x I) Z = 0 (the stage equations times A^-1/h) with a Newton
  /// matrix (A^-1/h x I) - diag(J_i) whose J_i may differ from stage to stage: it follows the
  /// stiff subspace as it turns from stage to stage, where one J for all stages does not. `solve`
  /// applies the matrix's inverse: solve_per_stage() (J_i by differences) or solve_low_rank()
  /// (J_i = U_i V_i, the model's stiff part). If f_known, f holds F at the initial Z.
  template <class Solve>
  static NewtonOutcome solve_stages_stagewise(const Model& model, const State& y0, double h, const Solve& solve,
                                              const State& scale, Stages& z, Stages& f, bool f_known,
                                              double& faccon, double tolerance = kNewtonTolerance) {
    NewtonOutcome outcome;
    faccon = std::pow(std::max(faccon, std::numeric_limits<double>::epsilon()), 0.8);
    double previous_norm = 0.0, previous_rate = 0.0, theta = kJacobianReuseRate;
    State fi;
    for (int iteration = 1; iteration <= kMaxNewtonIterations; ++iteration) {
      outcome.iterations = iteration;
      if (iteration > 1 || !f_known) {
        for (int i = 0; i < kStages; ++i) {
          model.derivative(State(y0 + z.col(i)), fi);
          f.col(i) = fi;
        }
      }
      if (!f.allFinite()) return outcome;
      Stages residual = f;
      for (int i = 0; i < kStages; ++i)
        for (int k = 0; k < kStages; ++k) residual.col(i) -= (kAInverse[i][k] / h) * z.col(k);
      const Stages dz = solve(residual);
      if (!dz.allFinite()) return outcome;
      const double norm = rms(dz, scale);
      z += dz;
      const int verdict = newton_verdict(iteration, norm, previous_norm, previous_rate, theta, faccon, tolerance);
      if (verdict != 0) {
        outcome.converged = verdict > 0;
        outcome.contraction = theta;
        return outcome;
      }
    }
    return outcome;
  }

  static NewtonOutcome solve_stages_per_stage(const Model& model, const State& y0, double h,
                                              const PerStageFactorization& lu, const State& scale, Stages& z,
                                              Stages& f, double& faccon) {
    return solve_stages_stagewise(
        model, y0, h, [&lu](const Stages& r) { return solve_per_stage(lu, r); }, scale, z, f, true, faccon);
  }

  static NewtonOutcome solve_stages_low_rank(const Model& model, const State& y0, const LowRankFactorization& lr,
                                             const State& scale, Stages& z, double& faccon) {
    Stages f;
    return solve_stages_stagewise(
        model, y0, lr.h, [&lr](const Stages& r) { return solve_low_rank(lr, r); }, scale, z, f, false, faccon,
        kNewtonTolerance * kLowRankNewtonTightening);
  }

  template <class Derived>
  static double rms(const Eigen::MatrixBase<Derived>& dz, const State& scale) {
    double sum = 0.0;
    for (int i = 0; i < kStages; ++i) sum += dz.col(i).cwiseQuotient(scale).squaredNorm();
    return std::sqrt(sum / (kStages * kN));
  }

  /// radau5.f's ESTRAD: err = (gamma/h I - J)^-1 (f(y0) + (e_1 Z_1 + e_2 Z_2 + e_3 Z_3)/h),
  /// the difference to the embedded order-3 solution filtered by (I - h/gamma J)^-1 so that
  /// stiff components do not count (sec. IV.8, eq. 8.20). At the first step and after a
  /// rejection the filter is applied once more, to f(y0 + err) (eq. 8.21), and the smaller of the
  /// two is used: radau5.f takes the second only when the first fails, which is the same test.
  /// Radau5ToleranceMap maps the result to the user's tolerance.
  void estimate_error(const Model& model, const State& y0, const State& f0, const State& y1, double dt,
                      const Stages& z, bool improve, State& error) const {
    const State combination = (z * kErrorWeights) / dt;
    // (gamma/h I - J)^-1: J's stiff part alone after a low-rank Newton, else the real LU.
    const auto filter = [&](const State& b) -> State {
      if constexpr (kStiffRank > 0) {
        if (used_low_rank_) return filter_low_rank(start_factors_, kGamma / dt, b);
      }
      return lu_.real.solve(b);
    };
    State err = filter(f0 + combination);
    if (improve) {
      const State scale = (1.0 + y0.cwiseAbs().cwiseMax(y1.cwiseAbs()).array()).matrix();
      const double n = static_cast<double>(kN);
      const double norm = std::sqrt(err.cwiseQuotient(scale).squaredNorm() / n);
      State f_err;
      model.derivative(State(y0 + err), f_err);
      const State second = filter(f_err + combination);
      const double second_norm = std::sqrt(second.cwiseQuotient(scale).squaredNorm() / n);
      if (second_norm < norm || !std::isfinite(norm)) err = second;
    }
    error = err;
  }

  // Radau IIA, s = 3: nodes, error weights and the eigen-decomposition A^-1 = T diag(gamma,
  // alpha -+ i beta) T^-1 (radau5.f, also SciPy's radau.py). gamma = 3 + 3^(2/3) - 3^(1/3),
  // alpha = 3 + (3^(1/3) - 3^(2/3))/2, beta = (3^(5/6) + 3^(7/6))/2.
  static constexpr double kSqrt6 = 2.449489742783178098197284;
  static constexpr double kA[kStages][kStages] = {
      {(88.0 - 7.0 * kSqrt6) / 360.0, (296.0 - 169.0 * kSqrt6) / 1800.0, (-2.0 + 3.0 * kSqrt6) / 225.0},
      {(296.0 + 169.0 * kSqrt6) / 1800.0, (88.0 + 7.0 * kSqrt6) / 360.0, (-2.0 - 3.0 * kSqrt6) / 225.0},
      {(16.0 - kSqrt6) / 36.0, (16.0 + kSqrt6) / 36.0, 1.0 / 9.0},
  };
  // A^-1 (computed from kA, rounded to double).
  static constexpr double kAInverse[kStages][kStages] = {
      {3.224744871391589, 1.167840084690405, -0.2531972647421809},
      {-3.567840084690405, 0.7752551286084112, 1.053197264742181},
      {5.531972647421809, -7.531972647421810, 5.0},
  };
  static constexpr double kC[kStages] = {(4.0 - kSqrt6) / 10.0, (4.0 + kSqrt6) / 10.0, 1.0};
  static constexpr double kGamma = 3.637834252744495732208418513577775;
  static constexpr double kAlpha = 2.681082873627752133895790743211112;
  static constexpr double kBeta = 3.050430199247410569426377624787569;
  static inline const Eigen::Matrix3d kT = (Eigen::Matrix3d() << 0.09443876248897524, -0.14125529502095421,
                                            0.03002919410514742, 0.25021312296533332, 0.20412935229379994,
                                            -0.38294211275726192, 1.0, 1.0, 0.0)
                                               .finished();
  static inline const Eigen::Matrix3d kTInverse = (Eigen::Matrix3d() << 4.17871859155190428, 0.32768282076106237,
                                                   0.52337644549944951, -4.17871859155190428, -0.32768282076106237,
                                                   0.47662355450055044, 0.50287263494578682, -2.57192694985560522,
                                                   0.59603920482822492)
                                                      .finished();
  // e_i of the estimate: (-13 - 7 sqrt 6)/3, (-13 + 7 sqrt 6)/3, -1/3.
  static inline const Eigen::Vector3d kErrorWeights =
      Eigen::Vector3d((-13.0 - 7.0 * kSqrt6) / 3.0, (-13.0 + 7.0 * kSqrt6) / 3.0, -1.0 / 3.0);
  // The cubic through (0, 0), (c_i, Z_i): coefficients of x, x^2, x^3 = Z P (SciPy's P).
  static inline const Eigen::Matrix3d kDensePolynomial =
      (Eigen::Matrix3d() << 13.0 / 3.0 + 7.0 * kSqrt6 / 3.0, -23.0 / 3.0 - 22.0 * kSqrt6 / 3.0, 10.0 / 3.0 + 5.0 * kSqrt6,
       13.0 / 3.0 - 7.0 * kSqrt6 / 3.0, -23.0 / 3.0 + 22.0 * kSqrt6 / 3.0, 10.0 / 3.0 - 5.0 * kSqrt6, 1.0 / 3.0,
       -8.0 / 3.0, 10.0 / 3.0)
          .finished();

  Jacobian jacobian_ = Jacobian::Zero();     // J(y0) of the simplified Newton and the error estimate
  Jacobian stage_jacobians_[kStages];          // of the per-stage Newton
  Jacobian jacobian_at_start_ = Jacobian::Zero();  // J near y0 of the last per-stage step
  Factorization lu_;
  PerStageFactorization per_stage_lu_;
  StiffFactors start_factors_;  // U, V at the attempt's y0 (the low-rank error filter)
  bool used_low_rank_ = false;
  Stages z_ = Stages::Zero(), previous_polynomial_ = Stages::Zero();
  double previous_step_ = 0.0, real_step_ = 0.0, complex_step_ = 0.0;  // h of the LU decompositions
  double contraction_ = kJacobianReuseRate, faccon_ = 1.0;
  bool have_jacobian_ = false, jacobian_is_fresh_ = false, have_predictor_ = false, attempt_pending_ = false;
  bool first_step_ = true, per_stage_newton_ = false, used_per_stage_ = false;
  int per_stage_steps_left_ = 0, per_stage_run_ = kPerStageNewtonSteps;
  bool returned_to_simplified_ = false;
  RadauStatistics statistics_;
  long earlier_work_ = 0;  // work of the runs before the last restart()
};


}  // namespace spinning_top
