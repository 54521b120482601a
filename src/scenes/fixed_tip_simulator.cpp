// The fixed_tip scene's simulators, one per integrator that serves it (the registry's rows): the
// scene's drivers are instantiated here and nowhere else.
#include "hybrid_simulator.hpp"

namespace spinning_top {
namespace scene_factory {

std::unique_ptr<Simulator> make_fixed_tip_simulator(const SceneConfig& config) { return make_scene_simulator<FixedTip>(config); }

}  // namespace scene_factory
}  // namespace spinning_top
