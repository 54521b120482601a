#include <cstdio>
#include <cstdlib>
#include <string>
#include "spinning_top/simulator.hpp"
using namespace spinning_top;
// The work of requests, for instruction counts (bench/request_instructions.sh): one simulator of
// SCENE with INTEGRATOR (step 1e-4 s, tolerance 1e-12, viscous friction FRICTION) answers N
// requests of 1 ms (N from the environment, default 1000). The difference of two counts, N = 2000
// and N = 1000, is the work of the requests from 1 s to 2 s alone, without start-up and
// construction: a measure of the per-step cost that does not depend on the machine's load.
// Usage: request_instructions SCENE INTEGRATOR FRICTION
int main(int argc, char** argv) {
  SceneConfig c;
  c.scene = parse_scene(argv[1]);
  c.integrator.type = parse_integrator(argv[2]);
  c.integrator.step = 1e-4;
  c.integrator.tolerance = 1e-12;
  c.initial.tilt = 0.3; c.initial.spin = 150.0;
  if (c.scene == SceneType::kViscous) c.top.friction = std::stod(argv[3]);
  auto sim = make_simulator(c);
  const int n = std::getenv("N") ? std::atoi(std::getenv("N")) : 1000;
  for (int i = 1; i <= n; ++i) sim->advance_to(i * 1e-3);
  std::printf("%ld\n", sim->steps());
}
