// Pluck and tap tests through `crackle run`: free vibration released from a static deflection or a
// mode shape (transient.release), the ring-down analysis of the spectrum stage against the modal
// frequencies of the same mesh (lumped mass, as the transient), and the FRF of an impact.
#include <gtest/gtest.h>

#include "cli_testing.hpp"

#include <Eigen/SparseCholesky>
#include <array>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

#include <nlohmann/json.hpp>

#include "contact/contact.hpp"
#include "pipeline/model.hpp"
#include "pipeline/release.hpp"
#include "scene/scene.hpp"
#include "transient/excitation.hpp"

namespace fs = std::filesystem;

namespace {

/// A steel cantilever 0.2 x 0.02 x 0.01 m of p = 1 clamped at x = 0, with a half-depth edge crack
/// from the top face at x = 0.04 (overridden away where a test needs no crack).
const std::string kBeam = cli_testing::cantilever("[10, 1, 2]", false);

const char* kCrack = R"(crack:
  plane: {normal: x, at: 0.04}
  region: {y: [0.0, 0.02], z: [0.005, 0.01]}
)";

fs::path scratch() {
  static const fs::path dir = fs::temp_directory_path() / ("crackle-test-pluck-" + std::to_string(::getpid()));
  fs::create_directories(dir);
  return dir;
}

int crackle_run(const std::string& name, const std::string& scene_text, std::string* output) {
  const fs::path scene = scratch() / (name + ".yaml");
  std::ofstream(scene) << scene_text;
  const cli_testing::Result result = cli_testing::crackle("run " + scene.string() + " -o " + (scratch() / name).string() + " -q");
  *output = result.output;
  return result.exit_code;
}

nlohmann::json read_json(const fs::path& path) {
  std::ifstream in(path);
  return nlohmann::json::parse(in);
}

/// Column `header` of a CSV file with a header row.
std::vector<double> csv_column(const fs::path& path, const std::string& header) {
  std::ifstream in(path);
  std::string line;
  std::getline(in, line);
  std::stringstream names(line);
  std::string name;
  int column = -1;
  for (int c = 0; std::getline(names, name, ','); ++c) {
    if (name == header) column = c;
  }
  EXPECT_GE(column, 0) << header << " not in " << path;
  std::vector<double> values;
  while (std::getline(in, line)) {
    std::stringstream fields(line);
    std::string field;
    for (int c = 0; std::getline(fields, field, ','); ++c) {
      if (c == column) values.push_back(std::stod(field));
    }
  }
  return values;
}

const nlohmann::json& ringdown_of(const nlohmann::json& spectrum) { return spectrum["probes"]["tip"]["ringdown"]; }

}  // namespace

// A linear single mode: released from the first mode shape of the uncracked body with a
// mass-proportional damping ratio set at that mode's frequency, the ring-down has exactly that
// frequency and ratio.
TEST(Pluck, LinearSingleModeRingsAtItsFrequencyWithTheSetDampingRatio) {
  const std::string scene = std::string(kBeam) + R"(modal: {modes: 2, mass: lumped}
transient:
  model: full
  release:
    mode: {number: 1, amplitude: 1.0e-4}
  damping: {ratio: 0.02, at: {mode: 1}}
  duration: 0.15
  progress: false
  probes:
    - {name: tip, point: [0.2, 0.01, 0.01]}
spectrum: {harmonics: 2, subharmonics: false}
)";
  std::string log;
  ASSERT_EQ(crackle_run("mode", scene, &log), 0) << log;
  const nlohmann::json modal = read_json(scratch() / "mode" / "modal.json");
  const double f1 = modal["variants"]["uncracked"]["frequencies_hz"][0].get<double>();
  const nlohmann::json ringdown = ringdown_of(read_json(scratch() / "mode" / "spectrum.json"));
  EXPECT_NEAR(ringdown["natural_frequency_hz"].get<double>(), f1, 0.01 * f1) << log;
  EXPECT_NEAR(ringdown["damping_ratio"].get<double>(), 0.02, 0.01 * 0.02) << log;
  EXPECT_EQ(ringdown["modal_comparison"]["reference"], "uncracked");
  EXPECT_EQ(ringdown["modal_comparison"]["mode"], 1);
  // The probe starts where the scaled mode shape puts it, at rest.
  const std::vector<double> tip = csv_column(scratch() / "mode" / "probes.csv", "tip u_z [m]");
  ASSERT_FALSE(tip.empty());
  EXPECT_NEAR(std::abs(tip[0]), 1.0e-4, 2e-6);
}

// Released from a static tip load, U(0) is the static deflection: the same as a direct solve of
// K u = f (an independent sparse Cholesky), and the tip deflection of Euler-Bernoulli theory
// P L^3 / (3 E I) within the 3D beam's own error on this mesh (p = 2).
TEST(Pluck, StaticReleaseStartsFromTheStaticDeflection) {
  const std::string text = R"(mesh:
  box: {size: [0.2, 0.02, 0.01], cells: [20, 2, 2], order: 2}
material: {E: 210.0e9, nu: 0.3, rho: 7850.0}
boundary:
  - {face: x-, fix: [x, y, z]}
transient:
  model: full
  release:
    static: {face: x+, direction: z, amplitude: 50.0}
  duration: 1.0e-5
  progress: false
  probes:
    - {name: tip, point: [0.2, 0.01, 0.01]}
)";
  std::string log;
  ASSERT_EQ(crackle_run("static", text, &log), 0) << log;
  const std::vector<double> tip = csv_column(scratch() / "static" / "probes.csv", "tip u_z [m]");
  const std::vector<double> time = csv_column(scratch() / "static" / "probes.csv", "time [s]");
  ASSERT_FALSE(tip.empty());
  ASSERT_EQ(time[0], 0.0);

  using namespace crackle;
  const scene::Scene scene = scene::parse_scene(text, "static.yaml");
  const pipeline::Model model = pipeline::build_model(scene);
  const fem::System& system = *model.system(mesh::Variant::uncracked);
  fem::LoadPlacement placement{"tip", {}, model.mesh.face_sets.at("x+"), Vec3(0.0, 0.0, 50.0)};
  const VectorX force = system.load_shape(placement).dense(system.n_dofs());
  const SparseMatrix stiffness = system.assemble_stiffness();
  Eigen::SimplicialLDLT<SparseMatrix> solver(fem::restrict_to_free(stiffness, system.constraints()));
  ASSERT_EQ(solver.info(), Eigen::Success);
  const VectorX u = fem::expand_from_free(
      solver.solve(fem::free_right_hand_side(stiffness, force, system.constraints())), system.constraints(), true);
  const Index node = transient::nearest_node(model.mesh, Vec3(0.2, 0.01, 0.01));
  const double direct = u[system.dofs().dof(node, 2)];
  // Two different factorisations (CHOLMOD supernodal, Eigen's LDL^T) of K agree to round-off,
  // eps kappa(K) with kappa ~ 1e8 on this mesh (measured: 4e-10 relative).
  EXPECT_NEAR(tip[0], direct, 1e-8 * std::abs(direct));
  const double inertia = 0.02 * std::pow(0.01, 3) / 12.0;
  const double beam = 50.0 * std::pow(0.2, 3) / (3.0 * 210.0e9 * inertia);
  EXPECT_NEAR(tip[0], beam, 0.01 * beam) << "tip " << tip[0] << " m, beam theory " << beam << " m";
}

using cli_testing::cracked_release;

// The breathing crack: a bilinear oscillator rings at 2 f_u f_o / (f_u + f_o) and carries
// harmonics; without contact, the open body rings at its open frequency.
TEST(Pluck, BreathingCantileverRingsAtTheBilinearFrequency) {
  std::string log;
  ASSERT_EQ(crackle_run("breathing", cracked_release("penalty"), &log), 0) << log;
  const nlohmann::json ringdown = ringdown_of(read_json(scratch() / "breathing" / "spectrum.json"));
  const nlohmann::json& comparison = ringdown["modal_comparison"];
  EXPECT_EQ(comparison["reference"], "bilinear");
  EXPECT_EQ(comparison["mode"], 1);
  EXPECT_LT(std::abs(comparison["relative_difference"].get<double>()), 5e-4) << log;
  EXPECT_GT(ringdown["harmonics"][1]["relative_amplitude"].get<double>(), 1e-3) << log;
}

TEST(Pluck, OpenCantileverWithoutContactRingsAtTheOpenFrequency) {
  std::string log;
  ASSERT_EQ(crackle_run("open", cracked_release("none"), &log), 0) << log;
  const nlohmann::json ringdown = ringdown_of(read_json(scratch() / "open" / "spectrum.json"));
  const nlohmann::json& comparison = ringdown["modal_comparison"];
  EXPECT_EQ(comparison["reference"], "open");
  EXPECT_EQ(comparison["mode"], 1);
  EXPECT_LT(std::abs(comparison["relative_difference"].get<double>()), 5e-4) << log;
}

// A hammer blow (half-sine of 0.1 ms) at the tip of the uncracked beam: the FRF H = u_z / F_z has
// its peaks at modal frequencies, within the frequency resolution of the record.
TEST(Tap, ImpactFrfPeaksAtTheModalFrequencies) {
  const std::string scene = std::string(kBeam) + R"(modal: {modes: 6, mass: lumped}
transient:
  model: full
  excitation: {point: [0.2, 0.01, 0.01], direction: z, amplitude: 100.0, kind: pulse, duration: 1.0e-4}
  damping: {ratio: 0.05, at: {mode: 1}}
  duration: 0.1
  progress: false
  probes:
    - {name: tip, point: [0.2, 0.01, 0.01]}
spectrum: {harmonics: 2, subharmonics: false}
)";
  std::string log;
  ASSERT_EQ(crackle_run("tap", scene, &log), 0) << log;
  const nlohmann::json spectrum = read_json(scratch() / "tap" / "spectrum.json");
  const nlohmann::json& frf = spectrum["probes"]["tip"]["frf"];
  const double resolution = frf["resolution_hz"].get<double>();
  const nlohmann::json modal = read_json(scratch() / "tap" / "modal.json");
  const nlohmann::json& frequencies = modal["variants"]["uncracked"]["frequencies_hz"];
  const std::vector<double> peaks = frf["peaks_hz"].get<std::vector<double>>();
  ASSERT_GE(peaks.size(), 2u) << log;
  for (double peak : peaks) {
    double nearest = 1e300;
    for (const auto& f : frequencies) nearest = std::min(nearest, std::abs(f.get<double>() - peak));
    EXPECT_LT(nearest, resolution) << "FRF peak at " << peak << " Hz\n" << log;
  }
  EXPECT_NEAR(peaks[0], frequencies[0].get<double>(), resolution);
  EXPECT_TRUE(fs::exists(scratch() / "tap" / "frf_tip.csv"));
}

// The nonlinear static problem of a release: pulled open (tip load down, the top crack in
// tension) no pair closes and U(0) is the open body's linear solution; pushed shut (tip load up)
// the closed pairs penetrate, the open ones gap, and K u + f_contact(u) = f holds to round-off.
TEST(Pluck, StaticReleaseSolvesTheContactProblem) {
  using namespace crackle;
  const std::string text = std::string(kBeam) + kCrack + R"(transient:
  model: full
  release:
    static: {face: x+, direction: z, amplitude: 50.0}
  duration: 1.0e-5
)";
  const scene::Scene scene = scene::parse_scene(text, "contact.yaml");
  const pipeline::Model model = pipeline::build_model(scene);
  const fem::System& system = *model.system(mesh::Variant::open);
  const mesh::DofMap& dofs = system.dofs();
  const contact::ContactOptions options;  // automatic penalty, closed crack (g0 = 0)
  const double penalty = contact::choose_penalty(model.mesh, model.materials, options).normal_penalty;
  for (const double sign : {-1.0, 1.0}) {
    fem::LoadPlacement placement{"tip", {}, model.mesh.face_sets.at("x+"), Vec3(0.0, 0.0, sign * 50.0)};
    const VectorX force = system.load_shape(placement).dense(system.n_dofs());
    const pipeline::StaticContact springs{model.mesh.crack_pairs, penalty, 0.0};
    const pipeline::StaticSolution solution = pipeline::solve_static(system, force, &springs);
    const pipeline::StaticSolution open = pipeline::solve_static(system, force, nullptr);
    ASSERT_GT(solution.n_pairs, 0);
    if (sign < 0.0) {
      EXPECT_EQ(solution.n_closed, 0);
      EXPECT_LT((solution.displacement - open.displacement).norm(), 1e-12 * open.displacement.norm());
      continue;
    }
    EXPECT_EQ(solution.n_closed, solution.n_pairs);
    // Residual of the penalty law over the free DOFs, the contact force from eq. (25d) directly.
    VectorX residual = -force;
    system.stiffness().apply_add(1.0, solution.displacement, residual);
    for (const mesh::CrackPair& pair : model.mesh.crack_pairs) {
      if (dofs.dof_node[pair.minus] == dofs.dof_node[pair.plus]) continue;
      double gap = 0.0;
      for (int a = 0; a < 3; ++a) {
        gap += pair.normal[a] * (solution.displacement[dofs.dof(pair.minus, a)] -
                                 solution.displacement[dofs.dof(pair.plus, a)]);
      }
      const double pressure = gap < 0.0 ? -penalty * gap : 0.0;  // compressive spring force / area
      for (int a = 0; a < 3; ++a) {
        residual[dofs.dof(pair.minus, a)] -= pressure * pair.area * pair.normal[a];
        residual[dofs.dof(pair.plus, a)] += pressure * pair.area * pair.normal[a];
      }
    }
    for (Index dof = 0; dof < system.n_dofs(); ++dof) {
      if (system.constraints().fixed[dof]) residual[dof] = 0.0;
    }
    EXPECT_LT(residual.norm(), 1e-8 * force.norm());
    // Pressed shut, the crack is nearly tied: the tip moves less than the open body's.
    const Index tip = transient::nearest_node(model.mesh, Vec3(0.2, 0.01, 0.01));
    EXPECT_LT(solution.displacement[dofs.dof(tip, 2)], open.displacement[dofs.dof(tip, 2)]);
  }
}
