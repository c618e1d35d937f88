// End-to-end tests of `crackle sweep` (modal -> reduced model -> harmonic balance) on a small
// cracked cantilever: the super-harmonic resonance of A2/A1 at f_b/2, the public fields of
// sweep.csv and sweep.json, and file:line errors for bad sweep keys.
#include <gtest/gtest.h>

#include "cli_testing.hpp"

#include <array>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

#include <nlohmann/json.hpp>

namespace fs = std::filesystem;

namespace {

/// The 10 x 1 x 1 cantilever of test_run.cpp (p = 1, half-depth edge crack, 5 % damping at mode 1),
/// swept through half its first bilinear frequency.
const std::string kScene = cli_testing::cantilever("[10, 1, 1]") + R"(transient:
  excitation: {face: x+, direction: z, amplitude: 20.0, frequency: {mode: 1, ratio: 0.5}}
  damping: {ratio: 0.05, at: {mode: 1}}
  periods: 60
  probes:
    - {name: tip, point: [0.2, 0.01, 0.01]}
sweep:
  frequency: {from: {mode: 1, ratio: 0.46}, to: {mode: 1, ratio: 0.54}}
  harmonics: 15
  points: 40
)";

fs::path scratch() {
  static const fs::path dir = fs::temp_directory_path() / ("crackle-test-sweep-" + std::to_string(::getpid()));
  fs::create_directories(dir);
  return dir;
}

int crackle_sweep(const std::string& name, const std::string& text, const std::string& overrides, std::string* output) {
  const fs::path scene = scratch() / (name + ".yaml");
  std::ofstream(scene) << text;
  const std::string command = std::string(CRACKLE_BINARY_DIR) + "/apps/crackle sweep " + scene.string() + " -o " +
                              (scratch() / name).string() + " -q " + overrides + " 2>&1";
  FILE* pipe = popen(command.c_str(), "r");
  std::array<char, 4096> buffer;
  std::string out;
  while (std::fgets(buffer.data(), buffer.size(), pipe)) out += buffer.data();
  const int status = pclose(pipe);
  if (output) *output = out;
  return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
}

TEST(SweepCommand, SuperHarmonicPeakAtHalfTheBilinearFrequency) {
  std::string output;
  ASSERT_EQ(crackle_sweep("hb", kScene, "", &output), 0) << output;
  const fs::path folder = scratch() / "hb";
  std::ifstream json_file(folder / "sweep.json");
  const nlohmann::json sweep = nlohmann::json::parse(json_file);
  const double bilinear = sweep["bilinear_hz"];
  const double peak = sweep["probes"]["tip"]["peak_a2_over_a1"]["frequency_hz"];
  EXPECT_NEAR(peak / (0.5 * bilinear), 1.0, 5e-3) << output;
  EXPECT_GT(sweep["probes"]["tip"]["peak_a2_over_a1"]["value"].get<double>(), 0.01);
  EXPECT_TRUE(sweep["completed"].get<bool>());
  EXPECT_GE(sweep["points"].get<int>(), 40);
  for (const char* key : {"settings", "events", "warnings", "stages", "model", "wall_s", "seconds_per_point"})
    EXPECT_TRUE(sweep.contains(key)) << key;
  EXPECT_EQ(sweep["settings"]["method"], "harmonic_balance");
  EXPECT_NEAR(sweep["settings"]["from_hz"].get<double>() / bilinear, 0.46, 1e-12);
  std::ifstream csv_file(folder / "sweep.csv");
  std::string header;
  std::getline(csv_file, header);
  for (const char* field : {"excitation frequency [Hz]", "tip u_z A1 [m]", "tip u_z phase1 [rad]", "tip u_z A15 [m]",
                            "tip u_z A2/A1 [-]", "tip u_z A3/A1 [-]", "tip u_z A1/2/A1 [-]", "stable",
                            "newton iterations [-]", "residual [-]"})
    EXPECT_NE(header.find(field), std::string::npos) << field;
  int rows = 0;
  for (std::string line; std::getline(csv_file, line);) ++rows;
  EXPECT_EQ(rows, sweep["points"].get<int>());
  EXPECT_TRUE(fs::exists(folder / "sweep_tip.dat"));
}

TEST(SweepCommand, BadSweepKeysGiveFileAndLine) {
  std::string output;
  std::string text = kScene;
  text.replace(text.find("harmonics: 15"), 13, "harmonics: -2");
  EXPECT_EQ(crackle_sweep("bad", text, "", &output), 2);
  const std::string file = (scratch() / "bad.yaml").string();
  EXPECT_NE(output.find(file + ":17: sweep.harmonics: expected an integer in 1..200, got -2"), std::string::npos)
      << output;
  EXPECT_FALSE(fs::exists(scratch() / "bad" / "sweep.json"));
  EXPECT_EQ(crackle_sweep("none", std::string(kScene).substr(0, std::string(kScene).find("sweep:")), "", &output), 2);
  EXPECT_NE(output.find("sweep: expected a sweep section"), std::string::npos) << output;
}

}  // namespace
