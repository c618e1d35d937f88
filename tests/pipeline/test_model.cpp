// Which mesh each analysis gets under mesh.box.grading (pipeline::MeshUse): auto grades the modal
// and the reduced models towards the crack front and leaves the full explicit transient uniform.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <string>

#include "pipeline/model.hpp"
#include "scene/scene.hpp"

namespace crackle {
namespace {

namespace fs = std::filesystem;

/// Crack pairs of the run's mesh of a p = 1 cracked cantilever under `grading` and `model`.
std::size_t run_crack_pairs(const std::string& grading, const std::string& model) {
  const fs::path path = fs::temp_directory_path() / "crackle-test-model-grading.yaml";
  std::ofstream(path) << "mesh:\n  box: {size: [0.2, 0.02, 0.01], cells: [10, 2, 1], order: 1}\n"
                         "material: {E: 210.0e9, nu: 0.3, rho: 7850.0}\n"
                         "boundary:\n  - {face: x-, fix: [x, y, z]}\n"
                         "crack:\n  plane: {normal: x, at: 0.04}\n  region: {y: [0.0, 0.02], z: [0.005, 0.01]}\n"
                         "transient:\n"
                         "  excitation: {point: [0.2, 0.01, 0.01], direction: z, amplitude: 1.0, frequency: 100}\n"
                         "  periods: 2\n  probes:\n    - {name: tip, point: [0.2, 0.01, 0.01]}\n";
  const scene::Scene scene = scene::load_scene(path.string(), {{"mesh.box.grading", grading}, {"transient.model", model}});
  return pipeline::build_model(scene, pipeline::run_mesh_use(scene)).mesh.crack_pairs.size();
}

TEST(MeshUse, AutoGradingGradesTheReducedRunNotTheFullOne) {
  const std::size_t uniform = run_crack_pairs("none", "reduced");
  EXPECT_EQ(run_crack_pairs("auto", "full"), uniform);  // the explicit step would pay the smallest cell
  EXPECT_GT(run_crack_pairs("auto", "reduced"), uniform);
  EXPECT_EQ(run_crack_pairs("auto", "reduced"), run_crack_pairs("always", "full"));
}

}  // namespace
}  // namespace crackle
