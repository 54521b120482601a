// Cost of the per-step event check (doc/integrators.md, "Events"): CPU time of 10 s of the toy
// top through make_simulator, with a request every 1 ms (the node's pattern) and with a single
// request at 10 s, for the cases the event check was measured on. Prints one line per case:
// steps, the median CPU time of a run over `rounds` rounds (each round the median of `repeats`
// runs), the spread of the round medians, and us per step of the median and of the lowest round
// median (on a shared machine the lowest is the least disturbed). Asserts nothing (speed is
// measured, never asserted in a test).
//   event_overhead [rounds=5] [repeats=7] [case substring] [every_1ms|one_at_10s]
// The last two select one case and one request pattern, e.g. to count its instructions with
// valgrind --tool=callgrind event_overhead 1 1 splitting6 every_1ms (stable where CPU time is not).
#include <time.h>

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <vector>

#include "spinning_top/simulator.hpp"
#include "bench_support.hpp"

namespace {

using spinning_top::bench::cpu_seconds;
using namespace spinning_top;

double median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  return v[v.size() / 2];
}

struct Case {
  const char* name;
  SceneConfig config;
};

SceneConfig toy(SceneType scene, IntegratorType type) {
  SceneConfig c;
  c.scene = scene;
  c.initial.tilt = 0.3;
  c.initial.spin = 150.0;
  c.integrator.type = type;
  c.integrator.step = 1e-3;
  c.integrator.tolerance = 1e-10;
  return c;
}

/// One run: reset, then requests every `interval` up to 10 s (interval 10: one request).
double run_once(Simulator& sim, double interval, long& steps, Event& event) {
  const double start = cpu_seconds();
  sim.reset();
  const long n = static_cast<long>(10.0 / interval + 0.5);
  event = Event::kNone;
  for (long i = 1; i <= n && event == Event::kNone; ++i) event = sim.advance_to(static_cast<double>(i) * interval);
  const double elapsed = cpu_seconds() - start;
  steps = sim.steps();
  return elapsed;
}

}  // namespace

int main(int argc, char** argv) {
  const int rounds = argc > 1 ? std::atoi(argv[1]) : 5;
  const int repeats = argc > 2 ? std::atoi(argv[2]) : 7;
  const std::string only_case = argc > 3 ? argv[3] : "", only_pattern = argc > 4 ? argv[4] : "";
  SceneConfig viscous = toy(SceneType::kViscous, IntegratorType::kDop853);
  viscous.top.friction = 0.5;
  // A top whose R comes to 1 % of m g once per nutation period (0.032 s): kicked at 0.99 times the
  // nutation rate 4.92160737 rad/s at which R's minimum touches zero (test_events_within_step.cpp
  // finds that threshold with exact). The steps around each minimum cannot be cleared by the screen.
  SceneConfig near_graze = toy(SceneType::kFrictionless, IntegratorType::kGauss6);
  near_graze.top.gravity = 9.81;
  near_graze.initial.tilt = 0.5;
  near_graze.initial.nutation_rate = 0.99 * 4.9216073696993581;
  SceneConfig near_graze_dop853 = near_graze;
  near_graze_dop853.integrator.type = IntegratorType::kDop853;
  const std::vector<Case> cases = {
      {"viscous k=0.5, dop853 1e-10", viscous},
      {"fixed tip, splitting6 1 ms", toy(SceneType::kFixedTip, IntegratorType::kSplitting6)},
      {"fixed tip, gauss6 1 ms", toy(SceneType::kFixedTip, IntegratorType::kGauss6)},
      {"frictionless, gauss6 1 ms", toy(SceneType::kFrictionless, IntegratorType::kGauss6)},
      {"fixed tip, dop853 1e-10", toy(SceneType::kFixedTip, IntegratorType::kDop853)},
      {"near graze, gauss6 1 ms", near_graze},
      {"near graze, dop853 1e-10", near_graze_dop853},
  };
  std::printf("%-30s %-10s %7s %10s %20s %9s %9s\n", "case", "requests", "steps", "ms/10 s", "(round spread)", "us/step",
              "min");
  for (const Case& c : cases) {
    if (std::string(c.name).find(only_case) == std::string::npos) continue;
    auto sim = make_simulator(c.config);
    for (double interval : {1e-3, 10.0}) {
      if (!only_pattern.empty() && only_pattern != (interval < 1.0 ? "every_1ms" : "one_at_10s")) continue;
      std::vector<double> round_medians;
      long steps = 0;
      Event event = Event::kNone;
      for (int r = 0; r < rounds; ++r) {
        std::vector<double> times;
        for (int k = 0; k < repeats; ++k) times.push_back(run_once(*sim, interval, steps, event));
        round_medians.push_back(median(times));
      }
      const double m = median(round_medians);
      const auto [lo, hi] = std::minmax_element(round_medians.begin(), round_medians.end());
      std::printf("%-30s %-10s %7ld %10.3f %9.3f-%-9.3f %9.4f %9.4f%s\n", c.name,
                  interval < 1.0 ? "every 1ms" : "one at 10s", steps, 1e3 * m, 1e3 * *lo, 1e3 * *hi,
                  1e6 * m / static_cast<double>(steps), 1e6 * *lo / static_cast<double>(steps),
                  event == Event::kNone ? "" : (std::string(" event ") + to_string(event)).c_str());
    }
  }
  return 0;
}
