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

// Both variants are cached by the fingerprint of their K and M: a second run of the same cracked
// body reads both; a deeper crack changes the open K (solved again) but not the uncracked one (read).
TEST(ModalCache, OpenVariantIsCachedUntilTheCrackChanges) {
  const fs::path cache = fs::temp_directory_path() / ("crackle-modal-cache-open-" + std::to_string(::getpid()));
  fs::remove_all(cache);
  mesh::CrackSpec crack = modal::testing::edge_crack();
  const auto solve = [&](const mesh::CrackSpec& spec) {
    mesh::Mesh mesh = modal::testing::box_mesh(Vec3(1.0, 0.1, 0.2), {10, 1, 4}, 1, spec);
    std::vector<fem::DirichletCondition> clamp = {modal::testing::fix(mesh, "x-", {0, 1, 2})};
    ModalOptions options;
    options.modes = 3;
    options.variants = {mesh::Variant::uncracked, mesh::Variant::open};
    options.cache_directory = cache;
    return run_modal(mesh, modal::testing::steel(0.3), clamp, options);
  };
  const ModalResult first = solve(crack);
  const ModalResult second = solve(crack);
  EXPECT_FALSE(first.variants[1].modes.report.from_cache);
  EXPECT_TRUE(second.variants[0].modes.report.from_cache);
  EXPECT_TRUE(second.variants[1].modes.report.from_cache);
  EXPECT_EQ(first.variants[1].modes.frequencies_hz, second.variants[1].modes.frequencies_hz);
  EXPECT_EQ(first.pairs[0].f_bilinear_hz, second.pairs[0].f_bilinear_hz);
  // The MAC is read with the modes: the same matrix, and no mass matrix assembled for it.
  EXPECT_EQ(first.mac, second.mac);
  EXPECT_GT(first.variants[0].mass.nonZeros(), 0);
  EXPECT_EQ(second.variants[0].mass.nonZeros(), 0);
  EXPECT_EQ(second.variants[1].mass.nonZeros(), 0);
  crack.region[kZ] = {0.0, 0.15};
  const ModalResult deeper = solve(crack);
  EXPECT_TRUE(deeper.variants[0].modes.report.from_cache);
  EXPECT_FALSE(deeper.variants[1].modes.report.from_cache);
  EXPECT_LT(deeper.variants[1].modes.frequencies_hz[0], first.variants[1].modes.frequencies_hz[0]);
  // A new open solve: its MAC computed on the uncracked mass (assembled now), not read.
  EXPECT_GT(deeper.variants[0].mass.nonZeros(), 0);
  EXPECT_NE(deeper.mac, first.mac);
  const ModalResult deeper_again = solve(crack);
  EXPECT_EQ(deeper_again.mac, deeper.mac);
  EXPECT_EQ(deeper_again.variants[0].mass.nonZeros(), 0);
  fs::remove_all(cache);
}

// The MAC's key holds its weighting: a plain MAC is not read for a mass-weighted one.
TEST(ModalCache, TheMacIsCachedPerWeighting) {
  const fs::path cache = fs::temp_directory_path() / ("crackle-modal-cache-mac-" + std::to_string(::getpid()));
  fs::remove_all(cache);
  const auto solve = [&](MacWeighting weighting) {
    mesh::Mesh mesh = modal::testing::box_mesh(Vec3(1.0, 0.1, 0.2), {10, 1, 4}, 1, modal::testing::edge_crack());
    std::vector<fem::DirichletCondition> clamp = {modal::testing::fix(mesh, "x-", {0, 1, 2})};
    ModalOptions options;
    options.modes = 3;
    options.variants = {mesh::Variant::uncracked, mesh::Variant::open};
    options.cache_directory = cache;
    options.mac = weighting;
    return run_modal(mesh, modal::testing::steel(0.3), clamp, options);
  };
  const ModalResult weighted = solve(MacWeighting::mass);
  const ModalResult plain = solve(MacWeighting::plain);
  EXPECT_TRUE(plain.variants[1].modes.report.from_cache);
  EXPECT_GT((plain.mac - weighted.mac).cwiseAbs().maxCoeff(), 1e-6);
  EXPECT_EQ(solve(MacWeighting::plain).mac, plain.mac);
  EXPECT_EQ(solve(MacWeighting::mass).mac, weighted.mac);
  fs::remove_all(cache);
}
