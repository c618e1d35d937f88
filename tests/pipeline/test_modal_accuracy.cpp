// pipeline/modal_accuracy: `crackle modal`'s frequency estimate (modal.json accuracy): which element
// orders are its levels, and the estimate of a coarse grid's frequencies against a finer grid of the
// same body at the highest order, extrapolated by its own levels (the reference).
#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <sstream>

#include <unistd.h>

#include <nlohmann/json.hpp>

#include "pipeline/commands.hpp"
#include "pipeline/modal_accuracy.hpp"
#include "scene/scene.hpp"

namespace crackle::pipeline {
namespace {

namespace fs = std::filesystem;

// A steel cantilever 100 x 20 x 10 mm with a 3 mm edge crack at 25 mm (data/beam.yaml's section).
std::string beam_scene(const std::string& cells, int order, const std::string& accuracy = "") {
  return "mesh:\n  box: {size: [0.1, 0.02, 0.01], cells: " + cells + ", order: " + std::to_string(order) +
         "}\n"
         "material: {E: 210.0e9, nu: 0.3, rho: 7850.0}\n"
         "boundary:\n  - {face: x-, fix: [x, y, z]}\n"
         "crack:\n  plane: {normal: x, at: 0.025}\n  region: {y: [0.0, 0.02], z: [0.007, 0.01]}\n"
         "modal: {modes: 3}\n" +
         accuracy;
}

TEST(ModalAccuracy, TheLevelsAreTheLowerOrdersFromTwoOrWhenAskedTheOrdersAbove) {
  auto plan = [](int order, const std::string& accuracy = "", int ranks = 1) {
    return modal_level_plan(scene::parse_scene(beam_scene("[8, 2, 1]", order, accuracy), "beam.yaml"), ranks);
  };
  EXPECT_EQ(plan(4).orders, (std::vector<int>{2, 3, 4}));
  EXPECT_EQ(plan(3).orders, (std::vector<int>{2, 3}));  // order 1 is no level: it locks in bending
  EXPECT_EQ(plan(4).run_order, 4);
  // Three lower orders are checked by order 2 on the cells doubled; two levels, or levels above, not.
  ASSERT_TRUE(plan(4).check_cells.has_value());
  EXPECT_EQ(*plan(4).check_cells, (std::array<int, 3>{16, 4, 2}));
  EXPECT_FALSE(plan(3).check_cells.has_value());
  EXPECT_FALSE(plan(2, "accuracy: {estimate: on}\n").check_cells.has_value());
  // Below order 3 only when asked: the orders above, up to the highest.
  EXPECT_FALSE(plan(2).estimate);
  EXPECT_NE(plan(2).reason.find("accuracy.estimate: on"), std::string::npos) << plan(2).reason;
  EXPECT_EQ(plan(2, "accuracy: {estimate: on}\n").orders, (std::vector<int>{2, 3, 4}));
  EXPECT_EQ(plan(1, "accuracy: {tolerance: 0.001}\n").orders, (std::vector<int>{1, 2, 3}));
  EXPECT_EQ(*plan(1, "accuracy: {tolerance: 0.001}\n").tolerance, 0.001);
  // Off, or under mpirun: none, with the reason.
  EXPECT_FALSE(plan(4, "accuracy: {estimate: off}\n").estimate);
  EXPECT_FALSE(plan(4, "", 2).estimate);
  EXPECT_NE(plan(4, "", 2).reason.find("mpirun"), std::string::npos);
}

nlohmann::json solve(const fs::path& directory, const std::string& scene) {
  fs::create_directories(directory);
  std::ofstream(directory / "scene.yaml") << scene;
  ModalCommandOptions options;
  options.scene_path = (directory / "scene.yaml").string();
  options.output_directory = directory / "out";
  std::ostringstream out;
  run_modal_command(options, out);
  std::ifstream file(directory / "out" / "modal.json");
  return nlohmann::json::parse(file);
}

// The reference frequencies of beam_scene: the grid [16, 4, 2] at order 4 (graded as crackle modal
// grades it), extrapolated by its own levels (orders 2, 3, 4: value x (1 + delta / safety factor) of
// its modal.json accuracy.pairs[mode][field].components.mesh, the levels' delta where it has a check
// level, which only widens its estimate). Converged by hand once (a 62 s, 8.8 GB solve, too long for
// the suite; docs/benchmarks.md 11.9): the grid [8, 4, 2] extrapolated the same way agrees to
// 1.2e-4 on modes 1-2 and 2.4e-4 on mode 3, under a third of the smallest true error of the coarse
// grids below (7.6e-4). Rows: f_uncracked, f_open, f_bilinear [Hz]; columns: modes 1-3.
constexpr double kReferenceHz[3][3] = {{835.9293307, 1629.885741, 5011.616366},
                                       {776.8824708, 1585.825274, 4995.275966},
                                       {805.3495419, 1607.567013, 5003.433206}};

// The effectivity of every frequency of a coarse grid at order 4 (levels 2, 3, 4 and the check level)
// against the reference above, with whether it was verified.
struct Effectivity {
  std::string field;
  std::size_t mode = 0;
  double effectivity = 0.0;
  bool verified = false;
  std::string where;
};
std::vector<Effectivity> effectivities(const std::string& name, const std::string& coarse_cells) {
  const fs::path directory =
      fs::temp_directory_path() / ("crackle-modal-effectivity-" + name + "-" + std::to_string(::getpid()));
  const nlohmann::json coarse = solve(directory / "coarse", beam_scene(coarse_cells, 4));
  fs::remove_all(directory);
  EXPECT_TRUE(coarse["accuracy"]["estimated"].get<bool>()) << coarse["accuracy"].dump();
  std::vector<Effectivity> out;
  const char* fields[3] = {"f_uncracked_hz", "f_open_hz", "f_bilinear_hz"};
  for (int f = 0; f < 3; ++f) {
    for (std::size_t mode = 0; mode < 3; ++mode) {
      const double truth = kReferenceHz[f][mode];
      const nlohmann::json& estimate = coarse["accuracy"]["pairs"][mode][fields[f]];
      const double value = estimate["value"].get<double>();
      out.push_back({fields[f], mode, estimate["error"].get<double>() / (std::abs(truth - value) / value),
                     estimate["verified"].get<bool>(),
                     std::string(fields[f]) + " mode " + std::to_string(mode + 1) + ": " + estimate.dump()});
    }
  }
  return out;
}

// 12.5 mm cells: the estimate holds the true error of every frequency, and overstates that of the
// bilinear frequencies at most 3 times (DETECTION.md's test of effectivity). Measured: 2.04-3.51
// (docs/benchmarks.md 11.9).
TEST(ModalAccuracy, ACoarseGridsEstimateHoldsItsErrorAgainstAFinerGrid) {
  for (const Effectivity& e : effectivities("8x2x1", "[8, 2, 1]")) {
    if (!e.verified) continue;
    EXPECT_GE(e.effectivity, 1.0) << e.where;
    if (e.field == "f_bilinear_hz") EXPECT_LE(e.effectivity, 3.0) << e.where;
  }
}

// 25 mm cells, one through the thickness: the three p-levels look asymptotic and are not (without the
// check level the third mode's estimate was 0.23 of its error). The check level (order 2 on cells x 2)
// disagrees with them: every estimate covers its error, and the third mode is not verified. Measured:
// 1.61-5.62; f_bilinear 1 verified at 3.29 (over the [1, 3] of DETECTION.md: an overestimate).
TEST(ModalAccuracy, AGridTooCoarseForItsLevelsIsCaughtByTheCheckLevel) {
  for (const Effectivity& e : effectivities("4x2x1", "[4, 2, 1]")) {
    EXPECT_GE(e.effectivity, 1.0) << e.where;
    if (e.mode == 2) EXPECT_FALSE(e.verified) << e.where;
  }
}

// modal.json carries an estimate of every frequency at the place of its value, modes.csv its error
// columns, and the line says which orders were run. At order 3 the levels are orders 2 and 3: three
// times their change, not verified, which an order-2 solve of the same scene reproduces. (The
// effectivity is the test above and docs/benchmarks.md 11.9.)
TEST(ModalAccuracy, ModalJsonCarriesAnEstimateOfEveryFrequencyAndTwoLevelsAreNotVerified) {
  const fs::path directory = fs::temp_directory_path() / ("crackle-modal-accuracy-" + std::to_string(::getpid()));
  const nlohmann::json p4 = solve(directory / "p4", beam_scene("[4, 2, 1]", 4));
  const nlohmann::json p3 = solve(directory / "p3", beam_scene("[4, 2, 1]", 3));
  const nlohmann::json p2 = solve(directory / "p2", beam_scene("[4, 2, 1]", 2));
  EXPECT_FALSE(p2["accuracy"]["estimated"].get<bool>());
  EXPECT_NE(p2["accuracy"]["reason"].get<std::string>().find("order 2"), std::string::npos);
  const nlohmann::json& accuracy = p4["accuracy"];
  ASSERT_TRUE(accuracy["estimated"].get<bool>()) << accuracy.dump();
  EXPECT_EQ(accuracy["orders"], nlohmann::json({2, 3, 4}));
  ASSERT_EQ(accuracy["runs"].size(), 4u);  // orders 2, 3, 4 and the check level
  EXPECT_EQ(accuracy["runs"][3]["order"], 2);
  EXPECT_EQ(accuracy["runs"][3]["cells"], nlohmann::json({8, 4, 2}));
  EXPECT_TRUE(accuracy["runs"][3]["check"].get<bool>());
  EXPECT_EQ(accuracy["pairs"][0]["f_open_hz"]["components"]["mesh"]["check"]["level"], "order 2 on cells [8,4,2]");
  for (const char* variant : {"uncracked", "open"}) {
    const nlohmann::json& values = p4["variants"][variant]["frequencies_hz"];
    const nlohmann::json& estimates = accuracy["variants"][variant]["frequencies_hz"];
    ASSERT_EQ(estimates.size(), values.size());
    for (std::size_t i = 0; i < values.size(); ++i) {
      EXPECT_EQ(estimates[i]["value"].get<double>(), values[i].get<double>());
      EXPECT_GT(estimates[i]["error"].get<double>(), 0.0);
    }
  }
  ASSERT_EQ(accuracy["pairs"].size(), p4["pairs"].size());
  for (std::size_t mode = 0; mode < p4["pairs"].size(); ++mode) {
    for (const char* field : {"f_uncracked_hz", "f_open_hz", "f_bilinear_hz", "ratio"}) {
      EXPECT_EQ(accuracy["pairs"][mode][field]["value"].get<double>(), p4["pairs"][mode][field].get<double>());
      // Two levels: 3 |f(3) - f(2)| / f(3), from the order-2 solve of the same scene.
      const double f3 = p3["pairs"][mode][field].get<double>(), f2 = p2["pairs"][mode][field].get<double>();
      const nlohmann::json& two = p3["accuracy"]["pairs"][mode][field];
      EXPECT_FALSE(two["verified"].get<bool>());
      EXPECT_NEAR(two["error"].get<double>(), 3.0 * std::abs(f3 - f2) / std::abs(f3), 1e-12) << field;
    }
  }
  std::ifstream table(directory / "p4" / "out" / "modes.csv");
  std::string header, first;
  std::getline(table, header);
  std::getline(table, first);
  EXPECT_NE(header.find("f_open error [-]"), std::string::npos) << header;
  const double f_open_error = std::stod(first.substr(first.find_last_of(',', first.rfind(',') - 1) + 1));
  EXPECT_DOUBLE_EQ(f_open_error, accuracy["pairs"][0]["f_open_hz"]["error"].get<double>()) << first;
  fs::remove_all(directory);
}

}  // namespace
}  // namespace crackle::pipeline
