// The per-scene factories, one translation unit each (src/scenes/*_simulator.cpp), so that
// make_simulator (src/simulator.cpp) needs none of the integrators' headers.
#pragma once

#include <memory>

#include "spinning_top/simulator.hpp"

namespace spinning_top {
namespace scene_factory {

/// Build the scene's simulator for a validated configuration.
std::unique_ptr<Simulator> make_fixed_tip_simulator(const SceneConfig& config);
std::unique_ptr<Simulator> make_frictionless_simulator(const SceneConfig& config);
std::unique_ptr<Simulator> make_viscous_simulator(const SceneConfig& config);

}  // namespace scene_factory
}  // namespace spinning_top
