// End-to-end tests of `crackle sweep` (modal -> reduced model -> harmonic balance) on a small
// cracked cantilever: the super-harmonic resonance of A2/A1 at f_b/2, the public fields of
// sweep.csv and sweep.json, file:line errors for bad sweep keys, and harmonic balance against the
// reduced transient (stepped sine) and the full explicit transient (`crackle run`) around f_b/2.
#include <gtest/gtest.h>

#include "cli_testing.hpp"

#include <algorithm>
#include <cmath>
#include <map>
#include <vector>
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
  model: full
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
  const cli_testing::Result result =
      cli_testing::crackle("sweep " + scene.string() + " -o " + (scratch() / name).string() + " -q " + overrides);
  if (output) *output = result.output;
  return result.exit_code;
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

/// The columns of a sweep.csv by header (numbers only).
std::map<std::string, std::vector<double>> read_csv(const fs::path& path) {
  std::ifstream in(path);
  std::string line;
  std::getline(in, line);
  std::vector<std::string> headers;
  std::stringstream header_stream(line);
  for (std::string field; std::getline(header_stream, field, ',');) headers.push_back(field);
  std::map<std::string, std::vector<double>> columns;
  while (std::getline(in, line)) {
    std::stringstream row(line);
    std::size_t i = 0;
    for (std::string field; std::getline(row, field, ',') && i < headers.size(); ++i)
      columns[headers[i]].push_back(std::stod(field));
  }
  return columns;
}

/// Column `name` of an ascending frequency table, interpolated linearly at `hz`.
double interpolate(const std::map<std::string, std::vector<double>>& table, const std::string& name, double hz) {
  const std::vector<double>& f = table.at("excitation frequency [Hz]");
  const std::vector<double>& y = table.at(name);
  for (std::size_t i = 0; i + 1 < f.size(); ++i)
    if (f[i] <= hz && hz <= f[i + 1]) return y[i] + (y[i + 1] - y[i]) * (hz - f[i]) / (f[i + 1] - f[i]);
  ADD_FAILURE() << hz << " Hz is outside the sweep";
  return 0.0;
}

TEST(SweepCommand, HarmonicBalanceMatchesTheReducedAndTheFullTransient) {
  // HB (H = 30, converged for A1..A3: A3 moves by < 1e-4 from H = 15) on a dense branch through
  // f_b/2, interpolated between neighbouring points (spacing 0.04 % of f: interpolation error ~1e-5).
  const std::string cache = (scratch() / "cache").string();
  std::string output;
  ASSERT_EQ(crackle_sweep("dense", kScene,
                          "--modal-cache " + cache + " --set sweep.harmonics=30 --set sweep.points=200 "
                          "--set sweep.frequency.from.ratio=0.47 --set sweep.frequency.to.ratio=0.53",
                          &output), 0) << output;
  const auto branch = read_csv(scratch() / "dense" / "sweep.csv");
  // (a) the reduced transient run to steady state (stepped sine) at five frequencies around f_b/2
  ASSERT_EQ(crackle_sweep("lab", kScene,
                          "--modal-cache " + cache + " --set sweep.method=stepped_sine --set sweep.points=5 "
                          "--set sweep.frequency.from.ratio=0.48 --set sweep.frequency.to.ratio=0.52 "
                          "--set sweep.tolerance=1e-7",
                          &output), 0) << output;
  const auto lab = read_csv(scratch() / "lab" / "sweep.csv");
  ASSERT_EQ(lab.at("excitation frequency [Hz]").size(), 10u);
  for (std::size_t i = 0; i < 5; ++i) {
    const double hz = lab.at("excitation frequency [Hz]")[i];
    for (const char* order : {"A1", "A2", "A3"}) {
      const std::string column = std::string("tip u_z ") + order + " [m]";
      const double reference = lab.at(column)[i];
      const double balance = interpolate(branch, column, hz);
      std::printf("  %.4f Hz %s: HB %.6e reduced transient %.6e (%+.2e)\n", hz, order, balance, reference,
                  balance / reference - 1.0);
      EXPECT_NEAR(balance / reference, 1.0, 5e-3) << hz << " Hz " << order;
    }
  }
  // (b) the full explicit transient (`crackle run`, same mesh) at three of them: A2/A1 within 3 %
  const std::string spectrum = R"(spectrum:
  harmonics: 3
  subharmonics: false
  steady_state: {tolerance: 1.0e-4, min_periods: 10, window_periods: 4}
  plots: false
)";
  for (const double ratio : {0.49, 0.5, 0.51}) {
    const std::string name = "full" + std::to_string(int(ratio * 100));
    const fs::path scene = scratch() / (name + ".yaml");
    std::ofstream(scene) << kScene.substr(0, kScene.find("sweep:")) << spectrum;
    const std::string command = std::string(CRACKLE_BINARY_DIR) + "/apps/crackle run " + scene.string() + " -o " +
                                (scratch() / name).string() + " -q --set transient.excitation.frequency.ratio=" +
                                std::to_string(ratio) + " --set transient.periods=200 > /dev/null 2>&1";
    ASSERT_EQ(std::system(command.c_str()), 0) << command;
    std::ifstream run_file(scratch() / name / "run.json"), spectrum_file(scratch() / name / "spectrum.json");
    const nlohmann::json run = nlohmann::json::parse(run_file), full = nlohmann::json::parse(spectrum_file);
    const double hz = run["excitation_hz"];
    const double reference = full["probes"]["tip"]["indices"]["A2/A1"];
    const double balance = interpolate(branch, "tip u_z A2/A1 [-]", hz);
    std::printf("  %.4f Hz A2/A1: HB %.5f full explicit %.5f (%+.2e)\n", hz, balance, reference, balance / reference - 1.0);
    EXPECT_NEAR(balance / reference, 1.0, 0.03) << hz << " Hz";
  }
}

/// sweep.json of the run `name` under scratch().
nlohmann::json read_sweep_json(const std::string& name) {
  std::ifstream file(scratch() / name / "sweep.json");
  return nlohmann::json::parse(file);
}

TEST(SweepCommand, KrylovSolverMatchesDense) {
  // the same sweep through f_b/2 with the dense LU and with the matrix-free GMRES (sweep.solver):
  // the same branch, and sweep.json naming the solver and, for krylov, its GMRES statistics
  const std::string common = "--modal-cache " + (scratch() / "cache-solvers").string() +
                             " --set sweep.points=12 --set sweep.frequency.from.ratio=0.48"
                             " --set sweep.frequency.to.ratio=0.52";
  std::string output;
  std::map<std::string, nlohmann::json> runs;
  for (const char* solver : {"dense", "krylov", "auto"}) {
    // (the auto run also draws no plot: sweep.plots=false, as identify's and plan's forward runs)
    const std::string plots = std::string(solver) == "auto" ? " --set sweep.plots=false" : "";
    ASSERT_EQ(crackle_sweep(std::string("solver-") + solver, kScene, common + " --set sweep.solver=" + solver + plots, &output), 0)
        << output;
    runs[solver] = read_sweep_json(std::string("solver-") + solver);
    ASSERT_TRUE(runs[solver]["completed"].get<bool>()) << solver;
  }
  EXPECT_EQ(runs["dense"]["linear_solver"]["kind"], "dense");
  EXPECT_EQ(runs["krylov"]["linear_solver"]["kind"], "krylov");
  // auto: dense below the switch (the cantilever's few pairs x 31 harmonic components < 1500 unknowns)
  EXPECT_EQ(runs["auto"]["linear_solver"]["kind"], "dense");
  EXPECT_TRUE(fs::exists(scratch() / "solver-dense" / "sweep_tip.dat"));
  EXPECT_FALSE(fs::exists(scratch() / "solver-auto" / "sweep_tip.dat")) << "sweep.plots=false draws no plot";
  EXPECT_FALSE(fs::exists(scratch() / "solver-auto" / "sweep_tip.png"));
  EXPECT_FALSE(runs["dense"]["linear_solver"].contains("gmres_iterations"));
  EXPECT_EQ(runs["krylov"]["linear_solver"]["preconditioner"], "mean_stiffness+pair_blocks");
  const nlohmann::json& gmres = runs["krylov"]["linear_solver"];
  const long solves = gmres["gmres_solves"], iterations = gmres["gmres_iterations"];
  std::printf("  krylov: %ld GMRES solves, %ld iterations (at most %d per solve), %ld preconditioner factors\n", solves,
              iterations, gmres["gmres_max_iterations"].get<int>(), gmres["preconditioner_factors"].get<long>());
  EXPECT_GE(solves, runs["krylov"]["points"].get<long>());  // at least one Newton step per point
  EXPECT_GE(iterations, solves);
  EXPECT_GT(gmres["gmres_max_iterations"].get<int>(), 0);
  EXPECT_GT(gmres["preconditioner_factors"].get<long>(), 0);
  EXPECT_EQ(gmres["gmres_unconverged"].get<long>(), 0);
  // the same points, amplitudes within 1e-6 relative (the Newton tolerance on the small orders)
  const auto dense = read_csv(scratch() / "solver-dense" / "sweep.csv");
  const auto krylov = read_csv(scratch() / "solver-krylov" / "sweep.csv");
  const std::vector<double>& hz = dense.at("excitation frequency [Hz]");
  ASSERT_EQ(krylov.at("excitation frequency [Hz]").size(), hz.size());
  double worst = 0.0;
  for (std::size_t i = 0; i < hz.size(); ++i) {
    EXPECT_NEAR(krylov.at("excitation frequency [Hz]")[i] / hz[i], 1.0, 1e-9) << i;
    for (const char* order : {"A1", "A2", "A3"}) {
      const std::string column = std::string("tip u_z ") + order + " [m]";
      const double difference = std::abs(krylov.at(column)[i] / dense.at(column)[i] - 1.0);
      worst = std::max(worst, difference);
      EXPECT_LT(difference, 1e-6) << hz[i] << " Hz " << order;
    }
  }
  std::printf("  %zu points, A1..A3 of krylov within %.2e of dense\n", hz.size(), worst);
}

/// A crack outboard of the drive point (crack at 0.16, load at 0.1 of the 0.2 m cantilever) sees almost no
/// static gap: no bending moment passes beyond a point load. The continuation's gap scale was that static
/// response alone, so the arclength was all gap harmonics and the frequency crept: 171 points and 17 s
/// for this sweep (and 2000 points without reaching the end on the [20, 2, 2] p = 2 beam of
/// data/plan-beam.yaml). The scale's floor of a tenth of the linear gap response at the drive gives a
/// step that is mostly frequency, as where the load is outboard of the crack.
TEST(SweepCommand, ACrackOutboardOfTheDriveIsSweptInAboutTheRequestedPoints) {
  std::string text = cli_testing::cantilever("[10, 1, 2]");
  text.replace(text.find("at: 0.04"), 8, "at: 0.16");
  text += R"(transient:
  model: reduced
  excitation: {point: [0.1, 0.01, 0.01], direction: z, amplitude: 20.0, frequency: {mode: 1, ratio: 0.5}}
  damping: {ratio: 0.05, at: {mode: 1}}
  periods: 60
  probes:
    - {name: tip, point: [0.2, 0.01, 0.01]}
sweep:
  frequency: {from: {mode: 1, ratio: 1.7}, to: {mode: 1, ratio: 2.3}}
  harmonics: 15
  points: 40
  stability: true
  subharmonic: 2
  plots: false
)";
  std::string output;
  ASSERT_EQ(crackle_sweep("outboard", text, "", &output), 0) << output;
  std::ifstream json_file(scratch() / "outboard" / "sweep.json");
  const nlohmann::json sweep = nlohmann::json::parse(json_file);
  EXPECT_TRUE(sweep["completed"].get<bool>()) << sweep["warnings"].dump();
  EXPECT_LE(sweep["points"].get<int>(), 60) << "requested 40";
  // the response is the smooth tail of the first resonance: A1 at the tip falls and A2/A1 rises
  const auto table = read_csv(scratch() / "outboard" / "sweep.csv");
  const std::vector<double>& a1 = table.at("tip u_z A1 [m]");
  const std::vector<double>& ratio = table.at("tip u_z A2/A1 [-]");
  ASSERT_GE(a1.size(), 10u);
  EXPECT_LT(a1.back(), a1.front());
  EXPECT_GT(ratio.back(), ratio.front());
}

TEST(SweepCommand, BadSweepKeysGiveFileAndLine) {
  std::string output;
  std::string text = kScene;
  text.replace(text.find("harmonics: 15"), 13, "harmonics: -2");
  EXPECT_EQ(crackle_sweep("bad", text, "", &output), 2);
  const std::string file = (scratch() / "bad.yaml").string();
  EXPECT_NE(output.find(file + ":18: sweep.harmonics: expected an integer in 1..200, got -2"), std::string::npos)
      << output;
  EXPECT_FALSE(fs::exists(scratch() / "bad" / "sweep.json"));
  EXPECT_EQ(crackle_sweep("none", std::string(kScene).substr(0, std::string(kScene).find("sweep:")), "", &output), 2);
  EXPECT_NE(output.find("sweep: expected a sweep section"), std::string::npos) << output;
}

}  // namespace
