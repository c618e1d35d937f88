// pipeline/refinement: what `crackle run` and `crackle sweep` share in estimating their results: the
// next finer mesh (an order, then front layers), the choice of the component to refine (largest error
// per second, with its limits and the budget), the tolerance loop, and the temporary folders of the
// refinement runs.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <sstream>

#include "pipeline/refinement.hpp"

namespace crackle::pipeline {
namespace {

namespace fs = std::filesystem;

TEST(Refinement, AFinerMeshIsAnOrderUpThenOneMoreFrontLayer) {
  Setting setting;
  setting.order = 3;
  EXPECT_EQ(finer_mesh(setting).order, 4);
  EXPECT_EQ(finer_mesh(setting).layers, 0);
  setting.order = kHighestOrder;
  EXPECT_EQ(finer_mesh(setting).order, kHighestOrder);
  EXPECT_EQ(finer_mesh(setting).layers, 1);
  // Each component has its own key, so that no two refinement runs share a folder or an outcome.
  const Neighbours n = neighbours(setting, true);
  ASSERT_TRUE(n.coarse && n.coarser);
  EXPECT_EQ(n.coarser->order, kHighestOrder - 2);
  const std::vector<std::string> keys = {setting.key(),   n.coarse->key(), n.band.key(),      n.steps.key(),
                                         n.penalty.key(), n.harmonics.key(), n.window.key(), finer_mesh(setting).key()};
  for (std::size_t i = 0; i < keys.size(); ++i)
    for (std::size_t j = i + 1; j < keys.size(); ++j) EXPECT_NE(keys[i], keys[j]) << i << " " << j;
  // No mesh levels on a Gmsh mesh or below order 3.
  EXPECT_FALSE(neighbours(setting, false).coarse);
  setting.order = 2;
  EXPECT_FALSE(neighbours(setting, true).coarse);
}

TEST(Refinement, TheComponentWithTheLargestErrorPerSecondIsRefinedWithinItsLimitsAndTheBudget) {
  Setting here;
  here.order = kHighestOrder;
  const Neighbours n = neighbours(here, true);
  SettingSummary summary;
  summary.largest = {{"mesh", 0.004}, {"modes", 0.001}, {"window", 0.012}};
  std::string blocking;
  // window: 0.012 / 10 s beats mesh: 0.004 / 100 s and modes: 0.001 / 2 s.
  std::vector<RefinementChoice> choices = {
      {"mesh", finer_mesh(here), 100.0}, {"modes", n.band, 2.0}, {"window", n.window, 10.0}};
  std::optional<Setting> next = choose_refinement(choices, summary, 600.0, "none", blocking);
  ASSERT_TRUE(next);
  EXPECT_EQ(next->window, 1);
  EXPECT_TRUE(blocking.empty());
  // Over the budget: blocked, naming the component and its cost.
  next = choose_refinement(choices, summary, 5.0, "none", blocking);
  EXPECT_FALSE(next);
  EXPECT_NE(blocking.find("window"), std::string::npos) << blocking;
  EXPECT_NE(blocking.find("accuracy.budget"), std::string::npos) << blocking;
  // Past the last tightening of the steady state, and past the last front layer: blocked.
  Setting tight = here;
  tight.window = kMostWindowRefinements;
  choices = {{"window", neighbours(tight, true).window, 1.0}};
  EXPECT_FALSE(choose_refinement(choices, summary, 600.0, "none", blocking));
  EXPECT_NE(blocking.find("steady state tightened"), std::string::npos) << blocking;
  Setting layered = here;
  layered.layers = kMostExtraLayers;
  choices = {{"mesh", finer_mesh(layered), 1.0}};
  EXPECT_FALSE(choose_refinement(choices, summary, 600.0, "none", blocking));
  EXPECT_NE(blocking.find("front layers"), std::string::npos) << blocking;
  // Nothing with an error left.
  summary.largest.clear();
  EXPECT_FALSE(choose_refinement({{"modes", n.band, 1.0}}, summary, 600.0, "nothing left", blocking));
  EXPECT_EQ(blocking, "nothing left");
}

TEST(Refinement, TheToleranceLoopRefinesUntilMetOrBlockedOrUnverified) {
  std::ostringstream out;
  const auto describe = [](const Setting& s) { return "order " + std::to_string(s.order); };
  // The error halves per order: 4 % at order 2 is 1 % at order 4.
  const auto summarize = [](const Setting& s) {
    SettingSummary summary;
    summary.worst = 0.04 / double(1 << (s.order - 2));
    summary.largest["mesh"] = summary.worst;
    return summary;
  };
  const auto refine = [](const Setting& s, std::string& blocking) -> std::optional<Setting> {
    if (s.order >= kHighestOrder) {
      blocking = "mesh";
      return std::nullopt;
    }
    return finer_mesh(s);
  };
  Setting setting;
  setting.order = 2;
  SettingSummary summary = summarize(setting);
  ToleranceOutcome outcome = reach_tolerance(0.01, setting, summary, refine, summarize, describe, out);
  ASSERT_TRUE(outcome.met);
  EXPECT_TRUE(*outcome.met);
  EXPECT_EQ(setting.order, 4);
  EXPECT_NE(out.str().find("refining to order 3"), std::string::npos) << out.str();
  // A tolerance below what order 4 gives: blocked at order 4, not met.
  setting.order = 2;
  summary = summarize(setting);
  outcome = reach_tolerance(0.001, setting, summary, refine, summarize, describe, out);
  EXPECT_FALSE(*outcome.met);
  EXPECT_EQ(outcome.blocking, "mesh");
  // An estimate that is not verified ends the loop at once.
  setting.order = 2;
  summary = summarize(setting);
  summary.verified = false;
  outcome = reach_tolerance(0.01, setting, summary, refine, summarize, describe, out);
  EXPECT_FALSE(*outcome.met);
  EXPECT_EQ(setting.order, 2);
  EXPECT_NE(outcome.blocking.find("not verified"), std::string::npos);
  // No tolerance: nothing refined, nothing said.
  EXPECT_FALSE(reach_tolerance(std::nullopt, setting, summary, refine, summarize, describe, out).met);
}

TEST(Refinement, RefinementFoldersAreTemporaryAndTheChosenOneIsAdopted) {
  const fs::path output = fs::temp_directory_path() / ("crackle-test-refinement-" + std::to_string(::getpid()));
  fs::create_directories(output);
  Setting first, refined;
  first.order = 3;
  refined.order = 4;
  {
    RefinementFolders folders(output, "");
    EXPECT_EQ(folders.folder(first, true), output);
    const fs::path scratch = folders.folder(refined, false);
    EXPECT_TRUE(fs::is_directory(scratch));
    EXPECT_NE(scratch.parent_path(), output);
    EXPECT_EQ(folders.cache().parent_path(), scratch.parent_path());  // the cache is temporary too
    std::ofstream(scratch / "run.json") << "{}";
    folders.adopt(refined);
    EXPECT_TRUE(fs::exists(output / "run.json"));
  }
  for (const fs::directory_entry& entry : fs::directory_iterator(output)) {
    EXPECT_EQ(entry.path().filename().string().find(".tmp."), std::string::npos) << entry.path();
  }
  fs::remove_all(output);
}

}  // namespace
}  // namespace crackle::pipeline
