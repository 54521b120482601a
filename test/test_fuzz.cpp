// Issue 10, item 4: the fuzz harness (fuzz_harness.hpp) over a few thousand random cases in the
// test run. Each case's promises are checked there; this test fails on any broken one (printed
// with the case's seed, so that `fuzz_soak --seed N` replays it) and checks that the cases reach
// what they should: every scene and integrator run, refusals, live updates applied and refused,
// budgets exhausted, events. The wall bound per case is a hang guard, not a speed assertion.
#include <gtest/gtest.h>

#include <map>
#include <set>

#include "fuzz_harness.hpp"

namespace spinning_top {
namespace {

TEST(Fuzz, RandomConfigurationsStatesAndLiveUpdatesKeepEveryPromise) {
  constexpr int kCases = 5000;
  fuzz::Limits limits;
  std::vector<std::string> failures;
  std::map<std::string, int> refused_by_key, events, methods;
  std::set<SceneType> scenes_run;
  int ran = 0, out_of_budget = 0, updates_applied = 0, updates_refused = 0, resets = 0;
  double worst_norm = 0.0, worst_balance = 0.0, wall = 0.0, slowest = 0.0;
  for (int seed = 1; seed <= kCases; ++seed) {
    fuzz::Case c(static_cast<unsigned long long>(seed));
    const fuzz::Outcome o = c.run(limits);
    failures.insert(failures.end(), o.failures.begin(), o.failures.end());
    wall += o.wall;
    slowest = std::max(slowest, o.wall);
    if (o.kind == fuzz::Outcome::Kind::kRefused) {
      ++refused_by_key[o.refused_key];
      continue;
    }
    ++ran;
    scenes_run.insert(o.scene);
    ++methods[o.integrator];
    if (o.kind == fuzz::Outcome::Kind::kOutOfBudget) ++out_of_budget;
    ++events[o.event == Event::kNone ? "none" : to_string(o.event)];
    updates_applied += o.updates_applied;
    updates_refused += o.updates_refused;
    resets += o.resets;
    worst_norm = std::max(worst_norm, o.worst_norm_error);
    worst_balance = std::max(worst_balance, o.worst_balance);
  }
  std::printf("[ measured ] %d cases: %d ran (%d out of budget), %d refused; %d updates applied, %d refused; "
              "%d resets; %.1f s wall, slowest case %.2f s\n",
              kCases, ran, out_of_budget, kCases - ran, updates_applied, updates_refused, resets, wall, slowest);
  std::printf("[ measured ] worst | |q| - 1 | = %.3g, worst energy balance drift = %.3g of the allowed\n",
              worst_norm, worst_balance);
  for (const auto& kv : events) std::printf("[ measured ] ended by %-12s %d\n", kv.first.c_str(), kv.second);
  for (const auto& kv : methods) std::printf("[ measured ] ran %-12s %d\n", kv.first.c_str(), kv.second);
  for (const auto& kv : refused_by_key) std::printf("[ measured ] refused %-24s %d\n", kv.first.c_str(), kv.second);

  for (std::size_t i = 0; i < std::min<std::size_t>(failures.size(), 30); ++i) ADD_FAILURE() << failures[i];
  EXPECT_TRUE(failures.empty()) << failures.size() << " broken promises";
  // What the cases must have reached for the run to mean something.
  EXPECT_EQ(scenes_run.size(), 3u);
  for (const IntegratorInfo& row : integrator_registry())
    if (row.type != IntegratorType::kAuto) {
      EXPECT_GT(methods[row.name], 0) << row.name << " never ran";
    }
  EXPECT_GT(ran, kCases / 10);
  EXPECT_GT(kCases - ran, kCases / 10);
  EXPECT_GT(out_of_budget, 0);
  EXPECT_GT(updates_applied, 100);
  EXPECT_GT(updates_refused, 100);
  EXPECT_GT(events["lift_off"], 0);
  EXPECT_GT(events["fallen"], 0);
}

}  // namespace
}  // namespace spinning_top
