// `crackle identify` end to end: synthetic measurements of known cracks from modal solves on a finer
// mesh than the identify scene's (so that model error is present, as in reality) with Gaussian noise,
// the intervals against the truth, an unidentifiable case, and bad measurement input.
#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <filesystem>
#include <iostream>
#include <map>
#include <fstream>
#include <random>
#include <sstream>

#include <nlohmann/json.hpp>

#include "cli_testing.hpp"
#include "identify/forward.hpp"

namespace {

namespace fs = std::filesystem;
using cli_testing::crackle;
using nlohmann::json;

fs::path scratch(const std::string& name) {
  const fs::path dir = fs::path(CRACKLE_BINARY_DIR) / "tests" / "identify" / name;
  fs::remove_all(dir);
  fs::create_directories(dir);
  return dir;
}

json read_json(const fs::path& path) {
  std::ifstream stream(path);
  return json::parse(stream);
}

std::string read_text(const fs::path& path) {
  std::ifstream stream(path);
  std::stringstream text;
  text << stream.rdbuf();
  return text.str();
}

/// The identify scene of data/identify-beam.yaml with its measurements replaced by `measured` and,
/// when given, the truth of a synthetic test.
fs::path identify_scene(const fs::path& dir, const std::string& measured, int points = 7, double at = -1.0,
                        double z0 = -1.0) {
  std::string text = read_text(cli_testing::data("identify-beam.yaml"));
  const std::string from = "  measured: identify-beam.csv";
  text.replace(text.find(from), std::string(from).size(), "  measured: " + measured);
  const std::string map_from = "  map: {points: 7}";
  std::string map = "  map: {points: " + std::to_string(points) + "}";
  if (at > 0.0)
    map += "\n  truth:\n    crack.plane.at: " + std::to_string(at) + "\n    crack.region.z[0]: " + std::to_string(z0);
  text.replace(text.find(map_from), map_from.size(), map);
  const fs::path scene = dir / "identify.yaml";
  std::ofstream(scene) << text;
  return scene;
}

/// Modal frequencies of the beam with the crack at `at`, lower edge z0, on the finer mesh of
/// data/beam.yaml ([40, 4, 2], p = 2, graded towards the front): the "measured" part.
json truth_pairs(const fs::path& dir, double at, double z0) {
  const std::string arguments = "modal " + cli_testing::data("beam.yaml") + " -o " + (dir / "truth").string() +
                                " --set modal.solver=arpack --set modal.modes=5 --set crack.plane.at=" +
                                std::to_string(at) + " --set 'crack.region.z=[" + std::to_string(z0) + ", 0.01]'";
  const auto result = crackle(arguments, "OMP_NUM_THREADS=1");
  EXPECT_EQ(result.exit_code, 0) << result.output;
  return read_json(dir / "truth" / "modal.json")["pairs"];
}

/// A measurements CSV: f_uncracked of modes 1 and 3, f_bilinear of modes 1, 3 and 5 with relative
/// noise `noise` (seeded), sigma = noise x value.
void write_measurements(const fs::path& csv, const json& pairs, double noise, unsigned seed) {
  std::mt19937 generator(seed);
  std::normal_distribution<double> gauss(0.0, 1.0);
  std::ofstream out(csv);
  out << "quantity,mode,probe,drive_hz,value,sigma\n";
  const std::vector<std::pair<std::string, int>> rows = {
      {"f_uncracked", 1}, {"f_uncracked", 3}, {"f_bilinear", 1}, {"f_bilinear", 3}, {"f_bilinear", 5}};
  out.precision(10);
  for (const auto& [quantity, mode] : rows) {
    const double value = pairs[mode - 1][quantity + "_hz"].get<double>();
    const double sigma = noise * value;
    out << quantity << "," << mode << ",,," << value + sigma * gauss(generator) << "," << sigma << "\n";
  }
}

void expect_truth_inside(const json& result, double at, double z0) {
  const auto& interval = result["interval_95"];
  EXPECT_LE(interval["crack.plane.at"][0].get<double>(), at) << result.dump(1);
  EXPECT_GE(interval["crack.plane.at"][1].get<double>(), at) << result.dump(1);
  EXPECT_LE(interval["crack.region.z[0]"][0].get<double>(), z0) << result.dump(1);
  EXPECT_GE(interval["crack.region.z[0]"][1].get<double>(), z0) << result.dump(1);
  EXPECT_TRUE(result["identifiable"].get<bool>()) << result.dump(1);
  // The intervals are informative: narrower than half the bounds (0.16 m of position, 4.5 mm of depth).
  EXPECT_LT(interval["crack.plane.at"][1].get<double>() - interval["crack.plane.at"][0].get<double>(), 0.08);
  EXPECT_LT(interval["crack.region.z[0]"][1].get<double>() - interval["crack.region.z[0]"][0].get<double>(), 0.00225);
}

/// Identifies the crack of measurements `csv` with the map of `map` (built by the first call).
json identify_with_map(const fs::path& dir, const fs::path& csv, const fs::path& map, double at = -1.0,
                       double z0 = -1.0) {
  const fs::path scene = identify_scene(dir, csv.string(), 7, at, z0);
  fs::remove(dir / "out" / "identify.json");
  const auto result = crackle("identify " + scene.string() + " -o " + (dir / "out").string() + " --map-cache " +
                              map.string(), "OMP_NUM_THREADS=1");
  EXPECT_EQ(result.exit_code, 0) << result.output;
  return read_json(dir / "out" / "identify.json");
}

// One design, one map, several parts: the shipped measurements build the map; cracks near the root
// and at mid-span, shallow and deep, then 30 noisy replicas of one crack, each identified with the
// map cached (the fleet case). One test, so that no two processes write the map at once.
TEST(Identify, AFleetOfPartsOnOneMap) {
  const fs::path root = scratch("fleet");
  const fs::path map = root / "map";
  {
    // data/identify-beam.csv: the crack of data/beam.yaml (x = 0.05, z0 = 0.007) on its finer mesh.
    const auto result = crackle("identify " + cli_testing::data("identify-beam.yaml") + " -o " +
                                (root / "shipped").string() + " --map-cache " + map.string(), "OMP_NUM_THREADS=1");
    ASSERT_EQ(result.exit_code, 0) << result.output;
    const json document = read_json(root / "shipped" / "identify.json");
    expect_truth_inside(document, 0.05, 0.007);
    for (const char* name : {"identify_map.csv", "identify.json"}) EXPECT_TRUE(fs::exists(root / "shipped" / name)) << name;
    for (const char* field : {"estimate", "interval_95", "covariance", "correlation", "minima", "identifiable",
                              "reasons", "residuals", "chi2", "forward_runs", "wall_s"})
      EXPECT_TRUE(document.contains(field)) << field;
    const double correlation = document["correlation"][0][1].get<double>();
    EXPECT_GT(std::abs(correlation), 0.0);
    EXPECT_LT(std::abs(correlation), 1.0);
    // Every measurement has its model error and normalised residual.
    ASSERT_EQ(document["residuals"].size(), 5u);
    for (const json& row : document["residuals"]) {
      EXPECT_GT(row["model_error"].get<double>(), 0.0);
      EXPECT_TRUE(row["normalised"].is_number());
    }
    EXPECT_EQ(document["map"]["runs"].get<int>(), 49);
  }
  struct Crack {
    std::string name;
    double at, z0;
    unsigned seed;
  };
  for (const Crack& crack : {Crack{"deep-root", 0.04, 0.006, 11}, Crack{"shallow-mid", 0.11, 0.0085, 12}}) {
    SCOPED_TRACE(crack.name);
    const fs::path dir = root / crack.name;
    fs::create_directories(dir);
    write_measurements(dir / "measured.csv", truth_pairs(dir, crack.at, crack.z0), 5e-4, crack.seed);
    const json document = identify_with_map(dir, dir / "measured.csv", map, crack.at, crack.z0);
    expect_truth_inside(document, crack.at, crack.z0);
    EXPECT_TRUE(document["truth"]["inside_95"]["crack.plane.at"].get<bool>()) << document["truth"];
  }
  {
    // One measurement for two unknowns.
    const fs::path dir = root / "one-measurement";
    fs::create_directories(dir);
    std::ofstream(dir / "one.csv") << "quantity,mode,probe,drive_hz,value,sigma\nf_bilinear,1,,,205.6,0.1\n";
    const auto result = crackle("identify " + identify_scene(dir, (dir / "one.csv").string()).string() + " -o " +
                                (dir / "out").string() + " --map-cache " + map.string(), "OMP_NUM_THREADS=1");
    ASSERT_EQ(result.exit_code, 0) << result.output;
    const json document = read_json(dir / "out" / "identify.json");
    EXPECT_FALSE(document["identifiable"].get<bool>());
    EXPECT_NE(document["reasons"].dump().find("1 measurements for 2 unknowns"), std::string::npos) << document["reasons"];
    EXPECT_NE(result.output.find("NOT identifiable"), std::string::npos);
  }
  // 30 noisy replicas of the shipped crack: the intervals hold the truth in at least 90 % of them, and
  // the RMS error is within 1.5x the Cramer-Rao bound (the Gauss-Newton sd at the truth).
  const fs::path dir = root / "replicas";
  fs::create_directories(dir);
  const json pairs = truth_pairs(dir, 0.05, 0.007);
  constexpr int kReplicas = 30;
  const std::vector<std::string> keys = {"crack.plane.at", "crack.region.z[0]"};
  std::map<std::string, int> covered;
  std::map<std::string, double> squared, bound, noise_bound, sum;
  int forward_fits = 0, runs = 0;
  for (int replica = 0; replica < kReplicas; ++replica) {
    write_measurements(dir / "measured.csv", pairs, 5e-4, 100u + static_cast<unsigned>(replica));
    const json document = identify_with_map(dir, dir / "measured.csv", map, 0.05, 0.007);
    ASSERT_TRUE(document.contains("truth")) << document.dump(1);
    for (const std::string& key : keys) {
      covered[key] += document["truth"]["inside_95"][key].get<bool>() ? 1 : 0;
      squared[key] += std::pow(document["truth"]["error"][key].get<double>(), 2);
      bound[key] = document["truth"]["cramer_rao_sd"][key].get<double>();
      noise_bound[key] = document["truth"]["cramer_rao_noise_sd"][key].get<double>();
      sum[key] += document["truth"]["error"][key].get<double>();
    }
    forward_fits += document["local_fits"]["levenberg_marquardt"].get<int>();
    runs += document["forward_runs"].get<int>() - document["map"]["runs"].get<int>();
  }
  for (const std::string& key : keys) {
    const double rms = std::sqrt(squared[key] / kReplicas);
    std::cout << key << ": covered " << covered[key] << "/" << kReplicas << ", RMS error " << rms << ", mean error "
              << sum[key] / kReplicas << ", Cramer-Rao sd " << bound[key] << " (ratio " << rms / bound[key]
              << "), with the noise alone " << noise_bound[key] << "\n";
    EXPECT_GE(covered[key], 27) << key;
    EXPECT_LE(rms, 1.5 * bound[key]) << key;
  }
  std::cout << "Levenberg-Marquardt fits " << forward_fits << " of " << kReplicas << ", forward runs beyond the map " << runs << "\n";
}

TEST(Identify, ASymmetricPositionIsReportedWithBothMinima) {
  // A beam clamped at both ends: a crack at x and at L - x give the same frequencies.
  const fs::path dir = scratch("symmetric");
  std::string text = read_text(cli_testing::data("identify-beam.yaml"));
  const std::string clamp = "  - {face: x-, fix: [x, y, z]}\n";
  text.replace(text.find(clamp), clamp.size(), clamp + "  - {face: x+, fix: [x, y, z]}\n");
  // Its frequencies with the crack at 0.06 (z0 = 0.007), on the identify mesh itself.
  std::string truth_scene = text;
  truth_scene.erase(truth_scene.find("identify:"));
  std::ofstream(dir / "truth.yaml") << truth_scene;
  const auto truth = crackle("modal " + (dir / "truth.yaml").string() + " -o " + (dir / "truth").string() +
                             " --set crack.plane.at=0.06 --set 'crack.region.z=[0.007, 0.01]'", "OMP_NUM_THREADS=1");
  ASSERT_EQ(truth.exit_code, 0) << truth.output;
  const json pairs = read_json(dir / "truth" / "modal.json")["pairs"];
  write_measurements(dir / "measured.csv", pairs, 5e-4, 7);
  const std::string from = "  measured: identify-beam.csv";
  text.replace(text.find(from), from.size(), "  measured: " + (dir / "measured.csv").string());
  const std::string map_from = "  map: {points: 7}";
  text.replace(text.find(map_from), map_from.size(), "  map: {points: 5}");
  std::ofstream(dir / "identify.yaml") << text;
  const auto result = crackle("identify " + (dir / "identify.yaml").string() + " -o " + (dir / "out").string(),
                              "OMP_NUM_THREADS=1");
  ASSERT_EQ(result.exit_code, 0) << result.output;
  const json document = read_json(dir / "out" / "identify.json");
  EXPECT_FALSE(document["identifiable"].get<bool>()) << document.dump(1);
  EXPECT_NE(document["reasons"].dump().find("several minima fit equally well"), std::string::npos) << document["reasons"];
  ASSERT_GE(document["minima"].size(), 2u) << document.dump(1);
  // Both positions are among the minima, each with its intervals.
  bool near = false, far = false;
  for (const json& minimum : document["minima"]) {
    const double at = minimum["estimate"]["crack.plane.at"].get<double>();
    near = near || std::abs(at - 0.06) < 0.01;
    far = far || std::abs(at - 0.14) < 0.01;
    EXPECT_TRUE(minimum["interval_95"]["crack.plane.at"][0].is_number());
  }
  EXPECT_TRUE(near && far) << document["minima"].dump(1);

  // A rerun into the same folder reads the done forward runs back and redoes one recorded as failed
  // (a run killed by its machine): it does not stop at the old failure.
  const fs::path case_dir = dir / "out" / "map" / "runs" / "cases" / "0000";
  json record = read_json(case_dir / "case.json");
  record["status"] = "failed";
  record["error"] = "killed";
  std::ofstream(case_dir / "case.json") << record.dump(1);
  fs::remove(case_dir / "modal.json");
  const auto again = crackle("identify " + (dir / "identify.yaml").string() + " -o " + (dir / "out").string(),
                             "OMP_NUM_THREADS=1");
  ASSERT_EQ(again.exit_code, 0) << again.output;
  EXPECT_NE(again.output.find(" already done, 1 to run "), std::string::npos) << again.output;
  EXPECT_TRUE(fs::exists(case_dir / "modal.json"));
  EXPECT_EQ(read_json(dir / "out" / "identify.json")["minima"], document["minima"]);
}

TEST(Identify, FrequenciesAndHarmonicRatiosOfAConvergedModel) {
  // data/identify-beam-ratios.csv: the five frequencies and A2/A1, A3/A1 at the tip driven at
  // 103.153 Hz, those from the reduced model of data/beam.yaml on the default route's graded p = 4 mesh
  // (converged to 0.2 %, the full explicit model's to 2e-4 on that mesh family) with 5 % noise. The
  // forward model of the ratios is harmonic balance on the reduced model (a narrow sweep about
  // drive_hz) on the identify scene's coarse mesh, graded towards the front like the modal batch.
  const fs::path dir = scratch("ratios");
  const fs::path scene = identify_scene(dir, cli_testing::data("identify-beam-ratios.csv"), 5, 0.05, 0.007);
  const auto result = crackle("identify " + scene.string() + " -o " + (dir / "out").string(), "OMP_NUM_THREADS=1");
  ASSERT_EQ(result.exit_code, 0) << result.output;
  const json document = read_json(dir / "out" / "identify.json");
  expect_truth_inside(document, 0.05, 0.007);
  ASSERT_EQ(document["residuals"].size(), 7u);
  int ratios = 0;
  for (const json& row : document["residuals"]) {
    if (row["quantity"] == "A2/A1" || row["quantity"] == "A3/A1") {
      ++ratios;
      EXPECT_EQ(row["probe"], "tip");
      // The model value is the reduced model's at the drive frequency: within its model error (and
      // the 5 % noise) of the converged measured value.
      const double value = row["value"].get<double>(), model = row["model"].get<double>();
      const double error = row["model_error"].get<double>();
      EXPECT_GT(error, 0.0);
      EXPECT_LT(std::abs(model - value), 3.0 * std::hypot(row["sigma"].get<double>(), error)) << row;
      // On the graded mesh the ratios' model error at p = 2 is a few times their noise, not the
      // uniform grid's 59 % (A2/A1) and 140 % (A3/A1) that left them no weight (benchmarks 13.5, 13.7).
      EXPECT_LT(error / value, row["quantity"] == "A2/A1" ? 0.25 : 0.4) << row;
    }
  }
  EXPECT_EQ(ratios, 2);
  // The frequencies come from the sweep cases' own modal stage (the same graded mesh and modal
  // section): no study of `crackle modal` cases runs beside them, in the map or in the fits, and the
  // frequencies' model values are within their model error of the converged measurements.
  EXPECT_TRUE(fs::exists(dir / "out" / "map" / "sweep" / "runs"));
  EXPECT_FALSE(fs::exists(dir / "out" / "map" / "runs"));
  for (const auto& batch : fs::directory_iterator(dir / "out" / "fit")) {
    EXPECT_TRUE(fs::exists(batch.path() / "sweep" / "runs")) << batch.path();
    EXPECT_FALSE(fs::exists(batch.path() / "runs")) << batch.path();
  }
  int frequencies = 0;
  for (const json& row : document["residuals"]) {
    if (row["quantity"] == "A2/A1" || row["quantity"] == "A3/A1") continue;
    ++frequencies;
    const double value = row["value"].get<double>(), model = row["model"].get<double>();
    EXPECT_LT(std::abs(model - value), 3.0 * std::hypot(row["sigma"].get<double>(), row["model_error"].get<double>())) << row;
  }
  EXPECT_EQ(frequencies, 5);
}

TEST(Identify, AMeasuredDampingRatioIdentifiesTheDampingWithTheCrack) {
  // The beam's frequencies (modes 1, 3, 5 of the finer mesh) and the damping ratios of modes 1 and 3
  // of its ring-down: the scene's mass-proportional damping with xi = 0.03 at the uncracked mode 1,
  // xi_r = 0.03 f_u1 / f_b_r (5 % noise). The damping is a third unknown; the modal batches run each
  // crack once (the map's points that differ only in the damping are one run).
  const fs::path dir = scratch("damping");
  const double at = 0.05, z0 = 0.007, xi = 0.03;
  const json pairs = truth_pairs(dir, at, z0);
  write_measurements(dir / "measured.csv", pairs, 5e-4, 21);
  std::mt19937 generator(22);
  std::normal_distribution<double> gauss(0.0, 1.0);
  {
    std::ofstream out(dir / "measured.csv", std::ios::app);
    out.precision(10);
    for (int mode : {1, 3}) {
      const double value = xi * pairs[0]["f_uncracked_hz"].get<double>() / pairs[mode - 1]["f_bilinear_hz"].get<double>();
      out << "damping_ratio," << mode << ",,," << value * (1.0 + 0.05 * gauss(generator)) << "," << 0.05 * value << "\n";
    }
  }
  std::string text = read_text(identify_scene(dir, (dir / "measured.csv").string(), 5));
  const std::string depth = "    crack.region.z[0]: [0.005, 0.0095]";
  text.insert(text.find('\n', text.find(depth)) + 1, "    transient.damping.ratio: [0.01, 0.1]\n");
  // The sigmas are the synthetic noise's own: trusted. (Scaled by the fit, s^2 = chi^2/(n - k) is
  // about 0.09 here, as the frequencies' model errors dwarf their residuals, and every interval
  // would shrink to a third.)
  text.replace(text.find("  map: {points: 5}"), 18, "  map: {points: 5}\n  sigma: trusted");
  std::ofstream(dir / "damping.yaml") << text;
  const auto result = crackle("identify " + (dir / "damping.yaml").string() + " -o " + (dir / "out").string() + " -q",
                              "OMP_NUM_THREADS=1");
  ASSERT_EQ(result.exit_code, 0) << result.output;
  const json document = read_json(dir / "out" / "identify.json");
  expect_truth_inside(document, at, z0);
  const json& interval = document["interval_95"]["transient.damping.ratio"];
  EXPECT_LE(interval[0].get<double>(), xi) << document.dump(1);
  EXPECT_GE(interval[1].get<double>(), xi) << document.dump(1);
  EXPECT_LT(interval[1].get<double>() - interval[0].get<double>(), 0.2 * xi) << interval;  // two 5 % ratios
  // 125 map points but 25 cracks: one modal run each (with the model error's orders and the fits').
  EXPECT_EQ(document["map"]["runs"].get<int>(), 125);
  std::cout << "forward runs " << document["forward_runs"] << " for 125 map points\n";
  EXPECT_LT(document["forward_runs"].get<int>(), 60) << document["forward_runs"];
  for (const json& row : document["residuals"])
    if (row["quantity"] == "damping_ratio") EXPECT_LT(std::abs(row["normalised"].get<double>()), 4.0) << row;

  // The misfit's profile over each pair of the three unknowns: on every node of the pair's axes, the
  // least chi^2 over the third, never above the map's least in that slice (identify_map.csv), and
  // below it where the third unknown's best lies between its map points: the damping's 5 points lie
  // 0.0225 apart, its best near 0.03, so on every node of the crack pair's profile (measured 0.5-17 %
  // below), and the profile's least 18 % below the map's.
  std::map<std::vector<double>, double> map;
  {
    std::ifstream csv(dir / "out" / "identify_map.csv");
    std::string line;
    std::getline(csv, line);
    while (std::getline(csv, line)) {
      std::vector<double> row;
      std::stringstream cells(line);
      for (std::string cell; std::getline(cells, cell, ',');) row.push_back(std::stod(cell));
      ASSERT_EQ(row.size(), 4u) << line;
      map[{row[0], row[1], row[2]}] = row[3];
    }
  }
  ASSERT_EQ(map.size(), 125u);
  ASSERT_EQ(document["profiles"].size(), 3u);
  const std::vector<std::array<int, 2>> pair_of = {{0, 1}, {0, 2}, {1, 2}};
  const std::vector<std::string> keys = {"crack.plane.at", "crack.region.z[0]", "transient.damping.ratio"};
  double below = 0.0, least_map = HUGE_VAL, least_profile = HUGE_VAL;
  for (const auto& [point, chi2] : map) least_map = std::min(least_map, chi2);
  for (std::size_t q = 0; q < 3; ++q) {
    const json& profile = document["profiles"][q];
    EXPECT_EQ(profile["unknowns"], json({keys[pair_of[q][0]], keys[pair_of[q][1]]}));
    ASSERT_EQ(profile["chi2"].size(), 5u);
    for (std::size_t a = 0; a < 5; ++a) {
      ASSERT_EQ(profile["chi2"][a].size(), 5u);
      for (std::size_t b = 0; b < 5; ++b) {
        const double x = profile["axes"][0][a], y = profile["axes"][1][b], value = profile["chi2"][a][b];
        double slice = HUGE_VAL;
        for (const auto& [point, chi2] : map)
          if (std::abs(point[pair_of[q][0]] - x) < 1e-12 && std::abs(point[pair_of[q][1]] - y) < 1e-12) slice = std::min(slice, chi2);
        ASSERT_TRUE(std::isfinite(slice)) << x << " " << y;
        EXPECT_LE(value, slice * (1.0 + 1e-6)) << profile["unknowns"] << " at " << x << ", " << y;
        if (q == 0) below += value < (1.0 - 1e-3) * slice ? 1.0 : 0.0;
        if (q == 0) least_profile = std::min(least_profile, value);
      }
    }
  }
  EXPECT_EQ(below, 25.0);
  EXPECT_LT(least_profile, 0.9 * least_map);
  EXPECT_TRUE(fs::exists(dir / "out" / "identify_profiles.csv"));
  EXPECT_TRUE(fs::exists(dir / "out" / "identify_profiles.png"));
}

// The model error of a quantity from the three refinement orders: Richardson with all three; where a
// level has no value (a mode unpaired there), three times the change to the nearest level that has
// one, the finer first, not verified - it was 0 before, which weighed such a measurement by its sigma
// alone; with the run's level alone, 0 and not verified.
TEST(Identify, AModelErrorWithALevelMissingIsThreeTimesTheNearestChange) {
  using crackle::identify::refinement_error;
  const double nan = std::nan("");
  const auto full = refinement_error(100.0, 99.0, 98.9, 0);
  EXPECT_TRUE(std::isfinite(full.relative) && full.relative > 0.0);
  const auto finer = refinement_error(100.0, 99.0, nan, 0);
  EXPECT_NEAR(finer.relative, 3.0 * 1.0 / 100.0, 1e-15);
  EXPECT_FALSE(finer.verified);
  const auto coarser = refinement_error(100.0, 99.0, nan, 1);  // the run is the middle level
  EXPECT_NEAR(coarser.relative, 3.0 * 1.0 / 99.0, 1e-15);
  EXPECT_NEAR(refinement_error(nan, 99.0, 98.5, 1).relative, 3.0 * 0.5 / 99.0, 1e-15);
  EXPECT_NEAR(refinement_error(100.0, nan, 98.0, 0).relative, 3.0 * 2.0 / 100.0, 1e-15);
  const auto alone = refinement_error(nan, 99.0, nan, 1);
  EXPECT_EQ(alone.relative, 0.0);
  EXPECT_FALSE(alone.verified);
}

TEST(Identify, ASubharmonicIsReadOnTheStablePeriodTwoBranchElseZeroElseMissing) {
  // A sweep.csv about a drive of 100 Hz (rows: frequency, stable, branch period, tip A1/2/A1): the
  // period-one branch, then two segments of the period-two branch (down, then up from its start).
  using crackle::identify::SweepTable;
  using crackle::identify::subharmonic_value;
  const std::string stable = "stable [1 yes, 0 no, -1 not computed]", period = "branch period [excitation periods]";
  const auto table = [&](std::vector<std::vector<double>> rows) {
    SweepTable t;
    t.header = {"excitation frequency [Hz]", stable, period, "tip u_z A1/2/A1 [-]"};
    t.rows = std::move(rows);
    return t;
  };
  // stable period-two rows around 100 Hz (0.4 Hz apart): interpolated; a row at 100 Hz itself (sweep.solve_at) is read
  SweepTable t = table({{99.4, 1, 1, 0}, {99.7, 0, 1, 0}, {100.3, 0, 1, 0}, {99.8, 1, 2, 2.0}, {100.2, 1, 2, 4.0}});
  EXPECT_DOUBLE_EQ(subharmonic_value(t, "tip", 100.0), 3.0);
  EXPECT_TRUE(crackle::identify::period_two_exists(t, 100.0));
  t.rows.push_back({100, 1, 2, 3.5});
  EXPECT_DOUBLE_EQ(subharmonic_value(t, "tip", 100.0), 3.5);
  // no stable period-two branch at the drive, a stable period-one one: no sub-harmonic (0)
  t = table({{99.7, 1, 1, 0}, {100.3, 1, 1, 0}, {99.8, 0, 2, 2.0}, {100.2, 0, 2, 4.0}});
  EXPECT_EQ(subharmonic_value(t, "tip", 100.0), 0.0);
  EXPECT_FALSE(crackle::identify::period_two_exists(t, 100.0));
  // neither stable, or the drive outside the rows: missing (NaN), never 0
  t = table({{99.7, 0, 1, 0}, {100.3, 0, 1, 0}, {99.8, 0, 2, 2.0}, {100.2, 0, 2, 4.0}});
  EXPECT_TRUE(std::isnan(subharmonic_value(t, "tip", 100.0)));
  EXPECT_TRUE(std::isnan(subharmonic_value(t, "tip", 200.0)));
  // the end of one segment and the start of the next (85 -> 115 Hz, further apart than the
  // continuation's longest step of 0.75 % of the drive) are not neighbours
  t = table({{99.7, 0, 1, 0}, {100.3, 0, 1, 0}, {85, 1, 2, 1.0}, {115, 1, 2, 1.0}});
  EXPECT_TRUE(std::isnan(subharmonic_value(t, "tip", 100.0)));
  EXPECT_FALSE(crackle::identify::period_two_exists(t, 100.0));
  // a probe the table lacks
  EXPECT_TRUE(std::isnan(subharmonic_value(t, "root", 100.0)));
}

TEST(Identify, BadMeasurementsAreRefusedWithFileLineAndColumn) {
  const fs::path dir = scratch("bad");
  const std::string header = "quantity,mode,probe,drive_hz,value,sigma\n";
  struct Case {
    std::string rows, expected;
  };
  const std::vector<Case> cases = {
      {"f_bilnear,1,,,205.6,0.1\n", "measured.csv:2: row.quantity: expected one of f_uncracked"},
      {"f_bilinear,1,,,205.6,\n", "measured.csv:2: column sigma: expected a standard deviation > 0"},
      {"f_bilinear,9,,,205.6,0.1\n", "measured.csv:2: mode: expected a mode the scene solves (modal.modes = 5), got 9"},
      {"A2/A1,,hammer,102.9,0.12,0.01\n", "measured.csv:2: probe: expected a probe of the scene's transient.probes, got 'hammer'"},
      {"f_bilinear,1,,,nan,0.1\n", "measured.csv:2: column value: expected a finite number, got 'nan'"},
  };
  for (const Case& c : cases) {
    std::ofstream(dir / "measured.csv") << header << c.rows;
    const fs::path scene = identify_scene(dir, (dir / "measured.csv").string(), 3);
    const auto result = crackle("identify " + scene.string() + " -o " + (dir / "out").string());
    EXPECT_EQ(result.exit_code, 2) << c.rows << result.output;
    EXPECT_NE(result.output.find(c.expected), std::string::npos) << c.rows << result.output;
    EXPECT_FALSE(fs::exists(dir / "out" / "identify.json"));
  }
  // A sub-harmonic needs the sweep's stability, which is frictionless.
  std::ofstream(dir / "measured.csv") << header << "A1/2/A1,,tip,206.0,1.5,0.1\n";
  std::string friction = read_text(identify_scene(dir, (dir / "measured.csv").string(), 3));
  const std::string region = "  region: {y: [0.0, 0.02], z: [0.0075, 0.01]}\n";
  friction.insert(friction.find(region) + region.size(), "  contact: {friction: 0.3}\n");
  std::ofstream(dir / "friction.yaml") << friction;
  auto refused = crackle("identify " + (dir / "friction.yaml").string() + " -o " + (dir / "out").string());
  EXPECT_EQ(refused.exit_code, 2) << refused.output;
  EXPECT_NE(refused.output.find("measured.csv:2: quantity A1/2/A1: expected a scene without friction"), std::string::npos)
      << refused.output;
  // A wrong header, and an unknown key path, name what was expected.
  std::ofstream(dir / "measured.csv") << "quantity,mode,value,sigma\nf_bilinear,1,205.6,0.1\n";
  auto result = crackle("identify " + identify_scene(dir, (dir / "measured.csv").string(), 3).string() + " -o " +
                        (dir / "out").string());
  EXPECT_EQ(result.exit_code, 2);
  EXPECT_NE(result.output.find("measured.csv:1: expected the header quantity,mode,probe,drive_hz,value,sigma"),
            std::string::npos)
      << result.output;
  std::string text = read_text(identify_scene(dir, (dir / "measured.csv").string(), 3));
  text.replace(text.find("crack.plane.at: [0.02"), 14, "crack.plane.ta");
  std::ofstream(dir / "key.yaml") << text;
  result = crackle("identify " + (dir / "key.yaml").string() + " -o " + (dir / "out").string());
  EXPECT_EQ(result.exit_code, 2);
  EXPECT_NE(result.output.find("identify.unknowns.crack.plane.ta"), std::string::npos) << result.output;
  std::ofstream(dir / "measured.csv") << header << "f_bilinear,1,,,205.6,0.1\n";
  text = read_text(identify_scene(dir, (dir / "measured.csv").string(), 3));
  text.replace(text.find("  map: {points: 3}"), 18, "  map: {points: 3}\n  sigma: trusting");
  std::ofstream(dir / "sigma.yaml") << text;
  result = crackle("identify " + (dir / "sigma.yaml").string() + " -o " + (dir / "out").string());
  EXPECT_EQ(result.exit_code, 2);
  EXPECT_NE(result.output.find("identify.sigma: expected one of scaled, trusted, got 'trusting'"), std::string::npos)
      << result.output;
  // An unknown that no measured quantity depends on: the frequencies do not depend on the damping.
  std::ofstream(dir / "measured.csv") << header << "f_bilinear,1,,,205.6,0.1\nf_bilinear,3,,,1280.0,0.5\n";
  text = read_text(identify_scene(dir, (dir / "measured.csv").string(), 3));
  const std::string depth = "    crack.region.z[0]: [0.005, 0.0095]";
  text.insert(text.find('\n', text.find(depth)) + 1, "    transient.damping.ratio: [0.01, 0.1]\n");
  std::ofstream(dir / "damping.yaml") << text;
  result = crackle("identify " + (dir / "damping.yaml").string() + " -o " + (dir / "out").string());
  EXPECT_EQ(result.exit_code, 2) << result.output;
  EXPECT_NE(result.output.find("damping.yaml:30: identify.unknowns.transient.damping.ratio: expected an unknown that "
                               "a measured quantity depends on, got 'transient.damping.ratio', which the measured "
                               "frequencies (crackle modal) do not depend on; measure a damping_ratio or a harmonic "
                               "ratio"),
            std::string::npos)
      << result.output;
}

}  // namespace
