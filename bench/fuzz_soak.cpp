// Issue 10, item 4: the long runs behind the README's "Reliability" figures.
//   fuzz: the test's harness (test/fuzz_harness.hpp) over many more cases (1e5 by default), the
//         same promises; writes DIR/fuzz.md and exits 1 if any is broken.
//   soak: each shipped scene (config/*.yaml's toy top) with the default integrator for one
//         simulated hour at the node's 1 kHz (3.6e6 requests): | |q| - 1 |, the energy balance
//         E + W - E0 per 10-minute window (no drift: the windows' worst does not grow), and, for
//         the integrable scenes, the attitude against dop853 at tolerance 1e-13 after the hour;
//         writes DIR/soak.md.
//   replay: fuzz_soak --seed N prints a fuzz case's keys (as --set options for simulate) and its
//         outcome.
// Usage: fuzz_soak [--output-dir DIR] [--cases N] [--hours H] [--skip-fuzz] [--skip-soak] [--seed N]
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <string>
#include <vector>

#include "fuzz_harness.hpp"
#include "spinning_top/scenes/fixed_tip.hpp"
#include "spinning_top/scenes/frictionless.hpp"
#include "spinning_top/scenes/viscous.hpp"

namespace spinning_top {
namespace {

double cpu_seconds() { return static_cast<double>(std::clock()) / CLOCKS_PER_SEC; }

std::string format(const char* pattern, double value) {
  char buffer[64];
  std::snprintf(buffer, sizeof buffer, pattern, value);
  return buffer;
}

int replay(unsigned long long seed) {
  fuzz::Case keys_case(seed);
  std::printf("seed %llu:", seed);
  for (const auto& kv : keys_case.draw_keys()) std::printf(" --set '%s=%s'", kv.first.c_str(), kv.second.c_str());
  std::printf("\n");
  fuzz::Case c(seed);
  const fuzz::Outcome o = c.run(fuzz::Limits());
  std::printf("outcome: %s%s, event %s, integrator %s, %d updates applied, %d refused, %d resets\n",
              o.kind == fuzz::Outcome::Kind::kRefused ? "refused " : o.kind == fuzz::Outcome::Kind::kRan ? "ran" : "out of budget",
              o.refused_key.c_str(), o.event == Event::kNone ? "none" : to_string(o.event), o.integrator.c_str(),
              o.updates_applied, o.updates_refused, o.resets);
  for (const std::string& f : o.failures) std::printf("BROKEN: %s\n", f.c_str());
  return o.failures.empty() ? 0 : 1;
}

int run_fuzz(long cases, const std::string& dir) {
  const double start = cpu_seconds();
  const fuzz::Limits limits;
  fuzz::Tally t;
  for (long seed = 1; seed <= cases; ++seed) {
    t.add(fuzz::Case(static_cast<unsigned long long>(seed)).run(limits), static_cast<unsigned long long>(seed));
    if (seed % 10000 == 0) std::fprintf(stderr, "fuzz: %ld cases, %zu broken promises\n", seed, t.failures.size());
  }
  const double cpu = cpu_seconds() - start;
  std::ofstream md(dir + "/fuzz.md");
  md << "Fuzz (bench/fuzz_soak, the harness of test/test_fuzz.cpp): " << cases << " cases, seeds 1 to " << cases
     << ", " << format("%.0f", cpu) << " s of CPU (slowest case " << format("%.2f", t.slowest) << " s wall, seed "
     << t.slowest_seed << ").\n\n";
  md << "| outcome | cases |\n|---|---|\n";
  md << "| refused at construction, naming the key | " << cases - t.ran << " |\n";
  md << "| ran | " << t.ran << " |\n";
  md << "| ... of which stopped by their work budget (" << limits.steps_per_case << " steps) | " << t.out_of_budget
     << " |\n";
  for (const auto& kv : t.events) md << "| ... ended by event " << kv.first << " | " << kv.second << " |\n";
  md << "\nLive updates applied " << t.updates_applied << ", refused " << t.updates_refused
     << " (state unchanged, bit for bit); resets " << t.resets << ".\n";
  md << "Worst | |q| - 1 | " << format("%.2g", t.worst_norm_error) << "; worst energy-balance drift "
     << format("%.2f", t.worst_balance) << " of the allowed 1e-3 (|B0| + m g h).\n";
  md << "**Broken promises: " << t.failures.size() << "**.\n\n";
  md << "Methods that ran:";
  for (const auto& kv : t.methods) md << " " << kv.first << " " << kv.second << ";";
  md << "\n\nRefusals by key:";
  for (const auto& kv : t.refused_by_key) md << " " << kv.first << " " << kv.second << ";";
  md << "\n";
  for (std::size_t i = 0; i < std::min<std::size_t>(t.failures.size(), 50); ++i) md << "\n- " << t.failures[i];
  std::printf("fuzz: %ld cases, %ld ran, %zu broken promises, %.0f s CPU\n", cases, t.ran, t.failures.size(), cpu);
  return t.failures.empty() ? 0 : 1;
}

SceneConfig toy_scene(SceneType scene) {
  // config/*.yaml
  SceneConfig config;
  config.scene = scene;
  config.initial.tilt = 0.3;
  config.initial.spin = 150.0;
  if (scene == SceneType::kViscous) config.top.friction = 0.02;
  return config;
}

/// B = E - C wZ^2/2 + W of a snapshot, computed by the scene's model from the state the snapshot
/// shows (not from E, whose rounding at the spin's energy would hide 1e-15 of B).
double energy_balance(const SceneConfig& config, const Snapshot& s) {
  auto attitude_and_rates = [&](auto& y) {
    y[0] = s.attitude.w(), y[1] = s.attitude.x(), y[2] = s.attitude.y(), y[3] = s.attitude.z();
    y[4] = s.body_rates.x(), y[5] = s.body_rates.y();
  };
  switch (config.scene) {
    case SceneType::kFixedTip: {
      FixedTip::State y;
      attitude_and_rates(y);
      return FixedTip(config.top, config.initial).energy_balance(y);
    }
    case SceneType::kFrictionless: {
      Frictionless::State y;
      attitude_and_rates(y);
      return Frictionless(config.top, config.initial).energy_balance(y);
    }
    case SceneType::kViscous: {
      Viscous::State y;
      attitude_and_rates(y);
      y[Viscous::kX] = s.outputs.center_of_mass.x(), y[Viscous::kY] = s.outputs.center_of_mass.y();
      y[Viscous::kVx] = s.outputs.center_of_mass_velocity.x(), y[Viscous::kVy] = s.outputs.center_of_mass_velocity.y();
      y[Viscous::kWork] = s.outputs.dissipated_energy;
      return Viscous(config.top, config.initial).energy_balance(y);
    }
  }
  return 0.0;
}

double attitude_angle(const Quaternion& a, const Quaternion& b) {
  return 2.0 * std::asin(std::min(1.0, (a.conjugate() * b).vec().norm()));
}

void run_soak(double hours, const std::string& dir) {
  std::ofstream md(dir + "/soak.md");
  const double duration = 3600.0 * hours, window = 600.0 * std::min(1.0, hours);
  md << "Soak (bench/fuzz_soak): each shipped scene with the default integrator for " << format("%g", duration)
     << " s simulated at 1 kHz (" << format("%.3g", duration * 1000) << " requests, as the node): the energy balance "
        "|B - B0| / (|B0| + m g h), B = E - C wZ^2/2 + W computed by the scene's model from each published state, "
        "worst per " << format("%g", window) << " s window (a drift would grow from window to window); the attitude "
        "after the run against dop853 at tolerances 1e-13 and 1e-14 (their distance to each other shows the "
        "reference's own error).\n\n";
  md << "| scene | method | CPU [s] | worst \\| \\|q\\| - 1 \\| | energy balance per window (first ... last) | "
        "attitude vs dop853 1e-13 / 1e-14 (1e-13 vs 1e-14) | ended |\n|---|---|---|---|---|---|---|\n";
  for (SceneType scene : {SceneType::kFixedTip, SceneType::kFrictionless, SceneType::kViscous}) {
    const SceneConfig config = toy_scene(scene);
    auto simulator = make_simulator(config);
    const TopParameters& top = config.top;
    const double b0 = energy_balance(config, simulator->snapshot());
    const double scale = std::abs(b0) + top.mass * top.gravity * top.tip_distance;
    std::vector<double> windows;
    double worst_norm = 0.0, window_worst = 0.0;
    Event event = Event::kNone;
    const long ticks = std::lround(duration * 1000.0);
    const double cpu_start = cpu_seconds();
    long tick = 1;
    for (; tick <= ticks && event == Event::kNone; ++tick) {
      event = simulator->advance_to(static_cast<double>(tick) / 1000.0);
      const Snapshot s = simulator->snapshot();
      worst_norm = std::max(worst_norm, std::abs(s.attitude.norm() - 1.0));
      window_worst = std::max(window_worst, std::abs(energy_balance(config, s) - b0) / scale);
      if (tick % std::lround(window * 1000.0) == 0) {
        windows.push_back(window_worst);
        window_worst = 0.0;
      }
    }
    const double cpu = cpu_seconds() - cpu_start;
    if (tick % std::lround(window * 1000.0) != 1) windows.push_back(window_worst);  // the last, partial window
    std::string against = "-";
    if (scene != SceneType::kViscous && event == Event::kNone) {
      Quaternion references[2];
      for (int k = 0; k < 2; ++k) {
        SceneConfig reference = config;
        reference.integrator.type = IntegratorType::kDop853;
        reference.integrator.tolerance = k == 0 ? 1e-13 : 1e-14;
        auto dop853 = make_simulator(reference);
        for (long i = 1; i <= std::lround(duration); ++i) dop853->advance_to(static_cast<double>(i));
        references[k] = dop853->snapshot().attitude;
      }
      const Quaternion q = simulator->snapshot().attitude;
      against = format("%.2g / ", attitude_angle(q, references[0])) + format("%.2g rad", attitude_angle(q, references[1])) +
                format(" (%.2g rad)", attitude_angle(references[0], references[1]));
    }
    std::string series;
    for (std::size_t i = 0; i < windows.size(); ++i) series += (i ? ", " : "") + format("%.1e", windows[i]);
    const double worst = windows.empty() ? window_worst : *std::max_element(windows.begin(), windows.end());
    md << "| " << to_string(scene) << " | " << to_string(simulator->integrator_choice().method) << " | "
       << format("%.1f", cpu) << " | " << format("%.1e", worst_norm) << " | " << series << " | " << against << " | "
       << (event == Event::kNone ? format("ran %g s", duration) : std::string(to_string(event)) + format(" at %.6g s", simulator->time()))
       << " |\n";
    std::printf("soak %s: %.1f s CPU, worst |q| error %.1e, worst balance %.1e, vs dop853 %s\n", to_string(scene), cpu,
                worst_norm, worst, against.c_str());
  }
}

}  // namespace
}  // namespace spinning_top

int main(int argc, char** argv) {
  std::string dir = ".";
  long cases = 100000;
  double hours = 1.0;
  bool fuzz = true, soak = true;
  for (int i = 1; i < argc; ++i) {
    const std::string arg = argv[i];
    auto value = [&]() -> std::string {
      if (i + 1 >= argc) {
        std::fprintf(stderr, "fuzz_soak: %s needs a value\n", arg.c_str());
        std::exit(2);
      }
      return argv[++i];
    };
    if (arg == "--output-dir") dir = value();
    else if (arg == "--cases") cases = std::stol(value());
    else if (arg == "--hours") hours = std::stod(value());
    else if (arg == "--skip-fuzz") fuzz = false;
    else if (arg == "--skip-soak") soak = false;
    else if (arg == "--seed") return spinning_top::replay(std::stoull(value()));
    else {
      std::fprintf(stderr, "usage: fuzz_soak [--output-dir DIR] [--cases N] [--hours H] [--skip-fuzz] [--skip-soak] [--seed N]\n");
      return 2;
    }
  }
  int status = 0;
  if (soak) spinning_top::run_soak(hours, dir);
  if (fuzz) status = spinning_top::run_fuzz(cases, dir);
  return status;
}
