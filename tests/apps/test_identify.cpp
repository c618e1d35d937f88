// `crackle identify` end to end: synthetic measurements of known cracks from modal solves on a finer
// mesh than the identify scene's (so that model error is present, as in reality) with Gaussian noise,
// the intervals against the truth, an unidentifiable case, and bad measurement input.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <random>
#include <sstream>

#include <nlohmann/json.hpp>

#include "cli_testing.hpp"

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

/// The identify scene of data/identify-beam.yaml with its measurements replaced by `csv`.
fs::path identify_scene(const fs::path& dir, const std::string& measured, int points = 7) {
  std::string text = read_text(cli_testing::data("identify-beam.yaml"));
  const std::string from = "  measured: identify-beam.csv";
  text.replace(text.find(from), std::string(from).size(), "  measured: " + measured);
  const std::string map_from = "  map: {points: 7}";
  text.replace(text.find(map_from), map_from.size(), "  map: {points: " + std::to_string(points) + "}");
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

/// Identifies one crack of the beam from synthetic measurements; returns identify.json.
json identify_crack(const std::string& name, double at, double z0, unsigned seed) {
  const fs::path dir = scratch(name);
  write_measurements(dir / "measured.csv", truth_pairs(dir, at, z0), 5e-4, seed);
  const fs::path scene = identify_scene(dir, (dir / "measured.csv").string(), 5);
  const auto result = crackle("identify " + scene.string() + " -o " + (dir / "out").string(), "OMP_NUM_THREADS=1");
  EXPECT_EQ(result.exit_code, 0) << result.output;
  return read_json(dir / "out" / "identify.json");
}

TEST(Identify, ADeepCrackNearTheRootLiesInsideItsIntervals) {
  const json result = identify_crack("deep-root", 0.04, 0.006, 11);
  expect_truth_inside(result, 0.04, 0.006);
  // Every measurement has its model error and normalised residual.
  ASSERT_EQ(result["residuals"].size(), 5u);
  for (const json& row : result["residuals"]) {
    EXPECT_GT(row["model_error"].get<double>(), 0.0);
    EXPECT_TRUE(row["normalised"].is_number());
  }
  EXPECT_GT(result["forward_runs"].get<int>(), 25);
}

TEST(Identify, AShallowCrackAtMidSpanLiesInsideItsIntervals) {
  const json result = identify_crack("shallow-mid", 0.11, 0.0085, 12);
  expect_truth_inside(result, 0.11, 0.0085);
}

TEST(Identify, TheShippedMeasurementsGiveTheirCrackAndEveryOutput) {
  // data/identify-beam.csv: the crack of data/beam.yaml (x = 0.05, z0 = 0.007) on its finer mesh.
  const fs::path dir = scratch("shipped");
  const auto result = crackle("identify " + cli_testing::data("identify-beam.yaml") + " -o " + (dir / "out").string() +
                              " --map-cache " + (dir / "map").string(), "OMP_NUM_THREADS=1");
  ASSERT_EQ(result.exit_code, 0) << result.output;
  const json document = read_json(dir / "out" / "identify.json");
  expect_truth_inside(document, 0.05, 0.007);
  for (const char* name : {"identify_map.csv", "identify.json"}) EXPECT_TRUE(fs::exists(dir / "out" / name)) << name;
  for (const char* field : {"estimate", "interval_95", "covariance", "correlation", "minima", "identifiable", "reasons",
                            "residuals", "chi2", "forward_runs", "wall_s"})
    EXPECT_TRUE(document.contains(field)) << field;
  const double correlation = document["correlation"][0][1].get<double>();
  EXPECT_GT(std::abs(correlation), 0.0);
  EXPECT_LT(std::abs(correlation), 1.0);
  // A second measurement set on the same design reuses the cached map: no map runs again.
  const auto again = crackle("identify " + cli_testing::data("identify-beam.yaml") + " -o " + (dir / "again").string() +
                             " --map-cache " + (dir / "map").string(), "OMP_NUM_THREADS=1");
  ASSERT_EQ(again.exit_code, 0) << again.output;
  const json second = read_json(dir / "again" / "identify.json");
  EXPECT_LT(second["wall_s"].get<double>(), 0.8 * document["wall_s"].get<double>());
}

TEST(Identify, OneMeasurementForTwoUnknownsIsNotIdentifiable) {
  const fs::path dir = scratch("one-measurement");
  std::ofstream(dir / "one.csv") << "quantity,mode,probe,drive_hz,value,sigma\nf_bilinear,1,,,205.6,0.1\n";
  const fs::path scene = identify_scene(dir, (dir / "one.csv").string(), 3);
  const auto result = crackle("identify " + scene.string() + " -o " + (dir / "out").string(), "OMP_NUM_THREADS=1");
  ASSERT_EQ(result.exit_code, 0) << result.output;
  const json document = read_json(dir / "out" / "identify.json");
  EXPECT_FALSE(document["identifiable"].get<bool>());
  EXPECT_NE(document["reasons"].dump().find("1 measurements for 2 unknowns"), std::string::npos) << document["reasons"];
  EXPECT_NE(result.output.find("NOT identifiable"), std::string::npos);
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
}

}  // namespace
