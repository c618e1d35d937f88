// `crackle run` with transient.model: auto and the accuracy estimate (DETECTION.md sec. 1): the default
// route on data/beam.yaml as written, checked against a reference converged by hand (effectivity of
// the estimate), the routes that fall back to the full model and say why, the tolerance loop, and
// bad accuracy input.
#include <gtest/gtest.h>

#include "cli_testing.hpp"

#include <cmath>
#include <filesystem>
#include <fstream>
#include <string>

#include <nlohmann/json.hpp>

namespace fs = std::filesystem;

namespace {

// The converged signature of data/beam.yaml (docs/benchmarks.md section 11.1): the reduced model on
// graded meshes finer than the default route's in every component: order 4 with 5 front layers
// (the route has 3; the rest extrapolated from 3 -> 4 -> 5), [20, 2, 2] cells against [20, 2, 1],
// the band doubled and the steady state to 1e-5 (the scene's 1e-3). The bilinear frequency's
// reference refines every direction (docs/benchmarks.md 11.9): the graded [40, 4, 2] grid at order 4
// extrapolated by its orders 2-4 in DOFs^-1/3 (205.3987 Hz), which the route's own [20, 2, 1] grid
// extrapolated the same way reproduces to 2.5e-5 (205.4039 Hz). (The earlier 205.4561 Hz refined only
// z and the front layers; the uncracked body's f_1 alone falls 0.021 % from [20, 2, 1] to [40, 4, 2].)
constexpr double kReferenceA2 = 0.15486;
constexpr double kReferenceBilinearHz = 205.3987;

fs::path scratch() {
  static const fs::path dir = fs::temp_directory_path() / ("crackle-test-accuracy-" + std::to_string(::getpid()));
  fs::create_directories(dir);
  return dir;
}

nlohmann::json read_json(const fs::path& path) {
  std::ifstream in(path);
  return nlohmann::json::parse(in);
}

cli_testing::Result run_scene_text(const std::string& name, const std::string& text, const std::string& extra = "") {
  const fs::path scene = scratch() / (name + ".yaml");
  std::ofstream(scene) << text;
  return cli_testing::crackle("run " + scene.string() + " -o " + (scratch() / name).string() + " -q " + extra);
}

/// The cracked p = 1 cantilever driven at its tip (cli_testing, written for the full model) with
/// transient.model `model` and `transient` lines added.
std::string forced(const std::string& model, const std::string& transient_lines) {
  std::string text = cli_testing::cantilever("[10, 2, 1]") +
                     cli_testing::forced_tip("    - {name: tip, point: [0.2, 0.01, 0.01]}\n");
  const std::string marker = "  model: full\n";
  text.replace(text.find(marker), marker.size(), "  model: " + model + "\n" + transient_lines);
  return text;
}

// The README's main job: the beam as a user writes it (uniform cells [40, 4, 2], p = 2, no accuracy
// keys). The route takes the reduced model on its own graded mesh, says so in run.json, lands within
// 1 % of the converged A2/A1, and the estimate it reports holds the true error: effectivity in [1, 3]
// for A2/A1, at least 1 for the bilinear frequency.
TEST(DefaultRoute, TheBeamAsWrittenGivesItsConvergedSignatureWithAnEstimateThatHoldsIt) {
  const fs::path out = scratch() / "beam";
  const cli_testing::Result result =
      cli_testing::crackle("run " + std::string(CRACKLE_SOURCE_DIR) + "/data/beam.yaml -o " + out.string() + " -q");
  ASSERT_EQ(result.exit_code, 0) << result.output;
  EXPECT_NE(result.output.find("accuracy tip: A2/A1 = "), std::string::npos) << result.output;

  const nlohmann::json run = read_json(out / "run.json");
  ASSERT_TRUE(run.contains("route")) << run.dump(2);
  EXPECT_EQ(run["route"]["model"], "reduced");
  EXPECT_TRUE(run["route"]["automatic"].get<bool>());
  EXPECT_NE(run["route"]["reason"].get<std::string>().find("harmonic-drive signature run"), std::string::npos);
  EXPECT_EQ(run["route"]["scene_mesh"]["cells"], nlohmann::json::parse("[40, 4, 2]"));
  EXPECT_EQ(run["route"]["mesh"]["cells"], nlohmann::json::parse("[20, 2, 1]"));
  EXPECT_EQ(run["route"]["mesh"]["order"], 4);
  EXPECT_TRUE(run["accuracy"]["met"].get<bool>());

  const nlohmann::json spectrum = read_json(out / "spectrum.json");
  const nlohmann::json& accuracy = spectrum["accuracy"];
  EXPECT_TRUE(accuracy["estimated"].get<bool>());
  EXPECT_EQ(accuracy["tolerance"].get<double>(), 0.01);
  EXPECT_TRUE(accuracy["met"].get<bool>());
  EXPECT_TRUE(accuracy["verified"].get<bool>());

  const double a2 = spectrum["probes"]["tip"]["indices"]["A2/A1"].get<double>();
  const double a2_true_error = std::abs(a2 - kReferenceA2) / kReferenceA2;
  EXPECT_LT(a2_true_error, 0.01) << "A2/A1 = " << a2;
  const nlohmann::json& a2_estimate = accuracy["probes"]["tip"]["A2/A1"];
  EXPECT_EQ(a2_estimate["value"].get<double>(), a2);
  EXPECT_TRUE(a2_estimate["verified"].get<bool>());
  for (const char* component : {"mesh", "modes", "steps", "penalty", "window"}) {
    EXPECT_TRUE(a2_estimate["components"].contains(component)) << component;
  }
  const double a2_effectivity = a2_estimate["error"].get<double>() / a2_true_error;
  EXPECT_GE(a2_effectivity, 1.0) << "estimate " << a2_estimate["error"] << ", true error " << a2_true_error;
  EXPECT_LE(a2_effectivity, 3.0) << "estimate " << a2_estimate["error"] << ", true error " << a2_true_error;
  // The estimate (the trusted corrections with their signs and margins) never exceeds the sum of the
  // components' moduli, the conservative bound, which holds their root-sum-square.
  EXPECT_LE(a2_estimate["error"].get<double>(), a2_estimate["sum"].get<double>() * (1.0 + 1e-12));
  EXPECT_LE(a2_estimate["rss"].get<double>(), a2_estimate["sum"].get<double>());

  const nlohmann::json& fb = accuracy["mode"]["f_bilinear"];
  const double fb_true_error = std::abs(fb["value"].get<double>() - kReferenceBilinearHz) / kReferenceBilinearHz;
  const double fb_effectivity = fb["error"].get<double>() / fb_true_error;
  EXPECT_TRUE(fb["verified"].get<bool>());
  // Richardson in DOFs^-1/3 with Fs = 3 (as crackle modal's): measured 2.75.
  EXPECT_GE(fb_effectivity, 1.0) << "estimate " << fb["error"] << ", true error " << fb_true_error;
  EXPECT_LE(fb_effectivity, 3.0) << "estimate " << fb["error"] << ", true error " << fb_true_error;
}

// A 2 mm crack at x = 0.11 m settles after 12 periods, so its first analysis window holds the start
// ramp and the windows' changes fall 45x, faster than the damping lets the transient decay (12.4x per
// window): taken as it stood, the window component was 0.35 of the window's true error, hidden by the
// mesh part of the other sign (docs/benchmarks.md 11.11). The window's true error is measured here
// (the same setting run to the steady state 1e-5, the modes from the first run's cache); the whole
// estimate is checked against the same crack on a grid refined in every direction: graded [40, 4, 2]
// cells at order 4 with 5 front layers, the band doubled and the steady state to 1e-5 (198 s, 19 GB,
// computed once).
constexpr double kFineReferenceA2Crack2mmAt011 = 0.016716781727411225;

TEST(DefaultRoute, AWindowHoldingTheStartRampIsBoundedByTheDampingAndTheEstimateHoldsAgainstAFinerGrid) {
  const std::string scene = std::string(CRACKLE_SOURCE_DIR) + "/data/beam.yaml";
  const std::string crack = " --set crack.plane.at=0.11 --set crack.region.z=[0.008,0.01] --set spectrum.plots=false";
  const std::string cache = " --modal-cache " + (scratch() / "crack-2mm-cache").string();
  const cli_testing::Result route =
      cli_testing::crackle("run " + scene + " -o " + (scratch() / "crack-2mm").string() + " -q" + crack + cache);
  ASSERT_EQ(route.exit_code, 0) << route.output;
  const cli_testing::Result settled = cli_testing::crackle(
      "run " + scene + " -o " + (scratch() / "crack-2mm-settled").string() + " -q" + crack + cache +
      " --set spectrum.steady_state.tolerance=1e-5 --set transient.periods=400 --set accuracy.estimate=off");
  ASSERT_EQ(settled.exit_code, 0) << settled.output;
  const nlohmann::json spectrum = read_json(scratch() / "crack-2mm" / "spectrum.json");
  EXPECT_EQ(read_json(scratch() / "crack-2mm" / "run.json")["route"]["mesh"]["order"], 4);
  const nlohmann::json& estimate = spectrum["accuracy"]["probes"]["tip"]["A2/A1"];
  const double value = estimate["value"].get<double>();
  ASSERT_TRUE(estimate["verified"].get<bool>()) << estimate.dump(2);

  const nlohmann::json& window = estimate["components"]["window"];
  EXPECT_GT(window["levels_ratio"].get<double>(), window["decay_ratio_bound"].get<double>()) << window.dump();
  EXPECT_FALSE(window["asymptotic"].get<bool>());
  const double steady = read_json(scratch() / "crack-2mm-settled" / "spectrum.json")["probes"]["tip"]["indices"]["A2/A1"];
  const double window_error = (steady - value) / value;
  const double window_effectivity = window["delta"].get<double>() / window_error;  // signed: the same sign
  EXPECT_GE(window_effectivity, 1.0) << "window " << window["delta"] << ", its true error " << window_error;
  EXPECT_LE(window_effectivity, 3.0) << "window " << window["delta"] << ", its true error " << window_error;

  const double true_error = std::abs(value - kFineReferenceA2Crack2mmAt011) / kFineReferenceA2Crack2mmAt011;
  EXPECT_LT(true_error, 0.01);
  const double effectivity = estimate["error"].get<double>() / true_error;
  EXPECT_GE(effectivity, 1.0) << "estimate " << estimate["error"] << ", true error " << true_error;
  EXPECT_LE(effectivity, 3.0) << "estimate " << estimate["error"] << ", true error " << true_error;
}

// Where the reduced model's validity conditions do not hold, auto takes the full model and says why;
// the full model's signature is then not estimated, and spectrum.json says that too.
TEST(DefaultRoute, TakesTheFullModelWithItsReasonWhereTheReducedOneDoesNotServe) {
  const cli_testing::Result stepped = run_scene_text("time-step", forced("auto", "  time_step: 5.0e-7\n"));
  ASSERT_EQ(stepped.exit_code, 0) << stepped.output;
  const nlohmann::json run = read_json(scratch() / "time-step" / "run.json");
  EXPECT_EQ(run["route"]["model"], "full");
  EXPECT_NE(run["route"]["reason"].get<std::string>().find("transient.time_step"), std::string::npos);
  EXPECT_FALSE(run["route"].contains("mesh"));
  const nlohmann::json spectrum = read_json(scratch() / "time-step" / "spectrum.json");
  EXPECT_FALSE(spectrum["accuracy"]["estimated"].get<bool>());
  EXPECT_NE(spectrum["accuracy"]["reason"].get<std::string>().find("full model"), std::string::npos);
  const nlohmann::json transient = read_json(scratch() / "time-step" / "transient.json");
  EXPECT_FALSE(transient.contains("model") && transient["model"] == "reduced");

  const cli_testing::Result initial = run_scene_text(
      "initial", forced("auto", "  initial:\n    - {velocity: [0, 0, 0.01]}\n"));
  ASSERT_EQ(initial.exit_code, 0) << initial.output;
  EXPECT_NE(read_json(scratch() / "initial" / "run.json")["route"]["reason"].get<std::string>().find("transient.initial"),
            std::string::npos);
}

// transient.model: reduced as written keeps the scene's mesh; its estimate runs, and at order 1 the
// mesh part cannot be estimated: the estimate says `verified: false` with the reason instead of a
// small number. No tolerance without transient.model: auto unless asked.
TEST(Accuracy, AnExplicitReducedRunOnItsOwnMeshSaysWhenItsMeshErrorIsNotEstimated) {
  const cli_testing::Result result = run_scene_text("reduced-p1", forced("reduced", ""));
  ASSERT_EQ(result.exit_code, 0) << result.output;
  const nlohmann::json run = read_json(scratch() / "reduced-p1" / "run.json");
  EXPECT_FALSE(run["route"]["automatic"].get<bool>());
  EXPECT_FALSE(run["route"].contains("mesh"));
  const nlohmann::json accuracy = read_json(scratch() / "reduced-p1" / "spectrum.json")["accuracy"];
  EXPECT_TRUE(accuracy["estimated"].get<bool>());
  EXPECT_TRUE(accuracy["tolerance"].is_null());
  EXPECT_FALSE(accuracy.contains("met"));
  const nlohmann::json& a2 = accuracy["probes"]["tip"]["A2/A1"];
  EXPECT_FALSE(a2["verified"].get<bool>());
  EXPECT_NE(a2["components"]["mesh"]["reason"].get<std::string>().find("order 3"), std::string::npos);
  EXPECT_NE(result.output.find("not verified"), std::string::npos) << result.output;
  // The other components ran and are numbers.
  for (const char* component : {"modes", "steps", "penalty"}) {
    EXPECT_TRUE(a2["components"][component]["delta"].is_number()) << component;
  }
}

// A tolerance the setting cannot reach: the run ends with met: false and names what blocks, and the
// output folder holds the files of the setting it reports (no temporary folder left behind).
TEST(Accuracy, AToleranceThatCannotBeMetEndsWithMetFalseAndTheBlockingComponent) {
  const cli_testing::Result result = run_scene_text(
      "unmet", forced("reduced", "") + "accuracy: {tolerance: 1.0e-9, budget: 60}\n");
  ASSERT_EQ(result.exit_code, 0) << result.output;
  const nlohmann::json accuracy = read_json(scratch() / "unmet" / "spectrum.json")["accuracy"];
  EXPECT_FALSE(accuracy["met"].get<bool>());
  ASSERT_TRUE(accuracy.contains("blocking"));
  EXPECT_FALSE(accuracy["blocking"].get<std::string>().empty());
  EXPECT_GT(accuracy["error"].get<double>(), 1.0e-9);
  EXPECT_NE(result.output.find("not met"), std::string::npos) << result.output;
  for (const fs::directory_entry& entry : fs::directory_iterator(scratch() / "unmet")) {
    EXPECT_EQ(entry.path().filename().string().find(".tmp."), std::string::npos) << entry.path();
  }
}

/// The cracked p = 3 cantilever graded towards its front, driven at `amplitude` N, with a tolerance on
/// A1 that its own setting misses (0.29 %) and order 4 meets (0.12 %).
std::string graded_toleranced(const std::string& amplitude) {
  std::string text = forced("reduced", "") + "accuracy: {tolerance: 0.002, quantities: [A1]}\n";
  const std::string mesh = "cells: [10, 2, 1], order: 1, grading: none", graded = "cells: [20, 2, 1], order: 3, grading: always";
  text.replace(text.find(mesh), mesh.size(), graded);
  const std::string drive = "amplitude: 20.0";
  text.replace(text.find(drive), drive.size(), "amplitude: " + amplitude);
  return text;
}

// A run whose tolerance loop refined (to order 4) leaves the setting it reached in run.json; a run of
// the same mesh at another drive started there (`--accuracy-start`, as a study's cases that share a
// mesh are) meets the tolerance at that setting with fewer refinement runs, and - the bilinear
// oscillator being homogeneous in the drive - has the same A2/A1 and 1.5 times the A1 to round-off.
TEST(Accuracy, ARunStartsItsToleranceLoopWhereAnEarlierRunOfTheSameMeshEnded) {
  // Both share a modal cache, as a study's cases do: the follower's order-4 run reads its modes and
  // reduction from it.
  const std::string cache = " --modal-cache " + (scratch() / "start-cache").string();
  const cli_testing::Result leader = run_scene_text("leader", graded_toleranced("20.0"), cache + " --set spectrum.plots=true");
  ASSERT_EQ(leader.exit_code, 0) << leader.output;
  const nlohmann::json first = read_json(scratch() / "leader" / "spectrum.json");
  ASSERT_TRUE(first["accuracy"]["met"].get<bool>()) << first["accuracy"].dump(1);
  const nlohmann::json reached = read_json(scratch() / "leader" / "run.json")["accuracy"]["reached"];
  EXPECT_EQ(reached, first["accuracy"]["reached"]);
  EXPECT_EQ(reached["order"], 4) << reached;
  // The folder holds the adopted run's figures: refinement runs write their data and scripts only,
  // and the adoption draws them, over the PNGs the scene's own run drew earlier (no PNG older than
  // its script).
  int scripts = 0;
  for (const fs::directory_entry& entry : fs::directory_iterator(scratch() / "leader")) {
    if (entry.path().extension() != ".gp") continue;
    ++scripts;
    const fs::path png = fs::path(entry.path()).replace_extension(".png");
    ASSERT_TRUE(fs::exists(png)) << png;
    EXPECT_GE(fs::last_write_time(png), fs::last_write_time(entry.path())) << png;
  }
  EXPECT_EQ(scripts, 2) << "the tip's history and spectrum";

  const std::string start = (scratch() / "leader" / "run.json").string();
  const cli_testing::Result follower =
      run_scene_text("follower", graded_toleranced("30.0"), "--accuracy-start " + start + cache);
  ASSERT_EQ(follower.exit_code, 0) << follower.output;
  EXPECT_NE(follower.output.find("accuracy: the tolerance starts at order 4"), std::string::npos) << follower.output;
  const nlohmann::json second = read_json(scratch() / "follower" / "spectrum.json");
  EXPECT_TRUE(second["accuracy"]["met"].get<bool>());
  EXPECT_EQ(second["accuracy"]["reached"], reached);
  EXPECT_EQ(second["accuracy"]["started_from"], start);
  EXPECT_LT(second["accuracy"]["runs"].size(), first["accuracy"]["runs"].size());
  const nlohmann::json& a = first["accuracy"]["probes"]["tip"];
  const nlohmann::json& b = second["accuracy"]["probes"]["tip"];
  EXPECT_NEAR(b["A2/A1"]["value"].get<double>() / a["A2/A1"]["value"].get<double>(), 1.0, 1e-9);
  EXPECT_NEAR(b["A1"]["value"].get<double>() / a["A1"]["value"].get<double>(), 1.5, 1e-9);
  EXPECT_NEAR(b["A1"]["error"].get<double>(), a["A1"]["error"].get<double>(), 1e-9);

  // Bad start files are refused before anything runs, naming the file and what was expected.
  const cli_testing::Result missing =
      run_scene_text("start-missing", graded_toleranced("30.0"), "--accuracy-start " + (scratch() / "none.json").string());
  EXPECT_NE(missing.exit_code, 0);
  EXPECT_NE(missing.output.find("none.json"), std::string::npos) << missing.output;
  const std::string transient = (scratch() / "leader" / "transient.json").string();
  const cli_testing::Result unreached =
      run_scene_text("start-unreached", graded_toleranced("30.0"), "--accuracy-start " + transient);
  EXPECT_EQ(unreached.exit_code, 2) << unreached.output;
  EXPECT_NE(unreached.output.find("transient.json: accuracy.reached: expected the setting an estimate reached"),
            std::string::npos)
      << unreached.output;
  EXPECT_FALSE(fs::exists(scratch() / "start-unreached" / "run.json"));
  // Without a tolerance there is no loop to start: the file is not used, and the run says so.
  const cli_testing::Result untoleranced = run_scene_text("start-unused", forced("reduced", ""), "--accuracy-start " + start);
  ASSERT_EQ(untoleranced.exit_code, 0) << untoleranced.output;
  EXPECT_NE(untoleranced.output.find("not used: the estimate has no tolerance to reach"), std::string::npos)
      << untoleranced.output;
}

// At the highest order on a mesh that is not graded there is no finer mesh the loop can run (no
// front layers to add): it stops there, met: false, and names it (it once failed with a message
// about mesh.box.grading, exit 2, on the front-layer override it tried).
TEST(Accuracy, AnUngradedMeshAtTheHighestOrderBlocksTheToleranceAndSaysWhy) {
  std::string text = forced("reduced", "") + "accuracy: {tolerance: 0.003}\n";
  const std::string mesh = "order: 1, grading: none";
  text.replace(text.find(mesh), mesh.size(), "order: 4, grading: none");
  const cli_testing::Result result = run_scene_text("ungraded-p4", text);
  ASSERT_EQ(result.exit_code, 0) << result.output;
  const nlohmann::json accuracy = read_json(scratch() / "ungraded-p4" / "spectrum.json")["accuracy"];
  EXPECT_FALSE(accuracy["met"].get<bool>());
  EXPECT_NE(accuracy["blocking"].get<std::string>().find("not graded"), std::string::npos) << accuracy["blocking"];
  EXPECT_EQ(accuracy["reached"]["order"], 4);
  EXPECT_EQ(accuracy["reached"]["layers"], 0);
}

// The full model stays the reference: data/gmsh-cracked-box.yaml's default route (the reduced model
// on the scene's Gmsh mesh) and the full explicit model on the same mesh, both over the same 12
// periods (no steady-state stop, so both analyse the same window). Their difference is the reduced
// model's error alone (the mesh is the same), and the estimate's reduced-model parts (modes, steps,
// penalty, window) hold it; the mesh part says it is not estimated on a Gmsh mesh (verified: false).
// Measured: A1 4.5e-4, A2/A1 1.07 % (estimate 2.9 %); docs/benchmarks.md section 11.8.
TEST(DefaultRoute, TheGmshBoxAgreesWithTheFullModelOnItsMeshWithinItsEstimate) {
  const std::string scene = std::string(CRACKLE_SOURCE_DIR) + "/data/gmsh-cracked-box.yaml";
  const std::string same = " --set transient.periods=12 --set spectrum.steady_state.tolerance=0 --set spectrum.plots=false";
  const cli_testing::Result reduced =
      cli_testing::crackle("run " + scene + " -o " + (scratch() / "gmsh-route").string() + " -q" + same);
  ASSERT_EQ(reduced.exit_code, 0) << reduced.output;
  const cli_testing::Result full = cli_testing::crackle("run " + scene + " -o " + (scratch() / "gmsh-full").string() +
                                                        " -q --set transient.model=full" + same);
  ASSERT_EQ(full.exit_code, 0) << full.output;
  const nlohmann::json route = read_json(scratch() / "gmsh-route" / "run.json")["route"];
  EXPECT_EQ(route["model"], "reduced");
  EXPECT_NE(route["reason"].get<std::string>().find("Gmsh mesh"), std::string::npos);
  const nlohmann::json accuracy = read_json(scratch() / "gmsh-route" / "spectrum.json")["accuracy"];
  const nlohmann::json reference = read_json(scratch() / "gmsh-full" / "spectrum.json")["probes"]["top"];
  const auto a1_of = [](const nlohmann::json& probe) {
    for (const nlohmann::json& harmonic : probe["harmonics"])
      if (harmonic["order"].get<double>() == 1.0) return harmonic["amplitude"].get<double>();
    return 0.0;
  };
  const double a1_full = a1_of(reference), a2_full = reference["indices"]["A2/A1"].get<double>();
  for (const auto& [quantity, truth] : {std::pair<std::string, double>{"A1", a1_full}, {"A2/A1", a2_full}}) {
    const nlohmann::json& estimate = accuracy["probes"]["top"][quantity];
    EXPECT_FALSE(estimate["verified"].get<bool>()) << quantity;
    EXPECT_NE(estimate["components"]["mesh"]["reason"].get<std::string>().find("Gmsh"), std::string::npos);
    const double difference = std::abs(estimate["value"].get<double>() - truth) / std::abs(truth);
    EXPECT_GT(difference, 0.0) << quantity;  // two models, not one run twice
    EXPECT_LE(difference, estimate["error"].get<double>()) << quantity << ": reduced " << estimate["value"]
                                                           << ", full " << truth;
  }
}

TEST(Accuracy, BadAccuracyInputIsAClearError) {
  const cli_testing::Result full_on =
      run_scene_text("full-on", forced("full", "") + "accuracy: {estimate: on}\n");
  EXPECT_EQ(full_on.exit_code, 2) << full_on.output;
  EXPECT_NE(full_on.output.find("accuracy.estimate: expected auto or off with transient.model: full"),
            std::string::npos)
      << full_on.output;

  // A tolerance the full model cannot honour is said, not ignored.
  const cli_testing::Result full_tolerance =
      run_scene_text("full-tolerance", forced("full", "") + "accuracy: {tolerance: 0.01}\n");
  EXPECT_EQ(full_tolerance.exit_code, 0) << full_tolerance.output;
  EXPECT_NE(full_tolerance.output.find("note: accuracy: not estimated: the full model"), std::string::npos)
      << full_tolerance.output;

  std::string no_spectrum = forced("auto", "");
  no_spectrum = no_spectrum.substr(0, no_spectrum.find("spectrum:")) + "accuracy: {tolerance: 0.01}\n";
  const cli_testing::Result missing = run_scene_text("no-spectrum", no_spectrum);
  EXPECT_EQ(missing.exit_code, 2) << missing.output;
  EXPECT_NE(missing.output.find("accuracy: expected a spectrum:, sweep: or modal: section"), std::string::npos) << missing.output;

  const cli_testing::Result bad_tolerance =
      run_scene_text("bad-tolerance", forced("auto", "") + "accuracy: {tolerance: 2}\n");
  EXPECT_EQ(bad_tolerance.exit_code, 2) << bad_tolerance.output;
  EXPECT_NE(bad_tolerance.output.find("accuracy.tolerance"), std::string::npos) << bad_tolerance.output;
}

}  // namespace
