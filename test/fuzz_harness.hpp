// The fuzz harness of issue 10, shared by the test run (test/test_fuzz.cpp: a few thousand
// cases) and the benchmark (bench/fuzz_soak.cpp: 1e5 cases). A case is a random configuration
// given as the keys of a scene file (text, through the same parse_scene_config() as the node and
// `simulate`), log-uniform over many decades, with garbage mixed in (NaN, inf, 1e400, words), run
// to a random duration with live updates (g, k, tolerance, step; garbage too) and resets.
// run_case() checks what the core promises and returns every broken promise as text:
//   - a refusal is an InvalidParameter whose key is a configuration key and whose message starts
//     with it; a refused live update changes nothing (the snapshot stays bit for bit);
//   - no other exception; no hang (a per-case wall bound, a generous guard);
//   - every snapshot finite, | |q| - 1 | <= 1e-12, R >= 0, e_Zz > 0;
//   - the energy balance B = E - C wZ^2/2 + W within the guard's tolerance of its value at the
//     last (re)start or update (events.hpp: kEnergyBalanceTolerance), so energy plus friction
//     work never grows beyond it in the viscous scene;
//   - no non_finite event.
#pragma once

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <map>
#include <random>
#include <set>
#include <string>
#include <vector>

#include "spinning_top/config.hpp"
#include "spinning_top/integrator_registry.hpp"
#include "spinning_top/simulator.hpp"

namespace spinning_top {
namespace fuzz {

struct Limits {
  long steps_per_case = 20000;    ///< work budget of one case (the core's WorkBudget), all requests together
  double wall_per_case = 30.0;    ///< [s] a case slower than this is reported as a hang
  double max_duration = 2.0;      ///< [s] simulated, drawn log-uniform from 1e-3 s
  int samples = 20;               ///< requests per case
};

struct Outcome {
  enum class Kind { kRefused, kRan, kOutOfBudget } kind = Kind::kRefused;
  std::string refused_key;     ///< the key named by the refusal at construction
  Event event = Event::kNone;  ///< what ended the run (kNone: reached its duration)
  std::string integrator;      ///< what ran (integrator_choice().method), "" when refused
  SceneType scene = SceneType::kFixedTip;
  int updates_refused = 0, updates_applied = 0, resets = 0;
  double worst_norm_error = 0.0;     ///< max | |q| - 1 |
  double worst_balance = 0.0;        ///< max |B - B0| as a fraction of what is allowed (1: the limit)
  double wall = 0.0;                 ///< [s]
  std::vector<std::string> failures; ///< broken promises, each with the case's seed
};

class Case {
 public:
  explicit Case(unsigned long long seed) : seed_(seed), rng_(seed) {}

  /// The scene file's keys of this case.
  ParameterMap draw_keys() {
    ParameterMap keys;
    const double scene_draw = uniform(0.0, 1.0);
    const std::string scene = scene_draw < 0.33 ? "fixed_tip" : scene_draw < 0.66 ? "frictionless" : scene_draw < 0.995 ? "viscous" : "ice";
    keys["scene"] = scene;
    keys["integrator"] = draw_integrator();
    keys["mass"] = number(log_uniform(1e-4, 1e3));
    const double a = log_uniform(1e-8, 1e1);
    keys["inertia_transverse"] = number(a);
    keys["inertia_axial"] = number(a * uniform(0.01, 2.02));  // a few above 2A: refused
    keys["tip_distance"] = number(chance(0.05) ? 0.0 : log_uniform(1e-5, 1.0));
    keys["gravity"] = number(chance(0.05) ? 0.0 : log_uniform(1e-2, 1e3));
    if (scene == "viscous" || chance(0.02)) keys["friction"] = number(chance(0.05) ? 0.0 : log_uniform(1e-6, 1e12));
    keys["initial/tilt"] = number(chance(0.1) ? log_uniform(1e-9, 1e-3) : uniform(-1.6, 1.6));
    keys["initial/spin"] = number(chance(0.05) ? 0.0 : signed_log_uniform(1e-2, 1e7));
    if (chance(0.7)) keys["initial/precession_rate"] = number(signed_log_uniform(1e-3, 1e4));
    if (chance(0.7)) keys["initial/nutation_rate"] = number(signed_log_uniform(1e-3, 1e4));
    keys["initial/heading"] = number(uniform(-10.0, 10.0));
    keys["initial/spin_angle"] = number(uniform(-10.0, 10.0));
    if (scene == "viscous" || chance(0.02)) {
      if (chance(0.5)) keys["initial/velocity_x"] = number(signed_log_uniform(1e-4, 10.0));
      if (chance(0.5)) keys["initial/velocity_y"] = number(signed_log_uniform(1e-4, 10.0));
    }
    if (chance(0.5)) keys["tolerance"] = number(log_uniform(1e-14, 1e-2));
    if (chance(0.5)) keys["step"] = number(log_uniform(1e-8, 1e-1));
    for (auto& kv : keys)
      if (chance(0.015)) kv.second = garbage();
    return keys;
  }

  Outcome run(const Limits& limits) {
    const auto wall_start = std::chrono::steady_clock::now();
    Outcome outcome;
    const ParameterMap keys = draw_keys();
    std::unique_ptr<Simulator> simulator;
    try {
      simulator = make_simulator(parse_scene_config(keys, /*require_all=*/false));
    } catch (const InvalidParameter& refusal) {
      outcome.refused_key = refusal.parameter();
      check_refusal(refusal, outcome);
      return outcome;
    } catch (const std::exception& other) {
      fail(outcome, std::string("construction threw a non-InvalidParameter exception: ") + other.what());
      return outcome;
    }
    outcome.kind = Outcome::Kind::kRan;
    outcome.scene = simulator->config().scene;
    const double duration = log_uniform(1e-3, limits.max_duration);
    rebaseline(*simulator);
    check_snapshot(*simulator, outcome);
    outcome.event = simulator->event();
    for (int i = 1; i <= limits.samples && outcome.event == Event::kNone; ++i) {
      const double t = duration * i / limits.samples;
      try {
        const long remaining = limits.steps_per_case - simulator->steps() - steps_before_reset_;
        outcome.event = simulator->advance_to(t, WorkBudget::steps(std::max(0L, remaining)));
        if (outcome.event == Event::kNone && simulator->time() < t) {
          outcome.kind = Outcome::Kind::kOutOfBudget;
          check_snapshot(*simulator, outcome);
          break;
        }
      } catch (const InvalidParameter& refusal) {
        // A request may be refused only for a fixed step's substep count (1e12 per request).
        if (refusal.parameter() != "step") fail(outcome, std::string("advance_to refused: ") + refusal.what());
        break;
      } catch (const std::exception& other) {
        fail(outcome, std::string("advance_to threw: ") + other.what());
        break;
      }
      check_snapshot(*simulator, outcome);
      if (outcome.event != Event::kNone) break;
      if (chance(0.15)) live_update(*simulator, outcome);
      if (chance(0.03)) {
        steps_before_reset_ += simulator->steps();
        simulator->reset();
        ++outcome.resets;
        rebaseline(*simulator);
        check_snapshot(*simulator, outcome);
        outcome.event = simulator->event();
      }
      if (seconds_since(wall_start) > limits.wall_per_case) {
        fail(outcome, "hang guard: more than " + number(limits.wall_per_case) + " s of wall time");
        break;
      }
    }
    if (outcome.event == Event::kNonFinite) fail(outcome, "non_finite event");
    outcome.integrator = to_string(simulator->integrator_choice().method);
    outcome.wall = seconds_since(wall_start);
    return outcome;
  }

  unsigned long long seed() const { return seed_; }

 private:
  static std::string number(double value) {
    char buffer[40];
    std::snprintf(buffer, sizeof buffer, "%.17g", value);
    return buffer;
  }
  static double seconds_since(std::chrono::steady_clock::time_point start) {
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  }
  double uniform(double lo, double hi) { return std::uniform_real_distribution<double>(lo, hi)(rng_); }
  bool chance(double p) { return uniform(0.0, 1.0) < p; }
  double log_uniform(double lo, double hi) { return std::exp(uniform(std::log(lo), std::log(hi))); }
  double signed_log_uniform(double lo, double hi) { return (chance(0.5) ? -1.0 : 1.0) * log_uniform(lo, hi); }
  std::string garbage() {
    static const char* const values[] = {"nan", "inf", "-inf", "1e400", "-1", "0", "abc", "", "1e-320", "0x10",
                                         "1,5", " 2", "9.8kg", "true"};
    return values[std::uniform_int_distribution<int>(0, 13)(rng_)];
  }
  std::string draw_integrator() {
    if (chance(0.3)) return "auto";
    if (chance(0.01)) return "euler";
    const auto& rows = integrator_registry();
    return rows[std::uniform_int_distribution<std::size_t>(0, rows.size() - 1)(rng_)].name;
  }
  /// A live value: like the file's, or garbage, or a huge or tiny extreme.
  double live_value(double lo, double hi) {
    const double draw = uniform(0.0, 1.0);
    if (draw < 0.05) return std::numeric_limits<double>::quiet_NaN();
    if (draw < 0.08) return std::numeric_limits<double>::infinity();
    if (draw < 0.10) return -log_uniform(lo, hi);
    if (draw < 0.12) return 1e300;
    return log_uniform(lo, hi);
  }

  void fail(Outcome& outcome, const std::string& what) {
    outcome.failures.push_back("seed " + std::to_string(seed_) + ": " + what);
  }

  void check_refusal(const InvalidParameter& refusal, Outcome& outcome) {
    const std::vector<std::string> keys = parameter_keys();
    const std::string& key = refusal.parameter();
    if (std::find(keys.begin(), keys.end(), key) == keys.end() && key != "initial")
      fail(outcome, "refusal names '" + key + "', not a configuration key: " + refusal.what());
    if (std::string(refusal.what()).rfind(key + ": ", 0) != 0)
      fail(outcome, std::string("refusal message does not start with its key: ") + refusal.what());
  }

  void rebaseline(const Simulator& simulator) { baseline_ = balance(simulator.snapshot(), simulator.config().top); }

  static double balance(const Snapshot& s, const TopParameters& top) {
    const double spin_energy = 0.5 * top.inertia_axial * s.body_rates.z() * s.body_rates.z();
    return s.outputs.energy - spin_energy + s.outputs.dissipated_energy;
  }

  void check_snapshot(const Simulator& simulator, Outcome& outcome) {
    const Snapshot s = simulator.snapshot();
    const ModelOutputs& o = s.outputs;
    const bool finite = std::isfinite(s.time) && s.attitude.coeffs().allFinite() && s.body_rates.allFinite() &&
                        o.center_of_mass.allFinite() && o.contact_point.allFinite() && o.contact_force.allFinite() &&
                        std::isfinite(o.normal_force) && std::isfinite(o.energy) && std::isfinite(o.dissipated_energy);
    if (!finite) {
      fail(outcome, "non-finite snapshot at t = " + number(s.time));
      return;
    }
    const std::string where = " at t = " + number(s.time) + " in " + to_string(s.phase) + (simulator.event() == Event::kNone ? "" : std::string(" (event ") + to_string(simulator.event()) + ")") + ", " + simulator.integrator_description();
    const double norm_error = std::abs(s.attitude.norm() - 1.0);
    outcome.worst_norm_error = std::max(outcome.worst_norm_error, norm_error);
    if (norm_error > 1e-12) fail(outcome, "| |q| - 1 | = " + number(norm_error) + where);
    // R >= 0, up to the round-off of a floor force that is 0 in theory (g = 0 and the top at
    // rest apart from its spin: R = m z_G'' = 0 comes out as +-1e-17 of its terms' scale).
    const TopParameters& p = simulator.config().top;
    const double force_scale = p.mass * (p.gravity + p.tip_distance * s.body_rates.squaredNorm());
    const bool initial_event = s.time == 0.0 && simulator.event() != Event::kNone;  // the state as given
    if (o.normal_force < -64.0 * 2.2e-16 * force_scale && !initial_event)
      fail(outcome, "R = " + number(o.normal_force) + " < 0 in a snapshot" + where);
    // e_Zz as the model computes it (kinematics.hpp, vertical_in_body): at a located fall it is
    // within ulps of 0, where another formula (the rotation matrix of q) may round to the other side.
    const Quaternion& q = s.attitude;
    // (A top with a rim may turn past the horizontal in flight, its rim above the floor.)
    if (!(1.0 - 2.0 * (q.x() * q.x() + q.y() * q.y()) > 0.0) &&
        !(s.phase == Phase::kFlight && simulator.config().top.rim_radius > 0.0))
      fail(outcome, "e_Zz <= 0 in a snapshot" + where);
    if (!(o.contact_point.z() >= 0.0)) fail(outcome, "the tip under the floor, z_P = " + number(o.contact_point.z()) + where);
    if (s.phase == Phase::kFlight && (o.normal_force != 0.0 || o.contact_force.norm() != 0.0))
      fail(outcome, "a floor force in flight" + where);
    const TopParameters& top = simulator.config().top;
    const double spin_energy = 0.5 * top.inertia_axial * s.body_rates.z() * s.body_rates.z();
    const double scale = std::abs(baseline_) + top.mass * top.gravity * top.tip_distance;
    // The tolerance of the guard, plus the rounding of E - C wZ^2/2 computed here from E.
    const double allowed = kEnergyBalanceTolerance * scale + 64.0 * 2.2e-16 * (spin_energy + scale);
    const double drift = std::abs(balance(s, top) - baseline_);
    if (allowed > 0.0) outcome.worst_balance = std::max(outcome.worst_balance, drift / allowed);
    if (drift > allowed)
      fail(outcome, "energy balance moved by " + number(drift) + " J, more than " + number(allowed) + " J, at t = " +
                        number(s.time) + " (" + simulator.integrator_description() + ")");
  }

  void live_update(Simulator& simulator, Outcome& outcome) {
    TopParameters top = simulator.config().top;
    IntegratorSettings integrator = simulator.config().integrator;
    switch (std::uniform_int_distribution<int>(0, 3)(rng_)) {
      case 0: top.gravity = live_value(1e-2, 1e3); break;
      case 1: top.friction = live_value(1e-6, 1e12); break;
      case 2: integrator.tolerance = live_value(1e-14, 1e-2); break;
      default: integrator.step = live_value(1e-8, 1e-1); break;
    }
    const Snapshot before = simulator.snapshot();
    try {
      simulator.update(top, integrator);
      ++outcome.updates_applied;
      rebaseline(simulator);
      check_snapshot(simulator, outcome);
    } catch (const InvalidParameter& refusal) {
      ++outcome.updates_refused;
      check_refusal(refusal, outcome);
      const Snapshot after = simulator.snapshot();
      if (!(after.time == before.time && after.attitude.coeffs() == before.attitude.coeffs() &&
            after.body_rates == before.body_rates && after.outputs.normal_force == before.outputs.normal_force))
        fail(outcome, std::string("a refused update changed the state: ") + refusal.what());
    } catch (const std::exception& other) {
      fail(outcome, std::string("update threw a non-InvalidParameter exception: ") + other.what());
    }
  }

  unsigned long long seed_;
  std::mt19937_64 rng_;
  double baseline_ = 0.0;
  long steps_before_reset_ = 0;
};

/// Many cases' outcomes summed (test_fuzz, bench/fuzz_soak): what they reached and every broken
/// promise.
struct Tally {
  long cases = 0, ran = 0, out_of_budget = 0, updates_applied = 0, updates_refused = 0, resets = 0;
  std::map<std::string, long> refused_by_key, events, methods;  ///< events: "(none)" for a full run
  std::set<SceneType> scenes_run;
  std::vector<std::string> failures;
  double worst_norm_error = 0.0, worst_balance = 0.0, wall = 0.0, slowest = 0.0;
  unsigned long long slowest_seed = 0;

  void add(const Outcome& o, unsigned long long seed) {
    ++cases;
    failures.insert(failures.end(), o.failures.begin(), o.failures.end());
    wall += o.wall;
    if (o.wall > slowest) slowest = o.wall, slowest_seed = seed;
    if (o.kind == Outcome::Kind::kRefused) {
      ++refused_by_key[o.refused_key];
      return;
    }
    ++ran;
    scenes_run.insert(o.scene);
    ++methods[o.integrator];
    if (o.kind == Outcome::Kind::kOutOfBudget) ++out_of_budget;
    ++events[o.event == Event::kNone ? "(none)" : to_string(o.event)];
    updates_applied += o.updates_applied;
    updates_refused += o.updates_refused;
    resets += o.resets;
    worst_norm_error = std::max(worst_norm_error, o.worst_norm_error);
    worst_balance = std::max(worst_balance, o.worst_balance);
  }
};

}  // namespace fuzz
}  // namespace spinning_top
