#include "spinning_top/ros/live_keys.hpp"

#include <cstring>

namespace spinning_top {
namespace ros_front_end {

// A key's holder (the third column of live_keys.def) as the two accessors of LiveKey.
#define SPINNING_TOP_LIVE_HOLDER_top(name) [](SceneConfig& c) { return &c.top.name; }, nullptr, #name
#define SPINNING_TOP_LIVE_HOLDER_integrator(name) [](SceneConfig& c) { return &c.integrator.name; }, nullptr, #name
#define SPINNING_TOP_LIVE_HOLDER_initial(name) [](SceneConfig& c) { return &c.initial.name; }, nullptr, "initial/" #name
#define SPINNING_TOP_LIVE_HOLDER_node(name) nullptr, [](NodeSettings& s) { return &s.name; }, nullptr

const std::vector<LiveKey>& live_keys() {
  static const std::vector<LiveKey> keys = {
#define SPINNING_TOP_LIVE_LEVEL(level, bit, meaning)
#define SPINNING_TOP_LIVE_KEY(name, level, holder, description) \
  {#name, level, &SpinningTopConfig::name, SPINNING_TOP_LIVE_HOLDER_##holder(name)},
#include "spinning_top/ros/live_keys.def"
#undef SPINNING_TOP_LIVE_KEY
#undef SPINNING_TOP_LIVE_LEVEL
  };
  return keys;
}

std::uint32_t changed_levels(const SpinningTopConfig& config, const SpinningTopConfig& old) {
  std::uint32_t levels = 0;
  for (const LiveKey& key : live_keys())
    if (config.*key.field != old.*key.field) levels |= key.level;
  return levels;
}

SceneConfig with_changes(SceneConfig top, const SpinningTopConfig& config, const SpinningTopConfig& old) {
  for (const LiveKey& key : live_keys())
    if (key.in_top != nullptr && config.*key.field != old.*key.field) *key.in_top(top) = config.*key.field;
  return top;
}

bool applies_to(const LiveKey& key, const SceneConfig& top) {
  return applies_only_to(key)[0] == '\0' || top.scene == SceneType::kViscous;
}

const char* applies_only_to(const LiveKey& key) {
  // The core's rule (validate(SceneConfig), simulator.cpp): friction in the viscous scene only.
  return std::strcmp(key.name, "friction") == 0 ? "the viscous scene" : "";
}

SceneConfig with_applicable_changes(SceneConfig top, const SpinningTopConfig& config, const SpinningTopConfig& old) {
  const SceneConfig unchanged = top;
  for (const LiveKey& key : live_keys())
    if (key.in_top != nullptr && config.*key.field != old.*key.field && applies_to(key, unchanged))
      *key.in_top(top) = config.*key.field;
  return top;
}

}  // namespace ros_front_end
}  // namespace spinning_top
