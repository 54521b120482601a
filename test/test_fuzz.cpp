// Issue 10, item 4: the fuzz harness (fuzz_harness.hpp) over a few thousand random cases in the
// test run. Each case's promises are checked there; this test fails on any broken one (printed
// with the case's seed, so that `fuzz_soak --seed N` replays it) and checks that the cases reach
// what they should: every scene and integrator run, refusals, live updates applied and refused,
// budgets exhausted, events. The wall bound per case is a hang guard, not a speed assertion.
#include <gtest/gtest.h>
#include <stdlib.h>

#include <cstdlib>

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

// Issue 19: random scene files (shapes, anchors and aliases, tags, quotes, number forms; see
// SceneFileCase) read as every front end reads one and run for 0.02 s: no crash, no non-finite
// output, no accepted garbage (a file holding something that must be refused, or a number YAML 1.1
// and 1.2 read differently), every refusal one line. Deterministic seeds.
TEST(Fuzz, RandomSceneFilesAreRefusedOrMeanTheSameToBothYamlVersions) {
  constexpr int kCases = 3000;
  std::string dir = ::testing::TempDir() + "test_fuzz_scene.XXXXXX";
  ASSERT_NE(mkdtemp(dir.data()), nullptr);
  long ran = 0, by_reader = 0, by_validation = 0, defective = 0, crashes = 0, non_finite = 0, garbage = 0;
  std::map<std::string, long> reader_reasons, validation_keys, mutations;
  std::vector<std::string> failures;
  for (int seed = 1; seed <= kCases; ++seed) {
    const fuzz::SceneFileOutcome o =
        fuzz::SceneFileCase(static_cast<unsigned long long>(seed)).run(dir + "/scene.yaml", 0.02, 5000);
    defective += o.had_defect;
    for (const std::string& m : o.mutations) ++mutations[m];
    switch (o.kind) {
      case fuzz::SceneFileOutcome::Kind::kRefusedByReader: ++by_reader, ++reader_reasons[o.reason]; break;
      case fuzz::SceneFileOutcome::Kind::kRefusedByValidation: ++by_validation, ++validation_keys[o.reason]; break;
      case fuzz::SceneFileOutcome::Kind::kRan: ++ran; break;
    }
    for (const std::string& f : o.failures) {
      crashes += f.find(": crash") != std::string::npos;
      non_finite += f.find("non-finite") != std::string::npos || f.find("non_finite") != std::string::npos;
      garbage += f.find("accepted garbage") != std::string::npos;
      failures.push_back(f);
    }
  }
  std::system(("rm -rf '" + dir + "'").c_str());
  std::printf("[ measured ] %d scene files (%ld with something to refuse): %ld ran, %ld refused by the reader, "
              "%ld by the validation; %ld crashes, %ld non-finite outputs, %ld accepted garbage\n",
              kCases, defective, ran, by_reader, by_validation, crashes, non_finite, garbage);
  for (const auto& kv : reader_reasons) std::printf("[ measured ] reader refused: %-28s %ld\n", kv.first.c_str(), kv.second);
  for (const auto& kv : validation_keys) std::printf("[ measured ] validation refused %-24s %ld\n", kv.first.c_str(), kv.second);
  for (const auto& kv : mutations) std::printf("[ measured ] mutation %-26s %ld\n", kv.first.c_str(), kv.second);

  for (std::size_t i = 0; i < std::min<std::size_t>(failures.size(), 30); ++i) ADD_FAILURE() << failures[i];
  EXPECT_EQ(crashes, 0);
  EXPECT_EQ(non_finite, 0);
  EXPECT_EQ(garbage, 0);
  EXPECT_TRUE(failures.empty()) << failures.size() << " broken promises";
  // What the cases must reach for the run to mean something.
  EXPECT_GT(ran, kCases / 5);
  EXPECT_GT(by_reader, kCases / 5);
  EXPECT_GT(by_validation, kCases / 50);
  for (const char* reason : {"anchor", "merge key", "a list", "quoted", "tag", "leading zero", "hexadecimal",
                             "YAML 1.1 reads it as text", "finite", "boolean", "32 bits", "given twice",
                             "YAML documents", "malformed YAML"})
    EXPECT_GT(reader_reasons[reason], 0) << reason << " never refused";
}

}  // namespace
}  // namespace spinning_top
