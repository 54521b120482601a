// The measurement behind kAutoFallbackTolerance (simulator.hpp; doc/integrators.md, "Fallback
// tolerance"): dop853 against exact over 10 s, every 1 ms, at tolerances 1e-10 ... 1e-13, on
// states exact accepts, including states near those it refuses (weak gravity near g = 0 on the
// frictionless floor, a start near the vertical). The error is the whole attitude's, the
// rotation angle between the quaternions (the spin angle included), and the axis's.
//
// Usage: fallback_tolerance [--output-dir DIR]   writes DIR/fallback_tolerance.csv
#include <time.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <iostream>
#include <memory>
#include <string>
#include <vector>

#include "spinning_top/simulator.hpp"
#include "bench_support.hpp"

using namespace spinning_top;

namespace {

using spinning_top::bench::cpu_seconds;

double rotation_angle(const Quaternion& a, const Quaternion& b) {
  return 2.0 * std::asin(std::min(1.0, (a.conjugate() * b).vec().norm()));
}

struct Case {
  std::string name;
  SceneConfig config;
};

std::vector<Case> cases() {
  std::vector<Case> all;
  for (SceneType scene : {SceneType::kFixedTip, SceneType::kFrictionless}) {
    SceneConfig toy;  // the toy top of config/<scene>.yaml
    toy.scene = scene;
    toy.initial.tilt = 0.3;
    toy.initial.spin = 150.0;
    const std::string prefix = std::string(to_string(scene)) + ": ";
    all.push_back({prefix + "toy top", toy});
    SceneConfig general = toy;
    general.initial.precession_rate = 5.0;
    general.initial.nutation_rate = 2.0;
    general.initial.heading = 0.7;
    general.initial.spin_angle = 1.3;
    all.push_back({prefix + "general state", general});
    SceneConfig slow = toy;
    slow.initial.spin = 60.0;
    slow.initial.nutation_rate = -1.0;
    all.push_back({prefix + "spin 60, thetadot -1", slow});
    SceneConfig weak = toy;
    weak.top.gravity = 0.01;
    all.push_back({prefix + "g 0.01", weak});
    SceneConfig near_vertical = toy;
    near_vertical.initial.tilt = scene == SceneType::kFixedTip ? 1e-2 : 1e-3;
    near_vertical.initial.nutation_rate = 1.0;
    all.push_back({prefix + "tilt " + (scene == SceneType::kFixedTip ? "1e-2" : "1e-3") + ", thetadot 1", near_vertical});
  }
  return all;
}

}  // namespace

int main(int argc, char** argv) {
  std::string output_dir = ".";
  for (int i = 1; i < argc; ++i) {
    if (!std::strcmp(argv[i], "--output-dir") && i + 1 < argc) {
      output_dir = argv[++i];
    } else {
      std::cerr << "usage: fallback_tolerance [--output-dir DIR]\n"
                   "dop853 against exact over 10 s on states exact accepts, at tolerances 1e-10 to 1e-13;\n"
                   "writes DIR/fallback_tolerance.csv (the measurement behind kAutoFallbackTolerance).\n";
      return std::strcmp(argv[i], "--help") ? 2 : 0;
    }
  }
  const std::string path = output_dir + "/fallback_tolerance.csv";
  std::ofstream csv(path);
  if (!csv) {
    std::cerr << "fallback_tolerance: cannot write " << path << "\n";
    return 1;
  }
  csv << "case,exact,tolerance,max_attitude_error_rad,max_axis_error_rad,horizon_s,steps,cpu_ms\n";
  const double duration = 10.0, interval = 1e-3;
  double worst_at_chosen = 0.0;
  for (const Case& c : cases()) {
    SceneConfig closed = c.config;
    closed.integrator.type = IntegratorType::kExact;
    std::unique_ptr<Simulator> exact;
    try {
      exact = make_simulator(closed);
    } catch (const InvalidParameter& refusal) {
      std::printf("%-40s exact refuses it: %s\n", c.name.c_str(), refusal.what());
      continue;
    }
    std::string exact_description = exact->integrator_description();
    std::replace(exact_description.begin(), exact_description.end(), ',', ';');
    std::printf("%-40s %s\n", c.name.c_str(), exact_description.c_str());
    for (const double tolerance : {1e-10, 1e-11, 1e-12, 1e-13}) {
      SceneConfig stepped = c.config;
      stepped.integrator.type = IntegratorType::kDop853;
      stepped.integrator.tolerance = tolerance;
      std::unique_ptr<Simulator> dop853 = make_simulator(stepped);
      exact->reset();
      double attitude = 0.0, axis = 0.0, horizon = duration;
      for (long i = 1; i <= std::lround(duration / interval); ++i) {
        const double t = i * interval;
        if (exact->advance_to(t) != Event::kNone || dop853->advance_to(t) != Event::kNone) {
          horizon = std::min(exact->time(), dop853->time());
          break;
        }
        const Snapshot a = exact->snapshot(), b = dop853->snapshot();
        attitude = std::max(attitude, rotation_angle(a.attitude, b.attitude));
        const Vector3 ea = a.attitude * Vector3::UnitZ(), eb = b.attitude * Vector3::UnitZ();
        axis = std::max(axis, std::atan2(ea.cross(eb).norm(), ea.dot(eb)));
      }
      dop853->reset();
      const double start = cpu_seconds();
      dop853->advance_to(horizon);
      const double cpu_ms = 1e3 * (cpu_seconds() - start);
      if (tolerance == kAutoFallbackTolerance) worst_at_chosen = std::max(worst_at_chosen, attitude);
      std::printf("    tolerance %g: attitude %.2e rad, axis %.2e rad over %g s, %ld steps, %.2f ms CPU\n", tolerance,
                  attitude, axis, horizon, dop853->steps(), cpu_ms);
      csv << '"' << c.name << "\"," << exact_description << ',' << tolerance << ',' << attitude << ',' << axis << ','
          << horizon << ',' << dop853->steps() << ',' << cpu_ms << '\n';
    }
  }
  std::printf("at kAutoFallbackTolerance = %g the largest attitude error is %.2e rad (requirement: 1e-9 rad)\n",
              kAutoFallbackTolerance, worst_at_chosen);
  std::printf("wrote %s\n", path.c_str());
  return 0;
}
