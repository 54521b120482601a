// What one step of the work budget costs in CPU time, method by method (issue 19, item 4): the
// budget (include/spinning_top/work_budget.hpp) counts work, not accepted steps, so that one
// allowance bounds the time of every method within a few times. Each case runs as a front end
// runs it, a request every 1 ms (dense output and answers included) within a run's allowance
// (WorkBudget::steps_left(N, work())), until the allowance runs out or 2 s are simulated; the CPU
// time of the thread is the best of 3 rounds. Prints, and writes bench/results/budget_time.md:
// CPU per accepted step (the budget's unit before issue 19), CPU per step of the budget, their
// spreads over the methods, and the CPU time that the default allowance (1e8) bounds.
// Also measures the unit costs behind the work counts: the model's f, and RADAU5's linear
// algebra (real and complex LU and solves of the viscous top's n = 11), in evaluations of f.
//
//   budget_time [OUTPUT.md]
#include <time.h>

#include <Eigen/Core>
#include <Eigen/LU>
#include <algorithm>
#include <complex>
#include <cstdio>
#include <string>
#include <vector>

#include "spinning_top/integrators/exact_stepper.hpp"
#include "spinning_top/integrators/radau.hpp"
#include "spinning_top/scenes/fixed_tip.hpp"
#include "spinning_top/scenes/frictionless.hpp"
#include "spinning_top/scenes/viscous.hpp"
#include "spinning_top/simulator.hpp"

using namespace spinning_top;

namespace {

double thread_cpu_seconds() {
  timespec ts;
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
  return static_cast<double>(ts.tv_sec) + 1e-9 * static_cast<double>(ts.tv_nsec);
}

struct Case {
  std::string name;
  SceneConfig config;
  double allowance;  // steps of the budget for the run
};

SceneConfig toy(SceneType scene, IntegratorType type) {
  SceneConfig c;
  c.scene = scene;
  c.initial.tilt = 0.3;
  c.initial.spin = 150.0;
  c.integrator.type = type;
  c.integrator.tolerance = 1e-12;
  c.integrator.step = 1e-3;
  if (scene == SceneType::kViscous) c.top.friction = 0.02;
  return c;
}

SceneConfig stiff(double friction, IntegratorType type, double tolerance) {
  SceneConfig c = toy(SceneType::kViscous, type);
  c.top.friction = friction;
  c.initial.precession_rate = 5.0;
  c.initial.nutation_rate = 2.0;
  c.initial.velocity_x = 0.05;
  c.integrator.tolerance = tolerance;
  return c;
}

struct Measured {
  long steps = 0, work = 0;
  double simulated = 0.0, cpu = 0.0;
};

Measured run(const Case& c) {
  Measured best;
  best.cpu = 1e300;
  for (int round = 0; round < 3; ++round) {
    const double start = thread_cpu_seconds();
    const auto simulator = make_simulator(c.config);
    for (int i = 1; i <= 2000; ++i) {
      const double t = i * 1e-3;
      const Event event = simulator->advance_to(t, WorkBudget::steps_left(c.allowance, simulator->work()));
      simulator->take_transitions();
      if (event != Event::kNone || simulator->time() < t) break;
    }
    const double cpu = thread_cpu_seconds() - start;
    if (cpu < best.cpu) best = {simulator->steps(), simulator->work(), simulator->time(), cpu};
  }
  return best;
}

volatile double sink;
template <class Model>
__attribute__((noinline)) void derive(const Model& m, const typename Model::State& y, typename Model::State& f) {
  m.derivative(y, f);
}
/// Best of 5 rounds of n calls, microseconds per call.
template <class F>
double per_call(F&& f, int n) {
  double best = 1e300;
  for (int round = 0; round < 5; ++round) {
    const double start = thread_cpu_seconds();
    for (int i = 0; i < n; ++i) f(i);
    best = std::min(best, (thread_cpu_seconds() - start) / n);
  }
  return 1e6 * best;
}

/// f's cost, and RADAU5's linear algebra in evaluations of f (radau.hpp, radau_work).
template <class Model>
std::string unit_costs(const Model& model, const char* name) {
  constexpr int n = Model::kStateSize;
  using M = Eigen::Matrix<double, n, n>;
  using CM = Eigen::Matrix<std::complex<double>, n, n>;
  using V = Eigen::Matrix<double, n, 1>;
  using CV = Eigen::Matrix<std::complex<double>, n, 1>;
  typename Model::State y = model.initial_state(), f;
  const typename Model::State y0 = y;
  const double eval = per_call(
      [&](int i) {
        if ((i & 1023) == 0) y = y0;
        derive(model, y, f);
        y += 1e-9 * f;
      },
      200000);
  sink = y[0];
  M j = M::Random();
  const double real_lu = per_call(
      [&](int i) {
        j(0, 0) += 1e-9 * i;
        const Eigen::PartialPivLU<M> lu(M::Identity() * 3.0 - j);
        sink = lu.matrixLU()(0, 0);
      },
      50000);
  const double complex_lu = per_call(
      [&](int i) {
        j(0, 0) += 1e-9 * i;
        const CM c = CM::Identity() * std::complex<double>(2.0, -3.0) - j.template cast<std::complex<double>>();
        const Eigen::PartialPivLU<CM> lu(c);
        sink = lu.matrixLU()(0, 0).real();
      },
      50000);
  const Eigen::PartialPivLU<M> rl(M::Identity() * 3.0 - j);
  const Eigen::PartialPivLU<CM> cl(CM::Identity() * std::complex<double>(2.0, -3.0) -
                                   j.template cast<std::complex<double>>());
  V r = V::Random();
  CV cr = CV::Random();
  const double real_solve = per_call(
      [&](int i) {
        r[0] += 1e-9 * i;
        const V x = rl.solve(r);
        sink = x[0];
      },
      200000);
  const double complex_solve = per_call(
      [&](int i) {
        cr[0] += 1e-9 * i;
        const CV x = cl.solve(cr);
        sink = x[0].real();
      },
      200000);
  const double inverse = per_call(
      [&](int i) {
        j(0, 0) += 1e-9 * i;
        const M p = Eigen::PartialPivLU<M>(M::Identity() * 3.0 - j).inverse();
        sink = p(0, 0);
      },
      50000);
  M a = M::Random();
  const M b = M::Random();
  const double product = per_call(
      [&](int i) {
        a(0, 0) += 1e-9 * i;
        const M p = a.lazyProduct(b);
        sink = p(0, 0);
      },
      50000);
  char line[512];
  std::snprintf(line, sizeof line,
                "| %s (n = %d) | %.4f | %.1f | %.1f | %.1f | %.1f | %.1f | %.1f |\n", name, n, eval, real_lu / eval,
                complex_lu / eval, real_solve / eval, complex_solve / eval, inverse / eval, product / eval);
  return line;
}

/// RADAU5's low-rank Newton (models with a stiff part): the factors of three stages and the
/// 3r x 3r LU, one Woodbury solve of the stage system, one filter of the error estimate; in
/// evaluations of f (radau.hpp, radau_work::low_rank_*).
template <class Model>
std::string low_rank_costs(const Model& model, const char* name) {
  using Radau = RadauIIA5<Model>;
  typename Model::State y = model.initial_state(), f;
  const typename Model::State y0 = y;
  const double eval = per_call(
      [&](int i) {
        if ((i & 1023) == 0) y = y0;
        derive(model, y, f);
        y += 1e-9 * f;
      },
      200000);
  typename Radau::StiffFactors factors;
  const double stiff_part = per_call(
      [&](int i) {
        y = y0;
        y[0] += 1e-12 * i;
        model.stiff_part(y, factors.u, factors.v);
        sink = factors.v(0, 0);
      },
      200000);
  typename Radau::Stages z = 1e-6 * Radau::Stages::Random();
  typename Radau::LowRankFactorization lr;
  const double decomposition = per_call(
      [&](int i) {
        z(0, 0) += 1e-12 * i;
        Radau::low_rank_factors(model, y0, z, 1e-4, lr);
        sink = lr.s.matrixLU()(0, 0);
      },
      50000);
  typename Radau::Stages r = Radau::Stages::Random();
  const double solve = per_call(
      [&](int i) {
        r(0, 0) += 1e-9 * i;
        const typename Radau::Stages x = Radau::solve_low_rank(lr, r);
        sink = x(0, 0);
      },
      200000);
  typename Model::State b = Model::State::Random();
  const double filter = per_call(
      [&](int i) {
        b[0] += 1e-9 * i;
        const typename Model::State x = Radau::filter_low_rank(lr.stage[0], 3.6e4, b);
        sink = x[0];
      },
      200000);
  char line[256];
  std::snprintf(line, sizeof line, "| %s (n = %d, rank %d) | %.4f | %.1f | %.1f | %.1f | %.1f |\n", name,
                Model::kStateSize, Model::kStiffRank, eval, stiff_part / eval, decomposition / eval, solve / eval,
                filter / eval);
  return line;
}

/// exact's construction (ExactStepper::restart, what a hybrid's landing costs): CPU against the
/// work it charges (ExactStepper: 300 units and 16 per Fourier term).
template <class Model>
std::string exact_build(const char* name, double tilt, double spin) {
  TopParameters top;
  InitialConditions initial;
  initial.tilt = tilt;
  initial.spin = spin;
  const Model model(top, initial);
  double best = 1e300;
  long work = 0;
  int terms = 0;
  for (int round = 0; round < 5; ++round) {
    ExactStepper<Model> stepper;
    const double start = thread_cpu_seconds();
    stepper.restart(model, 0.0, model.initial_state());
    best = std::min(best, thread_cpu_seconds() - start);
    work = stepper.work();
    terms = stepper.solution().terms();
  }
  char line[256];
  std::snprintf(line, sizeof line, "| %s, tilt %g, spin %g | %d | %.1f | %ld | %.4f |\n", name, tilt, spin, terms, 1e6 * best,
                work, 1e6 * best / static_cast<double>(work));
  return line;
}

}  // namespace

int main(int argc, char** argv) {
  const std::string out_path = argc > 1 ? argv[1] : "bench/results/budget_time.md";
  std::vector<Case> cases;
  auto add = [&](const std::string& name, const SceneConfig& config, double allowance) {
    cases.push_back({name, config, allowance});
  };
  add("fixed tip, rk4 1 ms", toy(SceneType::kFixedTip, IntegratorType::kRk4), 1e8);
  add("fixed tip, dopri5 1e-12", toy(SceneType::kFixedTip, IntegratorType::kDopri5), 1e8);
  add("fixed tip, dop853 1e-12", toy(SceneType::kFixedTip, IntegratorType::kDop853), 1e8);
  add("fixed tip, splitting4 1 ms", toy(SceneType::kFixedTip, IntegratorType::kSplitting4), 1e8);
  add("fixed tip, splitting8 1 ms", toy(SceneType::kFixedTip, IntegratorType::kSplitting8), 1e8);
  add("fixed tip, gauss6 1 ms", toy(SceneType::kFixedTip, IntegratorType::kGauss6), 1e8);
  add("fixed tip, radau5 1e-12", toy(SceneType::kFixedTip, IntegratorType::kRadau5), 1e8);
  add("fixed tip, exact", toy(SceneType::kFixedTip, IntegratorType::kExact), 1e8);
  add("frictionless, gauss6 1 ms", toy(SceneType::kFrictionless, IntegratorType::kGauss6), 1e8);
  add("frictionless, auto (exact)", toy(SceneType::kFrictionless, IntegratorType::kAuto), 1e8);
  {
    SceneConfig hops = toy(SceneType::kFrictionless, IntegratorType::kAuto);
    hops.initial.tilt = 0.8;
    hops.initial.precession_rate = 60.0;
    add("frictionless hops, auto (exact + flights)", hops, 1e8);
    hops.top.restitution = 0.5;
    hops.top.restitution_speed = 0.0;
    add("frictionless bounces (e = 0.5), auto", hops, 1e8);
    hops.top.restitution = 0.9;
    hops.integrator.type = IntegratorType::kDop853;
    add("frictionless bounces (e = 0.9), dop853 (Zeno)", hops, 1e7);
  }
  add("viscous k = 0.02, dop853 1e-12", toy(SceneType::kViscous, IntegratorType::kDop853), 1e8);
  add("viscous k = 0.02, radau5 1e-12", toy(SceneType::kViscous, IntegratorType::kRadau5), 1e8);
  add("viscous k = 0.02, auto", toy(SceneType::kViscous, IntegratorType::kAuto), 1e8);
  add("viscous k = 30, dop853 1e-12 (stiff: rejections)", stiff(30.0, IntegratorType::kDop853, 1e-12), 1e8);
  add("viscous k = 30, rodas4 1 ms", stiff(30.0, IntegratorType::kRodas4, 1e-12), 1e8);
  add("viscous k = 1e4, radau5 1e-14 (low-rank Newton)", stiff(1e4, IntegratorType::kRadau5, 1e-14), 1e8);
  add("viscous k = 1e5, radau5 1e-12 (low-rank Newton)", stiff(1e5, IntegratorType::kRadau5, 1e-12), 1e8);
  {
    SceneConfig fast = stiff(1e7, IntegratorType::kRadau5, 1e-14);
    fast.initial.spin = 2000.0;
    add("viscous k = 1e7, spin 2000, radau5 1e-14", fast, 1e8);
  }
  add("viscous k = 1e5, auto", stiff(1e5, IntegratorType::kAuto, 1e-12), 1e8);

  std::string table =
      "| case (a request every 1 ms, up to 2 s) | simulated [s] | accepted steps | budget steps | budget steps per "
      "accepted step | CPU per accepted step [us] | CPU per budget step [us] |\n|---|---|---|---|---|---|---|\n";
  double least_step = 1e300, most_step = 0.0, least_unit = 1e300, most_unit = 0.0;
  for (const Case& c : cases) {
    const Measured m = run(c);
    const double per_step = 1e6 * m.cpu / static_cast<double>(std::max(1L, m.steps));
    const double per_unit = 1e6 * m.cpu / static_cast<double>(std::max(1L, m.work));
    char line[512];
    std::snprintf(line, sizeof line, "| %s | %.3f | %ld | %ld | %.2f | %.3f | %.3f |\n", c.name.c_str(), m.simulated,
                  m.steps, m.work, static_cast<double>(m.work) / static_cast<double>(std::max(1L, m.steps)), per_step,
                  per_unit);
    std::fputs(line, stdout);
    std::fflush(stdout);
    table += line;
    // Exact answers requests from one span: its per-step figure is a per-run one (not a method's step).
    if (m.steps < 100) continue;
    least_step = std::min(least_step, per_step);
    most_step = std::max(most_step, per_step);
    least_unit = std::min(least_unit, per_unit);
    most_unit = std::max(most_unit, per_unit);
  }
  char summary[1024];
  std::snprintf(summary, sizeof summary,
                "\nOver the time-steppers: CPU per accepted step %.3f-%.3f us (%.0fx), per budget step %.3f-%.3f us "
                "(%.1fx).\nThe default allowance of 1e8 budget steps bounds a run at %.0f s of CPU (the costliest "
                "budget step above; counting accepted steps, as before: %.0f s).\n",
                least_step, most_step, most_step / least_step, least_unit, most_unit, most_unit / least_unit,
                1e8 * most_unit * 1e-6, 1e8 * most_step * 1e-6);
  std::fputs(summary, stdout);

  std::string units =
      "\n| f of | f [us] | real LU | complex LU | real solve | complex solve | LU + inverse | product |\n"
      "|---|---|---|---|---|---|---|---|\n";
  TopParameters top;
  top.friction = 1e4;
  InitialConditions initial;
  initial.tilt = 0.3;
  initial.spin = 150.0;
  initial.velocity_x = 0.05;
  units += unit_costs(Viscous(top, initial), "viscous");
  units += unit_costs(FixedTip(top, initial), "fixed tip");
  units +=
      "\nRADAU5's low-rank Newton (the model's stiff part U V), in evaluations of f:\n\n"
      "| f of | f [us] | stiff part (U, V) | 3 stages' factors + LU | Woodbury solve | error filter |\n"
      "|---|---|---|---|---|---|\n";
  units += low_rank_costs(Viscous(top, initial), "viscous");
  units +=
      "\nexact's construction (at each landing of a hopping run), against the work it charges:\n\n"
      "| state | Fourier terms | CPU [us] | work units | CPU per unit [us] |\n|---|---|---|---|---|\n";
  units += exact_build<FixedTip>("fixed tip", 0.3, 150.0);
  units += exact_build<FixedTip>("fixed tip", 1e-7, 3.2);
  units += exact_build<Frictionless>("frictionless", 0.3, 150.0);
  units += exact_build<Frictionless>("frictionless", 1.6e-7, 3.2);
  std::fputs(units.c_str(), stdout);

  std::FILE* out = std::fopen(out_path.c_str(), "w");
  if (!out) {
    std::perror(out_path.c_str());
    return 1;
  }
  std::fprintf(out, "# CPU per step of the work budget (bench/budget_time.cpp)\n\n%s%s\n"
                    "Linear algebra in evaluations of the model's f (n x n, Eigen's partial-pivoting LU):\n%s",
               table.c_str(), summary, units.c_str());
  std::fclose(out);
  std::printf("wrote %s\n", out_path.c_str());
  return 0;
}
