// The node's live keys have one table (include/spinning_top/ros/live_keys.def, issue 17): the
// dynamic_reconfigure parameters that cfg/SpinningTop.cfg generated are its keys, at its levels,
// with the configuration's defaults (those of the key table and of NodeSettings), and the node
// applies a change of each key to where it keeps it. No ROS master: the generated configuration
// and the table only.
#include <gtest/gtest.h>

#include <cstring>
#include <string>

#include "spinning_top/config.hpp"
#include "spinning_top/ros/live_keys.hpp"

namespace spinning_top {
namespace ros_front_end {
namespace {

bool same_bits(double a, double b) { return std::memcmp(&a, &b, sizeof a) == 0; }

TEST(LiveKeys, TheCfgsParametersAreTheTablesKeysAtTheirLevels) {
  const auto& parameters = SpinningTopConfig::__getParamDescriptions__();
  ASSERT_EQ(parameters.size(), live_keys().size());
  for (std::size_t i = 0; i < parameters.size(); ++i) {
    EXPECT_EQ(parameters[i]->name, live_keys()[i].name);
    EXPECT_EQ(parameters[i]->level, static_cast<std::uint32_t>(live_keys()[i].level)) << live_keys()[i].name;
    EXPECT_EQ(parameters[i]->type, "double") << live_keys()[i].name;
    // Each key is kept by a top or by the node, not both.
    EXPECT_NE(live_keys()[i].in_top == nullptr, live_keys()[i].in_node == nullptr) << live_keys()[i].name;
  }
}

TEST(LiveKeys, TheCfgsDefaultsAreTheConfigurationsDefaults) {
  const SpinningTopConfig& cfg = SpinningTopConfig::__getDefault__();
  SceneConfig keys = parse_scene_config({}, /*require_all=*/false);  // the key table's defaults
  NodeSettings node;
  for (const LiveKey& key : live_keys()) {
    const double expected = key.in_top != nullptr ? *key.in_top(keys) : *key.in_node(node);
    EXPECT_TRUE(same_bits(cfg.*key.field, expected)) << key.name << ": " << cfg.*key.field << " != " << expected;
  }
}

TEST(LiveKeys, AChangeOfEachKeyReachesWhereItIsKeptAndOnlyThere) {
  const SpinningTopConfig old = SpinningTopConfig::__getDefault__();
  SceneConfig start;
  for (const LiveKey& key : live_keys()) {
    SpinningTopConfig config = old;
    config.*key.field += 0.5;
    EXPECT_EQ(changed_levels(config, old), static_cast<std::uint32_t>(key.level)) << key.name;
    SceneConfig changed = with_changes(start, config, old);
    if (key.in_top == nullptr) continue;  // the node's pacing: not a top's
    EXPECT_EQ(*key.in_top(changed), config.*key.field) << key.name;
    *key.in_top(changed) = *key.in_top(start);  // the rest is unchanged
    EXPECT_EQ(std::memcmp(&changed.top, &start.top, sizeof start.top), 0) << key.name;
    EXPECT_EQ(std::memcmp(&changed.initial, &start.initial, sizeof start.initial), 0) << key.name;
    EXPECT_EQ(changed.integrator.step, start.integrator.step) << key.name;
    EXPECT_EQ(changed.integrator.tolerance, start.integrator.tolerance) << key.name;
  }
  EXPECT_EQ(changed_levels(old, old), 0u);
}

// Issue 19: friction acts on viscous tops only; a change of it leaves another top as it was, and
// every other key reaches every scene.
TEST(LiveKeys, AKeyReachesOnlyTheTopsItAppliesTo) {
  const SpinningTopConfig old = SpinningTopConfig::__getDefault__();
  for (const SceneType scene : {SceneType::kFixedTip, SceneType::kFrictionless, SceneType::kViscous}) {
    SceneConfig start;
    start.scene = scene;
    for (const LiveKey& key : live_keys()) {
      if (key.in_top == nullptr) continue;
      SpinningTopConfig config = old;
      config.*key.field += 0.5;
      const bool applies = applies_to(key, start);
      EXPECT_EQ(applies, std::string(key.name) != "friction" || scene == SceneType::kViscous) << key.name;
      EXPECT_EQ(applies, applies_only_to(key)[0] == '\0' || scene == SceneType::kViscous) << key.name;
      const SceneConfig changed = with_applicable_changes(start, config, old);
      EXPECT_EQ(*key.in_top(const_cast<SceneConfig&>(changed)), applies ? config.*key.field : *key.in_top(start))
          << key.name << " in " << to_string(scene);
    }
  }
}

}  // namespace
}  // namespace ros_front_end
}  // namespace spinning_top
