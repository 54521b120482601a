// The stiff and extreme cases' table (issue 4; doc/extreme_cases.md): runs every scene of
// config/extreme/ at the node's 1 ms rate with its configured integrator (the default `auto`
// unless the case names one) over a long horizon, and writes what it measured:
//   <output-dir>/extreme_cases.csv  one row per error figure
//   <output-dir>/extreme_cases.md   the Markdown table the README shows
// Usage: extreme_cases [--output-dir DIR] [--cpu-budget S] [--integrator NAME] (--help).
// The gtests (test/test_extreme_cases.cpp) assert the same figures on short runs.
#include <sys/stat.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <functional>
#include <iostream>
#include <sstream>
#include <string>
#include <vector>

#include "extreme_cases.hpp"

#ifndef SPINNING_TOP_SOURCE_DIR
#error "SPINNING_TOP_SOURCE_DIR must name the package's source directory"
#endif

namespace spinning_top {
namespace extreme {
namespace {

struct Figure {
  std::string name;
  double value;
};

struct Outcome {
  std::string text;      ///< "stable", "fallen at 0.250221 s", "refused: ..."
  std::vector<Figure> figures;
  std::string integrator;
  double horizon = 0.0, end_time = 0.0, cpu = 0.0;
  bool finite = true;
};

double mgh(const SceneConfig& c) { return c.top.mass * c.top.gravity * c.top.tip_distance; }

double l_scale(const SceneConfig& c) {
  const Vector3 w = initial_body_rates(c.initial);
  const double a = c.scene == SceneType::kFixedTip ? c.top.inertia_about_tip() : c.top.inertia_transverse;
  return std::hypot(a * std::hypot(w.x(), w.y()), c.top.inertia_axial * w.z());
}

void invariants(const SceneConfig& c, const CaseRun& run, std::vector<Figure>& out) {
  out.push_back({"max |E-E0|/(m g h)", max_abs_energy_change(run) / mgh(c)});
  out.push_back({"max |Lz-Lz0|/|L0|", max_abs_lz_change(run) / l_scale(c)});
}

/// How far theta leaves the cubic's band [theta0, theta1], in units of the band's width.
void tilt_band(const SceneConfig& c, const CaseRun& run, std::vector<Figure>& out) {
  const ReducedTop top(c);
  const auto [low, high] = top.other_roots();
  const double u1 = std::abs(high - top.u0()) < std::abs(low - top.u0()) ? high : low;
  const double lo = std::min(c.initial.tilt, std::acos(u1)), hi = std::max(c.initial.tilt, std::acos(u1));
  double excess = 0.0;
  for (const Snapshot& s : run.samples) {
    const double t = tilt_of(s);
    excess = std::max({excess, lo - t, t - hi});
  }
  out.push_back({"theta outside cubic band/width", excess / (hi - lo)});
}

void event_time(const CaseRun& run, double expected, std::vector<Figure>& out) {
  out.push_back({"|t_event - t_quadrature| [s]", std::abs(run.event_time - expected)});
}

using Measure = std::function<void(const SceneConfig&, const CaseRun&, std::vector<Figure>&)>;

struct Case {
  const char* name;
  double horizon;         ///< [s] simulated (an event ends it earlier)
  const char* expected;   ///< the physical expectation, one line
  Measure measure;
};

std::vector<Case> cases() {
  return {
      {"sleeping_upright", 10.0, "stays upright: tilt 0, R = m g",
       [](const SceneConfig& c, const CaseRun& run, std::vector<Figure>& out) {
         double tilt = 0.0, force = 0.0;
         for (const Snapshot& s : run.samples) {
           tilt = std::max(tilt, tilt_of(s));
           force = std::max(force, std::abs(s.outputs.normal_force / (c.top.mass * c.top.gravity) - 1.0));
         }
         out.push_back({"max tilt [rad]", tilt});
         out.push_back({"max |R/(m g) - 1|", force});
       }},
      {"sleeping_tilted", 10.0, "tilt in [1, 1.0411] x 1e-8 rad (linear theory)",
       [](const SceneConfig& c, const CaseRun& run, std::vector<Figure>& out) {
         const SleepingTopLinear linear(c);
         double distance = 0.0, highest = 0.0;
         for (const Snapshot& s : run.samples) {
           const Vector3 e = axis_of(s);
           distance = std::max(distance, std::abs(std::complex<double>(e.x(), e.y()) - linear.sigma(s.time)));
           highest = std::max(highest, tilt_of(s));
         }
         out.push_back({"max tilt / linear-theory max", highest / linear.max_tilt()});
         out.push_back({"max |axis - linear theory|/theta0", distance / c.initial.tilt});
       }},
      {"fast_spin", 10.0, "no event; E, Lz conserved; theta in cubic band; nutation 4.19 ms",
       [](const SceneConfig& c, const CaseRun& run, std::vector<Figure>& out) {
         invariants(c, run, out);
         tilt_band(c, run, out);
         std::vector<double> tilt;
         for (const Snapshot& s : run.samples) tilt.push_back(tilt_of(s));
         const double period = 2.0 * M_PI / dominant_frequency(tilt, kNodeStep);
         out.push_back({"nutation period rel. error", std::abs(period / ReducedTop(c).nutation_period() - 1.0)});
       }},
      {"slow_spin", 10.0, "fallen at 0.250221 s (quadrature)",
       [](const SceneConfig& c, const CaseRun& run, std::vector<Figure>& out) {
         event_time(run, ReducedTop(c).time_from_turning_point(0.0), out);
       }},
      {"near_horizontal", 10.0, "no event (lower root u = 0.0485 > 0); E, Lz conserved",
       [](const SceneConfig& c, const CaseRun& run, std::vector<Figure>& out) {
         invariants(c, run, out);
         tilt_band(c, run, out);
       }},
      {"zero_spin", 10.0, "fallen at 0.175595 s (quadrature, frictionless)",
       [](const SceneConfig& c, const CaseRun& run, std::vector<Figure>& out) {
         event_time(run, ReducedTop(c).time_from_turning_point(0.0), out);
       }},
      {"lift_off", 10.0, "lift_off at 0.0211234 s, theta = 15.08 deg (quadrature)",
       [](const SceneConfig& c, const CaseRun& run, std::vector<Figure>& out) {
         const ReducedTop top(c);
         event_time(run, top.time_from_turning_point(top.lift_off_height(top.other_roots().second)), out);
       }},
      {"stiff_friction_1e-6", 10.0, "no event; E + W = E0; fixed-tip motion to O(m/k)", nullptr},
      {"stiff_friction_1e-8", 10.0, "no event; E + W = E0; fixed-tip motion to O(m/k)", nullptr},
      {"disk_like", 10.0, "no event; E, Lz conserved; theta in cubic band",
       [](const SceneConfig& c, const CaseRun& run, std::vector<Figure>& out) {
         invariants(c, run, out);
         tilt_band(c, run, out);
       }},
      {"rod_like", 10.0, "fallen at 0.153766 s (quadrature; stable only above 2266 rad/s)",
       [](const SceneConfig& c, const CaseRun& run, std::vector<Figure>& out) {
         event_time(run, ReducedTop(c).time_from_turning_point(0.0), out);
       }},
      {"torque_free", 10.0, "free precession about fixed L at |L|/A = 225.06 rad/s; R = m g",
       [](const SceneConfig& c, const CaseRun& run, std::vector<Figure>& out) {
         const FreePrecession exact(c);
         double distance = 0.0, force = 0.0;
         for (const Snapshot& s : run.samples) {
           distance = std::max(distance, angle_between(axis_of(s), exact.axis(s.time)));
           force = std::max(force, std::abs(s.outputs.normal_force / (c.top.mass * c.top.gravity) - 1.0));
         }
         out.push_back({"max axis angle to closed form [rad]", distance});
         out.push_back({"max |R/(m g) - 1|", force});
         out.push_back({"max |E-E0|/E0", max_abs_energy_change(run) / run.samples.front().outputs.energy});
       }},
      {"tiny_h", 1.0, "free precession to O(h): within m g h t^2/(2 A0) = 0.0123 rad at 1 s",
       [](const SceneConfig& c, const CaseRun& run, std::vector<Figure>& out) {
         const FreePrecession free(c);
         double distance = 0.0;
         for (const Snapshot& s : run.samples)
           distance = std::max(distance, angle_between(axis_of(s), free.axis(s.time)));
         out.push_back({"max axis angle to h=0 closed form [rad]", distance});
         out.push_back({"max |E-E0|/(m g h)", max_abs_energy_change(run) / mgh(c)});
       }},
      {"huge_gravity", 10.0, "no event; E, Lz conserved; theta in cubic band; nutation 9.19 ms",
       [](const SceneConfig& c, const CaseRun& run, std::vector<Figure>& out) {
         invariants(c, run, out);
         tilt_band(c, run, out);
         std::vector<double> tilt;
         for (const Snapshot& s : run.samples) tilt.push_back(tilt_of(s));
         const double period = 2.0 * M_PI / dominant_frequency(tilt, kNodeStep);
         out.push_back({"nutation period rel. error", std::abs(period / ReducedTop(c).nutation_period() - 1.0)});
       }},
      {"tiny_step", 10.0, "rk4 at 1e-6 s matches dopri5 at tolerance 1e-13", nullptr},
      {"huge_step", 10.0, "refused (step) or stable with bounded energy error", nullptr},
      {"huge_step_default", 10.0, "refused (step) or stable with bounded energy error", nullptr},
  };
}

/// A Markdown table cell: '|' would end the cell.
std::string cell(const std::string& text) {
  std::string out;
  for (char ch : text) out += (ch == '|') ? std::string("\\|") : std::string(1, ch);
  return out;
}

std::string source_file(const std::string& name) {
  return std::string(SPINNING_TOP_SOURCE_DIR) + "/config/extreme/" + name + ".yaml";
}

std::string format(double v, const char* f = "%.3g") {
  char buffer[64];
  std::snprintf(buffer, sizeof buffer, f, v);
  return buffer;
}

/// Viscous with tiny m/k: the energy balance, the tip pinned at -(m/k) v_G, and the axis's
/// distance to a fixed-tip run with the same initial state.
void stiff_friction(const SceneConfig& c, const CaseRun& run, std::vector<Figure>& out) {
  const double epsilon = c.top.mass / c.top.friction;
  SceneConfig fixed = c;
  fixed.scene = SceneType::kFixedTip;
  fixed.top.friction = 0.0;
  const CaseRun reference = run_at_node_rate(fixed, run.end_time());
  double pinned = 0.0, deviation = 0.0;
  for (size_t i = 0; i < run.samples.size() && i < reference.samples.size(); ++i) {
    const ModelOutputs& o = run.samples[i].outputs;
    const Vector3 v(o.center_of_mass_velocity.x(), o.center_of_mass_velocity.y(), 0.0);
    pinned = std::max(pinned, (o.contact_point + epsilon * v).norm());
    deviation = std::max(deviation, angle_between(axis_of(run.samples[i]), axis_of(reference.samples[i])));
  }
  out.push_back({"max |E+W-E0|/(m g h)", max_energy_balance_error(run) / mgh(c)});
  out.push_back({"max axis angle to fixed tip / (m/k) [1/s]", deviation / epsilon});
  out.push_back({"max |x_P + (m/k) v_G| / h", pinned / c.top.tip_distance});
}

void tiny_step(const std::string& name, const CaseRun& run, std::vector<Figure>& out) {
  ParameterMap values = read_scene_file(source_file(name));
  values["integrator"] = "dopri5";
  values["tolerance"] = "1e-13";
  values.erase("step");
  const CaseRun reference = run_at_node_rate(parse_scene_config(values, true), run.end_time());
  double distance = 0.0;
  for (size_t i = 0; i < run.samples.size() && i < reference.samples.size(); ++i)
    distance = std::max(distance, angle_between(axis_of(run.samples[i]), axis_of(reference.samples[i])));
  out.push_back({"max axis angle to reference [rad]", distance});
}

/// integrator_override: run every case that does not name its own integrator with this one.
Outcome run_case(const Case& c, double cpu_budget, const std::string& integrator_override) {
  Outcome outcome;
  outcome.horizon = c.horizon;
  SceneConfig config;
  try {
    ParameterMap values = read_scene_file(source_file(c.name));
    if (!integrator_override.empty() && !values.count("integrator")) values["integrator"] = integrator_override;
    config = parse_scene_config(values, true);
    // The seed's lift-off is where the contact model ends: the run flies on by default
    // (HYBRID.md), so stop it there to time the event against the quadrature (as
    // test_extreme_cases does; the flight after it: test_hybrid).
    if (std::string(c.name) == "lift_off") config.after_lift_off = AfterLiftOff::kStop;
    make_simulator(config);
  } catch (const InvalidParameter& refused) {
    outcome.text = std::string("refused: ") + refused.what();
    outcome.integrator = "-";
    return outcome;
  }
  const CaseRun run = run_at_node_rate(config, c.horizon, kNodeStep, cpu_budget);
  outcome.integrator = run.integrator;
  outcome.end_time = run.end_time();
  outcome.cpu = run.cpu_seconds;
  outcome.finite = run.all_finite;
  if (run.event != Event::kNone)
    outcome.text = std::string(to_string(run.event)) + " at " + format(run.event_time, "%.9g") + " s";
  else if (run.out_of_budget)
    outcome.text = "stable to " + format(run.end_time(), "%.4g") + " s (CPU budget)";
  else
    outcome.text = "stable";
  const std::string name = c.name;
  if (c.measure) {
    c.measure(config, run, outcome.figures);
  } else if (name.rfind("stiff_friction", 0) == 0) {
    stiff_friction(config, run, outcome.figures);
  } else if (name == "tiny_step") {
    tiny_step(name, run, outcome.figures);
  } else {  // huge steps, run rather than refused
    outcome.figures.push_back({"max |E-E0|/(m g h)", max_abs_energy_change(run) / mgh(config)});
  }
  return outcome;
}

}  // namespace
}  // namespace extreme
}  // namespace spinning_top

int main(int argc, char** argv) {
  using namespace spinning_top::extreme;
  std::string output_dir = std::string(SPINNING_TOP_SOURCE_DIR) + "/bench/results";
  double cpu_budget = 60.0;
  std::string integrator;  // empty: each scene file's own (the default auto)
  for (int i = 1; i < argc; ++i) {
    const std::string arg = argv[i];
    if (arg == "--output-dir" && i + 1 < argc) {
      output_dir = argv[++i];
    } else if (arg == "--integrator" && i + 1 < argc) {
      integrator = argv[++i];
    } else if (arg == "--cpu-budget" && i + 1 < argc) {
      cpu_budget = std::atof(argv[++i]);
    } else {
      std::cerr << "usage: extreme_cases [--output-dir DIR] [--cpu-budget SECONDS_PER_CASE] [--integrator NAME]\n"
                   "Runs config/extreme/*.yaml at the node's 1 ms rate and writes extreme_cases.csv and\n"
                   "extreme_cases.md to DIR (default: the package's bench/results). With --integrator, the\n"
                   "cases that do not name their own integrator run with NAME instead of auto, and the\n"
                   "files are extreme_cases-NAME.{csv,md}.\n";
      return arg == "--help" ? 0 : 2;
    }
  }
  mkdir(output_dir.c_str(), 0755);
  const std::vector<Case> all = cases();
  const std::string stem = output_dir + "/extreme_cases" + (integrator.empty() ? "" : "-" + integrator);
  std::ofstream csv(stem + ".csv");
  std::ofstream md(stem + ".md");
  if (!csv || !md) {
    std::cerr << "extreme_cases: cannot write to " << output_dir << "\n";
    return 1;
  }
  csv << "case,scene,integrator,horizon_s,end_time_s,outcome,all_finite,expected,figure,value,cpu_s\n";
  md << "| case | scene | integrator (auto's pick) | simulated | outcome | expected | error figures | CPU [s] |\n"
        "|---|---|---|---|---|---|---|---|\n";
  int failures = 0;
  for (size_t k = 0; k < all.size(); ++k) {
    const Case& c = all[k];
    std::fprintf(stderr, "[extreme %2zu/%zu] %-20s ", k + 1, all.size(), c.name);
    std::fflush(stderr);
    Outcome o;
    std::string scene = "?";
    try {
      scene = spinning_top::read_scene_file(source_file(c.name))["scene"];
      o = run_case(c, cpu_budget, integrator);
    } catch (const std::exception& e) {
      o.text = std::string("error: ") + e.what();
      ++failures;
    }
    std::fprintf(stderr, "%s (%.3g s CPU)\n", o.text.c_str(), o.cpu);
    std::string figures;
    for (const Figure& f : o.figures) {
      csv << c.name << ',' << scene << ",\"" << o.integrator << "\"," << c.horizon << ',' << o.end_time << ",\""
          << o.text << "\"," << (o.finite ? 1 : 0) << ",\"" << c.expected << "\",\"" << f.name << "\","
          << format(f.value, "%.6g") << ',' << format(o.cpu, "%.6g") << '\n';
      figures += (figures.empty() ? "" : "; ") + f.name + " = " + format(f.value, "%.2g");
    }
    if (o.figures.empty())
      csv << c.name << ',' << scene << ",\"" << o.integrator << "\"," << c.horizon << ",0,\"" << o.text << "\","
          << (o.finite ? 1 : 0) << ",\"" << c.expected << "\",,," << format(o.cpu, "%.6g") << '\n';
    std::string outcome = o.text;
    if (!o.finite) outcome += " (NON-FINITE OUTPUT)";
    md << "| `" << c.name << "` | " << scene << " | " << cell(o.integrator) << " | " << format(o.end_time, "%.4g")
       << " s | " << cell(outcome) << " | " << cell(c.expected) << " | " << cell(figures.empty() ? "-" : figures) << " | "
       << format(o.cpu, "%.2g") << " |\n";
    if (!o.finite) ++failures;
  }
  std::fprintf(stderr, "[extreme] wrote %s.csv and .md\n", stem.c_str());
  return failures == 0 ? 0 : 1;
}
