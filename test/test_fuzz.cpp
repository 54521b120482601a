// Issue 10, item 4: the fuzz harness (fuzz_harness.hpp) over a few thousand random cases in the
// test run. Each case's promises are checked there; this test fails on any broken one (printed
// with the case's seed, so that `fuzz_soak --seed N` replays it) and checks that the cases reach
// what they should: every scene and integrator run, refusals, live updates applied and refused,
// budgets exhausted, events. The wall bound per case is a hang guard, not a speed assertion.
#include <gtest/gtest.h>

#include "fuzz_harness.hpp"

namespace spinning_top {
namespace {

TEST(Fuzz, RandomConfigurationsStatesAndLiveUpdatesKeepEveryPromise) {
  constexpr int kCases = 5000;
  const fuzz::Limits limits;
  fuzz::Tally t;
  for (int seed = 1; seed <= kCases; ++seed) t.add(fuzz::Case(static_cast<unsigned long long>(seed)).run(limits), seed);
  std::printf("[ measured ] %d cases: %ld ran (%ld out of budget), %ld refused; %ld updates applied, %ld refused; "
              "%ld resets; %.1f s wall, slowest case %.2f s (seed %llu)\n",
              kCases, t.ran, t.out_of_budget, t.cases - t.ran, t.updates_applied, t.updates_refused, t.resets, t.wall,
              t.slowest, t.slowest_seed);
  std::printf("[ measured ] worst | |q| - 1 | = %.3g, worst energy balance drift = %.3g of the allowed\n",
              t.worst_norm_error, t.worst_balance);
  for (const auto& kv : t.events) std::printf("[ measured ] ended by %-12s %ld\n", kv.first.c_str(), kv.second);
  for (const auto& kv : t.methods) std::printf("[ measured ] ran %-12s %ld\n", kv.first.c_str(), kv.second);
  for (const auto& kv : t.refused_by_key)
    std::printf("[ measured ] refused %-24s %ld\n", kv.first.c_str(), kv.second);

  for (std::size_t i = 0; i < std::min<std::size_t>(t.failures.size(), 30); ++i) ADD_FAILURE() << t.failures[i];
  EXPECT_TRUE(t.failures.empty()) << t.failures.size() << " broken promises";
  // What the cases must have reached for the run to mean something.
  EXPECT_EQ(t.scenes_run.size(), 3u);
  for (const IntegratorInfo& row : integrator_registry())
    if (row.type != IntegratorType::kAuto) {
      EXPECT_GT(t.methods[row.name], 0) << row.name << " never ran";
    }
  EXPECT_GT(t.ran, kCases / 10);
  EXPECT_GT(kCases - t.ran, kCases / 10);
  EXPECT_GT(t.out_of_budget, 0);
  EXPECT_GT(t.updates_applied, 100);
  EXPECT_GT(t.updates_refused, 100);
  EXPECT_GT(t.events["lift_off"], 0);
  EXPECT_GT(t.events["fallen"], 0);
}

}  // namespace
}  // namespace spinning_top
