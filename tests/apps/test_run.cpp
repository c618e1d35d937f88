// End-to-end tests of `crackle run` (modal -> transient -> spectrum) on a small cracked cantilever.
#include <gtest/gtest.h>

#include "cli_testing.hpp"

#include <array>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <string>

#include <nlohmann/json.hpp>

namespace fs = std::filesystem;

namespace {

/// A 10 x 1 x 1 cantilever of p = 1 with a half-depth edge crack, driven at half its first
/// bilinear frequency; mass-proportional damping of 5 % at mode 1.
const std::string kScene = cli_testing::cantilever("[10, 1, 1]") + R"(modal: {modes: 2}
transient:
  model: full
  excitation: {face: x+, direction: z, amplitude: 20.0, frequency: {mode: 1, ratio: 0.5}}
  damping: {ratio: 0.05, at: {mode: 1}}
  periods: 60
  progress: false
  probes:
    - {name: tip, point: [0.2, 0.01, 0.01]}
spectrum:
  harmonics: 3
  subharmonics: true
  steady_state: {tolerance: 0}
  plots: false
)";

fs::path scratch() {
  static const fs::path dir = fs::temp_directory_path() / ("crackle-test-run-" + std::to_string(::getpid()));
  fs::create_directories(dir);
  return dir;
}

/// Runs `crackle run` on kScene with overrides; returns the exit code.
int crackle_run(const std::string& name, const std::string& overrides, std::string* output = nullptr) {
  const fs::path scene = scratch() / "small.yaml";
  if (!fs::exists(scene)) std::ofstream(scene) << kScene;
  const cli_testing::Result result =
      cli_testing::crackle("run " + scene.string() + " -o " + (scratch() / name).string() + " -q " + overrides);
  if (output) *output = result.output;
  return result.exit_code;
}

nlohmann::json read_json(const fs::path& path) {
  std::ifstream in(path);
  return nlohmann::json::parse(in);
}

}  // namespace

TEST(Run, LinearBodyHasNoHigherHarmonicsAndTheBreathingCrackHas) {
  std::string log;
  ASSERT_EQ(crackle_run("tied", "--set transient.variant=uncracked", &log), 0) << log;
  ASSERT_EQ(crackle_run("cracked", "", &log), 0) << log;
  const nlohmann::json tied = read_json(scratch() / "tied" / "spectrum.json");
  const nlohmann::json cracked = read_json(scratch() / "cracked" / "spectrum.json");
  const nlohmann::json& linear = tied["probes"]["tip"]["indices"];
  const nlohmann::json& breathing = cracked["probes"]["tip"]["indices"];
  // A linear system driven by one tone answers with that tone alone.
  EXPECT_LT(linear["A2/A1"].get<double>(), 1e-8);
  EXPECT_LT(linear["A3/A1"].get<double>(), 1e-8);
  // The breathing crack turns it into harmonics: A2/A1 many orders of magnitude larger.
  EXPECT_GT(breathing["A2/A1"].get<double>(), 0.05);
  EXPECT_GT(breathing["A2/A1"].get<double>(), 1e6 * linear["A2/A1"].get<double>());
  // Excitation at half the first bilinear frequency of the modal stage.
  const nlohmann::json modal = read_json(scratch() / "cracked" / "modal.json");
  const double bilinear = modal["pairs"][0]["f_bilinear_hz"].get<double>();
  EXPECT_NEAR(cracked["excitation_hz"].get<double>(), 0.5 * bilinear, 1e-9 * bilinear);
  EXPECT_EQ(cracked["probes"]["tip"]["component"], "z");
  // Only the stages the scene needs ran, and the output files exist.
  const nlohmann::json run = read_json(scratch() / "cracked" / "run.json");
  ASSERT_EQ(run["stages"].size(), 3u);
  for (const auto& stage : run["stages"]) EXPECT_TRUE(stage["ran"].get<bool>()) << stage;
  for (const char* file : {"transient.json", "energy.csv", "probes.csv", "spectrum_tip.csv", "modes.csv"}) {
    EXPECT_TRUE(fs::exists(scratch() / "cracked" / file)) << file;
  }
}

TEST(Run, ModalStageIsSkippedWhenNothingRefersToAMode) {
  std::string log;
  ASSERT_EQ(crackle_run("hz", "--set transient.excitation.frequency=100 --set transient.damping.at=200 "
                              "--set transient.periods=4 --set modal.modes=1 --set spectrum.harmonics=2",
                        &log),
            0)
      << log;
  // modal: is still in the scene, so it runs; without it (no key refers to a mode) it does not.
  const fs::path scene = scratch() / "no-modal.yaml";
  std::string text = kScene;
  text.erase(text.find("modal: {modes: 2}\n"), std::string("modal: {modes: 2}\n").size());
  std::ofstream(scene) << text;
  const std::string command = std::string(CRACKLE_BINARY_DIR) + "/apps/crackle run " + scene.string() + " -o " +
                              (scratch() / "no-modal").string() +
                              " -q --set transient.excitation.frequency=100 --set transient.damping.at=200"
                              " --set transient.periods=4 > /dev/null 2>&1";
  ASSERT_EQ(std::system(command.c_str()), 0);
  const nlohmann::json run = read_json(scratch() / "no-modal" / "run.json");
  EXPECT_EQ(run["stages"][0]["name"], "modal");
  EXPECT_FALSE(run["stages"][0]["ran"].get<bool>());
  EXPECT_FALSE(fs::exists(scratch() / "no-modal" / "modal.json"));
  EXPECT_DOUBLE_EQ(run["excitation_hz"].get<double>(), 100.0);
}

TEST(Run, SteadyStateStopsEarlyWithTheSameIndices) {
  std::string log;
  ASSERT_EQ(crackle_run("full", "--set transient.periods=120", &log), 0) << log;
  ASSERT_EQ(crackle_run("early", "--set transient.periods=120 --set spectrum.steady_state.tolerance=1e-4 "
                                 "--set spectrum.steady_state.window_periods=4",
                        &log),
            0)
      << log;
  const nlohmann::json full = read_json(scratch() / "full" / "spectrum.json");
  const nlohmann::json early = read_json(scratch() / "early" / "spectrum.json");
  EXPECT_TRUE(early["steady_state"]["settled"].get<bool>());
  EXPECT_LT(early["steady_state"]["periods_used"].get<int>(), 60);
  EXPECT_EQ(full["steady_state"]["periods_used"].get<int>(), 120);
  for (const char* index : {"A2/A1", "A3/A1"}) {
    const double reference = full["probes"]["tip"]["indices"][index].get<double>();
    EXPECT_NEAR(early["probes"]["tip"]["indices"][index].get<double>(), reference, 1e-3 * reference) << index;
  }
}

TEST(Run, SceneWithoutTransientIsAClearError) {
  const fs::path scene = scratch() / "modal-only.yaml";
  std::ofstream(scene) << "mesh:\n  box: {size: [1, 1, 1], cells: [1, 1, 1], order: 1}\n"
                          "material: {E: 1.0e9, nu: 0.3, rho: 1000}\n";
  const std::string command = std::string(CRACKLE_BINARY_DIR) + "/apps/crackle run " + scene.string() + " -o " +
                              (scratch() / "none").string() + " > /dev/null 2>&1";
  const int status = std::system(command.c_str());
  EXPECT_EQ(WEXITSTATUS(status), 2);
}

/// With 8 modes, uncracked mode 7 of the delaminated plate has no open partner (two local modes
/// of the delaminated ply took open places 5 and 7): a frequency relative to its bilinear
/// frequency is refused instead of taken from a mismatched pair.
TEST(Run, BilinearFrequencyOfAnUnpairedModeIsAClearError) {
  const cli_testing::Result result =
      cli_testing::crackle("run " + cli_testing::data("composite-plate.yaml") + " -o " + (scratch() / "unpaired").string() +
                           " -q --set modal.modes=8 --set transient.excitation.frequency.mode=7");
  const std::string& text = result.output;
  EXPECT_EQ(result.exit_code, 2) << text;
  EXPECT_NE(text.find("transient.excitation.frequency.mode: mode 7 has no open partner among the 8 open modes "
                      "computed"),
            std::string::npos)
      << text;
  EXPECT_FALSE(fs::exists(scratch() / "unpaired" / "transient.json"));
}
