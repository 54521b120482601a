// The viscous scene's default (integrator: auto) from k = 0 to m/k = 1e-8 s: its error against an
// independent reference and its CPU time, at the node's request pattern (a state every 1 ms), and
// the work-precision of radau9 / radau5 / dop853 against Boost.Odeint's RKF78 and rosenbrock4
// (doc/integrators.md, "Viscous: the default and its accuracy").
//
// Errors over the run, sampled every 1 ms: the whole attitude (the rotation angle between the
// computed and the reference quaternion, which includes the azimuth about the axis), the normal
// force R / (m g), and the energy balance |E + W - E0| / (m g h) (PHYSICS.md: dE/dt = -k |v_P|^2).
// References: dop853 at tolerance 1e-14 where friction is not stiff (lambda = k (1/m + h^2/A)
// <= 2.5e5 1/s: at most ~5e6 steps per 10 s), checked against dop853 at 1e-13; above, radau5 at
// 1e-15 (100x tighter than the default's radau9 at 1e-13), checked against radau5 at 1e-14 over the whole run
// (self-convergence) and against dop853 at 1e-14 over the first 2.4e6 / lambda seconds (what
// dop853 can afford at its stability limit).
//
// Usage: viscous_default [--duration S] [--output-dir DIR] [--quick] [--case NAME] [--no-peers] [--sweep]
//                        [--repeats N]  (CPU: median of N runs, 3 by default, 1 with --quick)
// (--sweep: radau9, radau5 and dop853 at tolerances 1e-8 ... 1e-14 for every case, as for the peers)
// Writes DIR/viscous_default.csv and DIR/viscous_peers.csv; prints markdown tables.
#include <time.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <functional>
#include <iostream>
#include <memory>
#include <string>
#include <vector>

#include "spinning_top/integrators/registry_rows.hpp"
#include "spinning_top/integrators/radau.hpp"
#include "spinning_top/scenes/viscous.hpp"
#include "spinning_top/simulator.hpp"
#include "bench_support.hpp"

namespace odeint = boost::numeric::odeint;
using namespace spinning_top;

namespace {

using spinning_top::bench::cpu_seconds;

constexpr double kInterval = 1e-3;        // the node's default request period
constexpr double kAttitudeTarget = 1e-9;  // rad
constexpr double kNormalForceTarget = 1e-8;  // m g
// Exact decades (a tolerance computed by repeated division differs in its last bits, and at 2000
// rad/s over 10 s that alone moves the attitude by ~2e-9 rad: the runs are that sensitive).
constexpr double kTolerances[] = {1e-8, 1e-9, 1e-10, 1e-11, 1e-12, 1e-13, 1e-14};

/// Median CPU time of `repeats` runs (the machine is shared: the median filters the others' load).
double median_cpu(const std::function<void()>& run, int repeats) {
  std::vector<double> times;
  for (int i = 0; i < repeats; ++i) {
    const double start = cpu_seconds();
    run();
    times.push_back(cpu_seconds() - start);
  }
  std::sort(times.begin(), times.end());
  return times[times.size() / 2];
}

struct Sample {
  Quaternion attitude;
  double normal_force, balance;  // R [N], E + W - E0 [J]
};

struct Trajectory {
  std::vector<Sample> samples;  // t = 0, kInterval, ... up to the duration or the event
  Event event = Event::kNone;
  double event_time = NAN;
  long steps = 0;
  std::string integrator;
};

/// The simulator's states every kInterval, as the node asks for them.
Trajectory sample(const SceneConfig& config, double duration) {
  Trajectory run;
  std::unique_ptr<Simulator> simulator = make_simulator(config);
  run.integrator = simulator->integrator_description();
  const double e0 = simulator->snapshot().outputs.energy;
  auto record = [&] {
    const Snapshot s = simulator->snapshot();
    run.samples.push_back({s.attitude, s.outputs.normal_force, s.outputs.energy + s.outputs.dissipated_energy - e0});
  };
  record();
  const long n = std::lround(duration / kInterval);
  for (long i = 1; i <= n; ++i) {
    const Event event = simulator->advance_to(i * kInterval);
    if (event != Event::kNone) {
      run.event = event;
      run.event_time = simulator->time();
      break;
    }
    record();
  }
  run.steps = simulator->steps();
  return run;
}

/// CPU time of the same requests without recording (median of `repeats`).
double request_cpu(const SceneConfig& config, double duration, int repeats) {
  return median_cpu(
      [&] {
        std::unique_ptr<Simulator> simulator = make_simulator(config);
        const long n = std::lround(duration / kInterval);
        for (long i = 1; i <= n; ++i)
          if (simulator->advance_to(i * kInterval) != Event::kNone) break;
      },
      repeats);
}

struct Errors {
  double attitude = 0.0, normal_force = 0.0, balance = 0.0;  // rad, m g, m g h
  bool meets_target() const { return attitude <= kAttitudeTarget && normal_force <= kNormalForceTarget; }
};

Errors compare(const std::vector<Sample>& run, const std::vector<Sample>& reference, const TopParameters& top,
               size_t count = SIZE_MAX) {
  const double mg = top.mass * top.gravity, mgh = mg * top.tip_distance;
  Errors e;
  const size_t n = std::min({run.size(), reference.size(), count});
  for (size_t i = 0; i < n; ++i) {
    const double angle = run[i].attitude.angularDistance(reference[i].attitude);
    e.attitude = std::max(e.attitude, std::isfinite(angle) ? angle : M_PI);
    e.normal_force = std::max(e.normal_force, std::abs(run[i].normal_force - reference[i].normal_force) / mg);
    // h = 0 has no m g h: its balance is scaled by the toy top's m g h (h = 0.02 m).
    e.balance = std::max(e.balance, std::abs(run[i].balance) / (mgh > 0.0 ? mgh : mg * 0.02));
  }
  return e;
}

SceneConfig named(SceneConfig c, IntegratorType type, double tolerance) {
  c.integrator.type = type;
  c.integrator.tolerance = tolerance;
  return c;
}

double friction_rate(const TopParameters& p) {
  return p.friction * (1.0 / p.mass + p.tip_distance * p.tip_distance / p.inertia_transverse);
}

struct Reference {
  Trajectory trajectory;
  std::string method;
  double self_check_attitude = 0.0, self_check_force = 0.0;    // vs the same method one decade looser
  double cross_check_attitude = NAN, cross_check_force = NAN;  // radau5 vs dop853 on a short span
  double cross_check_span = 0.0;
};

constexpr double kStiffReferenceRate = 2.5e5;  // lambda above which dop853 at 1e-14 is not affordable

/// radau5 through its driver, which allows a tolerance below validate()'s 1e-14 floor (radau5
/// maps it to 0.1 tol^(2/3) = 1e-11 at 1e-15: far from round-off).
Trajectory sample_radau(const SceneConfig& config, double tolerance, double duration) {
  const Viscous model(config.top, config.initial);
  AdaptiveDriver<Viscous, RadauIIA5<Viscous>> driver(tolerance);
  driver.reset(model, 0.0, model.initial_state());
  Trajectory run;
  run.integrator = driver.description();
  const double e0 = model.outputs(model.initial_state()).energy;
  auto record = [&] {
    const ModelOutputs o = model.outputs(driver.state());
    run.samples.push_back({attitude_of(driver.state()), o.normal_force, o.energy + o.dissipated_energy - e0});
  };
  record();
  for (long i = 1; i <= std::lround(duration / kInterval); ++i) {
    const Event event = driver.advance_to(model, i * kInterval);
    if (event != Event::kNone) {
      run.event = event;
      run.event_time = driver.time();
      break;
    }
    record();
  }
  run.steps = driver.steps();
  return run;
}

Reference make_reference(const SceneConfig& config, double duration) {
  Reference r;
  const double lambda = friction_rate(config.top);
  if (lambda <= kStiffReferenceRate) {
    r.method = "dop853 1e-14";
    r.trajectory = sample(named(config, IntegratorType::kDop853, 1e-14), duration);
    const Errors self = compare(sample(named(config, IntegratorType::kDop853, 1e-13), duration).samples,
                                r.trajectory.samples, config.top);
    r.self_check_attitude = self.attitude;
    r.self_check_force = self.normal_force;
  } else {
    r.method = "radau5 1e-15";
    r.trajectory = sample_radau(config, 1e-15, duration);
    const Errors self = compare(sample_radau(config, 1e-14, duration).samples, r.trajectory.samples, config.top);
    r.self_check_attitude = self.attitude;
    r.self_check_force = self.normal_force;
    r.cross_check_span = std::min(duration, std::max(kInterval, std::floor(2.4e6 / lambda / kInterval) * kInterval));
    const Trajectory explicit_run = sample(named(config, IntegratorType::kDop853, 1e-14), r.cross_check_span);
    const Errors cross = compare(explicit_run.samples, r.trajectory.samples, config.top, explicit_run.samples.size());
    r.cross_check_attitude = cross.attitude;
    r.cross_check_force = cross.normal_force;
  }
  return r;
}

// ---------- cases ----------
struct Case {
  std::string name;
  SceneConfig config;  // friction set per run
};

SceneConfig toy_viscous() {
  SceneConfig c;
  c.scene = SceneType::kViscous;
  c.initial.tilt = 0.3;
  c.initial.spin = 150.0;
  return c;  // TopParameters() is the toy top: m 0.1, A 4e-5, C 6e-5, h 0.02
}

std::vector<Case> cases() {
  std::vector<Case> list;
  list.push_back({"toy", toy_viscous()});
  SceneConfig c = toy_viscous();
  c.top.tip_distance = 0.0;  // torque-free: the attitude error is all azimuth and nutation phase
  list.push_back({"h0", c});
  c = toy_viscous();
  c.initial.spin = 2000.0;
  list.push_back({"fast_spin", c});
  c = toy_viscous();
  c.initial.tilt = 1.4835298641951802;  // 85 deg, config/extreme/near_horizontal.yaml
  list.push_back({"near_horizontal", c});
  c = toy_viscous();
  c.top.inertia_axial = 1.9 * c.top.inertia_transverse;
  list.push_back({"disk_like", c});
  c = toy_viscous();
  c.top.inertia_axial = 8e-7;  // config/extreme/rod_like.yaml: spun like the toy, it falls
  list.push_back({"rod_like", c});
  c = toy_viscous();
  c.initial.velocity_x = 0.1;  // G slides at 10 cm/s: v_P(0) != 0, an initial layer of length 1/lambda
  c.initial.precession_rate = 5.0;
  c.initial.nutation_rate = 2.0;
  list.push_back({"slip", c});
  return list;
}

std::string number(double value) {
  char text[32];
  std::snprintf(text, sizeof text, "%.3g", value);
  return text;
}

std::string csv_safe(std::string s) {
  std::replace(s.begin(), s.end(), ',', ';');
  return s;
}

// ---------- Boost.Odeint peers on the same derivative() ----------
using Array = std::array<double, Viscous::kStateSize>;
struct OdeintSystem {
  const Viscous* model;
  void operator()(const Array& x, Array& dxdt, double) const {
    Viscous::State y, dy;
    for (int i = 0; i < Viscous::kStateSize; ++i) y[i] = x[i];
    model->derivative(y, dy);
    for (int i = 0; i < Viscous::kStateSize; ++i) dxdt[i] = dy[i];
  }
};
using Vector = boost::numeric::ublas::vector<double>;
using Matrix = boost::numeric::ublas::matrix<double>;
struct UblasRhs {
  const Viscous* model;
  void operator()(const Vector& x, Vector& dxdt, double) const {
    Viscous::State y, dy;
    for (int i = 0; i < Viscous::kStateSize; ++i) y[i] = x[i];
    model->derivative(y, dy);
    for (int i = 0; i < Viscous::kStateSize; ++i) dxdt[i] = dy[i];
  }
};
/// Central differences (rosenbrock4 needs J; the system is autonomous, df/dt = 0).
struct UblasJacobian {
  const Viscous* model;
  void operator()(const Vector& x, Matrix& jac, double, Vector& dfdt) const {
    constexpr int n = Viscous::kStateSize;
    const UblasRhs rhs{model};
    Vector xp = x, fp(n), fm(n);
    for (int j = 0; j < n; ++j) {
      const double h = 1e-7 * std::max(1.0, std::abs(x[j]));
      xp[j] = x[j] + h;
      rhs(xp, fp, 0.0);
      xp[j] = x[j] - h;
      rhs(xp, fm, 0.0);
      xp[j] = x[j];
      for (int i = 0; i < n; ++i) jac(i, j) = (fp[i] - fm[i]) / (2.0 * h);
    }
    for (int i = 0; i < n; ++i) dfdt[i] = 0.0;
  }
};

template <class X>
Sample sample_of(const Viscous& model, const X& x, double e0) {
  Viscous::State y;
  for (int i = 0; i < Viscous::kStateSize; ++i) y[i] = x[i];
  normalize_attitude(y);
  const ModelOutputs o = model.outputs(y);
  return {attitude_of(y), o.normal_force, o.energy + o.dissipated_energy - e0};
}

struct PeerRow {
  std::string label, method;
  double k, tolerance, cpu;
  long steps;
  Errors errors;
};

/// Work-precision on the node's pattern (a state every 1 ms) for one k: ours through the
/// Simulator, odeint's RKF78 (no dense output: integrate_const clips its steps at the samples)
/// and rosenbrock4 (dense output) on the same equations.
void peers(const Case& base, double k, double duration, const Reference& reference, int repeats, bool with_odeint,
           std::vector<PeerRow>& rows) {
  SceneConfig config = base.config;
  config.top.friction = k;
  const Viscous model(config.top, config.initial);
  const double e0 = model.outputs(model.initial_state()).energy;
  const double lambda = friction_rate(config.top);
  const std::string label = base.name + " k=" + number(k);
  constexpr double kMaxCpu = 20.0;  // a run beyond this is not repeated at tighter tolerances
  auto ours = [&](IntegratorType type, double tolerance) {
    const SceneConfig c = named(config, type, tolerance);
    const Trajectory run = sample(c, duration);
    const double cpu = request_cpu(c, duration, repeats);
    rows.push_back({label, to_string(type), k, tolerance, cpu, run.steps, compare(run.samples, reference.trajectory.samples, config.top)});
    std::fprintf(stderr, "  %s %s %g: %.3g s\n", label.c_str(), to_string(type), tolerance, cpu);
    return cpu;
  };
  for (const double tolerance : kTolerances)
    if (ours(IntegratorType::kRadau9, tolerance) > kMaxCpu) break;
  for (const double tolerance : kTolerances)
    if (ours(IntegratorType::kRadau5, tolerance) > kMaxCpu) break;
  if (lambda <= 2.5e6)
    for (const double tolerance : kTolerances)
      if (ours(IntegratorType::kDop853, tolerance) > kMaxCpu) break;
  if (!with_odeint) return;
  Array x0;
  {
    const Viscous::State y = model.initial_state();
    for (int i = 0; i < Viscous::kStateSize; ++i) x0[i] = y[i];
  }
  const OdeintSystem system{&model};
  if (lambda <= 2.5e6) {
    // RKF78 has no dense output: its steps are clipped at the samples, by hand rather than by
    // integrate_const, which starts at the sample interval: at k = 1e5 that first step's error
    // estimate is NaN, and odeint's controller accepts it (NaN > 1 is false).
    for (const double tolerance : kTolerances) {
      std::vector<Sample> samples;
      long steps = 0;
      bool finite = true;
      auto run = [&](bool record) {
        Array x = x0;
        auto stepper = odeint::make_controlled(tolerance, tolerance, odeint::runge_kutta_fehlberg78<Array>());
        double t = 0.0, dt = 1e-6;
        steps = 0;
        if (record) samples.push_back(sample_of(model, x, e0));
        for (long i = 1; i <= std::lround(duration / kInterval) && finite; ++i) {
          const double t_sample = i * kInterval;
          while (t < t_sample && finite) {
            double trial = std::min(dt, t_sample - t);
            const double clipped = trial;
            if (stepper.try_step(system, x, t, trial) == odeint::success) {
              ++steps;
              if (clipped < dt) trial = std::max(trial, dt);  // a clipped step does not shrink the next
              finite = std::all_of(x.begin(), x.end(), [](double v) { return std::isfinite(v); });
            }
            dt = trial;
          }
          if (record) samples.push_back(sample_of(model, x, e0));
        }
      };
      run(true);
      const double cpu = finite ? median_cpu([&] { run(false); }, repeats) : NAN;
      Errors e = compare(samples, reference.trajectory.samples, config.top);
      if (!finite) e.attitude = e.normal_force = INFINITY;
      rows.push_back({label, "odeint runge_kutta_fehlberg78", k, tolerance, cpu, steps, e});
      std::fprintf(stderr, "  %s rkf78 %g: %.3g s\n", label.c_str(), tolerance, cpu);
      if (!(cpu <= kMaxCpu)) break;
    }
  }
  if (lambda > 0.0) {
    Vector ux0(Viscous::kStateSize);
    for (int i = 0; i < Viscous::kStateSize; ++i) ux0[i] = x0[i];
    const auto stiff_system = std::make_pair(UblasRhs{&model}, UblasJacobian{&model});
    for (const double tolerance : {1e-6, 1e-7, 1e-8, 1e-9, 1e-10, 1e-11, 1e-12}) {
      std::vector<Sample> samples;
      long steps = 0;
      auto run = [&](bool record) {
        Vector x = ux0;
        auto stepper = odeint::make_dense_output(tolerance, tolerance, odeint::rosenbrock4<double>());
        steps = static_cast<long>(odeint::integrate_const(stepper, stiff_system, x, 0.0, duration + 0.5 * kInterval,
                                                          kInterval, [&](const Vector& xs, double) {
                                                            if (record) samples.push_back(sample_of(model, xs, e0));
                                                          }));
      };
      const double start = cpu_seconds();
      run(true);
      const double first = cpu_seconds() - start;
      const double cpu = first > kMaxCpu ? first : median_cpu([&] { run(false); }, repeats);
      rows.push_back({label, "odeint rosenbrock4 (dense output)", k, tolerance, cpu, steps,
                      compare(samples, reference.trajectory.samples, config.top)});
      std::fprintf(stderr, "  %s rosenbrock4 %g: %.3g s\n", label.c_str(), tolerance, cpu);
      if (cpu > kMaxCpu) break;
    }
  }
}

}  // namespace

int main(int argc, char** argv) {
  double duration = 10.0;
  std::string output_dir = ".", only;
  bool quick = false, with_peers = true, sweep = false;
  int repeats = 3;
  for (int i = 1; i < argc; ++i) {
    const std::string arg = argv[i];
    if (arg == "--duration" && i + 1 < argc) {
      duration = std::atof(argv[++i]);
    } else if (arg == "--output-dir" && i + 1 < argc) {
      output_dir = argv[++i];
    } else if (arg == "--case" && i + 1 < argc) {
      only = argv[++i];
    } else if (arg == "--quick") {
      quick = true;
      repeats = 1;
    } else if (arg == "--repeats" && i + 1 < argc) {
      repeats = std::max(1, std::atoi(argv[++i]));
    } else if (arg == "--no-peers") {
      with_peers = false;
    } else if (arg == "--sweep") {
      sweep = true;
    } else {
      std::cerr << "usage: viscous_default [--duration S] [--output-dir DIR] [--quick] [--case NAME] [--no-peers] [--sweep] [--repeats N]\n"
                   "The viscous default's error (attitude angle, R, energy balance) and CPU from k = 0 to\n"
                   "m/k = 1e-8 s against a reference, and radau9 / radau5 / dop853 against odeint's RKF78 and\n"
                   "rosenbrock4 at k = 0.5, 1e5 and 1e7; writes viscous_default.csv and viscous_peers.csv.\n";
      return arg == "--help" ? 0 : 2;
    }
  }
  if (!(duration > 0.0 && std::isfinite(duration))) {
    std::cerr << "viscous_default: --duration must be a finite number > 0\n";
    return 2;
  }
  const std::vector<double> all_k = {0.0, 0.02, 0.5, 5.0, 50.0, 500.0, 5e3, 5e4, 1e5, 1e6, 1e7};
  const std::vector<double> variant_k = {0.5, 5e3, 1e5, 1e7};
  std::ofstream csv(output_dir + "/viscous_default.csv");
  csv << "case,k,m_over_k,lambda,integrator,steps,cpu_seconds,event,max_attitude_error_rad,max_normal_force_error_mg,"
         "max_energy_balance_error_mgh,reference,reference_self_check_rad,reference_self_check_mg,"
         "reference_cross_check_rad,reference_cross_check_mg,cross_check_span_s\n";
  csv.precision(4);
  std::printf("# bench/viscous_default (%g s, a state every 1 ms; CPU: median of %d run%s)\n\n"
              "The default (integrator: auto, default tolerance) against the reference:\n\n",
              duration, repeats, repeats == 1 ? "" : "s");
  std::printf("| case | k [N s/m] | lambda [1/s] | auto picks | steps | CPU [s] | attitude [rad] | R [m g] | E+W-E0 [m g h] | reference (self-check rad, m g) |\n");
  std::printf("|---|---|---|---|---|---|---|---|---|---|\n");
  std::vector<PeerRow> peer_rows;
  for (const Case& c : cases()) {
    if (!only.empty() && c.name != only) continue;
    for (const double k : c.name == "toy" ? all_k : variant_k) {
      if (quick && c.name != "toy" && k != 1e5) continue;
      SceneConfig config = c.config;
      config.top.friction = k;
      std::fprintf(stderr, "%s k=%g: reference\n", c.name.c_str(), k);
      const Reference reference = make_reference(config, duration);
      const Trajectory run = sample(config, duration);  // integrator: auto, default settings
      const double cpu = request_cpu(config, duration, repeats);
      const Errors e = compare(run.samples, reference.trajectory.samples, config.top);
      const std::string event = run.event == Event::kNone ? "" : std::string(to_string(run.event)) + " at " + number(run.event_time) + " s (reference " + number(reference.trajectory.event_time) + " s)";
      csv << c.name << "," << k << "," << (k > 0 ? config.top.mass / k : INFINITY) << "," << friction_rate(config.top)
          << "," << csv_safe(run.integrator) << "," << run.steps << "," << cpu << "," << event << "," << e.attitude << ","
          << e.normal_force << "," << e.balance << "," << reference.method << "," << reference.self_check_attitude << ","
          << reference.self_check_force << "," << reference.cross_check_attitude << "," << reference.cross_check_force
          << "," << reference.cross_check_span << "\n";
      csv.flush();
      std::printf("| %s | %s | %s | %s | %ld | %.3g | %.2g | %.2g | %.2g | %s (%.1g, %.1g)%s |\n", c.name.c_str(),
                  number(k).c_str(), number(friction_rate(config.top)).c_str(), run.integrator.c_str(), run.steps, cpu,
                  e.attitude, e.normal_force, e.balance, reference.method.c_str(), reference.self_check_attitude,
                  reference.self_check_force,
                  std::isnan(reference.cross_check_attitude)
                      ? ""
                      : (", vs dop853 over " + number(reference.cross_check_span) + " s: " +
                         number(reference.cross_check_attitude) + " rad, " + number(reference.cross_check_force) + " m g")
                            .c_str());
      std::fflush(stdout);
      if (with_peers && c.name == "toy" && (k == 0.5 || k == 1e5 || k == 1e7))
        peers(c, k, duration, reference, repeats, true, peer_rows);
      else if (sweep)
        peers(c, k, duration, reference, repeats, false, peer_rows);
    }
  }
  if (!peer_rows.empty()) {
    std::ofstream peer_csv(output_dir + "/viscous_peers.csv");
    peer_csv << "case,method,k,tolerance,cpu_seconds,steps,max_attitude_error_rad,max_normal_force_error_mg,"
                "max_energy_balance_error_mgh,meets_target\n";
    peer_csv.precision(4);
    std::printf("\nradau9, radau5 and dop853 through the Simulator, odeint's RKF78 (steps clipped at the samples) and "
                "rosenbrock4 (dense output):\n");
    std::printf("\n| case | method | tolerance | steps | CPU [s] | attitude [rad] | R [m g] | E+W-E0 [m g h] | meets 1e-9 rad, 1e-8 m g |\n");
    std::printf("|---|---|---|---|---|---|---|---|---|\n");
    for (const PeerRow& r : peer_rows) {
      peer_csv << csv_safe(r.label) << "," << r.method << "," << r.k << "," << r.tolerance << "," << r.cpu << "," << r.steps
               << "," << r.errors.attitude << "," << r.errors.normal_force << "," << r.errors.balance << ","
               << (r.errors.meets_target() ? "yes" : "no") << "\n";
      std::printf("| %s | %s | %g | %ld | %.3g | %.2g | %.2g | %.2g | %s |\n", r.label.c_str(), r.method.c_str(), r.tolerance,
                  r.steps, r.cpu, r.errors.attitude, r.errors.normal_force, r.errors.balance,
                  r.errors.meets_target() ? "yes" : "no");
    }
  }
  return 0;
}
