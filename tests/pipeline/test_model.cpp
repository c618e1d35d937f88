// Which mesh each analysis gets under mesh.box.grading (pipeline::MeshUse): auto grades the modal
// mesh towards the crack front; the full and the reduced transient share one mesh, so that
// switching transient.model changes the cost, not the answer.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <string>

#include "pipeline/model.hpp"
#include "scene/scene.hpp"

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

}  // namespace
}  // namespace crackle
