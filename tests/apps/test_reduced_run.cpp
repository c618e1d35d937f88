// `crackle run` with transient.model: reduced against the full explicit model on the same small
// meshes (HYBRID.md §2-3): faces tied, a crack held closed by a preload, free vibration of a
// breathing beam, undamped chattering, and the cached reduction shared by a study.
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

/// A 10 x 2 x 1 cantilever of p = 1 (the test_run.cpp beam) with a half-depth edge crack at x = 0.04.
const std::string kBody = cli_testing::cantilever("[10, 2, 1]");

/// Harmonic point load at the tip, 5 % damping, 40 periods, spectrum over the last 10.
const std::string kForced = cli_testing::forced_tip("    - {name: tip, point: [0.2, 0.01, 0.01]}\n");

/// A short tip pulse, then free vibration without damping.
const char* kPulse = R"(transient:
  model: full
  excitation: {point: [0.2, 0.01, 0.01], direction: z, amplitude: 20.0, kind: pulse, duration: 2.0e-4}
  duration: 0.1
  progress: false
  probes:
    - {name: tip, point: [0.2, 0.01, 0.01]}
)";

fs::path scratch() {
  static const fs::path dir = fs::temp_directory_path() / ("crackle-test-reduced-" + std::to_string(::getpid()));
  fs::create_directories(dir);
  return dir;
}

/// `crackle run` of kBody + `rest` with overrides, into scratch()/name.
void crackle_run(const std::string& name, const std::string& rest, const std::string& overrides) {
  const fs::path scene = scratch() / (name + ".yaml");
  std::ofstream(scene) << kBody << rest;
  const std::string arguments = "run " + scene.string() + " -o " + (scratch() / name).string() + " -q " + overrides;
  const cli_testing::Result result = cli_testing::crackle(arguments);
  ASSERT_EQ(result.exit_code, 0) << arguments << "\n" << result.output;
}

nlohmann::json read_json(const fs::path& path) {
  std::ifstream in(path);
  return nlohmann::json::parse(in);
}

double tip_a1(const std::string& name) {
  const nlohmann::json spectrum = read_json(scratch() / name / "spectrum.json");
  for (const nlohmann::json& harmonic : spectrum["probes"]["tip"]["harmonics"]) {
    if (harmonic["order"].get<double>() == 1.0) return harmonic["amplitude"].get<double>();
  }
  return 0.0;
}

/// Column of probes.csv by header prefix, from `from_time` on.
std::vector<double> column(const std::string& name, const std::string& header, double from_time,
                           std::vector<double>* times) {
  std::ifstream in(scratch() / name / "probes.csv");
  std::string line;
  std::getline(in, line);
  while (!line.empty() && line[0] == '#') std::getline(in, line);
  std::stringstream heads(line);
  std::string cell;
  int index = 0, wanted = -1;
  while (std::getline(heads, cell, ',')) {
    if (cell.rfind(header, 0) == 0 && wanted < 0) wanted = index;
    ++index;
  }
  std::vector<double> values;
  while (std::getline(in, line)) {
    std::stringstream row(line);
    std::vector<double> cells;
    while (std::getline(row, cell, ',')) cells.push_back(std::stod(cell));
    if (cells.empty() || cells[0] < from_time) continue;
    values.push_back(cells[wanted]);
    if (times) times->push_back(cells[0]);
  }
  return values;
}

/// Mean frequency [Hz] of a free vibration from its upward mean crossings (linear interpolation).
double crossing_frequency(const std::string& name) {
  std::vector<double> times;
  const std::vector<double> u = column(name, "tip u_z", 2e-3, &times);
  double mean = 0.0;
  for (double v : u) mean += v;
  mean /= static_cast<double>(u.size());
  std::vector<double> crossings;
  for (std::size_t i = 1; i < u.size(); ++i) {
    const double a = u[i - 1] - mean, b = u[i] - mean;
    if (a < 0.0 && b >= 0.0) crossings.push_back(times[i - 1] + (times[i] - times[i - 1]) * a / (a - b));
  }
  if (crossings.size() < 3) return 0.0;
  return (crossings.size() - 1) / (crossings.back() - crossings.front());
}

}  // namespace

TEST(ReducedRun, FacesTiedSteadyStateEqualsTheFullModelAndNeedsTheResidualFlexibility) {
  crackle_run("tied-full", kForced, "--set transient.variant=uncracked");
  crackle_run("tied-reduced", kForced, "--set transient.variant=uncracked --set transient.model=reduced");
  crackle_run("tied-modes-only", kForced,
              "--set transient.variant=uncracked --set transient.model=reduced "
              "--set transient.reduced.residual_flexibility=false");
  const double full = tip_a1("tied-full"), reduced = tip_a1("tied-reduced"), modes_only = tip_a1("tied-modes-only");
  const double error = std::abs(reduced / full - 1.0), error_modes_only = std::abs(modes_only / full - 1.0);
  std::printf("tied A1: full %.6e, reduced %.6e (%.2e), modes only %.6e (%.2e)\n", full, reduced, error, modes_only,
              error_modes_only);
  EXPECT_LT(error, 3e-3);
  EXPECT_GT(error_modes_only, 3.0 * error);
  const nlohmann::json transient = read_json(scratch() / "tied-reduced" / "transient.json");
  EXPECT_EQ(transient["model"], "reduced");
  EXPECT_EQ(transient["pairs"], 0);
  EXPECT_GT(transient["modes"].get<int>(), 0);
  EXPECT_EQ(transient["steps_per_period"], 40);
}

TEST(ReducedRun, CrackClosedByAPreloadVibratesAsTheUncrackedBody) {
  crackle_run("tied-pulse", kPulse, "--set transient.variant=uncracked --set transient.model=reduced "
                                    "--set transient.reduced.max_frequency=5000");
  crackle_run("closed-pulse", kPulse, "--set crack.gap=-1e-6 --set transient.model=reduced "
                                      "--set transient.reduced.max_frequency=5000");
  const double tied = crossing_frequency("tied-pulse"), closed = crossing_frequency("closed-pulse");
  std::printf("preloaded crack: %.3f Hz, uncracked %.3f Hz, ratio %.5f\n", closed, tied, closed / tied);
  EXPECT_GE(closed / tied, 0.999);
}

TEST(ReducedRun, FreeVibrationOfABreathingBeamMatchesTheFullModel) {
  crackle_run("breathing-full", kPulse, "");
  crackle_run("breathing-reduced", kPulse, "--set transient.model=reduced --set transient.reduced.max_frequency=5000");
  crackle_run("open-pulse", kPulse, "--set transient.model=reduced --set transient.reduced.max_frequency=5000 "
                                    "--set crack.gap=1e-3");
  crackle_run("uncracked-pulse", kPulse, "--set transient.model=reduced --set transient.reduced.max_frequency=5000 "
                                         "--set transient.variant=uncracked");
  const double full = crossing_frequency("breathing-full"), reduced = crossing_frequency("breathing-reduced");
  const double open = crossing_frequency("open-pulse"), uncracked = crossing_frequency("uncracked-pulse");
  std::printf("breathing: full %.3f Hz, reduced %.3f Hz; open %.3f, uncracked %.3f\n", full, reduced, open, uncracked);
  EXPECT_LT(std::abs(reduced / full - 1.0), 2e-3);
  EXPECT_GT(reduced, open);
  EXPECT_LT(reduced, uncracked);
}

TEST(ReducedRun, UndampedChatteringKeepsItsEnergyBalance) {
  // About 1000 periods of the first mode (~ 200 Hz on this mesh), the crack breathing every period.
  crackle_run("chatter", kPulse, "--set transient.model=reduced --set transient.reduced.max_frequency=5000 "
                                 "--set transient.duration=5.0");
  const nlohmann::json transient = read_json(scratch() / "chatter" / "transient.json");
  std::printf("chattering: %lld steps, energy error %.3e, contact fraction %.3f\n",
              transient["steps"].get<long long>(), transient["energy_error"].get<double>(),
              transient["contact_fraction"].get<double>());
  EXPECT_LT(transient["energy_error"].get<double>(), 1e-3);
  EXPECT_GT(transient["contact_fraction"].get<double>(), 0.05);
  EXPECT_LT(transient["contact_fraction"].get<double>(), 0.95);
}

TEST(ReducedRun, ADelaminationWithUnresolvedClosuresStaysStableAndConvergesInTheStep) {
  // data/composite-plate.yaml on a coarse [6, 4, 4] p = 2 mesh: 9 delamination pairs, 29 modes;
  // the closed system's stiffest frequency (~300 kHz) is ~20 x the highest mode the step
  // resolves, so almost every closure is a single step. The plain trapezoidal contact force gained
  // energy there until A1 reached 5e5 m (energy error 0.83, status "completed"); the switching
  // steps now conserve energy, and the signature agrees with a 4 x finer step.
  const std::string scene = cli_testing::data("composite-plate.yaml");
  const std::string common = " -q --modal-cache " + (scratch() / "plate-cache").string() +
                             " --set mesh.box.grading.mode=none --set mesh.box.cells=[6,4,4] --set transient.periods=20"
                             " --set spectrum.steady_state.tolerance=0 --set spectrum.plots=false"
                             " --set transient.model=reduced";
  for (const auto& [name, steps] : {std::pair<std::string, int>{"plate-40", 40}, {"plate-160", 160}}) {
    const std::string arguments = "run " + scene + " -o " + (scratch() / name).string() + common +
                                  " --set transient.reduced.steps_per_period=" + std::to_string(steps);
    const cli_testing::Result result = cli_testing::crackle(arguments);
    ASSERT_EQ(result.exit_code, 0) << arguments << "\n" << result.output;
  }
  const auto indices = [](const std::string& name) {
    const nlohmann::json spectrum = read_json(scratch() / name / "spectrum.json");
    double a1 = 0.0, a2 = 0.0;
    for (const nlohmann::json& harmonic : spectrum["probes"]["top"]["harmonics"]) {
      if (harmonic["order"].get<double>() == 1.0) a1 = harmonic["amplitude"].get<double>();
      if (harmonic["order"].get<double>() == 2.0) a2 = harmonic["amplitude"].get<double>();
    }
    return std::pair<double, double>{a1, a2 / a1};
  };
  const auto [a1, ratio] = indices("plate-40");
  const auto [a1_fine, ratio_fine] = indices("plate-160");
  const nlohmann::json transient = read_json(scratch() / "plate-40" / "transient.json");
  std::printf("coarse plate: A1 %.6e (fine %.6e), A2/A1 %.5e (fine %.5e), energy error %.2e, %lld switching steps, %lld unconserved\n",
              a1, a1_fine, ratio, ratio_fine, transient["energy_error"].get<double>(),
              transient["switching"]["steps"].get<long long>(),
              transient["switching"]["unconserved_steps"].get<long long>());
  EXPECT_LT(transient["energy_error"].get<double>(), 1e-3);
  EXPECT_GT(transient["switching"]["steps"].get<long long>(), 100);
  // A step whose gain the velocity jump cannot remove even after the end-of-step force: rare.
  EXPECT_LE(transient["switching"]["unconserved_steps"].get<long long>(),
            transient["switching"]["steps"].get<long long>() / 100);
  EXPECT_LT(std::abs(a1 / a1_fine - 1.0), 1e-3);
  EXPECT_LT(std::abs(ratio / ratio_fine - 1.0), 0.02);
}

TEST(ReducedRun, StudyOverExcitationFrequencyComputesTheReductionOnce) {
  const fs::path scene = scratch() / "study.yaml";
  std::string forced = kForced;
  forced.replace(forced.find("periods: 40"), 11, "periods: 20");
  forced.replace(forced.find("model: full"), 11, "model: reduced");
  std::ofstream(scene) << kBody << forced << R"(study:
  vary:
    transient.excitation.frequency: [140, 150, 160]
  outputs: [spectrum]
)";
  const fs::path output = scratch() / "study";
  const cli_testing::Result result =
      cli_testing::crackle("study " + scene.string() + " -o " + output.string() + " -j 1");
  ASSERT_EQ(result.exit_code, 0) << result.output;
  int computed = 0, cached = 0;
  for (const auto& entry : fs::directory_iterator(output / "cases")) {
    const fs::path file = entry.path() / "transient.json";
    if (!fs::exists(file)) continue;
    const nlohmann::json transient = read_json(file);
    EXPECT_EQ(transient["model"], "reduced");
    (transient["reduction_cached"].get<bool>() ? cached : computed) += 1;
  }
  EXPECT_EQ(computed, 1);
  EXPECT_EQ(cached, 2);
}
