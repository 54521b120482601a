// Work-precision benchmark (issue 4, doc/benchmark.md): error against CPU time for every
// integrator the core offers and for Boost.Odeint's steppers on the same equations, plus the
// energy error of long runs.
//
// Usage: work_precision [--output-dir DIR] [--duration S] [--long-steps N] [--quick] [--scene NAME]
// Writes DIR/work_precision.csv, DIR/long_run_energy.csv, DIR/reference_check.csv and
// DIR/dense_sampling.csv (the cost of a state every 1 ms, what the node asks for).
#include <time.h>
#include <unistd.h>

#include <algorithm>
#include <array>
// GCC 12 flags odeint's copy of a stepper's scratch state (rkf78's m_x_tmp, overwritten before
// use) as uninitialized, depending on inlining: a false positive inside Boost.
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wuninitialized"
#pragma GCC diagnostic ignored "-Wmaybe-uninitialized"
#include <boost/numeric/odeint.hpp>
#pragma GCC diagnostic pop
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <functional>
#include <iostream>
#include <limits>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "reference_solution.hpp"
#include "spinning_top/integrator_registry.hpp"
#include "spinning_top/simulator.hpp"
#include "spinning_top/scenes/fixed_tip.hpp"
#include "spinning_top/scenes/frictionless.hpp"
#include "spinning_top/scenes/viscous.hpp"

namespace odeint = boost::numeric::odeint;
using namespace spinning_top;
using bench::QuadratureReference;

namespace {

double cpu_seconds() {
  timespec ts;
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &ts);
  return ts.tv_sec + 1e-9 * ts.tv_nsec;
}

/// Median CPU time of repeats of run(): repeats while cheap (<= ~0.3 s per point in total),
/// so noise from other processes on the shared machine is filtered for the fast runs.
double median_cpu(const std::function<void()>& run) {
  std::vector<double> times;
  double total = 0.0;
  while (true) {
    const double start = cpu_seconds();
    run();
    const double t = cpu_seconds() - start;
    times.push_back(t);
    total += t;
    if (times.size() >= 7 || (times.size() >= 3 && total > 0.3) || total > 1.0) break;
  }
  std::sort(times.begin(), times.end());
  return times[times.size() / 2];
}

// ---------- scenes ----------
struct Scene {
  std::string name;
  SceneConfig config;
};

SceneConfig toy_top(SceneType type, double friction) {
  SceneConfig c;
  c.scene = type;
  c.top.mass = 0.1;
  c.top.inertia_transverse = 4e-5;
  c.top.inertia_axial = 6e-5;
  c.top.tip_distance = 0.02;
  c.top.gravity = 9.80665;
  c.top.friction = friction;
  c.initial.tilt = 0.3;
  c.initial.spin = 150.0;
  return c;
}

// ---------- reference: axis, normal force at any (monotone) time ----------
struct RefSample {
  Vector3 axis;
  double normal_force;
};

Vector3 axis_from_euler(double theta, double phi) {
  return Vector3(std::sin(theta) * std::sin(phi), -std::sin(theta) * std::cos(phi), std::cos(theta));
}

class Reference {
 public:
  virtual ~Reference() = default;
  virtual void restart() = 0;
  virtual RefSample at(double t) = 0;  // t non-decreasing between restarts
};

/// Analytic (quadrature) reference; R from the scene model at the reference's Euler angles
/// and rates (R does not depend on phi or psi by symmetry).
template <class Model>
class AnalyticReference : public Reference {
 public:
  AnalyticReference(const SceneConfig& c, bool frictionless)
      : config_(c), quadrature_(c.top, c.initial, frictionless), model_(c.top, c.initial) {}
  void restart() override {}
  RefSample at(double t) override {
    const QuadratureReference::Sample s = quadrature_.at(t);
    InitialConditions ic = config_.initial;
    ic.tilt = s.theta;
    ic.heading = s.phi;
    ic.nutation_rate = s.theta_dot;
    ic.precession_rate = s.phi_dot;
    ic.spin_angle = 0.0;
    typename Model::State y = model_.initial_state();
    set_initial_attitude_and_rates(ic, y);
    return RefSample{axis_from_euler(s.theta, s.phi), model_.normal_force(y)};
  }
  const QuadratureReference& quadrature() const { return quadrature_; }

 private:
  SceneConfig config_;
  QuadratureReference quadrature_;
  Model model_;
};

/// Numerical reference: the core's most accurate adaptive method at a tight tolerance. Samples
/// on the 1 ms grid are computed once (dense output); other times (odeint's own steps) come
/// from a second run in lockstep with the run being graded.
class NumericalReference : public Reference {
 public:
  NumericalReference(SceneConfig c, IntegratorType type, double tolerance, double duration) {
    c.integrator.type = type;
    c.integrator.tolerance = tolerance;
    sim_ = make_simulator(c);
    const long n = std::lround(duration / kGrid);
    for (long i = 0; i <= n; ++i) cache_.push_back(advance(i * kGrid));
    sim_->reset();
  }
  void restart() override { sim_->reset(); }
  RefSample at(double t) override {
    const double k = t / kGrid;
    const long i = std::lround(k);
    if (std::abs(k - i) < 1e-9 && i >= 0 && i < static_cast<long>(cache_.size())) return cache_[i];
    return advance(t);
  }

 private:
  static constexpr double kGrid = 1e-3;
  RefSample advance(double t) {
    sim_->advance_to(t);
    const Snapshot s = sim_->snapshot();
    return RefSample{s.attitude * Vector3::UnitZ(), s.outputs.normal_force};
  }
  std::unique_ptr<Simulator> sim_;
  std::vector<RefSample> cache_;
};

// ---------- errors accumulated over a run ----------
struct Errors {
  double attitude = 0.0;  // max angle between computed and reference axis [rad]
  double energy = 0.0;    // max |E - E0| (or |E + W - E0|) / (m g h)
  double normal = 0.0;    // max |R - R_ref| / (m g)
  void add(const Vector3& axis, const Vector3& ref_axis, double energy_error, double r, double r_ref) {
    double angle = std::atan2(axis.cross(ref_axis).norm(), axis.dot(ref_axis));
    if (!std::isfinite(angle) || !std::isfinite(energy_error) || !std::isfinite(r)) {
      angle = M_PI;  // a blown-up run: worst possible attitude
      energy_error = r = std::numeric_limits<double>::infinity();
    }
    attitude = std::max(attitude, angle);
    energy = std::max(energy, std::abs(energy_error));
    normal = std::max(normal, std::abs(r - r_ref));
  }
};

// ---------- odeint adaptor ----------
template <class Model>
struct OdeintSystem {
  static constexpr int N = Model::kStateSize;
  using Array = std::array<double, N>;
  const Model* model;
  void operator()(const Array& x, Array& dxdt, double /*t*/) const {
    typename Model::State y, dy;
    for (int i = 0; i < N; ++i) y[i] = x[i];
    model->derivative(y, dy);
    for (int i = 0; i < N; ++i) dxdt[i] = dy[i];
  }
};

/// The same system on ublas vectors for rosenbrock4, with a central finite-difference Jacobian
/// (odeint's rosenbrock4 needs J and df/dt; the system is autonomous so df/dt = 0).
template <class Model>
struct UblasSystem {
  static constexpr int N = Model::kStateSize;
  using Vec = boost::numeric::ublas::vector<double>;
  using Mat = boost::numeric::ublas::matrix<double>;
  const Model* model;
  void eval(const Vec& x, Vec& dxdt) const {
    typename Model::State y, dy;
    for (int i = 0; i < N; ++i) y[i] = x[i];
    model->derivative(y, dy);
    for (int i = 0; i < N; ++i) dxdt[i] = dy[i];
  }
};

template <class Model>
struct UblasRhs {
  const UblasSystem<Model>* sys;
  void operator()(const typename UblasSystem<Model>::Vec& x, typename UblasSystem<Model>::Vec& dxdt, double) const {
    sys->eval(x, dxdt);
  }
};

template <class Model>
struct UblasJacobian {
  const UblasSystem<Model>* sys;
  void operator()(const typename UblasSystem<Model>::Vec& x, typename UblasSystem<Model>::Mat& jac, double,
                  typename UblasSystem<Model>::Vec& dfdt) const {
    constexpr int N = Model::kStateSize;
    typename UblasSystem<Model>::Vec xp = x, fp(N), fm(N);
    for (int j = 0; j < N; ++j) {
      const double h = 1e-7 * std::max(1.0, std::abs(x[j]));
      xp[j] = x[j] + h;
      sys->eval(xp, fp);
      xp[j] = x[j] - h;
      sys->eval(xp, fm);
      xp[j] = x[j];
      for (int i = 0; i < N; ++i) jac(i, j) = (fp[i] - fm[i]) / (2.0 * h);
    }
    for (int i = 0; i < N; ++i) dfdt[i] = 0.0;
  }
};

template <class Model, class X>
Errors grade_state(const Model& model, const X& x, double t, double e0, double mgh, Reference& ref, Errors& e) {
  typename Model::State y;
  for (int i = 0; i < Model::kStateSize; ++i) y[i] = x[i];
  normalize_attitude(y);  // the axis (and R, E) of the normalized quaternion
  const ModelOutputs out = model.outputs(y);
  const RefSample r = ref.at(t);
  const Vector3 axis = attitude_of(y) * Vector3::UnitZ();
  e.add(axis, r.axis, (out.energy + out.dissipated_energy - e0) / mgh, out.normal_force / model.parameters().mass / model.parameters().gravity,
        r.normal_force / model.parameters().mass / model.parameters().gravity);
  return e;
}

// ---------- output rows ----------
struct Row {
  std::string scene, family, method, parameter_name;
  double parameter, cpu, attitude, energy, normal;
  long steps;
};

std::ofstream open_csv(const std::string& path, const std::string& header) {
  std::ofstream f(path);
  if (!f) {
    std::cerr << "work_precision: cannot write " << path << "\n";
    std::exit(1);
  }
  f << header << "\n";
  f.precision(6);
  return f;
}

/// One progress line on stderr: rewritten in place on a terminal, one line each in a log.
void progress(const std::string& text) {
  static const bool terminal = isatty(STDERR_FILENO) != 0;
  if (terminal) std::fprintf(stderr, "\r\033[K%s", text.c_str());
  else if (!text.empty() && text.back() != '\n') std::fprintf(stderr, "%s\n", text.c_str());
  else std::fprintf(stderr, "%s", text.c_str());
  std::fflush(stderr);
}

/// A step or tolerance as %g (std::to_string prints 1e-9 as 0.000000).
std::string number(double value) {
  char text[32];
  std::snprintf(text, sizeof text, "%g", value);
  return text;
}

/// The simulator for c, or null where the core refuses it (a method not offered for this
/// scene, or a step beyond its limit): the sweeps skip those points.
std::unique_ptr<Simulator> simulator_or_null(const SceneConfig& c) {
  try {
    return make_simulator(c);
  } catch (const InvalidParameter&) {
    return nullptr;
  }
}

/// Every method of the registry (auto, which runs one of them, is measured separately).
std::vector<IntegratorType> our_integrators() {
  std::vector<IntegratorType> types;
  for (const IntegratorInfo& row : integrator_registry())
    if (row.kind != IntegratorKind::kAutomatic) types.push_back(row.type);
  return types;
}

IntegratorKind kind_of(IntegratorType type) { return integrator_info(type).kind; }

/// auto's series name: the method it ran, e.g. "auto (exact)" or "auto (dop853)" (a CSV field: no commas).
std::string auto_name(const Simulator& sim) {
  const IntegratorChoice choice = sim.integrator_choice();
  return "auto (" + std::string(to_string(choice.method)) + (choice.fallback ? " fallback" : "") + ")";
}

struct Options {
  std::string output_dir = ".";
  double duration = 10.0;
  long long_steps = 1000000;
  bool quick = false;
  std::string only_scene;  // --scene NAME: run one scene (for development)
};

std::vector<double> fixed_steps(bool quick) {
  std::vector<double> steps;
  for (double dt = 16e-3; dt > (quick ? 1e-4 : 1.5e-5); dt /= 2.0) steps.push_back(dt);
  return steps;
}
std::vector<double> tolerances(bool quick) {
  std::vector<double> tols;
  for (int e = 3; e <= 13; e += quick ? 2 : 1) tols.push_back(std::pow(10.0, -e));
  return tols;
}
// A sweep stops once errors are below what the reference can grade or one run costs too much.
constexpr double kErrorFloor = 3e-12;
constexpr double kMaxRunCpu = 1.5;

template <class Model>
void run_scene(const Scene& scene, Reference& ref, const Options& opt, std::vector<Row>& rows) {
  const SceneConfig& base = scene.config;
  const double duration = opt.duration;
  const double mgh = base.top.mass * base.top.gravity * base.top.tip_distance;
  const Model model(base.top, base.initial);
  const double e0 = model.outputs(model.initial_state()).energy;
  const double sample_interval = 1e-3;

  // --- ours, through the front ends' interface ---
  for (const IntegratorType type : our_integrators()) {
    SceneConfig c = base;
    c.integrator.type = type;
    // A closed form (exact) has neither step nor tolerance: one point (its cost does not depend on the accuracy).
    const bool closed_form = kind_of(type) == IntegratorKind::kClosedForm;
    const bool adaptive = kind_of(type) == IntegratorKind::kAdaptive;
    const std::vector<double> params =
        closed_form ? std::vector<double>{0.0} : adaptive ? tolerances(opt.quick) : fixed_steps(opt.quick);
    for (const double p : params) {
      if (closed_form) {
        // no step or tolerance: a single point
      } else if (adaptive) {
        c.integrator.tolerance = p;
      } else {
        c.integrator.step = p;
      }
      const std::unique_ptr<Simulator> sim = simulator_or_null(c);
      if (!sim) continue;  // this method is not offered for this scene, or not at this step
      progress(scene.name + ": " + to_string(type) + (closed_form ? "" : (adaptive ? " tol " : " step ") + number(p)));
      const double cpu = median_cpu([&] {
        sim->reset();
        sim->advance_to(duration);
      });
      if (sim->event() != Event::kNone) continue;
      const long steps = sim->steps();
      // Error run: samples every max(step, 1 ms), a multiple of the step (powers of two of
      // 1 ms), so sampling does not change the fixed-step methods' steps; adaptive ones answer
      // by dense output, which does not change theirs either.
      sim->reset();
      ref.restart();
      Errors err;
      const double interval = adaptive ? sample_interval : std::max(p, sample_interval);
      const long n = std::lround(duration / interval);
      for (long i = 0; i <= n; ++i) {
        const double t = i * interval;
        sim->advance_to(t);
        if (sim->event() != Event::kNone) break;
        const Snapshot s = sim->snapshot();
        const RefSample r = ref.at(t);
        err.add(s.attitude * Vector3::UnitZ(), r.axis, (s.outputs.energy + s.outputs.dissipated_energy - e0) / mgh,
                s.outputs.normal_force / (base.top.mass * base.top.gravity), r.normal_force / (base.top.mass * base.top.gravity));
      }
      rows.push_back({scene.name, "ours", to_string(type), closed_form ? "none" : adaptive ? "tolerance" : "step", p, cpu, err.attitude,
                      err.energy, err.normal, steps});
      if (err.attitude < kErrorFloor || cpu > kMaxRunCpu) break;
    }
  }

  // --- Boost.Odeint peers on the same derivative() ---
  using Sys = OdeintSystem<Model>;
  using Array = typename Sys::Array;
  const Sys sys{&model};
  Array x0;
  {
    typename Model::State y = model.initial_state();
    for (int i = 0; i < Model::kStateSize; ++i) x0[i] = y[i];
  }
  auto record = [&](const std::string& method, const std::string& pname, double p, double cpu, const Errors& e, long steps) {
    rows.push_back({scene.name, "odeint", method, pname, p, cpu, e.attitude, e.energy, e.normal, steps});
  };
  // runge_kutta4, fixed steps.
  for (const double dt : fixed_steps(opt.quick)) {
    progress(scene.name + ": odeint rk4 step " + number(dt));
    const long n = std::lround(duration / dt);
    odeint::runge_kutta4<Array> stepper;
    Array x;
    const double cpu = median_cpu([&] {
      x = x0;
      odeint::integrate_n_steps(stepper, sys, x, 0.0, dt, n);
    });
    x = x0;
    ref.restart();
    Errors err;
    const long every = std::max(1L, std::lround(sample_interval / dt));
    long k = 0;
    odeint::integrate_n_steps(stepper, sys, x, 0.0, dt, n, [&](const Array& xs, double t) {
      if (k++ % every == 0) grade_state(model, xs, t, e0, mgh, ref, err);
    });
    if (!std::isfinite(err.attitude)) err.attitude = M_PI;
    record("runge_kutta4", "step", dt, cpu, err, n);
    if (err.attitude < kErrorFloor || cpu > kMaxRunCpu) break;
  }
  // Controlled steppers: errors sampled at every accepted step.
  auto controlled = [&](const std::string& name, auto make_stepper) {
    for (const double tol : tolerances(opt.quick)) {
      progress(scene.name + ": odeint " + name + " tol " + number(tol));
      Array x;
      const double cpu = median_cpu([&] {
        x = x0;
        auto stepper = make_stepper(tol);
        odeint::integrate_adaptive(stepper, sys, x, 0.0, duration, 1e-4);
      });
      x = x0;
      ref.restart();
      Errors err;
      long steps = 0;
      auto stepper = make_stepper(tol);
      odeint::integrate_adaptive(stepper, sys, x, 0.0, duration, 1e-4, [&](const Array& xs, double t) {
        ++steps;
        grade_state(model, xs, t, e0, mgh, ref, err);
      });
      record(name, "tolerance", tol, cpu, err, steps - 1);
      if (err.attitude < kErrorFloor || cpu > kMaxRunCpu) break;
    }
  };
  controlled("runge_kutta_dopri5", [](double tol) {
    return odeint::make_controlled(tol, tol, odeint::runge_kutta_dopri5<Array>());
  });
  controlled("runge_kutta_fehlberg78", [](double tol) {
    return odeint::make_controlled(tol, tol, odeint::runge_kutta_fehlberg78<Array>());
  });
  // rosenbrock4 (finite-difference Jacobian) for the friction scenes.
  if (base.scene == SceneType::kViscous) {
    using USys = UblasSystem<Model>;
    const USys usys{&model};
    typename USys::Vec ux0(Model::kStateSize);
    for (int i = 0; i < Model::kStateSize; ++i) ux0[i] = x0[i];
    for (const double tol : tolerances(opt.quick)) {
      if (tol < 1e-11) break;  // the finite-difference Jacobian limits what it can reach
      progress(scene.name + ": odeint rosenbrock4 tol " + number(tol));
      typename USys::Vec x;
      auto system = std::make_pair(UblasRhs<Model>{&usys}, UblasJacobian<Model>{&usys});
      const double cpu = median_cpu([&] {
        x = ux0;
        auto stepper = odeint::make_controlled(tol, tol, odeint::rosenbrock4<double>());
        odeint::integrate_adaptive(stepper, system, x, 0.0, duration, 1e-4);
      });
      x = ux0;
      auto timed = odeint::make_controlled(tol, tol, odeint::rosenbrock4<double>());
      const long steps = static_cast<long>(odeint::integrate_adaptive(timed, system, x, 0.0, duration, 1e-4));
      // Graded by its dense output on the 1 ms grid (same controller, steps not clipped).
      x = ux0;
      ref.restart();
      Errors err;
      auto dense = odeint::make_dense_output(tol, tol, odeint::rosenbrock4<double>());
      odeint::integrate_const(dense, system, x, 0.0, duration + 0.5 * sample_interval, sample_interval,
                              [&](const typename USys::Vec& xs, double t) { grade_state(model, xs, t, e0, mgh, ref, err); });
      record("rosenbrock4", "tolerance", tol, cpu, err, steps);
      if (err.attitude < kErrorFloor || cpu > kMaxRunCpu) break;
    }
  }
}

// ---------- dense sampling: a state every 1 ms, what the node pays ----------
// The node asks for the state at every tick (1 ms). The ratio table above times one
// advance_to(10 s) with output off; here every method answers all 10000 requests. Ours: exact,
// auto (the node's default) and dop853 at 1e-10 (dense output); odeint: dopri5 through its dense
// output, RKF78 through integrate_const (it has no dense output, so its steps are clipped at the
// sample times). CPU only for the requests (advance_to / integrate_const), not the snapshots.
struct DenseRow {
  std::string scene, family, method, setting;
  double cpu, attitude;
  long samples;
};

template <class Model>
void dense_sampling(const Scene& scene, Reference& ref, const Options& opt, std::vector<DenseRow>& rows) {
  const SceneConfig& base = scene.config;
  const double interval = 1e-3, tolerance = 1e-10;
  const long n = std::lround(opt.duration / interval);
  struct Ours {
    IntegratorType type;
    std::string setting;
  };
  for (const Ours& o : {Ours{IntegratorType::kExact, "closed form"}, Ours{IntegratorType::kAuto, "defaults"},
                        Ours{IntegratorType::kDop853, "tolerance 1e-10"}}) {
    SceneConfig c = base;
    c.integrator.type = o.type;
    c.integrator.tolerance = tolerance;
    const std::unique_ptr<Simulator> sim = simulator_or_null(c);
    if (!sim) continue;  // this method is not offered for this scene, or not at this step
    progress(scene.name + ": dense sampling " + to_string(o.type));
    const double cpu = median_cpu([&] {
      sim->reset();
      for (long i = 1; i <= n; ++i) sim->advance_to(i * interval);
    });
    sim->reset();
    ref.restart();
    Errors err;
    for (long i = 0; i <= n; ++i) {
      if (sim->advance_to(i * interval) != Event::kNone) break;
      const Snapshot s = sim->snapshot();
      const RefSample r = ref.at(i * interval);
      err.add(s.attitude * Vector3::UnitZ(), r.axis, 0.0, 0.0, 0.0);
    }
    const std::string name = o.type == IntegratorType::kAuto ? auto_name(*sim) : to_string(o.type);
    rows.push_back({scene.name, "ours", name, o.setting, cpu, err.attitude, n});
  }
  using Sys = OdeintSystem<Model>;
  using Array = typename Sys::Array;
  const Model model(base.top, base.initial);
  const Sys sys{&model};
  Array x0;
  {
    const typename Model::State y = model.initial_state();
    for (int i = 0; i < Model::kStateSize; ++i) x0[i] = y[i];
  }
  auto grade = [&](const Array& x, double t, Errors& err) {
    typename Model::State y;
    for (int i = 0; i < Model::kStateSize; ++i) y[i] = x[i];
    normalize_attitude(y);
    err.add(attitude_of(y) * Vector3::UnitZ(), ref.at(t).axis, 0.0, 0.0, 0.0);
  };
  auto peer = [&](const std::string& name, auto make_stepper) {
    progress(scene.name + ": dense sampling odeint " + name);
    Array x;
    const double cpu = median_cpu([&] {
      x = x0;
      auto stepper = make_stepper();
      odeint::integrate_const(stepper, sys, x, 0.0, opt.duration + 0.5 * interval, interval);
    });
    x = x0;
    ref.restart();
    Errors err;
    auto stepper = make_stepper();
    odeint::integrate_const(stepper, sys, x, 0.0, opt.duration + 0.5 * interval, interval,
                            [&](const Array& xs, double t) { grade(xs, t, err); });
    rows.push_back({scene.name, "odeint", name, "tolerance 1e-10", cpu, err.attitude, n});
  };
  peer("runge_kutta_dopri5 (dense output)",
       [&] { return odeint::make_dense_output(tolerance, tolerance, odeint::runge_kutta_dopri5<Array>()); });
  peer("runge_kutta_fehlberg78 (steps clipped at samples)",
       [&] { return odeint::make_controlled(tolerance, tolerance, odeint::runge_kutta_fehlberg78<Array>()); });
}

// ---------- long runs: energy error vs simulated time ----------
template <class Model>
void long_runs(const Scene& scene, const Options& opt, std::ofstream& csv) {
  const SceneConfig& base = scene.config;
  const double step = 1e-3, tol = 1e-10;
  const long n = opt.quick ? opt.long_steps / 10 : opt.long_steps;
  const double horizon = n * step;
  const long samples = 200;
  const double mgh = base.top.mass * base.top.gravity * base.top.tip_distance;
  const Model model(base.top, base.initial);
  const double e0 = model.outputs(model.initial_state()).energy;
  auto write = [&](const std::string& family, const std::string& method, const std::string& setting, double t,
                   double err) {
    csv << scene.name << "," << family << "," << method << "," << setting << "," << t << "," << err << "\n";
  };
  std::vector<IntegratorType> types = our_integrators();
  types.push_back(IntegratorType::kAuto);
  for (const IntegratorType type : types) {
    SceneConfig c = base;
    c.integrator.type = type;
    c.integrator.step = step;
    c.integrator.tolerance = tol;
    const std::unique_ptr<Simulator> sim = simulator_or_null(c);
    if (!sim) continue;  // this method is not offered for this scene, or not at this step
    const IntegratorKind kind = kind_of(type);
    const std::string setting = kind == IntegratorKind::kAutomatic    ? "defaults"
                                : kind == IntegratorKind::kClosedForm ? "closed form"
                                : kind == IntegratorKind::kAdaptive   ? "tolerance 1e-10"
                                                                      : "step 1e-3";
    const std::string name = type == IntegratorType::kAuto ? auto_name(*sim) : to_string(type);
    for (long i = 1; i <= samples; ++i) {
      const double t = horizon * i / samples;
      if (i % 20 == 1) progress(scene.name + ": long run " + to_string(type) + " t " + number(t));
      if (sim->advance_to(t) != Event::kNone) break;
      const Snapshot s = sim->snapshot();
      write("ours", name, setting, t, (s.outputs.energy + s.outputs.dissipated_energy - e0) / mgh);
    }
  }
  // odeint peers: rk4 at the same step, dopri5 and rkf78 at the same tolerance.
  using Sys = OdeintSystem<Model>;
  using Array = typename Sys::Array;
  const Sys sys{&model};
  Array x0;
  {
    typename Model::State y = model.initial_state();
    for (int i = 0; i < Model::kStateSize; ++i) x0[i] = y[i];
  }
  auto energy_error = [&](const Array& x) {
    typename Model::State y;
    for (int i = 0; i < Model::kStateSize; ++i) y[i] = x[i];
    normalize_attitude(y);
    const ModelOutputs out = model.outputs(y);
    return (out.energy + out.dissipated_energy - e0) / mgh;
  };
  {
    progress(scene.name + ": long run odeint rk4");
    Array x = x0;
    odeint::runge_kutta4<Array> stepper;
    const long every = n / samples;
    long k = 0;
    odeint::integrate_n_steps(stepper, sys, x, 0.0, step, n, [&](const Array& xs, double t) {
      if (k > 0 && k % every == 0) write("odeint", "runge_kutta4", "step 1e-3", t, energy_error(xs));
      ++k;
    });
  }
  auto controlled = [&](const std::string& name, auto stepper) {
    progress(scene.name + ": long run odeint " + name);
    Array x = x0;
    auto dense = odeint::make_dense_output(tol, tol, stepper);
    odeint::integrate_const(dense, sys, x, 0.0, horizon + 0.5 * horizon / samples, horizon / samples,
                            [&](const Array& xs, double t) {
                              if (t > 0.0) write("odeint", name, "tolerance 1e-10", t, energy_error(xs));
                            });
  };
  controlled("runge_kutta_dopri5", odeint::runge_kutta_dopri5<Array>());
  // rkf78 has no dense output in odeint: sample by stepping to each sample time.
  {
    progress(scene.name + ": long run odeint runge_kutta_fehlberg78");
    Array x = x0;
    auto stepper = odeint::make_controlled(tol, tol, odeint::runge_kutta_fehlberg78<Array>());
    double t = 0.0;
    for (long i = 1; i <= samples; ++i) {
      const double t1 = horizon * i / samples;
      odeint::integrate_adaptive(stepper, sys, x, t, t1, 1e-4);
      t = t1;
      write("odeint", "runge_kutta_fehlberg78", "tolerance 1e-10", t, energy_error(x));
    }
  }
}

}  // namespace

int main(int argc, char** argv) {
  Options opt;
  for (int i = 1; i < argc; ++i) {
    const std::string arg = argv[i];
    if (arg == "--output-dir" && i + 1 < argc) {
      opt.output_dir = argv[++i];
    } else if (arg == "--duration" && i + 1 < argc) {
      opt.duration = std::atof(argv[++i]);
    } else if (arg == "--long-steps" && i + 1 < argc) {
      opt.long_steps = std::atol(argv[++i]);
    } else if (arg == "--scene" && i + 1 < argc) {
      opt.only_scene = argv[++i];
    } else if (arg == "--quick") {
      opt.quick = true;
    } else {
      std::cerr << "usage: work_precision [--output-dir DIR] [--duration S] [--long-steps N] [--quick] [--scene NAME]\n"
                   "Error vs CPU time of the core's integrators and Boost.Odeint's on the toy top (m 0.1,\n"
                   "A 4e-5, C 6e-5, h 0.02, spin 150, tilt 0.3) in each scene; writes work_precision.csv,\n"
                   "long_run_energy.csv, reference_check.csv and dense_sampling.csv to DIR (doc/benchmark.md).\n";
      return arg == "--help" ? 0 : 2;
    }
  }
  // The long runs sample every (steps / 200): fewer than 200 steps (after --quick's tenth) would
  // make that interval zero.
  if (!(opt.duration > 0.0 && std::isfinite(opt.duration)) || (opt.quick ? opt.long_steps / 10 : opt.long_steps) < 200) {
    std::cerr << "work_precision: --duration must be a finite number > 0 and --long-steps at least 200 "
                 "(2000 with --quick)\n";
    return 2;
  }
  const std::vector<Scene> scenes = {
      {"fixed_tip", toy_top(SceneType::kFixedTip, 0.0)},
      {"frictionless", toy_top(SceneType::kFrictionless, 0.0)},
      {"viscous", toy_top(SceneType::kViscous, 0.02)},             // m/k = 5 s (config/viscous.yaml)
      {"viscous_stiff", toy_top(SceneType::kViscous, 1000.0)},     // m/k = 1e-4 s: stiff
      {"viscous_very_stiff", toy_top(SceneType::kViscous, 1e5)},   // m/k = 1e-6 s: very stiff
  };

  // Reference checks: the quadrature against the best adaptive method at the tightest
  // tolerances, and the numerical references' self-consistency (two tolerances).
  std::ofstream check = open_csv(opt.output_dir + "/reference_check.csv",
                                 "scene,what,value");
  check.precision(10);
  std::vector<Row> rows;
  std::vector<DenseRow> dense_rows;
  for (const Scene& scene : scenes) {
    if (!opt.only_scene.empty() && scene.name != opt.only_scene) continue;
    const auto grade_numerical = [&](Reference& ref, IntegratorType type, double tol) {
      NumericalReference other(scene.config, type, tol, opt.duration);
      double worst = 0.0;
      for (long i = 0; i <= std::lround(opt.duration / 1e-3); ++i) {
        const double t = i * 1e-3;
        const Vector3 a = other.at(t).axis, b = ref.at(t).axis;
        worst = std::max(worst, std::atan2(a.cross(b).norm(), a.dot(b)));
      }
      ref.restart();
      return worst;
    };
    progress(scene.name + ": reference");
    {
      SceneConfig c = scene.config;
      c.integrator.type = IntegratorType::kAuto;
      std::string pick = make_simulator(c)->integrator_description();
      std::replace(pick.begin(), pick.end(), ',', ';');
      check << scene.name << ",auto picks (step 1e-3; tolerance 1e-10)," << pick << "\n";
    }
    if (scene.config.scene == SceneType::kViscous) {
      NumericalReference ref(scene.config, IntegratorType::kDop853, 1e-14, opt.duration);
      check << scene.name << ",reference,dop853 tolerance 1e-14 (dense output)\n";
      check << scene.name << ",max angle dop853(1e-14) vs dop853(1e-12) [rad]," << grade_numerical(ref, IntegratorType::kDop853, 1e-12) << "\n";
      check << scene.name << ",max angle dop853(1e-14) vs dop853(1e-13) [rad]," << grade_numerical(ref, IntegratorType::kDop853, 1e-13) << "\n";
      run_scene<Viscous>(scene, ref, opt, rows);
    } else {
      const bool frictionless = scene.config.scene == SceneType::kFrictionless;
      std::unique_ptr<Reference> ref;
      const QuadratureReference* q = nullptr;
      if (frictionless) {
        auto r = std::make_unique<AnalyticReference<Frictionless>>(scene.config, true);
        q = &r->quadrature();
        ref = std::move(r);
      } else {
        auto r = std::make_unique<AnalyticReference<FixedTip>>(scene.config, false);
        q = &r->quadrature();
        ref = std::move(r);
      }
      check << scene.name << ",reference,quadrature (bench/reference_solution.hpp)\n";
      check << scene.name << ",nutation period [s]," << q->period() << "\n";
      check << scene.name << ",theta_min [rad]," << std::acos(q->turning_point_high()) << "\n";
      check << scene.name << ",theta_max [rad]," << std::acos(q->turning_point_low()) << "\n";
      check << scene.name << ",mean precession rate [rad/s]," << q->mean_precession_rate() << "\n";
      check << scene.name << ",max angle quadrature vs dop853(1e-14) [rad]," << grade_numerical(*ref, IntegratorType::kDop853, 1e-14) << "\n";
      check << scene.name << ",max angle quadrature vs dop853(1e-12) [rad]," << grade_numerical(*ref, IntegratorType::kDop853, 1e-12) << "\n";
      if (frictionless) {
        run_scene<Frictionless>(scene, *ref, opt, rows);
        dense_sampling<Frictionless>(scene, *ref, opt, dense_rows);
      } else {
        run_scene<FixedTip>(scene, *ref, opt, rows);
        dense_sampling<FixedTip>(scene, *ref, opt, dense_rows);
      }
    }
  }
  {
    std::ofstream csv = open_csv(opt.output_dir + "/work_precision.csv",
                                 "scene,family,method,parameter_name,parameter,cpu_seconds,steps,"
                                 "max_attitude_error_rad,max_energy_error_rel_mgh,max_normal_force_error_rel_mg");
    for (const Row& r : rows)
      csv << r.scene << "," << r.family << "," << r.method << "," << r.parameter_name << "," << r.parameter << ","
          << r.cpu << "," << r.steps << "," << r.attitude << "," << r.energy << "," << r.normal << "\n";
  }
  {
    std::ofstream csv = open_csv(opt.output_dir + "/dense_sampling.csv",
                                 "scene,family,method,setting,cpu_seconds,samples,max_attitude_error_rad");
    for (const DenseRow& r : dense_rows)
      csv << r.scene << "," << r.family << "," << r.method << "," << r.setting << "," << r.cpu << "," << r.samples << ","
          << r.attitude << "\n";
  }
  {
    std::ofstream csv = open_csv(opt.output_dir + "/long_run_energy.csv",
                                 "scene,family,method,setting,time,energy_error_rel_mgh");
    csv.precision(6);
    for (const Scene& scene : scenes) {
      if (!opt.only_scene.empty() && scene.name != opt.only_scene) continue;
      if (scene.config.top.friction > 1.0) continue;  // stiff: its transient is over in ms, nothing to drift
      if (scene.config.scene == SceneType::kViscous) long_runs<Viscous>(scene, opt, csv);
      else if (scene.config.scene == SceneType::kFrictionless) long_runs<Frictionless>(scene, opt, csv);
      else long_runs<FixedTip>(scene, opt, csv);
    }
  }
  progress("work_precision: done\n");
  return 0;
}
