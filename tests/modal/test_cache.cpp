#include <gtest/gtest.h>

#include <filesystem>

#include "modal/cache.hpp"
#include "modal/modal.hpp"
#include "modal_meshes.hpp"

using namespace crackle;
using namespace crackle::modal;
namespace fs = std::filesystem;

TEST(ModalCache, SecondRunReadsTheUncrackedSolveAndAgreesExactly) {
  const fs::path cache = fs::temp_directory_path() / ("crackle-modal-cache-" + std::to_string(::getpid()));
  fs::remove_all(cache);
  mesh::Mesh mesh = modal::testing::box_mesh(Vec3(0.1, 0.01, 0.01), {10, 1, 1}, 2);
  std::vector<fem::DirichletCondition> clamp = {modal::testing::fix(mesh, "x-", {0, 1, 2})};
  ModalOptions options;
  options.modes = 4;
  options.variants = {mesh::Variant::uncracked};
  options.cache_directory = cache;
  const ModalResult first = run_modal(mesh, modal::testing::steel(0.3), clamp, options);
  const ModalResult second = run_modal(mesh, modal::testing::steel(0.3), clamp, options);
  EXPECT_FALSE(first.variants[0].modes.report.from_cache);
  EXPECT_TRUE(second.variants[0].modes.report.from_cache);
  EXPECT_EQ(first.variants[0].modes.frequencies_hz, second.variants[0].modes.frequencies_hz);
  EXPECT_EQ(first.variants[0].modes.shapes, second.variants[0].modes.shapes);
  // A different body (another Poisson ratio) has another key: solved, not read.
  const ModalResult other = run_modal(mesh, modal::testing::steel(0.25), clamp, options);
  EXPECT_FALSE(other.variants[0].modes.report.from_cache);
  EXPECT_NE(other.variants[0].modes.frequencies_hz[0], first.variants[0].modes.frequencies_hz[0]);
  fs::remove_all(cache);
}
