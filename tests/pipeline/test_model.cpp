// Which mesh each analysis gets under mesh.box.grading (pipeline::MeshUse): auto grades the modal
// mesh towards the crack front; the full and the reduced transient share one mesh, so that
// switching transient.model changes the cost, not the answer.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <filesystem>
#include <fstream>
#include <string>

#include "pipeline/model.hpp"
#include "scene/scene.hpp"
#include "study/plan.hpp"

namespace crackle {
namespace {

namespace fs = std::filesystem;

/// Crack pairs of the mesh a p = 1 cracked cantilever gets for `use` under `grading` and `model`.
std::size_t crack_pairs(const std::string& grading, const std::string& model, pipeline::MeshUse use) {
  const fs::path path = fs::temp_directory_path() / "crackle-test-model-grading.yaml";
  std::ofstream(path) << "mesh:\n  box: {size: [0.2, 0.02, 0.01], cells: [10, 2, 1], order: 1}\n"
                         "material: {E: 210.0e9, nu: 0.3, rho: 7850.0}\n"
                         "boundary:\n  - {face: x-, fix: [x, y, z]}\n"
                         "crack:\n  plane: {normal: x, at: 0.04}\n  region: {y: [0.0, 0.02], z: [0.005, 0.01]}\n"
                         "transient:\n"
                         "  excitation: {point: [0.2, 0.01, 0.01], direction: z, amplitude: 1.0, frequency: 100}\n"
                         "  periods: 2\n  probes:\n    - {name: tip, point: [0.2, 0.01, 0.01]}\n";
  const scene::Scene scene = scene::load_scene(path.string(), {{"mesh.box.grading", grading}, {"transient.model", model}});
  return pipeline::build_model(scene, use).mesh.crack_pairs.size();
}

TEST(MeshUse, AutoGradesTheModalMeshAndGivesBothTransientModelsOneMesh) {
  using pipeline::MeshUse;
  const std::size_t uniform = crack_pairs("none", "full", MeshUse::transient);
  EXPECT_GT(crack_pairs("auto", "full", MeshUse::modal), uniform);
  EXPECT_EQ(crack_pairs("auto", "full", MeshUse::transient), uniform);
  EXPECT_EQ(crack_pairs("auto", "reduced", MeshUse::transient), uniform);
  EXPECT_EQ(crack_pairs("always", "reduced", MeshUse::transient), crack_pairs("auto", "full", MeshUse::modal));
}

/// The cell next to `front` on its upper side (the line above it minus it).
double cell_above(const std::vector<double>& lines, double front) {
  const auto above = std::upper_bound(lines.begin(), lines.end(), front + 1e-12);
  return *above - front;
}

TEST(MeshUse, ModalStudyOverCrackDepthsGradesEveryCaseAndSharesOneMesh) {
  // A depth study on the modal analysis (graded under auto): each case grades towards its own
  // front at z = depth edge, yet all cases must keep one mesh (and one uncracked modal cache key).
  const std::string text =
      "mesh:\n  box: {size: [0.2, 0.02, 0.01], cells: [10, 2, 2], order: 2}\n"
      "material: {E: 210.0e9, nu: 0.3, rho: 7850.0}\n"
      "boundary:\n  - {face: x-, fix: [x, y, z]}\n"
      "crack:\n  plane: {normal: x, at: 0.04}\n  region: {y: [0.0, 0.02], z: [0.006, 0.01]}\n"
      "modal: {modes: 4}\n"
      "study:\n  vary: {crack.region.z: [[0.006, 0.01], [0.004, 0.01], [0.0025, 0.01]]}\n  outputs: [modal]\n";
  const study::StudyPlan plan = study::plan_study(text, "depths.yaml");
  ASSERT_EQ(plan.cases.size(), 3u);
  EXPECT_TRUE(plan.shares_grid_lines);
  const std::vector<double> fronts = {0.006, 0.004, 0.0025};
  std::array<std::vector<double>, 3> first;
  for (std::size_t c = 0; c < plan.cases.size(); ++c) {
    const scene::Scene shared = scene::parse_scene(plan.cases[c].scene_text, "case.yaml");
    const auto lines = pipeline::box_lines(shared, pipeline::MeshUse::modal);
    if (c == 0) first = lines;
    EXPECT_EQ(lines, first) << "case " << c << " meshes differently";
    EXPECT_EQ(plan.cases[c].modal_key, plan.cases.front().modal_key);
    // Graded towards its own front at least as finely as the case alone would be.
    const std::string alone_text =
        text.substr(0, text.find("study:")).replace(text.find("z: [0.006, 0.01]"), 16,
                                                    "z: [" + std::to_string(fronts[c]) + ", 0.01]");
    const scene::Scene alone = scene::parse_scene(alone_text, "alone.yaml");
    const auto alone_lines = pipeline::box_lines(alone, pipeline::MeshUse::modal);
    const auto alone_uniform = pipeline::box_lines(alone, pipeline::MeshUse::transient);
    EXPECT_LT(cell_above(alone_lines[2], fronts[c]), 0.5 * cell_above(alone_uniform[2], fronts[c]))
        << "case " << c << " alone is not graded";
    EXPECT_LE(cell_above(lines[2], fronts[c]), cell_above(alone_lines[2], fronts[c]) * (1 + 1e-9)) << "case " << c;
    // The transient keeps the uniform mesh (auto), with the shared crack edges only.
    const auto run_lines = pipeline::box_lines(shared, pipeline::MeshUse::transient);
    EXPECT_GT(cell_above(run_lines[2], fronts[c]), cell_above(lines[2], fronts[c]));
    EXPECT_LT(run_lines[2].size(), lines[2].size());
  }
}

}  // namespace
}  // namespace crackle
