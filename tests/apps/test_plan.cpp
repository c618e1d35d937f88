// `crackle plan` end to end on the coarse beam of data/identify-beam.yaml: a sensor at the node of
// the driven mode ranks below one on the crack's side, a sub-harmonic drive without a period-two
// branch is marked as having no response, `crackle identify` with the best- and the worst-ranked
// candidates finds the information the plan predicted (the best with the narrower intervals, the
// plan's best pair of sensors narrower still), and bad plan sections are refused with file:line.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <set>
#include <sstream>
#include <vector>

#include <nlohmann/json.hpp>

#include "cli_testing.hpp"

namespace {

namespace fs = std::filesystem;
using cli_testing::crackle;
using nlohmann::json;

fs::path scratch(const std::string& name) {
  const fs::path dir = fs::path(CRACKLE_BINARY_DIR) / "tests" / "plan" / name;
  fs::remove_all(dir);
  fs::create_directories(dir);
  return dir;
}

const std::string kBeam =
    "mesh:\n  box: {size: [0.2, 0.02, 0.01], cells: [20, 2, 2], order: 2}\n"
    "material: {E: 210.0e9, nu: 0.3, rho: 7850.0}\n"
    "boundary:\n  - {face: x-, fix: [x, y, z]}\n"
    "crack:\n  plane: {normal: x, at: 0.05}\n  region: {y: [0.0, 0.02], z: [0.007, 0.01]}\n"
    "modal: {modes: 3, solver: arpack}\n"
    "transient:\n  excitation: {point: [0.2, 0.01, 0.01], direction: z, amplitude: 20.0, frequency: {mode: 1, ratio: 0.5}}\n"
    "  damping: {ratio: 0.05, at: {mode: 1}}\n  periods: 60\n";

fs::path write_scene(const fs::path& dir, const std::string& plan) {
  const fs::path scene = dir / "plan.yaml";
  std::ofstream(scene) << kBeam << plan;
  return scene;
}

TEST(Plan, ASensorAtTheNodeOfTheDrivenModeRanksBelowOneOnTheCracksSide) {
  const fs::path dir = scratch("node");
  // Sensors along the top face; the drive at the tip at half the second flapwise mode (crackle's mode
  // 3): its second harmonic resonates with that mode, whose node (Euler-Bernoulli cantilever: x/L =
  // 0.7834, 157 mm) sees almost none of it. Also f/2 of mode 1 at 5 % damping: no period doubling;
  // and half the first mode, whose frequency feels the crack's depth but hardly where it is.
  std::string points = "[";
  for (int i = 1; i <= 10; ++i) points += (i > 1 ? ", " : "") + std::string("[") + std::to_string(0.02 * i) + ", 0.01, 0.01]";
  points += "]";
  const fs::path scene = write_scene(dir, "plan:\n  prior:\n    crack.plane.at: [0.03, 0.07]\n    crack.region.z[0]: [0.006, 0.008]\n"
                                          "  samples: 2\n  sensors:\n    points: " + points + "\n"
                                          "  drives:\n    points: [[0.2, 0.01, 0.01]]\n"
                                          "    frequencies: [{mode: 3, ratio: 0.5}, {mode: 1, ratio: 2.0}, {mode: 1, ratio: 0.5}]\n");
  const auto result = crackle("plan " + scene.string() + " -o " + (dir / "out").string() + " -j 2");
  ASSERT_EQ(result.exit_code, 0) << result.output;
  std::ifstream stream(dir / "out" / "plan.json");
  const json plan = json::parse(stream);
  const double node = 0.7834 * 0.2;
  int node_rank = 0, crack_side_rank = 0, last_of_mode_3 = 0, last_responding = 0, first_silent = 1 << 30;
  double node_ratio = 1.0, smallest_other = 1.0;
  for (const json& c : plan["candidates"]) {
    const double x = c["sensor"]["point"][0].get<double>();
    const int rank = c["rank"].get<int>();
    if (c["drive"]["ratio"].get<double>() < 1.5) {
      EXPECT_TRUE(c["responds"].get<bool>());
      last_responding = std::max(last_responding, rank);
    }
    if (c["drive"]["mode"].get<int>() == 3) {
      last_of_mode_3 = std::max(last_of_mode_3, rank);
      const double ratio = c["per_sample"][0]["values"]["A2/A1"].get<double>();
      if (std::abs(x - node) < 0.01) {
        node_rank = rank;
        node_ratio = ratio;
      } else {
        smallest_other = std::min(smallest_other, ratio);
      }
      if (std::abs(x - 0.04) < 1e-9) crack_side_rank = rank;
    } else if (c["drive"]["ratio"].get<double>() > 1.5) {
      // f/2 of mode 1: the sweep with stability finds no period-two branch, so no response.
      EXPECT_FALSE(c["responds"].get<bool>());
      EXPECT_EQ(c["responding_samples"].get<int>(), 0);
      EXPECT_TRUE(c["log_det"].is_null());
      first_silent = std::min(first_silent, rank);
    }
  }
  ASSERT_GT(node_rank, 0);
  EXPECT_GT(node_rank, crack_side_rank) << "the node's sensor should rank below the crack side's";
  EXPECT_EQ(node_rank, last_of_mode_3) << "the node's sensor should rank last of the driven mode's";
  EXPECT_LT(node_ratio, 0.2 * smallest_other) << "A2/A1 at the node should be the smallest by far";
  EXPECT_GT(first_silent, last_responding) << "candidates without a response rank after all that respond";
  // every forward value was there: no response was inferred from a sweep that stopped early
  EXPECT_TRUE(plan["notes"].empty()) << plan["notes"].dump();
  for (const json& c : plan["candidates"])
    for (const json& s : c["per_sample"]) EXPECT_FALSE(s["missing"].get<bool>());
  // The cross-check: each sub-harmonic sweep of the samples says there is no period-two branch.
  int subharmonic_sweeps = 0;
  for (const auto& entry : fs::directory_iterator(dir / "out" / "samples" / "runs" / "cases")) {
    std::ifstream sweep_stream(entry.path() / "sweep.json");
    const json sweep = json::parse(sweep_stream);
    if (sweep["settings"]["subharmonic"].get<int>() != 2) continue;  // the period: 2 for f/2
    ++subharmonic_sweeps;
    bool no_branch = false;
    for (const json& warning : sweep["warnings"])
      no_branch = no_branch || warning.get<std::string>().find("no period-two branch") != std::string::npos;
    EXPECT_TRUE(no_branch) << entry.path();
  }
  EXPECT_EQ(subharmonic_sweeps, 3 + 4) << "the model error's three levels and the four samples";
  // Greedy sets: each added sensor adds information.
  const json& sets = plan["best_sensors"]["sets"];
  ASSERT_EQ(sets.size(), 3u);
  for (std::size_t i = 1; i < sets.size(); ++i) EXPECT_GT(sets[i]["log_det"].get<double>(), sets[i - 1]["log_det"].get<double>());
  // and narrows every interval it predicts (F + F_s >= F); the set of one is the best candidate.
  // The terminal says which of a set's widths exceed the prior's range.
  EXPECT_NE(result.output.find("plan: mean 95 % widths against the prior's ranges with "), std::string::npos) << result.output;
  for (const char* key : {"crack.plane.at", "crack.region.z[0]"}) {
    EXPECT_NEAR(sets[0]["widths_95"]["mean"][key].get<double>(), plan["candidates"][0]["widths_95"]["mean"][key].get<double>(), 1e-12);
    EXPECT_NEAR(sets[0]["widths_95"]["worst"][key].get<double>(), plan["candidates"][0]["widths_95"]["worst"][key].get<double>(), 1e-12);
    for (std::size_t i = 1; i < sets.size(); ++i)
      for (const char* figure : {"mean", "worst"})
        EXPECT_LT(sets[i]["widths_95"][figure][key].get<double>(), sets[i - 1]["widths_95"][figure][key].get<double>()) << key;
  }
  std::ifstream vtu(dir / "out" / "plan_sensors.vtu");
  std::stringstream text;
  text << vtu.rdbuf();
  EXPECT_NE(text.str().find("NumberOfPoints=\"10\""), std::string::npos);
  // A rerun reuses every forward run (resumable, cached).
  const auto again = crackle("plan " + scene.string() + " -o " + (dir / "out").string() + " -j 2");
  ASSERT_EQ(again.exit_code, 0) << again.output;
  std::ifstream again_stream(dir / "out" / "plan.json");
  EXPECT_EQ(json::parse(again_stream)["candidates"], plan["candidates"]);
  // Every sweep reads its modes from the modal batch's solves (one cache folder for all batches):
  // no sweep case solved an eigenproblem of its own.
  int sweeps = 0;
  for (const char* stage : {"samples", "jacobian"}) {
    for (const auto& entry : fs::directory_iterator(dir / "out" / stage / "runs" / "cases")) {
      std::ifstream modal_stream(entry.path() / "modal.json");
      ASSERT_TRUE(modal_stream) << entry.path();
      const json modal = json::parse(modal_stream);
      for (const auto& [variant, solved] : modal["variants"].items())
        EXPECT_TRUE(solved["from_cache"].get<bool>()) << entry.path() << ": " << variant;
      ++sweeps;
    }
  }
  EXPECT_GT(sweeps, 20);

  // The cross-check with identify: the best-ranked candidate, the worst-ranked sensor of the same
  // drive and the worst-ranked candidate that responds, each identifying the plan's first sample from
  // the plan's own model values and noise sigmas (the driven mode's bilinear frequency, A2/A1 and
  // A3/A1 at the sensor). The plan's log det of the Fisher information (noise and model error) is
  // what identify's Gauss-Newton covariance at the truth gives, and its ranking holds.
  const json* best = nullptr;
  const json* worst_sensor = nullptr;
  const json* worst = nullptr;
  for (const json& c : plan["candidates"]) {
    if (!c["responds"].get<bool>()) continue;
    if (!best || c["rank"].get<int>() < (*best)["rank"].get<int>()) best = &c;
    if (!worst || c["rank"].get<int>() > (*worst)["rank"].get<int>()) worst = &c;
  }
  ASSERT_TRUE(best && worst && best != worst);
  for (const json& c : plan["candidates"])
    if (c["drive"] == (*best)["drive"] && (!worst_sensor || c["rank"].get<int>() > (*worst_sensor)["rank"].get<int>()))
      worst_sensor = &c;
  ASSERT_TRUE(worst_sensor && worst_sensor != best);
  EXPECT_NE((*best)["drive"], (*worst)["drive"]) << "the drive frequency should matter more than the sensor";
  const json& truth = plan["samples"][0]["theta"];
  const auto point_text = [](const json& p) {
    return "[" + std::to_string(p[0].get<double>()) + ", " + std::to_string(p[1].get<double>()) + ", " +
           std::to_string(p[2].get<double>()) + "]";
  };
  const auto number = [](double v) {
    std::ostringstream out;
    out.precision(17);
    out << v;
    return out.str();
  };
  // and the plan's best pair of sensors for the best drive (best_sensors, chosen greedily)
  const json& pair_set = plan["best_sensors"]["sets"][1];
  std::vector<const json*> pair;
  for (const json& name : pair_set["sensors"])
    for (const json& c : plan["candidates"])
      if (c["sensor"]["name"] == name && c["drive"]["mode"] == plan["best_sensors"]["drive"]["mode"] &&
          c["drive"]["ratio"] == plan["best_sensors"]["drive"]["ratio"] && c["drive"]["point"] == plan["best_sensors"]["drive"]["point"])
        pair.push_back(&c);
  ASSERT_EQ(pair.size(), 2u) << pair_set;
  ASSERT_EQ(pair[0], best) << "the best pair starts from the best single sensor";
  std::string probes = "  probes:\n";
  std::set<std::string> named;
  for (const json* c : {best, worst_sensor, worst, pair[1]}) {
    const std::string name = (*c)["sensor"]["name"].get<std::string>();
    if (named.insert(name).second)
      probes += "    - {name: " + name + ", point: " + point_text((*c)["sensor"]["point"]) + "}\n";
  }
  struct Identified {
    double log_det = 0.0, plan_log_det = 0.0;
    std::vector<double> widths;
    json reasons;  ///< why identify calls it not identifiable
  };
  // Identifies the first sample from the driven mode's bilinear frequency and the ratios at the
  // sensors of `candidates` (one drive).
  const auto identify = [&](const std::vector<const json*>& candidates) {
    const json& first = candidates.front()->at("per_sample")[0];
    const std::string mode = std::to_string(candidates.front()->at("drive")["mode"].get<int>());
    std::string tag, measured = "    - {quantity: f_bilinear, mode: " + mode + ", value: " +
                                number(first["values"]["f_bilinear"].get<double>()) + ", sigma: " +
                                number(first["noise_sigmas"]["f_bilinear"].get<double>()) + "}\n";
    for (const json* candidate : candidates) {
      const json& sample = candidate->at("per_sample")[0];
      const std::string sensor = candidate->at("sensor")["name"].get<std::string>();
      tag += sensor + "-";
      for (const std::string q : {"A2/A1", "A3/A1"})
        measured += "    - {quantity: " + q + ", probe: " + sensor + ", drive_hz: " + number(sample["drive_hz"].get<double>()) +
                    ", value: " + number(sample["values"][q].get<double>()) +
                    ", sigma: " + number(sample["noise_sigmas"][q].get<double>()) + "}\n";
    }
    tag += "mode" + mode;
    const fs::path scene_path = dir / ("identify-" + tag + ".yaml");
    std::ofstream(scene_path) << kBeam << probes << "identify:\n  unknowns:\n    crack.plane.at: [0.03, 0.07]\n"
                              << "    crack.region.z[0]: [0.006, 0.008]\n  measured:\n" << measured
                              << "  map: {points: 5}\n  sigma: trusted\n  truth:\n    crack.plane.at: "
                              << number(truth["crack.plane.at"].get<double>()) << "\n    crack.region.z[0]: "
                              << number(truth["crack.region.z[0]"].get<double>()) << "\n";
    const auto run = crackle("identify " + scene_path.string() + " -o " + (dir / ("identify-" + tag)).string() +
                             " --map-cache " + (dir / "identify-map").string() + " -j 2");
    Identified out;
    EXPECT_EQ(run.exit_code, 0) << run.output;
    std::ifstream stream(dir / ("identify-" + tag) / "identify.json");
    const json result = json::parse(stream);
    const json& c = result["covariance"];
    const double det = c[0][0].get<double>() * c[1][1].get<double>() - c[0][1].get<double>() * c[1][0].get<double>();
    out.log_det = -std::log(det);
    out.plan_log_det = first["log_det"].get<double>();  // a single sensor's
    out.reasons = result["reasons"];
    // Every local fit ends at or below its own map point by itself (bounded Gauss-Newton with
    // halving): at the node sensor the free step clipped to the bounds once stopped two fits at chi2
    // 72.9 beside map points of 1.10 and 1.41, which had to be redone from those points.
    EXPECT_EQ(result["local_fits"]["from_map_point"].get<int>(), 0) << tag;
    for (const char* key : {"crack.plane.at", "crack.region.z[0]"}) {
      out.widths.push_back(result["interval_95"][key][1].get<double>() - result["interval_95"][key][0].get<double>());
      EXPECT_TRUE(result["truth"]["inside_95"][key].get<bool>()) << tag << ": " << key;
    }
    return out;
  };
  const Identified at_best = identify({best}), at_worst_sensor = identify({worst_sensor}), at_worst = identify({worst});
  const Identified at_pair = identify(pair);
  // The plan's information is identify's: the same forward model, its Jacobian by other steps.
  for (const Identified* at : {&at_best, &at_worst_sensor, &at_worst}) EXPECT_NEAR(at->log_det, at->plan_log_det, 0.5);
  // The best-ranked candidate identifies the crack with narrower intervals than the worst-ranked, both
  // measured by identify (measured: [8.7 mm, 4.0 mm] at 0.5 f_b3 on the crack's side against [243 mm,
  // 6.8 mm] at 0.5 f_b1 next to the clamp), and its confidence ellipse (sqrt det of identify's
  // covariance) is the smaller.
  EXPECT_GT(at_best.log_det, at_worst.log_det + 1.0)
      << "identify's log det F: best " << at_best.log_det << ", worst " << at_worst.log_det;
  EXPECT_LT(at_best.widths[0], at_worst.widths[0]) << "the best-ranked candidate's position interval";
  EXPECT_LT(at_best.widths[1], at_worst.widths[1]) << "the best-ranked candidate's depth interval";
  // The worst's position interval is wider than the position's bounds (0.04 m): identify says that the
  // measurements do not determine it.
  EXPECT_GT(at_worst.widths[0], 0.04);
  EXPECT_NE(at_worst.reasons.dump().find("crack.plane.at: its 95 % interval"), std::string::npos) << at_worst.reasons;
  // At one drive the best sensor against the one at the node: the smaller ellipse and the narrower
  // position interval (8.7 mm against 47 mm); its depth interval is the wider (4.0 mm against 1.3 mm:
  // position and depth correlate at -0.96 at the crack's side), which the ranking by log det accepts
  // (docs/benchmarks.md section 15).
  EXPECT_GT(at_best.log_det, at_worst_sensor.log_det + 1.0)
      << "identify's log det F: best " << at_best.log_det << ", worst sensor " << at_worst_sensor.log_det;
  EXPECT_LT(at_best.widths[0], at_worst_sensor.widths[0]) << "the best-ranked sensor's position interval";
  // The plan's best pair (s2 and the node's s8: their ellipses cross) determines both unknowns
  // within their bounds (measured: [3.3 mm, 1.2 mm], log det 31.1 against the plan's mean 31.1),
  // narrower than either alone.
  EXPECT_GT(at_pair.log_det, at_best.log_det + 1.0);
  EXPECT_LT(at_pair.widths[0], at_best.widths[0]);
  EXPECT_LT(at_pair.widths[1], std::min(at_best.widths[1], at_worst_sensor.widths[1]));
  EXPECT_TRUE(at_pair.reasons.empty()) << at_pair.reasons;
  const auto report = [](const char* name, const Identified& at) {
    std::cout << "  " << name << ": log det F " << at.log_det << " (plan " << at.plan_log_det << "), 95 % widths ["
              << at.widths[0] << ", " << at.widths[1] << "] m\n";
  };
  std::cout << "plan against identify:\n";
  report("best", at_best);
  report("worst sensor of its drive", at_worst_sensor);
  report("worst", at_worst);
  report("best pair (log det: the single sensor's plan figure)", at_pair);
}

TEST(Plan, BadSectionsAreRefusedWithFileLineAndKey) {
  const fs::path dir = scratch("bad");
  const std::string good_prior = "  prior:\n    crack.plane.at: [0.03, 0.07]\n";
  const std::string good_drives = "  drives:\n    points: [[0.2, 0.01, 0.01]]\n    frequencies: [{mode: 1, ratio: 0.5}]\n";
  const std::string good_sensors = "  sensors: {face: z+, spacing: 0.05}\n";
  const struct {
    std::string plan, expected;
  } cases[] = {
      {"plan:\n" + good_prior + good_sensors + good_drives + "  nosie: {ratio: 0.1}\n", "plan.yaml:21: plan.nosie: expected one of"},
      {"plan:\n" + good_prior + "  sensors: {face: top, spacing: 0.05}\n" + good_drives, "plan.sensors.face: expected one of x-, x+"},
      {"plan:\n" + good_prior + good_sensors + "  drives:\n    points: [[0.2, 0.01, 0.01]]\n    frequencies: [{mode: 7, ratio: 0.5}]\n",
       "plan.drives.frequencies[0].mode: expected a mode the scene solves"},
      {"plan:\n" + good_prior + good_sensors, "plan.drives: expected a map"},
      {"plan:\n  prior:\n    crack.plane.att: [0.03, 0.07]\n" + good_sensors + good_drives, "plan.prior.crack.plane.att"},
      {"plan:\n" + good_prior + "  sensors: {points: [[0.3, 0.01, 0.01]]}\n" + good_drives, "plan.sensors.points[0]: expected a point of the body's box"},
      {"plan:\n" + good_prior + good_sensors + "  drives:\n    points: [[0.2, 0.01]]\n    frequencies: [{mode: 1, ratio: 0.5}]\n",
       "plan.drives.points[0]: expected a point [x, y, z]"},
  };
  for (const auto& c : cases) {
    const fs::path scene = write_scene(dir, c.plan);
    const auto result = crackle("plan " + scene.string() + " -o " + (dir / "out").string());
    EXPECT_EQ(result.exit_code, 2) << result.output;
    EXPECT_NE(result.output.find(c.expected), std::string::npos) << result.output;
    EXPECT_FALSE(fs::exists(dir / "out" / "plan.json"));
  }
}

}  // namespace
