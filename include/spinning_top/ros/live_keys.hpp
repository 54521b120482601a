// The node's live keys, from their one table (live_keys.def, which cfg/SpinningTop.cfg reads
// too): what dynamic_reconfigure changes, what applying a change takes, and where the node keeps
// each value (a top's SceneConfig or the node's NodeSettings).
#pragma once

#include <cstdint>
#include <vector>

#include "spinning_top/SpinningTopConfig.h"
#include "spinning_top/ros/node_settings.hpp"
#include "spinning_top/simulator.hpp"

namespace spinning_top {
namespace ros_front_end {

/// What applying a change takes (dynamic_reconfigure's level bits).
enum LiveLevel : std::uint32_t {
#define SPINNING_TOP_LIVE_LEVEL(level, bit, meaning) level = bit,
#define SPINNING_TOP_LIVE_KEY(name, level, holder, description)
#include "spinning_top/ros/live_keys.def"
#undef SPINNING_TOP_LIVE_KEY
#undef SPINNING_TOP_LIVE_LEVEL
};

struct LiveKey {
  const char* name;
  LiveLevel level;
  double SpinningTopConfig::*field;       ///< its value in dynamic_reconfigure's configuration
  double* (*in_top)(SceneConfig& top);    ///< where a top keeps it; null for the node's own
  double* (*in_node)(NodeSettings& node);  ///< where the node keeps it; null for a top's
  const char* scene_key;  ///< its key in a scene file (initial/spin for spin); null for the node's
};

/// Every live key, in the order of live_keys.def (and of the cfg).
const std::vector<LiveKey>& live_keys();

/// The levels of the keys whose values differ between `config` and `old`.
std::uint32_t changed_levels(const SpinningTopConfig& config, const SpinningTopConfig& old);

/// `top` with the value of every key held by a top that differs between `config` and `old`.
SceneConfig with_changes(SceneConfig top, const SpinningTopConfig& config, const SpinningTopConfig& old);

/// Whether a top of configuration `top` runs with `key` at all: friction acts in the viscous scene
/// only (validate(SceneConfig) refuses it in the others); every other key acts on every top. A
/// live change leaves a top alone for the keys that do not apply to it.
bool applies_to(const LiveKey& key, const SceneConfig& top);

/// What a key that does not apply everywhere needs (for a refusal when no top runs it):
/// "the viscous scene"; "" for a key that applies to every top.
const char* applies_only_to(const LiveKey& key);

/// with_changes() restricted to the keys that apply to `top` (applies_to()).
SceneConfig with_applicable_changes(SceneConfig top, const SpinningTopConfig& config, const SpinningTopConfig& old);

}  // namespace ros_front_end
}  // namespace spinning_top
