// Free vibration of the reduced transient (transient.model: reduced) from the initial states of
// transient.release and transient.initial, against the full explicit model on the same mesh: the
// release state projected on the retained modes, q(0) = Phi^T M U(0) (MODEL.md eq. 6, HYBRID.md §2).
#include <gtest/gtest.h>

#include "cli_testing.hpp"

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

namespace fs = std::filesystem;

namespace {

fs::path scratch() {
  static const fs::path dir = fs::temp_directory_path() / ("crackle-test-reduced-release-" + std::to_string(::getpid()));
  fs::create_directories(dir);
  return dir;
}

void crackle_run(const std::string& name, const std::string& scene_text, const std::string& overrides = "") {
  const fs::path scene = scratch() / (name + ".yaml");
  std::ofstream(scene) << scene_text;
  const cli_testing::Result result =
      cli_testing::crackle("run " + scene.string() + " -o " + (scratch() / name).string() + " -q " + overrides);
  ASSERT_EQ(result.exit_code, 0) << name << "\n" << result.output;
}

nlohmann::json read_json(const fs::path& path) {
  std::ifstream in(path);
  return nlohmann::json::parse(in);
}

/// Column `header` of probes.csv (comment lines skipped); empty if the file or the column is missing.
std::vector<double> probe_column(const std::string& name, const std::string& header) {
  std::ifstream in(scratch() / name / "probes.csv");
  std::string line;
  do std::getline(in, line);
  while (!line.empty() && line[0] == '#');
  std::stringstream names(line);
  std::string cell;
  int column = -1;
  for (int c = 0; std::getline(names, cell, ','); ++c) {
    if (cell.rfind(header, 0) == 0 && column < 0) column = c;
  }
  EXPECT_GE(column, 0) << header;
  std::vector<double> values;
  if (column < 0) return values;
  while (std::getline(in, line)) {
    std::stringstream fields(line);
    for (int c = 0; std::getline(fields, cell, ','); ++c) {
      if (c == column) values.push_back(std::stod(cell));
    }
  }
  return values;
}

/// The first sample of a probes.csv column (NaN when there is none, which fails every comparison).
double first(const std::string& name, const std::string& header) {
  const std::vector<double> values = probe_column(name, header);
  return values.empty() ? std::nan("") : values.front();
}

const nlohmann::json& ringdown(const nlohmann::json& spectrum) { return spectrum["probes"]["tip"]["ringdown"]; }

const char* kReduced = "--set transient.model=reduced --set transient.reduced.max_frequency=5000";

}  // namespace

// The static release: the full model starts from the static solution with the contact active; the
// reduced model from its projection on the retained modes, which is the reduced model's own static
// state (Phi^T M K^-1 = Omega^-2 Phi^T, and B K^-1 B^T, B K^-1 f are exact in the reduction). At t = 0
// the reduced probe lacks only the massless residual part C G_res f of the removed load (the truncated
// modes' static share, which the full model carries as vibration above max_frequency): it shrinks as
// modes are added. The ring-down is the full model's breathing frequency.
TEST(ReducedRelease, StaticReleaseStartsAtTheFullStaticDeflectionAndRingsAtTheFullBreathingFrequency) {
  crackle_run("static-full", cli_testing::cracked_release("penalty"));
  crackle_run("static-reduced", cli_testing::cracked_release("penalty"), kReduced);
  crackle_run("static-reduced-more", cli_testing::cracked_release("penalty"),
              "--set transient.model=reduced --set transient.reduced.max_frequency=40000");
  const double full0 = first("static-full", "tip u_z");
  const double reduced0 = first("static-reduced", "tip u_z");
  const double more0 = first("static-reduced-more", "tip u_z");
  const double error = std::abs(reduced0 / full0 - 1.0), error_more = std::abs(more0 / full0 - 1.0);
  const nlohmann::json transient = read_json(scratch() / "static-reduced" / "transient.json");
  const double full_f = ringdown(read_json(scratch() / "static-full" / "spectrum.json"))["natural_frequency_hz"];
  const nlohmann::json reduced_ringdown = ringdown(read_json(scratch() / "static-reduced" / "spectrum.json"));
  const double reduced_f = reduced_ringdown["natural_frequency_hz"];
  std::printf("static release: tip(0) full %.6e m, reduced %.6e m (%d modes, %.2e), %.6e m (%d modes, %.2e); "
              "displacement lost %.2e; ring-down full %.4f Hz, reduced %.4f Hz (%.2e)\n",
              full0, reduced0, transient["modes"].get<int>(), error, more0,
              read_json(scratch() / "static-reduced-more" / "transient.json")["modes"].get<int>(), error_more,
              transient["initial_state"]["displacement_lost"].get<double>(), full_f, reduced_f,
              reduced_f / full_f - 1.0);
  // The tip load's static share above 5 kHz at the tip: measured 3.9e-3 with 5 modes, 8e-6 with 29
  // (the first bending mode alone holds ~97 % of a cantilever's tip deflection under a tip load).
  EXPECT_LT(error, 1e-2);
  EXPECT_LT(error_more, 0.5 * error);
  EXPECT_LT(std::abs(reduced_f / full_f - 1.0), 2e-3);
  EXPECT_EQ(reduced_ringdown["modal_comparison"]["reference"], "bilinear");
  EXPECT_LT(std::abs(reduced_ringdown["modal_comparison"]["relative_difference"].get<double>()), 2e-3);
}

// Without contact the reduced model drops the crack pairs and rings at the open body's frequency.
TEST(ReducedRelease, WithoutContactTheReducedModelRingsAtTheOpenFrequency) {
  crackle_run("open-reduced", cli_testing::cracked_release("none"), kReduced);
  const nlohmann::json comparison = ringdown(read_json(scratch() / "open-reduced" / "spectrum.json"))["modal_comparison"];
  EXPECT_EQ(comparison["reference"], "open");
  EXPECT_EQ(comparison["mode"], 1);
  EXPECT_LT(std::abs(comparison["relative_difference"].get<double>()), 5e-4);
  EXPECT_EQ(read_json(scratch() / "open-reduced" / "transient.json")["pairs"], 0);
}

// A mode shape of the same eigenproblem (lumped mass) lies in the span of the retained modes: the
// projection keeps all of it, the probe starts at the scaled shape and rings at that mode's frequency.
TEST(ReducedRelease, ModeReleaseStartsOnTheModeAndRingsAtItsFrequency) {
  const std::string scene = cli_testing::cantilever("[10, 1, 2]", false) + R"(modal: {modes: 2, mass: lumped}
transient:
  model: full
  release:
    mode: {number: 1, amplitude: 1.0e-4}
  duration: 0.1
  progress: false
  probes:
    - {name: tip, point: [0.2, 0.01, 0.01]}
spectrum: {harmonics: 2, subharmonics: false}
)";
  crackle_run("mode-reduced", scene, kReduced);
  const nlohmann::json transient = read_json(scratch() / "mode-reduced" / "transient.json");
  EXPECT_LT(transient["initial_state"]["displacement_lost"].get<double>(), 1e-6);
  EXPECT_NEAR(std::abs(first("mode-reduced", "tip u_z")), 1.0e-4, 2e-6);
  const nlohmann::json comparison = ringdown(read_json(scratch() / "mode-reduced" / "spectrum.json"))["modal_comparison"];
  EXPECT_EQ(comparison["reference"], "uncracked");
  EXPECT_EQ(comparison["mode"], 1);
  EXPECT_LT(std::abs(comparison["relative_difference"].get<double>()), 5e-4);
}

// A uniform velocity on the outer quarter of the uncracked beam (transient.initial): the reduced
// model follows the full one; its largest tip deflection agrees within the share of the initial
// kinetic energy above max_frequency (transient.json initial_state.velocity_lost, in the mass norm).
TEST(ReducedRelease, UniformInitialVelocityGivesTheFullModelsSwing) {
  const std::string scene = cli_testing::cantilever("[10, 1, 2]", false) + R"(transient:
  model: full
  initial:
    - {velocity: [0, 0, 0.1], x: [0.15, 0.2]}
  duration: 0.01
  history: {samples_per_period: all}
  progress: false
  probes:
    - {name: tip, point: [0.2, 0.01, 0.01]}
)";
  crackle_run("velocity-full", scene);
  crackle_run("velocity-reduced", scene, "--set transient.model=reduced --set transient.reduced.max_frequency=20000");
  const auto largest = [](const std::vector<double>& values) {
    double peak = 0.0;
    for (double v : values) peak = std::max(peak, std::abs(v));
    return peak;
  };
  const double full = largest(probe_column("velocity-full", "tip u_z"));
  const double reduced = largest(probe_column("velocity-reduced", "tip u_z"));
  const double lost = read_json(scratch() / "velocity-reduced" / "transient.json")["initial_state"]["velocity_lost"];
  std::printf("initial velocity: largest tip u_z full %.6e m, reduced %.6e m (%.2e), velocity lost %.2e\n", full,
              reduced, reduced / full - 1.0, lost);
  EXPECT_GT(lost, 0.0);
  EXPECT_LT(std::abs(reduced / full - 1.0), 1e-2);
}

// A free body (no boundary condition) struck at its tip: the reduced model keeps its six rigid-body
// modes (frequency 0) with the elastic ones, so it drifts and turns as the full model does.
TEST(ReducedRelease, FreeBodyStruckByAPulseDriftsAsTheFullModel) {
  const std::string scene = R"(mesh:
  box: {size: [0.2, 0.02, 0.01], cells: [10, 1, 2], order: 1}
material: {E: 210.0e9, nu: 0.3, rho: 7850.0}
transient:
  model: full
  excitation: {point: [0.2, 0.01, 0.01], direction: z, amplitude: 20.0, kind: pulse, duration: 2.0e-4}
  duration: 0.02
  progress: false
  probes:
    - {name: tip, point: [0.2, 0.01, 0.01]}
)";
  crackle_run("free-full", scene);
  crackle_run("free-reduced", scene, kReduced);
  const std::vector<double> full = probe_column("free-full", "tip u_z"), reduced = probe_column("free-reduced", "tip u_z");
  ASSERT_GT(full.size(), 1u);
  ASSERT_GT(reduced.size(), 1u);
  const nlohmann::json transient = read_json(scratch() / "free-reduced" / "transient.json");
  std::printf("free body: %d modes; tip u_z at the end: full %.6e m, reduced %.6e m (%.2e)\n",
              transient["modes"].get<int>(), full.back(), reduced.back(), reduced.back() / full.back() - 1.0);
  EXPECT_GT(transient["modes"].get<int>(), 6);  // six rigid-body modes and the elastic ones up to 5 kHz
  // The drift dominates (rigid motion is exact in both); the elastic ringing above 5 kHz is what differs.
  EXPECT_LT(std::abs(reduced.back() / full.back() - 1.0), 1e-2);
}
