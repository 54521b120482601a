// The cost of hops (issue 18): a frictionless top that hops ten times and more, run piecewise in
// closed form (auto: exact in each contact phase, flight in closed form), against a top of the
// same body that stays on the floor (contact only), and against dop853 through the same hops.
// Each run answers the node's requests (1 ms) for 1 s; CPU time is the best of several runs (a
// benchmark, not a test: the figures depend on the machine). Writes bench/results/hop_cost.md.
#include <algorithm>
#include <cstdio>
#include <string>

#include "bench_support.hpp"
#include "spinning_top/simulator.hpp"

using namespace spinning_top;

namespace {

struct Case {
  const char* name;
  SceneConfig config;
};

SceneConfig frictionless(double tilt, double precession_rate, IntegratorType type) {
  SceneConfig c;
  c.scene = SceneType::kFrictionless;
  c.initial.tilt = tilt;
  c.initial.precession_rate = precession_rate;
  c.integrator.type = type;
  c.integrator.tolerance = 1e-12;
  return c;
}

}  // namespace

int main(int argc, char** argv) {
  const std::string out_path = argc > 1 ? argv[1] : "bench/results/hop_cost.md";
  const Case cases[] = {
      {"hopping (tilt 0.8, precession 60 rad/s), auto", frictionless(0.8, 60.0, IntegratorType::kAuto)},
      {"contact only (tilt 0.8, at rest), auto", frictionless(0.8, 0.0, IntegratorType::kAuto)},
      {"contact only (tilt 0.3, default), auto", frictionless(0.3, 0.0, IntegratorType::kAuto)},
      {"hopping, dop853 at 1e-12", frictionless(0.8, 60.0, IntegratorType::kDop853)},
  };
  std::FILE* out = std::fopen(out_path.c_str(), "w");
  if (!out) {
    std::perror(out_path.c_str());
    return 1;
  }
  std::fprintf(out, "| run (frictionless, 1 s, 1000 requests) | hops | steps | CPU per simulated second [ms] |\n");
  std::fprintf(out, "|---|---|---|---|\n");
  for (const Case& c : cases) {
    double best = 1e300;
    long steps = 0, hops = 0;
    for (int round = 0; round < 7; ++round) {
      const double start = bench::cpu_seconds();
      auto simulator = make_simulator(c.config);
      for (int i = 1; i <= 1000; ++i) {
        simulator->advance_to(i * 1e-3);
        simulator->take_transitions();
      }
      best = std::min(best, bench::cpu_seconds() - start);
      steps = simulator->steps();
      hops = simulator->hops().landings;
    }
    std::fprintf(out, "| %s | %ld | %ld | %.3f |\n", c.name, hops, steps, 1e3 * best);
    std::printf("%-55s hops %3ld  steps %6ld  CPU %.3f ms per simulated s\n", c.name, hops, steps, 1e3 * best);
  }
  std::fclose(out);
  return 0;
}
