// Studies at the edges: nested YAML aliases (a "billion laughs" file) and plans too large to run
// fail at once with a message naming the key and the limit; messages show what was written.
#include <gtest/gtest.h>

#include <chrono>
#include <string>

#include "core/errors.hpp"
#include "study/plan.hpp"

namespace crackle::study {
namespace {

/// Lines 1-5.
const std::string kBase =
    "mesh:\n"
    "  box: {size: [0.2, 0.02, 0.01], cells: [20, 2, 2], order: 1}\n"
    "material: {E: 210.0e9, nu: 0.3, rho: 7850.0}\n"
    "boundary:\n"
    "  - {face: x-, fix: [x, y, z]}\n";

std::string error_of(const std::string& text) {
  try {
    plan_study(text, "bomb.yaml");
  } catch (const InputError& error) {
    return error.what();
  }
  return "(no error)";
}

/// Ten levels of nine aliases each: 9^10 (3.5e9) values once expanded, in 11 lines.
std::string alias_bomb() {
  std::string text = "    material.nu:\n      - &a0 [0.3, 0.3, 0.3, 0.3, 0.3, 0.3, 0.3, 0.3, 0.3]\n";
  for (int level = 1; level <= 9; ++level) {
    const std::string alias = "*a" + std::to_string(level - 1);
    text += "      - &a" + std::to_string(level) + " [";
    for (int i = 0; i < 9; ++i) text += (i ? ", " : "") + alias;
    text += "]\n";
  }
  return text;
}

TEST(StudyLimits, NestedAliasesFailAtOnceNamingTheKeyAndTheLimit) {
  const auto start = std::chrono::steady_clock::now();
  EXPECT_EQ(error_of(kBase + "study:\n  vary:\n" + alias_bomb()),
            "bomb.yaml:8: study.vary.material.nu: expected at most 1000000 YAML nodes with aliases expanded, "
            "got more (nested aliases?)");
  EXPECT_LT(std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count(), 20.0);
}

TEST(StudyLimits, PlansTooLargeToRunAreRefused) {
  // 1000 x 1000 x 1000 cases.
  const std::string grid = kBase +
                           "study:\n  vary:\n"
                           "    material.E: {from: 1e9, to: 2e9, steps: 1000}\n"
                           "    material.nu: {from: 0.1, to: 0.3, steps: 1000}\n"
                           "    material.rho: {from: 1000, to: 8000, steps: 1000}\n";
  EXPECT_EQ(error_of(grid), "bomb.yaml:6: study.vary: expected at most 100000 cases, got more");
  EXPECT_EQ(error_of(kBase + "study:\n  vary:\n    material.E: {from: 1e9, to: 2e9, steps: 10000000}\n"),
            "bomb.yaml:8: study.vary.material.E.steps: expected an integer in 2..100000 (a study has at most "
            "100000 cases), got 10000000");
  EXPECT_EQ(error_of(kBase + "study:\n  vary:\n    material.E: {from: 1e9, to: 2e9, steps: 1e7}\n"),
            "bomb.yaml:8: study.vary.material.E.steps: expected an integer in 2..100000 (a study has at most "
            "100000 cases), got 1e7");
}

TEST(StudyLimits, EmptyVarySaysEmpty) {
  EXPECT_EQ(error_of(kBase + "study:\n  vary: {}\n"),
            "bomb.yaml:7: study.vary: expected a map from scene key paths (e.g. crack.region.z) to lists of "
            "values or ranges, got an empty map");
}

}  // namespace
}  // namespace crackle::study
