// The viscous scene's simulators, one per integrator that serves it (the registry's rows): the
// scene's drivers are instantiated here and nowhere else.
#include "hybrid_simulator.hpp"

namespace spinning_top {
namespace scene_factory {

std::unique_ptr<Simulator> make_viscous_simulator(const SceneConfig& config) { return make_scene_simulator<Viscous>(config); }

}  // namespace scene_factory
}  // namespace spinning_top
