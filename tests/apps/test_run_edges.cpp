// `crackle run`, `modal` and `check` at the edges, on the built executable: scenes that cannot fit
// in memory are refused before anything is built, points outside the body are refused, output
// folders are checked before the computation and owned by the run that writes them (a rerun leaves
// no debris of an earlier or killed run), probes.csv is decimated, snapshots come with a .pvd, and
// late messages name the key and the line.
#include <gtest/gtest.h>

#include "cli_testing.hpp"

#include <cmath>
#include <complex>
#include <filesystem>
#include <fstream>
#include <regex>
#include <sstream>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

namespace fs = std::filesystem;

namespace {

/// A 10 x 1 x 1 cantilever of p = 1 with a half-depth edge crack, driven at 100 Hz for 4 periods.
const std::string kScene = cli_testing::cantilever("[10, 1, 1]") + R"(transient:
  model: full
  excitation: {face: x+, direction: z, amplitude: 20.0, frequency: 100}
  periods: 4
  progress: false
  probes:
    - {name: tip, point: [0.2, 0.01, 0.01]}
spectrum:
  harmonics: 3
  steady_state: {tolerance: 0, min_periods: 2, window_periods: 2}
  plots: false
)";

using cli_testing::crackle;
using cli_testing::Result;

fs::path scratch() {
  static const fs::path dir = fs::temp_directory_path() / ("crackle-run-edges-" + std::to_string(::getpid()));
  fs::create_directories(dir);
  return dir;
}

fs::path scene_file(const std::string& name = "small.yaml", const std::string& text = kScene) {
  const fs::path path = scratch() / name;
  std::ofstream(path) << text;
  return path;
}

Result run(const std::string& folder, const std::string& extra = "", const fs::path& scene = scene_file()) {
  return crackle("run " + scene.string() + " -o " + (scratch() / folder).string() + " -q " + extra);
}

nlohmann::json read_json(const fs::path& path) {
  std::ifstream in(path);
  return nlohmann::json::parse(in);
}

std::size_t line_count(const fs::path& path) {
  std::ifstream in(path);
  std::size_t lines = 0;
  for (std::string line; std::getline(in, line);) ++lines;
  return lines;
}

}  // namespace

TEST(RunEdges, MeshesThatCannotFitInMemoryAreRefusedBeforeMeshing) {
  const std::string scene = scene_file().string();
  for (const std::string cells : {"[100000,100000,100000]", "[1000000000,1,1]"}) {
    for (const std::string command : {"check ", "modal ", "run "}) {
      SCOPED_TRACE(command + cells);
      const std::string output = command == "check " ? "" : " -o " + (scratch() / "memory").string();
      const Result result = crackle(command + scene + output + " --set 'mesh.box.cells=" + cells + "'");
      EXPECT_EQ(result.exit_code, 2) << result.output;
      EXPECT_NE(result.output.find("mesh.box.cells: expected a mesh that fits in memory, got " + cells.substr(0, 7)),
                std::string::npos)
          << result.output;
      EXPECT_NE(result.output.find("available (MemAvailable in /proc/meminfo"), std::string::npos) << result.output;
      EXPECT_EQ(result.output.find("bad_alloc"), std::string::npos) << result.output;
    }
  }
  EXPECT_FALSE(fs::exists(scratch() / "memory"));  // refused before anything was written
  // The key's line is named when the value comes from the file.
  std::string text = kScene;
  text.replace(text.find("cells: [10, 1, 1]"), 17, "cells: [100000, 100000, 100000]");
  const Result from_file = crackle("check " + scene_file("huge.yaml", text).string());
  EXPECT_EQ(from_file.exit_code, 2);
  EXPECT_NE(from_file.output.find("huge.yaml:2: mesh.box.cells: expected a mesh that fits in memory"), std::string::npos)
      << from_file.output;
}

TEST(RunEdges, AGradedMeshIsCountedWithItsLayersBeforeMeshing) {
  // The issue's aluminium cantilever: [50, 5, 3] cells of order 4 graded towards the front make 58 x 5 x
  // 12 cells, 720k DOFs: about 21 GiB for the modal stage's matrices. Counting the cells requested
  // and two per crack edge (52 x 7 x 5, 382k DOFs) said 11.1 GiB, the run went on and the kernel
  // killed it at 24 GB. Under a 12 GB address-space limit it is refused in a second with the key,
  // the graded cells and the figure.
  const std::string text = R"(mesh:
  box: {size: [0.25, 0.025, 0.012], cells: [50, 5, 3], order: 4, grading: always}
material: {E: 70.0e9, nu: 0.33, rho: 2700.0}
boundary:
  - {face: x-, fix: [x, y, z]}
crack:
  plane: {normal: x, at: 0.06}
  region: {y: [0.0, 0.025], z: [0.006, 0.012]}
transient:
  model: reduced
  excitation: {face: x+, direction: z, amplitude: 20.0, frequency: {mode: 1, ratio: 0.5}}
  damping: {ratio: 0.05, at: {mode: 1}}
  periods: 60
  probes:
    - {name: tip, point: [0.25, 0.0125, 0.012]}
spectrum: {harmonics: 5}
)";
  const fs::path scene = scene_file("aluminium.yaml", text);
  const Result result =
      crackle("run " + scene.string() + " -q -o " + (scratch() / "graded").string(), "ulimit -v 12000000;");
  EXPECT_EQ(result.exit_code, 2) << result.output;
  EXPECT_NE(result.output.find("aluminium.yaml:2: mesh.box.cells: expected a mesh that fits in memory, got [50, 5, 3] "
                               "cells of order 4 (58 x 5 x 12 with the crack's lines and the grading layers of "
                               "mesh.box.grading): about 239757 nodes"),
            std::string::npos)
      << result.output;
  EXPECT_FALSE(fs::exists(scratch() / "graded"));
  // The estimate is the mesh: crackle check counts the same nodes (the crack's copies besides).
  const Result checked = crackle("check " + scene.string() + " --no-assembly");
  ASSERT_EQ(checked.exit_code, 0) << checked.output;
  EXPECT_NE(checked.output.find("nodes        240261 (239757 + 504 crack-face copies)"), std::string::npos)
      << checked.output;
}

TEST(RunEdges, DevicesAsMeshFilesAndTooManySnapshotsAreRefused) {
  const Result device = crackle("check " + scene_file().string() + " --set 'mesh={gmsh: /dev/zero}'");
  EXPECT_EQ(device.exit_code, 2) << device.output;
  EXPECT_NE(device.output.find("mesh.gmsh: expected a Gmsh mesh file, got a device or pipe, '/dev/zero'"),
            std::string::npos)
      << device.output;
  const Result snapshots = run("snapshots", "--set transient.snapshots.count=1000000000");
  EXPECT_EQ(snapshots.exit_code, 2) << snapshots.output;
  EXPECT_NE(snapshots.output.find("transient.snapshots.count: expected at most one snapshot per step"),
            std::string::npos)
      << snapshots.output;
  EXPECT_EQ(snapshots.output.find("bad_alloc"), std::string::npos);
}

TEST(RunEdges, PointsOutsideTheBodyAreRefusedAndSnappingDistancesReported) {
  const Result probe = run("outside", "--set 'transient.probes[0].point=[10,10,10]'");
  EXPECT_EQ(probe.exit_code, 2) << probe.output;
  EXPECT_NE(probe.output.find("transient.probes[0].point: expected a point in the body (bounding box [0, 0.2] x "
                              "[0, 0.02] x [0, 0.01] m), got (10, 10, 10)"),
            std::string::npos)
      << probe.output;
  EXPECT_FALSE(fs::exists(scratch() / "outside"));  // bad input found late still writes nothing
  const Result load = run("outside-load", "--set 'transient.excitation={point: [0.2, 0.01, 0.5], amplitude: 1, "
                                          "frequency: 100}'");
  EXPECT_EQ(load.exit_code, 2) << load.output;
  EXPECT_NE(load.output.find("transient.excitation.point: expected a point in the body"), std::string::npos)
      << load.output;
  // crackle check makes the same refusals (before anything is assembled), and so does crackle sweep
  // (which would otherwise read the probe at its nearest node).
  for (const std::string set : {"'transient.probes[0].point=[10,10,10]'",
                                "'transient.excitation={point: [0.2, 0.01, 0.5], amplitude: 1, frequency: 100}'",
                                "'transient.probes[0]={name: tip, point: [0.1, 0.01, 0.01], side: upper}'"}) {
    SCOPED_TRACE(set);
    const Result checked = crackle("check " + scene_file().string() + " --no-assembly --set " + set);
    EXPECT_EQ(checked.exit_code, 2) << checked.output;
    const Result ran = run("outside-" + std::to_string(checked.output.size()), "--set " + set);
    EXPECT_EQ(ran.exit_code, 2) << ran.output;
    const auto error_line = [](const std::string& output) { return output.substr(output.find("crackle: error: ")); };
    EXPECT_EQ(error_line(checked.output), error_line(ran.output));  // word for word
  }
  const Result swept =
      crackle("sweep " + scene_file().string() + " -q -o " + (scratch() / "outside-sweep").string() +
              " --set 'transient.probes[0].point=[10,10,10]' --set 'sweep={frequency: {from: 90, to: 110}}'");
  EXPECT_EQ(swept.exit_code, 2) << swept.output;
  EXPECT_NE(swept.output.find("transient.probes[0].point: expected a point in the body"), std::string::npos)
      << swept.output;

  // A point inside snaps to its nearest node; transient.json says how far that is.
  const Result inside = run("inside", "--set 'transient.probes[0].point=[0.199, 0.02, 0.0099]'");
  ASSERT_EQ(inside.exit_code, 0) << inside.output;
  const nlohmann::json transient = read_json(scratch() / "inside" / "transient.json");
  ASSERT_EQ(transient["probes"].size(), 1u);
  EXPECT_EQ(transient["probes"][0]["name"], "tip");
  EXPECT_NEAR(transient["probes"][0]["distance_m"].get<double>(), std::hypot(0.001, 0.0001), 1e-9);
  EXPECT_TRUE(transient["warnings"].empty()) << transient["warnings"];
}

TEST(RunEdges, AProbeOnAClampedFaceIsAWarning) {
  const Result result = crackle("run " + scene_file().string() + " -o " + (scratch() / "clamped").string() +
                                " -q --set 'transient.probes[0].point=[0, 0.01, 0.01]'");
  ASSERT_EQ(result.exit_code, 0) << result.output;
  const std::string warning = "probe 'tip' (node ";
  EXPECT_NE(result.output.find("crackle: warning: " + warning), std::string::npos) << result.output;
  EXPECT_NE(result.output.find("held by a boundary condition"), std::string::npos) << result.output;
  const nlohmann::json transient = read_json(scratch() / "clamped" / "transient.json");
  ASSERT_FALSE(transient["warnings"].empty());
  EXPECT_EQ(transient["warnings"][0].get<std::string>().rfind(warning, 0), 0u) << transient["warnings"];
}

TEST(RunEdges, UnwritableOutputFoldersFailBeforeTheComputation) {
  const fs::path file = scratch() / "a-file";
  std::ofstream(file) << "not a folder\n";
  const std::string scene = scene_file().string();
  for (const std::string command : {"run ", "modal "}) {
    for (const fs::path& folder : {file, file / "below", fs::path("/proc/version/out")}) {
      SCOPED_TRACE(command + folder.string());
      const Result result = crackle(command + scene + " -o " + folder.string() + " --set modal.modes=2");
      EXPECT_EQ(result.exit_code, 4) << result.output;
      EXPECT_NE(result.output.find("crackle: error: " + folder.string() + ": cannot"), std::string::npos)
          << result.output;
      EXPECT_EQ(result.output.find("transient:"), std::string::npos) << result.output;  // nothing computed
    }
  }
  std::string study = kScene;
  study += "study:\n  vary: {transient.excitation.amplitude: [10, 20]}\n  outputs: [spectrum]\n";
  const Result result = crackle("study " + scene_file("study.yaml", study).string() + " -o " + (file / "s").string());
  EXPECT_EQ(result.exit_code, 4) << result.output;
  EXPECT_NE(result.output.find((file / "s").string() + ": cannot"), std::string::npos) << result.output;
}

TEST(RunEdges, ARerunRemovesTheDebrisOfAKilledRunAndRefusesForeignFiles) {
  const fs::path folder = scratch() / "rerun";
  ASSERT_EQ(run("rerun", "--set transient.snapshots.count=3").exit_code, 0);
  EXPECT_TRUE(fs::exists(folder / "snapshot_0002.vtu"));
  EXPECT_TRUE(fs::exists(folder / "crackle-run.json"));
  // What kill -9 in the middle of a write and an earlier, longer run leave behind.
  std::ofstream(folder / "probes.csv.tmp.4242") << "time [s]\n0.1\n";
  std::ofstream(folder / "snapshot_0099.vtu") << "<VTKFile/>\n";
  const Result rerun = run("rerun", "--set transient.snapshots.count=2");
  ASSERT_EQ(rerun.exit_code, 0) << rerun.output;
  EXPECT_NE(rerun.output.find("crackle: note: " + folder.string() + ": removed"), std::string::npos) << rerun.output;
  EXPECT_NE(rerun.output.find("leftover(s) of an interrupted write (probes.csv.tmp.4242)"), std::string::npos)
      << rerun.output;
  EXPECT_FALSE(fs::exists(folder / "probes.csv.tmp.4242"));
  EXPECT_FALSE(fs::exists(folder / "snapshot_0099.vtu"));
  EXPECT_FALSE(fs::exists(folder / "snapshot_0002.vtu"));
  EXPECT_TRUE(fs::exists(folder / "snapshot_0001.vtu"));
  for (const fs::directory_entry& entry : fs::directory_iterator(folder)) {
    EXPECT_EQ(entry.path().filename().string().find(".tmp."), std::string::npos) << entry.path();
  }
  const nlohmann::json marker = read_json(folder / "crackle-run.json");
  EXPECT_EQ(marker["commands"]["run"]["status"], "done");
  EXPECT_EQ(marker["commands"]["run"]["files"].size(), 9u) << marker;  // 2 snapshots, pvd, 6 files

  // A folder with files crackle run did not write is refused, or written into with --overwrite.
  std::ofstream(folder / "notes.txt") << "mine\n";
  const Result refused = run("rerun");
  EXPECT_EQ(refused.exit_code, 2) << refused.output;
  EXPECT_NE(refused.output.find("got files crackle run does not own: notes.txt; choose another folder (-o), or pass "
                                "--overwrite"),
            std::string::npos)
      << refused.output;
  EXPECT_TRUE(fs::exists(folder / "probes.csv"));  // nothing was removed
  ASSERT_EQ(run("rerun", "--overwrite").exit_code, 0);
  EXPECT_TRUE(fs::exists(folder / "notes.txt"));
}

TEST(RunEdges, ProbesCsvIsDecimatedAndSnapshotsComeWithAPvd) {
  ASSERT_EQ(run("decimated", "--set transient.snapshots.count=4").exit_code, 0);
  ASSERT_EQ(run("every-step", "--set transient.history.samples_per_period=all").exit_code, 0);
  const nlohmann::json transient = read_json(scratch() / "decimated" / "transient.json");
  const long long steps = transient["steps"];
  const long long interval = transient["probe_interval"];
  const double steps_per_period = steps / 4.0;
  EXPECT_EQ(interval, static_cast<long long>(steps_per_period / 64));
  EXPECT_GE(steps_per_period / interval, 64.0);
  EXPECT_EQ(line_count(scratch() / "decimated" / "probes.csv"), 1 + (steps + interval - 1) / interval);
  EXPECT_EQ(line_count(scratch() / "every-step" / "probes.csv"), 1 + static_cast<std::size_t>(steps));
  // The spectrum takes every step either way.
  const nlohmann::json a = read_json(scratch() / "decimated" / "spectrum.json");
  const nlohmann::json b = read_json(scratch() / "every-step" / "spectrum.json");
  EXPECT_EQ(a["probes"]["tip"].dump(), b["probes"]["tip"].dump());
  EXPECT_EQ(line_count(scratch() / "decimated" / "spectrum_tip.csv"),
            line_count(scratch() / "every-step" / "spectrum_tip.csv"));

  std::ifstream pvd(scratch() / "decimated" / "snapshots.pvd");
  const std::string text((std::istreambuf_iterator<char>(pvd)), std::istreambuf_iterator<char>());
  const std::regex dataset("<DataSet timestep=\"([0-9.e-]+)\" group=\"\" part=\"0\" file=\"(snapshot_000[0-9].vtu)\"/>");
  std::vector<double> times;
  for (auto it = std::sregex_iterator(text.begin(), text.end(), dataset); it != std::sregex_iterator(); ++it) {
    times.push_back(std::stod((*it)[1]));
    EXPECT_TRUE(fs::exists(scratch() / "decimated" / (*it)[2].str()));
  }
  ASSERT_EQ(times.size(), 4u) << text;
  const double end = transient["time"];
  for (int k = 0; k < 4; ++k) EXPECT_NEAR(times[k], end * (k + 1) / 4.0, 1.01 * end / steps);
}

// spectrum.window applies to the amplitude spectra (spectrum_<probe>.csv): with hann they are the
// Hann-windowed DFT of the last analysed periods of the record, checked here against the test's own
// DFT of probes.csv (every step); the harmonic tables stay the window-free ones.
TEST(RunEdges, SpectrumWindowShapesTheAmplitudeSpectrumAndNotTheHarmonics) {
  const std::string every_step = "--set transient.history.samples_per_period=all";
  ASSERT_EQ(run("window-auto", every_step).exit_code, 0);
  ASSERT_EQ(run("window-hann", every_step + " --set spectrum.window=hann").exit_code, 0);
  const nlohmann::json automatic = read_json(scratch() / "window-auto" / "spectrum.json");
  const nlohmann::json hann = read_json(scratch() / "window-hann" / "spectrum.json");
  EXPECT_EQ(automatic["amplitude_spectrum"]["window"], "rectangular");  // a period is a whole number of steps
  EXPECT_EQ(hann["amplitude_spectrum"]["window"], "hann");
  EXPECT_EQ(automatic["probes"].dump(), hann["probes"].dump());

  auto read_csv = [](const fs::path& path, int column) {
    std::ifstream in(path);
    std::vector<double> values;
    std::string line;
    std::getline(in, line);  // header
    while (std::getline(in, line)) {
      std::stringstream row(line);
      std::string cell;
      for (int c = 0; c <= column; ++c) std::getline(row, cell, ',');
      values.push_back(std::stod(cell));
    }
    return values;
  };
  const fs::path folder = scratch() / "window-hann";
  const std::vector<double> time = read_csv(folder / "probes.csv", 0);
  const std::vector<double> u_z = read_csv(folder / "probes.csv", 3);  // tip u_z, the analysed component
  const std::vector<double> amplitude = read_csv(folder / "spectrum_tip.csv", 1);
  ASSERT_GT(time.size(), 100u);
  const double dt = time[2] - time[1];
  const int per_period = static_cast<int>(std::lround(1.0 / (100.0 * dt)));
  const int n = 2 * per_period;  // window_periods: 2
  ASSERT_EQ(amplitude.size(), static_cast<std::size_t>(n / 2 + 1));
  double weight_sum = 0.0;
  std::vector<double> w(n);
  for (int i = 0; i < n; ++i) weight_sum += w[i] = 0.5 - 0.5 * std::cos(2.0 * M_PI * i / n);
  const std::size_t first = u_z.size() - n;
  for (int k = 0; k <= 5; ++k) {
    std::complex<double> sum = 0.0;
    for (int i = 0; i < n; ++i) sum += w[i] * u_z[first + i] * std::polar(1.0, -2.0 * M_PI * k * i / n);
    const double expected = (k == 0 ? 1.0 : 2.0) * std::abs(sum) / weight_sum;
    EXPECT_NEAR(std::abs(amplitude[k]), expected, 1e-9 * expected) << "bin " << k;
  }
  // The rectangular spectrum differs beside the drive's bin, where the Hann window leaks.
  const std::vector<double> rectangular = read_csv(scratch() / "window-auto" / "spectrum_tip.csv", 1);
  EXPECT_GT(std::abs(rectangular[3] - amplitude[3]), 0.01 * std::abs(amplitude[3]));
}

TEST(RunEdges, LateMessagesNameTheKeyAndTheLine) {
  std::string text = kScene;
  text.replace(text.find("frequency: 100"), 14, "frequency: 1e12");
  const Result nyquist = run("nyquist", "", scene_file("fast.yaml", text));
  EXPECT_EQ(nyquist.exit_code, 2) << nyquist.output;
  EXPECT_NE(nyquist.output.find("fast.yaml:11: transient.excitation.frequency: expected a frequency whose harmonic 3 "
                                "(spectrum.harmonics) lies below the Nyquist frequency"),
            std::string::npos)
      << nyquist.output;
  const Result overridden = run("nyquist", "--set transient.excitation.frequency=1e12");
  EXPECT_NE(overridden.output.find("small.yaml: transient.excitation.frequency"), std::string::npos)
      << overridden.output;

  const Result steps = run("steps", "--set transient.periods=1e9");
  EXPECT_EQ(steps.exit_code, 2) << steps.output;
  EXPECT_NE(steps.output.find("small.yaml: transient.periods: expected a run of at most 2e9 steps"), std::string::npos)
      << steps.output;
  text = kScene;
  text.replace(text.find("periods: 4"), 10, "periods: 1e9");
  const Result from_file = run("steps", "", scene_file("long.yaml", text));
  EXPECT_NE(from_file.output.find("long.yaml:12: transient.periods: expected a run of at most 2e9 steps"),
            std::string::npos)
      << from_file.output;
  EXPECT_FALSE(fs::exists(scratch() / "steps"));
}
