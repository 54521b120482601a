// The fuzz harness of issue 10 (and issue 19's scene-file part, SceneFileCase below), shared by the test run (test/test_fuzz.cpp: a few thousand
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
#include <fstream>
#include <map>
#include <random>
#include <regex>
#include <set>
#include <string>
#include <vector>

#include "spinning_top/config.hpp"
#include "spinning_top/integrator_registry.hpp"
#include "spinning_top/scene_file.hpp"
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
        const long remaining = limits.steps_per_case - simulator->work() - steps_before_reset_;
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
        steps_before_reset_ += simulator->work();
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


// ---------------------------------------------------------------------------------------------
// Issue 19: the scene file's structure. A SceneFileCase writes a random YAML file: a scene's keys
// in random shapes (block or flow maps, nested or flat initial/..., comments, CRLF, document
// markers) with random mutations (anchors and aliases, a small alias bomb, merge keys, lists,
// duplicate keys, a second document, deep nesting, null values, tags, quotes, unknown keys,
// stray bytes), and its numbers in random forms (17 or 6 digits, exponents, integers, leading
// zeros, underscores, hex/octal/binary, sexagesimal, .inf/.nan, booleans, deg(), 1e400, 300
// digits). It is read as every front end reads one (read_scene_file, parse_scene_config with
// the required keys, make_simulator) and run briefly. Counted and returned as failures:
//   - a crash: any exception but SceneFileError / InvalidParameter (a real crash ends the test);
//   - a refusal whose message is not one line of at most 600 characters, or an InvalidParameter
//     whose message does not start with its key;
//   - a non-finite output or a non_finite event in the run;
//   - accepted garbage: a file that reads and validates although it holds something that must be
//     refused (an alias, a list, a quoted or tagged number, ...: the generator knows what it put
//     in), or a number whose text YAML 1.1 (PyYAML's resolver, what rosparam gives the node) and
//     YAML 1.2 (the core schema) do not both read as the number simulate reads (strtod), checked
//     by an oracle written from both specifications, independent of the reader.
namespace yaml_oracle {

/// The number YAML 1.1 (PyYAML's implicit resolver, rosparam's loader) reads from the plain
/// scalar `text`, as the double the node gets; false if it reads something else (text, a
/// boolean, null) or a number rosparam cannot send (an int beyond 32 bits) or not finite.
inline bool yaml11_number(const std::string& text, double& value) {
  static const std::regex kFloat(
      "^(?:[-+]?(?:[0-9][0-9_]*)\\.[0-9_]*(?:[eE][-+][0-9]+)?|\\.[0-9][0-9_]*(?:[eE][-+][0-9]+)?"
      "|[-+]?[0-9][0-9_]*(?::[0-5]?[0-9])+\\.[0-9_]*|[-+]?\\.(?:inf|Inf|INF)|\\.(?:nan|NaN|NAN))$");
  static const std::regex kInt(
      "^(?:[-+]?0b[0-1_]+|[-+]?0[0-7_]+|[-+]?(?:0|[1-9][0-9_]*)|[-+]?0x[0-9a-fA-F_]+"
      "|[-+]?[1-9][0-9_]*(?::[0-5]?[0-9])+)$");
  static const std::regex kAngle("^(?:deg|rad)\\([^)]*\\)$");  // rosparam's own resolvers
  if (text.size() > 400 || std::regex_match(text, kAngle)) return false;  // an angle: rosparam evaluates it
  std::string digits;
  for (char c : text)
    if (c != '_') digits += c;
  double sign = 1.0;
  std::string body = digits;
  if (!body.empty() && (body[0] == '-' || body[0] == '+')) {
    sign = body[0] == '-' ? -1.0 : 1.0;
    body = body.substr(1);
  }
  auto sexagesimal = [&](const std::string& b) {
    double v = 0.0;
    std::size_t start = 0;
    for (std::size_t colon; (colon = b.find(':', start)) != std::string::npos; start = colon + 1)
      v = v * 60.0 + std::strtod(b.substr(start, colon - start).c_str(), nullptr);
    return v * 60.0 + std::strtod(b.substr(start).c_str(), nullptr);
  };
  if (std::regex_match(text, kInt)) {
    double v = 0.0;
    if (body.find(':') != std::string::npos) v = sexagesimal(body);
    else if (body.rfind("0b", 0) == 0) v = static_cast<double>(std::strtoull(body.c_str() + 2, nullptr, 2));
    else if (body.rfind("0x", 0) == 0) v = static_cast<double>(std::strtoull(body.c_str() + 2, nullptr, 16));
    else if (body.size() > 1 && body[0] == '0') v = static_cast<double>(std::strtoull(body.c_str(), nullptr, 8));
    else v = std::strtod(body.c_str(), nullptr);
    value = sign * v;
    return std::abs(value) <= 2147483647.0;  // an XML-RPC int
  }
  if (std::regex_match(text, kFloat)) {
    value = body.find(':') != std::string::npos ? sign * sexagesimal(body) : std::strtod(digits.c_str(), nullptr);
    return std::isfinite(value);
  }
  return false;
}

/// The number YAML 1.2's core schema reads from the plain scalar `text`; false if not a finite
/// number.
inline bool yaml12_number(const std::string& text, double& value) {
  static const std::regex kDecimal("^[-+]?[0-9]+$");
  static const std::regex kOctal("^0o[0-7]+$");
  static const std::regex kHex("^0x[0-9a-fA-F]+$");
  static const std::regex kFloat("^[-+]?(?:\\.[0-9]+|[0-9]+(?:\\.[0-9]*)?)(?:[eE][-+]?[0-9]+)?$");
  if (text.size() > 400) return false;
  if (std::regex_match(text, kOctal)) value = static_cast<double>(std::strtoull(text.c_str() + 2, nullptr, 8));
  else if (std::regex_match(text, kHex)) value = static_cast<double>(std::strtoull(text.c_str() + 2, nullptr, 16));
  else if (std::regex_match(text, kDecimal) || std::regex_match(text, kFloat)) value = std::strtod(text.c_str(), nullptr);
  else return false;
  return std::isfinite(value);
}

/// Whether both YAML versions read the plain scalar `text` as the number simulate reads from it.
inline bool both_read_the_same_number(const std::string& text) {
  double v11 = 0.0, v12 = 0.0;
  if (!yaml11_number(text, v11) || !yaml12_number(text, v12)) return false;
  char* end = nullptr;
  const double parsed = std::strtod(text.c_str(), &end);
  return v11 == v12 && parsed == v12;
}

/// Whether both YAML versions read the plain scalar `text` as this text (not a number, boolean
/// or null): what a name (scene: fixed_tip) must be.
inline bool both_read_text(const std::string& text) {
  static const std::regex kNotText(
      "^(?:yes|Yes|YES|no|No|NO|true|True|TRUE|false|False|FALSE|on|On|ON|off|Off|OFF|~|null|Null|NULL|)$");
  double v = 0.0;
  return !std::regex_match(text, kNotText) && !yaml11_number(text, v) && !yaml12_number(text, v);
}

}  // namespace yaml_oracle

struct SceneFileOutcome {
  enum class Kind { kRefusedByReader, kRefusedByValidation, kRan } kind = Kind::kRefusedByReader;
  std::string reason;                 ///< the refusal's gist, for the tally
  bool had_defect = false;            ///< the file holds something that must be refused
  std::vector<std::string> failures;  ///< crashes, non-finite outputs, accepted garbage, bad messages
  std::vector<std::string> mutations; ///< what the generator did (for the tally and a replay)
};

class SceneFileCase {
 public:
  explicit SceneFileCase(unsigned long long seed) : seed_(seed), rng_(seed) {}

  /// The file's text (deterministic in the seed).
  std::string draw_text() {
    text_.clear();
    defects_.clear();
    mutations_.clear();
    quoted_numbers_.clear();
    // Half the files are hostile (every mutation and number form at its rate), half plain (only
    // the harmless variations of shape and number form), so that many run.
    hostile_ = chance(0.5);
    const double scene_draw = uniform(0.0, 1.0);
    const std::string scene = scene_draw < 0.35 ? "fixed_tip" : scene_draw < 0.7 ? "frictionless" : "viscous";
    std::vector<std::pair<std::string, std::string>> top = {
        {"scene", name_value(scene)},
        {"mass", number_value("mass", 0.1 * uniform(0.5, 2.0))},
        {"inertia_transverse", number_value("inertia_transverse", 4e-5 * uniform(0.8, 1.2))},
        {"inertia_axial", number_value("inertia_axial", 6e-5 * uniform(0.8, 1.2))},
        {"tip_distance", number_value("tip_distance", 0.02 * uniform(0.5, 2.0))},
    };
    if (chance(0.6)) top.emplace_back("gravity", number_value("gravity", 9.80665 * uniform(0.5, 2.0)));
    if (scene == "viscous") top.emplace_back("friction", number_value("friction", log_uniform(1e-3, 1.0)));
    if (chance(0.2)) top.emplace_back("integrator", name_value(chance(0.5) ? "dop853" : "auto"));
    if (chance(0.1)) top.emplace_back("after_lift_off", name_value(chance(0.5) ? "stop" : "fly"));
    std::vector<std::pair<std::string, std::string>> initial = {
        {"tilt", number_value("initial/tilt", uniform(0.05, 0.8))},
        {"spin", number_value("initial/spin", uniform(50.0, 300.0))},
    };
    if (chance(0.5)) initial.emplace_back("precession_rate", number_value("initial/precession_rate", uniform(-5.0, 5.0)));
    if (scene == "viscous" && chance(0.5))
      initial.emplace_back("velocity_x", number_value("initial/velocity_x", uniform(-0.5, 0.5)));

    // Structural mutations, each recorded; the ones that must be refused are defects.
    const double rate = hostile_ ? 1.0 : 0.0;
    if (chance(0.07 * rate)) defect("an unknown key"), top.emplace_back(chance(0.5) ? "colour" : "mas", "1.0");
    if (chance(0.05 * rate)) defect("a duplicate key"), top.emplace_back("mass", "0.2");
    if (chance(0.05 * rate)) defect("a list"), top.emplace_back("gravity", chance(0.5) ? "[9.8, 1.0]" : "\n  - 9.8\n  - 1.0");
    if (chance(0.05 * rate)) defect("a null value"), top.emplace_back("tolerance", chance(0.5) ? "" : "~");
    if (chance(0.05 * rate)) defect("a merge key"), top.emplace_back("<<", "{restitution: 0.5}");
    if (chance(0.04 * rate)) defect("a deep unknown map"), top.emplace_back("deep", deep_map(static_cast<int>(uniform(2, 20))));
    if (chance(0.04 * rate)) mutations_.push_back("a tagged key"), top.front().first = "!!str " + top.front().first;
    if (chance(0.04)) mutations_.push_back("a quoted key"), top.front().first = "\"" + top.front().first + "\"";

    const bool flow_initial = chance(0.3), flat_initial = !flow_initial && chance(0.2);
    const std::string eol = chance(0.1) ? "\r\n" : "\n";
    if (chance(0.1)) text_ += "# a scene file" + eol;
    if (chance(0.1)) text_ += "---" + eol;
    if (chance(0.08 * rate)) {
      defect("an anchor and an alias");
      const std::size_t i = std::uniform_int_distribution<std::size_t>(1, top.size() - 1)(rng_);
      top[i].second = "&v " + top[i].second;
      top.emplace_back("rim_distance", "*v");
    }
    if (chance(0.04 * rate)) defect("an alias bomb"), text_ += alias_bomb() + eol;
    if (chance(0.1) && !flat_initial) {
      text_ += "{";
      for (std::size_t i = 0; i < top.size(); ++i)
        text_ += (i ? ", " : "") + top[i].first + ": " + flow(top[i].second);
      text_ += ", initial: {";
      for (std::size_t i = 0; i < initial.size(); ++i)
        text_ += (i ? ", " : "") + initial[i].first + ": " + flow(initial[i].second);
      text_ += "}}" + eol;
    } else {
      for (const auto& [key, value] : top) text_ += key + ": " + value + (chance(0.1) ? "   # m" : "") + eol;
      if (flat_initial) {
        for (const auto& [key, value] : initial) text_ += "initial/" + key + ": " + value + eol;
      } else if (flow_initial) {
        text_ += "initial: {";
        for (std::size_t i = 0; i < initial.size(); ++i)
          text_ += (i ? ", " : "") + initial[i].first + ": " + flow(initial[i].second);
        text_ += "}" + eol;
      } else {
        text_ += "initial:" + eol;
        for (const auto& [key, value] : initial) text_ += "  " + key + ": " + value + eol;
      }
    }
    if (chance(0.04 * rate)) defect("a second document"), text_ += "---" + eol + "mass: -1" + eol;
    if (chance(0.03)) mutations_.push_back("a document end"), text_ += "..." + eol;
    if (chance(0.04 * rate)) defect("a top-level list"), text_ = "- " + text_;
    if (chance(0.05 * rate)) {
      // A stray byte somewhere: whatever it makes, an accepted file is still checked by the oracle.
      mutations_.push_back("a stray byte");
      static const char kBytes[] = {'{', '}', '[', ']', ':', '&', '*', '!', '|', '>', '\'', '"', '%', '@', '`', '\t', '\0', '#', ','};
      const std::size_t at = std::uniform_int_distribution<std::size_t>(0, text_.size() - 1)(rng_);
      text_.insert(text_.begin() + static_cast<long>(at), kBytes[std::uniform_int_distribution<int>(0, sizeof kBytes - 1)(rng_)]);
    }
    return text_;
  }

  SceneFileOutcome run(const std::string& path, double duration, long max_steps) {
    SceneFileOutcome outcome;
    const std::string text = draw_text();
    outcome.mutations = mutations_;
    outcome.had_defect = !defects_.empty();
    std::ofstream(path, std::ios::binary | std::ios::trunc) << text;
    ParameterMap keys;
    try {
      keys = read_scene_file(path);
    } catch (const SceneFileError& e) {
      outcome.kind = SceneFileOutcome::Kind::kRefusedByReader;
      outcome.reason = gist(e.what());
      check_message(e.what(), outcome);
      return outcome;
    } catch (const std::exception& e) {
      fail(outcome, std::string("crash: read_scene_file threw ") + e.what());
      return outcome;
    }
    SceneConfig config;
    std::unique_ptr<Simulator> simulator;
    try {
      config = parse_scene_config(keys, /*require_all=*/true);
      simulator = make_simulator(config);
    } catch (const InvalidParameter& e) {
      outcome.kind = SceneFileOutcome::Kind::kRefusedByValidation;
      outcome.reason = e.parameter();
      check_message(e.what(), outcome);
      if (std::string(e.what()).rfind(e.parameter() + ": ", 0) != 0)
        fail(outcome, std::string("a refusal that does not start with its key: ") + e.what());
      return outcome;
    } catch (const std::exception& e) {
      fail(outcome, std::string("crash: validation threw ") + e.what());
      return outcome;
    }
    // Accepted: it must hold nothing that must be refused, and mean the same to both YAML versions.
    outcome.kind = SceneFileOutcome::Kind::kRan;
    for (const std::string& d : defects_) fail(outcome, "accepted garbage: " + d);
    for (const auto& [key, value] : keys) {
      const bool text_key = key == "scene" || key == "integrator" || key == "after_lift_off";
      if (text_key ? !yaml_oracle::both_read_text(value) : !yaml_oracle::both_read_the_same_number(value))
        fail(outcome, "accepted garbage: " + key + ": '" + value.substr(0, 60) +
                          "' is not what YAML 1.1 and 1.2 both read");
      if (!text_key && quoted_numbers_.count(key) != 0)
        fail(outcome, "accepted garbage: " + key + " was quoted or tagged: " + quoted_numbers_[key]);
    }
    try {
      const Event event = simulator->advance_to(duration, WorkBudget::steps(max_steps));
      const Snapshot s = simulator->snapshot();
      const ModelOutputs& o = s.outputs;
      if (!(std::isfinite(s.time) && s.attitude.coeffs().allFinite() && s.body_rates.allFinite() &&
            o.center_of_mass.allFinite() && o.contact_point.allFinite() && o.contact_force.allFinite() &&
            std::isfinite(o.normal_force) && std::isfinite(o.energy) && std::isfinite(o.dissipated_energy)))
        fail(outcome, "a non-finite output at t = " + std::to_string(s.time));
      if (event == Event::kNonFinite) fail(outcome, "a non_finite event");
    } catch (const std::exception& e) {
      fail(outcome, std::string("crash: the run threw ") + e.what());
    }
    return outcome;
  }

 private:
  double uniform(double lo, double hi) { return std::uniform_real_distribution<double>(lo, hi)(rng_); }
  bool chance(double p) { return uniform(0.0, 1.0) < p; }
  double log_uniform(double lo, double hi) { return std::exp(uniform(std::log(lo), std::log(hi))); }
  int pick(int n) { return std::uniform_int_distribution<int>(0, n - 1)(rng_); }

  void defect(const std::string& what) {
    defects_.push_back(what);
    mutations_.push_back(what);
  }
  void fail(SceneFileOutcome& outcome, const std::string& what) {
    outcome.failures.push_back("scene-file seed " + std::to_string(seed_) + ": " + what);
  }
  void check_message(const std::string& message, SceneFileOutcome& outcome) {
    if (message.find('\n') != std::string::npos || message.size() > 600)
      fail(outcome, "a refusal of " + std::to_string(message.size()) + " characters or several lines: " +
                        message.substr(0, 200));
  }
  static std::string gist(const std::string& message) {
    // "file:line:col: an anchor (&name): ..." or "key: '010' has a leading zero: ..." -> a few words
    static const std::vector<std::string> kinds = {
        "anchor", "alias", "merge key", "a list", "no value", "given twice", "YAML documents", "nested more",
        "YAML nodes", "quoted", "tag", "leading zero", "hexadecimal", "sexagesimal", "underscore",
        "YAML 1.1 reads it as text", "finite", "boolean", "rosparam converts", "32 bits", "not a number",
        "malformed YAML", "top level", "key is", "keys must"};
    for (const std::string& k : kinds)
      if (message.find(k) != std::string::npos) return k;
    return "other";
  }

  /// A name's value, sometimes quoted (fine for a name), tagged or mangled.
  std::string name_value(const std::string& name) {
    const double draw = uniform(0.0, 1.0);
    if (draw < 0.05) return "\"" + name + "\"";
    if (draw < 0.08) return "'" + name + "'";
    if (hostile_ && draw < 0.10) return mutations_.push_back("a tagged name"), "!!str " + name;
    if (hostile_ && draw < 0.12) return "on";  // a boolean in YAML 1.1: refused as no such name
    return name;
  }

  /// A number in a random written form, sometimes quoted or tagged (recorded).
  std::string number_value(const std::string& key, double value) {
    std::string text = number_text(value);
    const double wrap = hostile_ ? uniform(0.0, 1.0) : 1.0;
    if (wrap < 0.04) return quoted_numbers_[key] = "double quotes", defect("a quoted number"), "\"" + text + "\"";
    if (wrap < 0.07) return quoted_numbers_[key] = "single quotes", defect("a quoted number"), "'" + text + "'";
    if (wrap < 0.10) {
      static const char* const kTags[] = {"!!str ", "!!float ", "!!int ", "!foo ", "! "};
      const std::string tag = kTags[pick(5)];
      quoted_numbers_[key] = "tag " + tag;
      defect("a tagged number");
      return tag + text;
    }
    return text;
  }

  std::string number_text(double value) {
    char buffer[64];
    auto printed = [&](const char* format, double v) {
      std::snprintf(buffer, sizeof buffer, format, v);
      return std::string(buffer);
    };
    const long whole = std::lround(value);
    if (!hostile_) {
      // Forms both YAML versions read alike (an integer only where it is the value).
      switch (pick(4)) {
        case 0: return printed("%.4e", value);
        case 1: return whole == value ? std::to_string(whole) : printed("%.17g", value);
        default: return printed("%.17g", value);
      }
    }
    if (pick(3) == 0) return printed("%.17g", value);  // most keys of a hostile file stay valid
    switch (pick(14)) {
      case 0: case 1: case 2: return printed("%.17g", value);
      case 3: return printed("%g", value);           // 4e-05: text in YAML 1.1
      case 4: return printed("%.4e", value);         // 4.0000e-05
      case 5: return printed("%.3E", value);
      case 6: return std::to_string(whole);          // an integer
      case 7: return "0" + std::to_string(std::labs(whole));  // a leading zero
      case 8: {
        std::string t = printed("%.6f", value);
        t.insert(1, "_");
        return t;  // an underscore
      }
      case 9: {
        static const char* const kPrefixed[] = {"0x10", "0o17", "0b101", "0x1p3", "1:30", "-1:00:00.5", "+.5", "-.5",
                                                ".5", "1.", "1e2", "1E+2", "2.5e3", "00.25"};
        return kPrefixed[pick(14)];
      }
      case 10: {
        static const char* const kSpecial[] = {".inf", "-.inf", ".nan", "inf", "nan", "NaN", "yes", "no", "On",
                                               "true", "deg(30)", "rad(0.3)", "1e400", "-1e400", "1e-400",
                                               "9.8kg", "1,5", "0.1 0.2", "2001-01-01", "=", "0x", "+", "-0",
                                               "1e+400", "4.9e-324"};
        return kSpecial[pick(25)];
      }
      case 11: return std::string(static_cast<std::size_t>(uniform(20, 300)), '9');  // many digits
      case 12: return "1" + std::string(static_cast<std::size_t>(uniform(1, 12)), '0');  // 10 ... 1e12
      default: return printed("%.9g", value * std::pow(10.0, pick(9) - 4));  // other magnitudes
    }
  }

  /// A value as a flow map's entry shows it (a block list does not fit there).
  static std::string flow(const std::string& value) {
    return value.find('\n') != std::string::npos ? "[9.8, 1.0]" : value;
  }

  std::string deep_map(int depth) {
    std::string map = "1.0";
    for (int i = 0; i < depth; ++i) map = "{k" + std::to_string(i) + ": " + map + "}";
    return map;
  }

  std::string alias_bomb() {
    std::string bomb = "b0: &b0 {a: 1, b: 1, c: 1}";
    for (int i = 1; i <= 5; ++i)
      bomb += "\nb" + std::to_string(i) + ": &b" + std::to_string(i) + " {a: *b" + std::to_string(i - 1) + ", b: *b" +
              std::to_string(i - 1) + ", c: *b" + std::to_string(i - 1) + "}";
    return bomb;
  }

  unsigned long long seed_;
  std::mt19937_64 rng_;
  bool hostile_ = false;
  std::string text_;
  std::vector<std::string> defects_, mutations_;
  std::map<std::string, std::string> quoted_numbers_;  ///< numeric key -> how it was quoted or tagged
};

}  // namespace fuzz
}  // namespace spinning_top
