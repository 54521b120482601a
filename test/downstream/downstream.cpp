// A downstream package's use of spinning_top: its installed headers (simulator.hpp needs C++17:
// std::optional) and its core library, built and run by test_downstream.py.
#include <cstdio>
#include <exception>
#include <memory>
#include <optional>

#include "spinning_top/simulator.hpp"

int main() {
  try {
    const spinning_top::SceneConfig config;  // the defaults: the toy top on a fixed pivot
    const std::unique_ptr<spinning_top::Simulator> sim = spinning_top::make_simulator(config);
    sim->advance_to(0.01);
    const std::optional<spinning_top::MotionRange> range = sim->motion_range();
    std::printf("downstream: C++ %ld, t = %g s, %s, extremes %s\n", static_cast<long>(__cplusplus), sim->time(),
                sim->integrator_description().c_str(), range ? "in closed form" : "sampled");
    return sim->time() == 0.01 ? 0 : 1;
  } catch (const std::exception& error) {
    std::fprintf(stderr, "downstream: %s\n", error.what());
    return 1;
  }
}
