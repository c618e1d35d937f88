// Modal analysis of elastic boxes against theory (MODEL.md sec. 5, eqs. 25a, 25c): axial bar,
// Timoshenko cantilever, h-convergence rates, rigid-body modes, the two variants of a cracked
// beam, backend and mass-matrix agreement, output files.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <string>

#include <nlohmann/json.hpp>

#include "beam_theory.hpp"
#include "core/errors.hpp"
#include "modal/modal.hpp"
#include "modal_meshes.hpp"
#include "output/modal_json.hpp"

namespace crackle::modal {
namespace {

using testing::box_mesh;
using testing::edge_crack;
using testing::fix;
using testing::steel;

constexpr double kSoundSpeed = 5188.745216627708;  // sqrt(2.1e11 / 7800) [m/s]

/// Share of a mass-normalised free-DOF shape's squared entries in each displacement component.
Vec3 component_share(const VariantResult& variant, const VectorX& shape) {
  Vec3 share = Vec3::Zero();
  for (Index i = 0; i < shape.size(); ++i) share[variant.constraints.free_dofs[i] % 3] += shape[i] * shape[i];
  return share / share.sum();
}

TEST(ModalBar, AxialModesOfClampedFreeBarMatchTheory) {
  // nu = 0: the axial modes are exactly one-dimensional, f_n = (2n - 1) c / (4 L). Rollers on the
  // lateral faces remove bending, so the lowest modes are the axial ones.
  const mesh::Mesh mesh = box_mesh(Vec3(1.0, 0.1, 0.1), {8, 1, 1}, 4);
  const std::vector<fem::DirichletCondition> supports = {
      fix(mesh, "x-", {0}), fix(mesh, "y-", {1}), fix(mesh, "y+", {1}), fix(mesh, "z-", {2}), fix(mesh, "z+", {2})};
  ModalOptions options;
  options.modes = 3;
  const ModalResult result = run_modal(mesh, steel(0.0), supports, options);
  ASSERT_EQ(result.variants.size(), 1u);
  const ModeSet& modes = result.variants[0].modes;
  EXPECT_EQ(modes.n_rigid(), 0);
  EXPECT_EQ(modes.n_rigid_expected, 0);
  for (int n = 1; n <= 3; ++n) {
    const double exact = (2 * n - 1) * kSoundSpeed / 4.0;
    EXPECT_NEAR(modes.frequencies_hz[n - 1], exact, 1e-6 * exact) << "axial mode " << n;
    EXPECT_GT(component_share(result.variants[0], modes.shapes.col(n - 1))[0], 1.0 - 1e-12);
  }
  EXPECT_LT(modes.orthogonality_error, 1e-12);
}

TEST(ModalBar, AxialModesAmongBendingModesWithThreeRigidModes) {
  // Only u_x fixed on x-: y, z translations and the rotation about x stay free (3 rigid modes);
  // the axial modes are picked out by their shape.
  const mesh::Mesh mesh = box_mesh(Vec3(1.0, 0.1, 0.1), {8, 1, 1}, 4);
  ModalOptions options;
  options.modes = 12;
  const ModalResult result = run_modal(mesh, steel(0.0), {fix(mesh, "x-", {0})}, options);
  const VariantResult& variant = result.variants[0];
  EXPECT_EQ(variant.modes.n_rigid_expected, 3);
  ASSERT_EQ(variant.modes.n_rigid(), 3);
  std::vector<double> axial;
  for (int i = 0; i < variant.modes.n_modes(); ++i) {
    if (component_share(variant, variant.modes.shapes.col(i))[0] > 1.0 - 1e-9) axial.push_back(variant.modes.frequencies_hz[i]);
  }
  ASSERT_GE(axial.size(), 2u);
  for (int n = 1; n <= 2; ++n) {
    const double exact = (2 * n - 1) * kSoundSpeed / 4.0;
    EXPECT_NEAR(axial[n - 1], exact, 1e-6 * exact) << "axial mode " << n;
  }
}

TEST(ModalBeam, SlenderCantileverMatchesTimoshenko) {
  // L / t = 20, nu = 0.3: the first three bending modes in the thin direction (z) and the first
  // in the wide direction (y) within 1 % of Timoshenko theory (the 3D clamp differs slightly).
  const double length = 1.0, width = 0.1, thickness = 0.05;
  const mesh::Mesh mesh = box_mesh(Vec3(length, width, thickness), {20, 2, 1}, 3);
  ModalOptions options;
  options.modes = 8;
  const ModalResult result = run_modal(mesh, steel(0.3), {fix(mesh, "x-", {0, 1, 2})}, options);
  const VariantResult& variant = result.variants[0];
  EXPECT_EQ(variant.modes.n_rigid(), 0);
  testing::TimoshenkoBeam beam;
  beam.length = length;
  beam.poisson = 0.3;
  auto check = [&](double beam_width, double beam_thickness, int component, int count) {
    beam.width = beam_width;
    beam.thickness = beam_thickness;
    const std::vector<double> theory = beam.clamped_free_frequencies(count);
    ASSERT_EQ(static_cast<int>(theory.size()), count);
    std::vector<double> computed;
    for (int i = 0; i < variant.modes.n_modes(); ++i) {
      const Vec3 share = component_share(variant, variant.modes.shapes.col(i));
      if (share[component] > 0.5 && share[3 - component] < 0.01) computed.push_back(variant.modes.frequencies_hz[i]);
    }
    ASSERT_GE(static_cast<int>(computed.size()), count);
    for (int n = 0; n < count; ++n) {
      EXPECT_NEAR(computed[n], theory[n], 0.01 * theory[n]) << "bending mode " << n + 1 << " along " << axis_name(component);
    }
  };
  check(width, thickness, kZ, 3);
  check(thickness, width, kY, 1);
}

TEST(ModalBeam, EigenvalueErrorConvergesAtRateTwoP) {
  // Bending of a beam on end supports u_y = u_z = 0 (u_x free): its modes are sin/cos in x, so
  // they are smooth (a clamp's edge singularity would cap the rate near 1.6). With nu = 0 the
  // z-bending mode is exactly plane, so one element across y suffices. Eigenvalue error
  // ~ h^{2p}; the reference is p = 4 on the finest mesh.
  const Vec3 size(1.0, 0.2, 0.1);
  auto first_bending = [&](int order, int k) {
    const mesh::Mesh mesh = box_mesh(size, {4 * k, 1, k}, order);
    ModalOptions options;
    options.modes = 1;
    const ModalResult result = run_modal(mesh, steel(0.0), {fix(mesh, "x-", {1, 2}), fix(mesh, "x+", {1, 2})}, options);
    EXPECT_EQ(result.variants[0].modes.n_rigid(), 1);  // axial sliding
    const double f = result.variants[0].modes.frequencies_hz[0];
    return f * f;
  };
  const double reference = first_bending(4, 4);
  struct Case {
    int order;
    int coarse;
  };
  for (const Case c : {Case{1, 4}, Case{2, 2}, Case{3, 2}}) {
    const double coarse = first_bending(c.order, c.coarse) - reference;
    const double fine = first_bending(c.order, 2 * c.coarse) - reference;
    ASSERT_GT(coarse, 0.0);
    ASSERT_GT(fine, 0.0);
    const double rate = std::log2(coarse / fine);
    std::printf("p = %d: eigenvalue error %.3e -> %.3e, rate %.2f\n", c.order, coarse / reference, fine / reference, rate);
    EXPECT_GT(rate, 2.0 * c.order - 0.3) << "p = " << c.order;
    EXPECT_LT(rate, 2.0 * c.order + 0.5) << "p = " << c.order;
  }
}

TEST(ModalBlock, FreeBodyHasExactlySixRigidModesThenElasticOnes) {
  const mesh::Mesh mesh = box_mesh(Vec3(1.0, 0.5, 0.3), {6, 3, 2}, 2);
  VectorX slepc_frequencies;
  for (const Solver solver : {Solver::slepc, Solver::arpack}) {
    ModalOptions options;
    options.modes = 6;
    options.solver = solver;
    const ModalResult result = run_modal(mesh, steel(0.3), {}, options);
    const ModeSet& modes = result.variants[0].modes;
    EXPECT_EQ(modes.n_rigid_expected, 6);
    ASSERT_EQ(modes.n_rigid(), 6) << solver_name(solver);
    ASSERT_EQ(modes.n_modes(), 6);
    EXPECT_EQ(result.variants[0].n_pieces, 1);
    EXPECT_LT(modes.rigid_frequencies_hz.cwiseAbs().maxCoeff(), 1e-6 * modes.frequencies_hz[0]);
    EXPECT_GT(modes.frequencies_hz[0], 100.0);
    EXPECT_LT(modes.orthogonality_error, 1e-12);
    // Rigid shapes carry no strain energy: K phi ~ 0 relative to the elastic modes' K phi.
    if (solver == Solver::slepc) {
      slepc_frequencies = modes.frequencies_hz;
    } else {
      for (int i = 0; i < 6; ++i) EXPECT_NEAR(modes.frequencies_hz[i], slepc_frequencies[i], 1e-8 * slepc_frequencies[i]);
    }
  }
}


/// A clamped beam with grid lines graded geometrically (ratio 0.15, 8 layers) towards the line
/// x = 0.05 m, z = 7 mm (where data/beam.yaml has its crack front):
/// its thinnest cells make tr K / tr M, the scale of the rigid-mode test, so large that the
/// lowest bending frequency falls below rigid_tolerance * f_ref. It must still count as elastic
/// (a clamped body has no zero-energy modes), and agree with the same beam without grading.
/// (Before the gap test in solve_modes, mode 1 was dropped as a "mechanism" here.)
TEST(ModalBeam, StronglyGradedMeshKeepsItsLowestModeElastic) {
  mesh::BoxSpec box;
  box.size = Vec3(0.2, 0.02, 0.01);
  box.cells = {10, 1, 1};
  box.order = 2;
  ModalOptions options;
  options.modes = 3;
  options.variants = {mesh::Variant::uncracked};
  const mesh::Mesh uniform = mesh::build_box_mesh(box);
  const ModalResult reference = run_modal(uniform, steel(0.3), {fix(uniform, "x-", {0, 1, 2})}, options);
  for (int k = 1; k <= 8; ++k) {
    box.extra_lines[0].push_back(0.05 - 0.02 * std::pow(0.15, k));
    box.extra_lines[0].push_back(0.05 + 0.02 * std::pow(0.15, k));
    box.extra_lines[2].push_back(0.007 - 0.01 * std::pow(0.15, k));
    box.extra_lines[2].push_back(0.007 + 0.01 * std::pow(0.15, k));
  }
  const mesh::Mesh graded = mesh::build_box_mesh(box);
  const ModalResult result = run_modal(graded, steel(0.3), {fix(graded, "x-", {0, 1, 2})}, options);
  const ModeSet& modes = result.variants.front().modes;
  const double f_ref = std::sqrt(modes.report.reference_eigenvalue) / (2.0 * M_PI);
  std::printf("graded: f_ref = %.3g Hz, rigid threshold %.3g Hz, f1 = %.6g Hz (uniform %.6g Hz)\n", f_ref,
              options.rigid_tolerance * f_ref, modes.frequencies_hz[0],
              reference.variants.front().modes.frequencies_hz[0]);
  ASSERT_GT(options.rigid_tolerance * f_ref, modes.frequencies_hz[0]);  // the case this test is about
  EXPECT_EQ(modes.n_rigid(), 0);
  for (int i = 0; i < 3; ++i) {
    const double f = reference.variants.front().modes.frequencies_hz[i];
    // Extra lines refine a nested space: the frequencies can only go down, and by little.
    EXPECT_LE(modes.frequencies_hz[i], f * (1.0 + 1e-9)) << i;
    EXPECT_GT(modes.frequencies_hz[i], 0.99 * f) << i;
  }
}

/// Open-crack frequencies of the data/beam.yaml cantilever (3 mm edge crack at a quarter of the
/// length) at order p on uniform cells [nx, 1, nz], with the mesher's automatic grading or none.
std::vector<double> open_beam_frequencies(int order, int nx, int nz, mesh::Grading grading, int modes) {
  mesh::BoxSpec box;
  box.size = Vec3(0.2, 0.02, 0.01);
  box.cells = {nx, 1, nz};
  box.order = order;
  box.grading = grading;
  mesh::CrackSpec crack;
  crack.normal = kX;
  crack.at = 0.05;
  crack.region[kY] = {0.0, 0.02};
  crack.region[kZ] = {0.007, 0.01};
  const mesh::Mesh mesh = mesh::build_box_mesh(box, crack);
  ModalOptions options;
  options.modes = modes;
  options.variants = {mesh::Variant::open};
  const ModalResult result = run_modal(mesh, steel(0.3), {fix(mesh, "x-", {0, 1, 2})}, options);
  const VectorX& f = result.variants.front().modes.frequencies_hz;
  return std::vector<double>(f.data(), f.data() + f.size());
}

/// The crack front limits uniform meshes to about first-order convergence whatever p
/// (docs/benchmarks.md section 2); the mesher's default geometric grading towards the front
/// restores a clearly higher rate. Rates of f1 and f2 (the modes that open the crack) at p = 2 over
/// the cells [20,1,1] -> [40,1,2] -> [80,1,4], from successive differences (the y discretisation is
/// the same at every level, so the x-z refinement converges to a common limit). The clamped face's
/// own singularity, not graded, caps the graded rate further down: [80,1,4] -> [160,1,8] measured
/// 1.3 graded against 1.2 uniform, with changes 3.7e-4 against 1.9e-3.
TEST(ModalCrack, DefaultGradingRaisesTheConvergenceRateOfTheOpenCrack) {
  const int modes = 2;
  const mesh::Grading automatic{mesh::kAutoLayers, 0.2}, none{0, 0.2};
  const int n_x[] = {20, 40, 80};
  double rates[2] = {};
  for (int graded = 0; graded < 2; ++graded) {
    std::vector<std::vector<double>> f;
    for (int n : n_x) f.push_back(open_beam_frequencies(2, n, n / 20, graded ? automatic : none, modes));
    double change[2] = {};
    for (int level = 0; level < 2; ++level)
      for (int i = 0; i < modes; ++i)
        change[level] = std::max(change[level], std::abs(f[level][i] - f[level + 1][i]) / f[2][i]);
    rates[graded] = std::log2(change[0] / change[1]);
    std::printf("%s: f1 %.6f %.6f %.6f Hz, changes %.3e %.3e, rate %.2f\n", graded ? "graded" : "uniform", f[0][0],
                f[1][0], f[2][0], change[0], change[1], rates[graded]);
  }
  // Measured: uniform 0.71, graded 2.01 (changes 6.8e-3, 4.2e-3 against 3.7e-3, 9.2e-4).
  EXPECT_LT(rates[0], 1.2);
  EXPECT_GT(rates[1], 1.7);
  EXPECT_GT(rates[1], rates[0] + 1.0);
}

TEST(ModalCrack, UncrackedVariantEqualsTheMeshWithoutCrack) {
  mesh::BoxSpec box;
  box.size = Vec3(1.0, 0.1, 0.2);
  box.cells = {10, 1, 4};
  box.order = 2;
  const mesh::CrackSpec crack = edge_crack();
  const mesh::Mesh cracked = mesh::build_box_mesh(box, crack);
  const mesh::Mesh plain = mesh::build_box_mesh(box, mesh::grid_lines(box, crack), std::nullopt);
  ModalOptions options;
  options.modes = 6;
  const ModalResult with_crack = run_modal(cracked, steel(0.3), {fix(cracked, "x-", {0, 1, 2})}, options);
  const ModalResult without = run_modal(plain, steel(0.3), {fix(plain, "x-", {0, 1, 2})}, options);
  ASSERT_EQ(with_crack.variants.size(), 2u);
  ASSERT_EQ(without.variants.size(), 1u);
  const VariantResult* uncracked = with_crack.find(mesh::Variant::uncracked);
  const VariantResult* open = with_crack.find(mesh::Variant::open);
  ASSERT_TRUE(uncracked && open);
  EXPECT_EQ(uncracked->constraints.n_free(), without.variants[0].constraints.n_free());
  for (int i = 0; i < options.modes; ++i) {
    const double reference = without.variants[0].modes.frequencies_hz[i];
    EXPECT_NEAR(uncracked->modes.frequencies_hz[i], reference, 1e-10 * reference) << "mode " << i + 1;
    // Min-max: tying the faces only constrains, so the k-th open eigenvalue is below the k-th tied one.
    EXPECT_LE(open->modes.frequencies_hz[i], uncracked->modes.frequencies_hz[i] * (1.0 + 1e-12));
  }
  // Pairs: every mode is paired (the crack, off the mid-plane, mixes the higher modes a little),
  // the first (bending that opens the crack) drops clearly.
  ASSERT_EQ(with_crack.pairs.size(), 6u);
  for (const ModePair& pair : with_crack.pairs) {
    EXPECT_EQ(pair.open_mode, pair.uncracked_mode);
    EXPECT_GT(pair.mac, pair.uncracked_mode < 2 ? 0.99 : 0.8) << "mode " << pair.uncracked_mode + 1;
    EXPECT_LE(pair.f_open_hz, pair.f_uncracked_hz * (1.0 + 1e-12));
    EXPECT_LE(pair.f_open_hz, pair.f_bilinear_hz * (1.0 + 1e-12));
    EXPECT_LE(pair.f_bilinear_hz, pair.f_uncracked_hz * (1.0 + 1e-12));
    EXPECT_NEAR(pair.ratio, pair.f_open_hz / pair.f_uncracked_hz, 1e-15);
  }
  EXPECT_EQ(with_crack.pairs[0].open_mode, 0);
  EXPECT_LT(with_crack.pairs[0].ratio, 0.99);
}

TEST(ModalCrack, CrackCuttingAPieceOffGivesItsRigidModes) {
  // A crack through the whole section of a cantilever frees the outer part: six rigid modes in
  // the open variant, none in the uncracked one.
  mesh::CrackSpec crack;
  crack.normal = kX;
  crack.at = 0.5;
  crack.region[kY] = {0.0, 0.1};
  crack.region[kZ] = {0.0, 0.1};
  const mesh::Mesh mesh = box_mesh(Vec3(1.0, 0.1, 0.1), {8, 1, 1}, 2, crack);
  ModalOptions options;
  options.modes = 4;
  const ModalResult result = run_modal(mesh, steel(0.3), {fix(mesh, "x-", {0, 1, 2})}, options);
  const VariantResult* uncracked = result.find(mesh::Variant::uncracked);
  const VariantResult* open = result.find(mesh::Variant::open);
  ASSERT_TRUE(uncracked && open);
  EXPECT_EQ(uncracked->n_pieces, 1);
  EXPECT_EQ(uncracked->modes.n_rigid(), 0);
  EXPECT_EQ(open->n_pieces, 2);
  EXPECT_EQ(open->modes.n_rigid_expected, 6);
  EXPECT_EQ(open->modes.n_rigid(), 6);
  EXPECT_EQ(open->modes.n_modes(), 4);
  // The clamped half is a cantilever of half the length: its first bending frequency is about
  // four times the whole beam's.
  EXPECT_GT(open->modes.frequencies_hz[0], 3.5 * uncracked->modes.frequencies_hz[0]);
}

TEST(ModalCrack, SlepcAndArpackAgree) {
  const mesh::Mesh mesh = box_mesh(Vec3(1.0, 0.1, 0.2), {10, 1, 4}, 2, edge_crack());
  ModalOptions options;
  options.modes = 8;
  const ModalResult slepc = run_modal(mesh, steel(0.3), {fix(mesh, "x-", {0, 1, 2})}, options);
  options.solver = Solver::arpack;
  const ModalResult arpack = run_modal(mesh, steel(0.3), {fix(mesh, "x-", {0, 1, 2})}, options);
  options.solver = Solver::slepc;
  options.factorization = Factorization::mumps;
  const ModalResult mumps = run_modal(mesh, steel(0.3), {fix(mesh, "x-", {0, 1, 2})}, options);
  for (std::size_t v = 0; v < 2; ++v) {
    for (int i = 0; i < options.modes; ++i) {
      const double f = slepc.variants[v].modes.frequencies_hz[i];
      EXPECT_NEAR(arpack.variants[v].modes.frequencies_hz[i], f, 1e-8 * f);
      EXPECT_NEAR(mumps.variants[v].modes.frequencies_hz[i], f, 1e-8 * f);
    }
  }
  EXPECT_EQ(slepc.variants[0].modes.report.factorization, "cholmod");
  EXPECT_EQ(mumps.variants[0].modes.report.factorization, "mumps");
}

TEST(ModalMass, ConsistentAndLumpedConvergeTogether) {
  // Both masses converge to the same frequencies: their difference shrinks under refinement.
  double previous = 0.0;
  for (int k : {1, 2, 4}) {
    const mesh::Mesh mesh = box_mesh(Vec3(1.0, 0.1, 0.1), {4 * k, k, k}, 2);
    ModalOptions options;
    options.modes = 3;
    const ModalResult consistent = run_modal(mesh, steel(0.3), {fix(mesh, "x-", {0, 1, 2})}, options);
    options.lumped_mass = true;
    const ModalResult lumped = run_modal(mesh, steel(0.3), {fix(mesh, "x-", {0, 1, 2})}, options);
    EXPECT_LT(lumped.variants[0].modes.orthogonality_error, 1e-12);
    double difference = 0.0;
    for (int i = 0; i < 3; ++i) {
      const double f = consistent.variants[0].modes.frequencies_hz[i];
      difference = std::max(difference, std::abs(lumped.variants[0].modes.frequencies_hz[i] - f) / f);
    }
    EXPECT_LT(difference, 0.02) << "k = " << k;
    if (k > 1) EXPECT_LT(difference, 0.3 * previous) << "k = " << k;
    previous = difference;
  }
}

TEST(ModalInput, ModeCountIsLimitedByTheFreeDofs) {
  const mesh::Mesh mesh = box_mesh(Vec3(1.0, 1.0, 1.0), {1, 1, 1}, 1);
  ModalOptions options;
  options.modes = 19;  // 24 DOFs - 6 rigid-body modes = 18 elastic modes
  EXPECT_THROW(run_modal(mesh, steel(0.3), {}, options), InputError);
  options.modes = 0;
  EXPECT_THROW(run_modal(mesh, steel(0.3), {}, options), InputError);
  // All 18 elastic modes of one trilinear brick: both backends (ARPACK falls back to LAPACK).
  options.modes = 18;
  const ModalResult slepc = run_modal(mesh, steel(0.3), {}, options);
  options.solver = Solver::arpack;
  const ModalResult arpack = run_modal(mesh, steel(0.3), {}, options);
  EXPECT_EQ(slepc.variants[0].modes.n_rigid(), 6);
  EXPECT_EQ(arpack.variants[0].modes.n_rigid(), 6);
  for (int i = 0; i < 18; ++i) {
    const double f = slepc.variants[0].modes.frequencies_hz[i];
    EXPECT_NEAR(arpack.variants[0].modes.frequencies_hz[i], f, 1e-8 * f);
  }
}

TEST(ModalOutput, WritesJsonCsvVtuAndTable) {
  const mesh::Mesh mesh = box_mesh(Vec3(1.0, 0.1, 0.2), {5, 1, 4}, 1, [] {
    mesh::CrackSpec crack = edge_crack();
    crack.at = 0.4;
    return crack;
  }());
  ModalOptions options;
  options.modes = 4;
  const ModalResult result = run_modal(mesh, steel(0.3), {fix(mesh, "x-", {0, 1, 2})}, options);
  const std::filesystem::path directory =
      std::filesystem::path(CRACKLE_BINARY_DIR) / "tests" / "modal" / "output_test";
  std::filesystem::remove_all(directory);
  output::write_modal_outputs(directory, mesh, result);

  std::ifstream json_file(directory / "modal.json");
  const nlohmann::json document = nlohmann::json::parse(json_file);
  EXPECT_EQ(document["dofs"].get<int>(), result.find(mesh::Variant::open)->constraints.n_free());
  ASSERT_EQ(document["variants"]["uncracked"]["frequencies_hz"].size(), 4u);
  ASSERT_EQ(document["variants"]["open"]["frequencies_hz"].size(), 4u);
  EXPECT_DOUBLE_EQ(document["variants"]["open"]["frequencies_hz"][0].get<double>(),
                   result.find(mesh::Variant::open)->modes.frequencies_hz[0]);
  EXPECT_LT(document["variants"]["open"]["orthogonality_error"].get<double>(), 1e-12);
  ASSERT_EQ(document["pairs"].size(), 4u);
  EXPECT_EQ(document["pairs"][0]["uncracked_mode"].get<int>(), 1);
  EXPECT_TRUE(document["pairs"][0].contains("f_bilinear_hz"));
  EXPECT_TRUE(document["pairs"][0]["paired"].get<bool>());
  EXPECT_EQ(document["solver"]["backend"], "slepc");
  EXPECT_TRUE(document["timings_s"].contains("factorization"));
  EXPECT_TRUE(document["timings_s"].contains("iterations"));

  std::ifstream csv(directory / "modes.csv");
  std::string header;
  std::getline(csv, header);
  EXPECT_EQ(header, "mode [-],f_uncracked [Hz],open_mode [-],f_open [Hz],ratio [-],mac [-],f_bilinear [Hz],paired [-]");
  for (const char* name : {"modes_uncracked.vtu", "modes_open.vtu"}) {
    EXPECT_GT(std::filesystem::file_size(directory / name), 1000u) << name;
  }
  const std::string table = modal_table(result);
  EXPECT_NE(table.find("f_bilinear"), std::string::npos);
  EXPECT_NE(table.find("MAC"), std::string::npos);
}

TEST(ModalInput, NamesParseAndBadNamesAreInputErrors) {
  EXPECT_EQ(parse_word(kSolverWords, "arpack", "backend"), Solver::arpack);
  EXPECT_EQ(parse_factorization("mumps"), Factorization::mumps);
  EXPECT_EQ(parse_mac_weighting("plain"), MacWeighting::plain);
  EXPECT_EQ(parse_word(mesh::kVariantWords, "open", "variant"), mesh::Variant::open);
  for (const Solver solver : {Solver::slepc, Solver::arpack}) {
    EXPECT_EQ(parse_word(kSolverWords, solver_name(solver), "backend"), solver);  // the output's word reads back
  }
  try {
    parse_word(kSolverWords, "lapack", "modal backend");
    ADD_FAILURE() << "no exception";
  } catch (const InputError& error) {
    EXPECT_EQ(std::string(error.what()), "modal backend: expected one of slepc, arpack, got 'lapack'");
  }
  try {
    parse_factorization("lu");
    ADD_FAILURE() << "no exception";
  } catch (const InputError& error) {
    EXPECT_EQ(std::string(error.what()), "modal.factorization: expected one of automatic, cholmod, mumps, got 'lu'");
  }
}

}  // namespace
}  // namespace crackle::modal
