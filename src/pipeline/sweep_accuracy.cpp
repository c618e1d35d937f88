#include "pipeline/sweep_accuracy.hpp"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <iostream>
#include <limits>
#include <map>
#include <optional>

#include "accuracy/estimate.hpp"
#include "core/errors.hpp"
#include "core/resources.hpp"
#include "io/files.hpp"
#include "pipeline/accuracy.hpp"
#include "pipeline/modal_accuracy.hpp"
#include "pipeline/refinement.hpp"
#include "pipeline/sweep_refinements.hpp"

namespace crackle::pipeline {
namespace {

namespace fs = std::filesystem;

/// The harmonic-balance truncation error is taken as the change from H to H + 2, three times (an
/// order unknown, Fs = 3): on data/beam.yaml's route the peak A2/A1 at H = 15, 17, 21, 31 is
/// 0.154913, 0.154993, 0.154952, 0.154881, not monotone, so no rate can be fitted to it
/// (docs/benchmarks.md section 11.6).
constexpr double kHarmonicsOrder = 0.0;

EstimatePlan sweep_plan(const scene::Scene& scene, const RunRoute& route) {
  EstimatePlan plan;
  const scene::AccuracySection& accuracy = scene.accuracy;
  if (accuracy.estimate == scene::EstimateChoice::off) {
    plan.reason = "accuracy.estimate: off";
    return plan;
  }
  if (accuracy.estimate == scene::EstimateChoice::automatic && !route.automatic && !accuracy.tolerance) {
    plan.reason = "the sweep of the scene's mesh as written (" + route.reason.substr(0, route.reason.find(':')) +
                  " not auto): accuracy.estimate: on or an accuracy.tolerance estimates it";
    return plan;
  }
  plan.estimate = true;
  plan.tolerance = accuracy.tolerance;
  if (!plan.tolerance && route.automatic) plan.tolerance = 0.01;
  return plan;
}

/// One estimated number of the sweep's summary: where it sits in sweep.json (a JSON pointer, the
/// same in sweep.json `accuracy`), a label for the terminal, and the tolerance quantity it is the
/// value of ("" for the frequencies of peaks and events).
struct Quantity {
  std::string pointer;
  std::string label;
  std::string tolerance_quantity;
  bool modal = false;  ///< a result of the modal stage alone (only the mesh refines it)
};

/// The estimated numbers of a sweep: each probe's peaks (value and frequency), the bilinear
/// frequency, and the frequency of each fold and period doubling (by kind and order along the branch).
std::vector<Quantity> quantities_of(const nlohmann::json& document) {
  std::vector<Quantity> quantities;
  for (const auto& [name, probe] : document.at("probes").items()) {
    for (const auto& [key, quantity] : sweep_peak_keys()) {
      if (!probe.contains(key) || probe[key].is_null()) continue;
      const std::string at = "/probes/" + json_pointer_token(name) + "/" + key;
      quantities.push_back({at + "/value", name + " peak " + quantity, quantity});
      quantities.push_back({at + "/frequency_hz", name + " peak " + quantity + " at [Hz]", ""});
    }
  }
  if (document.contains("bilinear_hz") && !document["bilinear_hz"].is_null()) {
    quantities.push_back({"/bilinear_hz", "f_b [Hz]", "f_b", true});
  }
  std::map<std::string, int> seen;
  for (const nlohmann::json& event : document.at("events")) {
    const std::string kind = event.at("kind");
    if (kind != "fold" && kind != "period_doubling") continue;
    const std::string name = kind + " " + std::to_string(++seen[kind]);
    quantities.push_back({"/events/" + json_pointer_token(name), name + " [Hz]", ""});
  }
  return quantities;
}

/// The value of a quantity in a sweep (NaN where that sweep has no such peak or event).
double value_of(const nlohmann::json& document, const std::string& pointer) {
  if (pointer.rfind("/events/", 0) == 0) {
    const std::string name = pointer.substr(8);
    const std::string kind = name.substr(0, name.rfind(' '));
    const int index = std::stoi(name.substr(name.rfind(' ') + 1));
    int seen = 0;
    for (const nlohmann::json& event : document.at("events")) {
      if (event.at("kind") == kind && ++seen == index) return event.at("frequency_hz").get<double>();
    }
    return std::numeric_limits<double>::quiet_NaN();
  }
  const nlohmann::json::json_pointer at(pointer);
  if (!document.contains(at) || !document[at].is_number()) return std::numeric_limits<double>::quiet_NaN();
  return document[at].get<double>();
}

/// The components of one quantity at a setting (the modes from three band levels where `third_band`).
accuracy::Estimate estimate_of(const Quantity& quantity, RefinementSweeps& sweeps, const Setting& setting,
                               bool third_band) {
  const double value = value_of(sweeps.get(setting).document, quantity.pointer);
  const Neighbours n = neighbours(setting, sweeps.box_mesh());
  const auto at = [&](const Setting& level) { return value_of(sweeps.near(level).document, quantity.pointer); };
  std::vector<accuracy::Component> components;
  if (quantity.modal && n.coarse) {
    // The bilinear frequency: Richardson in DOFs^-1/3 with Fs = 3, as crackle modal's and run's
    // (a geometric rate in p was 0.56 of the true error on data/beam.yaml, docs/benchmarks.md 11.9).
    components.push_back(frequency_levels_component(n, setting, [&](const Setting& level) {
      const nlohmann::json& document = sweeps.near(level).document;
      return std::pair{value_of(document, quantity.pointer), document.at("model").value("free_dofs", 0.0)};
    }));
  } else {
    components.push_back(n.coarse ? mesh_component(value, true, at(*n.coarser), at(*n.coarse), sweeps.box_mesh())
                                  : mesh_component(value, false, 0.0, 0.0, sweeps.box_mesh()));
  }
  if (!quantity.modal) {  // the modal stage does not depend on the reduced model's band or on H
    const double band = at(n.band), harmonics = at(n.harmonics);
    components.push_back(modes_component(value, band,
                                         third_band ? at(n.band_twice) : std::numeric_limits<double>::quiet_NaN()));
    const double ratio = double(sweeps.harmonics(n.harmonics)) / sweeps.harmonics(setting);
    components.push_back(std::isfinite(harmonics)
                             ? accuracy::one_refinement("harmonics", value, harmonics, ratio, kHarmonicsOrder)
                             : missing_component("harmonics", value));
    if (sweeps.has_contact()) {  // the penalty's error falls as 1/k (MODEL.md eq. 25d)
      const double penalty = at(n.penalty);
      components.push_back(std::isfinite(penalty) ? accuracy::one_refinement("penalty", value, penalty, 4.0, 1.0)
                                                  : missing_component("penalty", value));
    }
  }
  return accuracy::combine(quantity.label, value, components);
}

/// Every quantity's estimate at a setting, with the largest error among the tolerance's quantities
/// and, per component, the largest |delta| among them.
struct SettingEstimate {
  nlohmann::json json = nlohmann::json::object();
  std::vector<accuracy::Estimate> lines;  ///< the tolerance's quantities, for the terminal
  SettingSummary summary;
};

SettingEstimate estimate_setting(RefinementSweeps& sweeps, const Setting& setting,
                                 const std::vector<std::string>& counted, std::optional<double> tolerance) {
  SettingEstimate result;
  const std::vector<Quantity> quantities = quantities_of(sweeps.get(setting).document);
  // The band x4 sweep where a counted quantity's two-level modes component asks for it.
  bool third_band = false;
  const Setting band = neighbours(setting, sweeps.box_mesh()).band;
  for (const Quantity& quantity : quantities) {
    const bool is_counted = std::find(counted.begin(), counted.end(), quantity.tolerance_quantity) != counted.end();
    if (quantity.modal || !is_counted) continue;
    const accuracy::Component modes =
        modes_component(value_of(sweeps.get(setting).document, quantity.pointer),
                        value_of(sweeps.near(band).document, quantity.pointer));
    if (std::isfinite(modes.delta) && needs_third_band(modes.delta, tolerance)) third_band = true;
  }
  for (const Quantity& quantity : quantities) {
    const accuracy::Estimate estimate = estimate_of(quantity, sweeps, setting, third_band);
    result.json[nlohmann::json::json_pointer(quantity.pointer)] = output::estimate_json(estimate);
    if (std::find(counted.begin(), counted.end(), quantity.tolerance_quantity) == counted.end()) continue;
    result.lines.push_back(estimate);
    add_to_summary(estimate, result.summary);
  }
  return result;
}

/// The next setting the tolerance refines to: the component with the largest error per second of
/// its refinement sweep, or empty with `blocking` saying why none can go on.
std::optional<Setting> refine(RefinementSweeps& sweeps, const Setting& setting, const SettingSummary& summary,
                              double budget_left, std::optional<double> tolerance, std::string& blocking) {
  const Neighbours n = neighbours(setting, sweeps.box_mesh());
  std::vector<RefinementChoice> choices;
  const double here = sweeps.get(setting).wall_s;
  if (n.coarse) {
    choices.push_back(mesh_choice(setting, sweeps.scene(), here * here / std::max(1e-3, sweeps.cost_s(*n.coarse))));
  }
  choices.push_back({"modes", n.band, sweeps.cost_s(n.band), ""});
  choices.push_back({"harmonics", n.harmonics, sweeps.cost_s(n.harmonics), ""});
  if (sweeps.has_contact()) choices.push_back({"penalty", n.penalty, sweeps.cost_s(n.penalty), ""});
  return choose_refinement(choices, summary, budget_left,
                           sweeps.box_mesh() && !n.coarse ? "mesh (not estimated below element order 3)"
                                                          : "none (no component has an error left)",
                           blocking, tolerance);
}

}  // namespace

void sweep_with_accuracy(const scene::Scene& scene, const RunRoute& route, const std::vector<scene::Override>& overrides,
                         const SweepCommandOptions& options, std::ostream& out, std::ostream& progress) {
  Stopwatch total;
  const fs::path& directory = options.output_directory;
  if (route.automatic) out << "route: " << route.reason << "\n";
  const EstimatePlan plan = sweep_plan(scene, route);
  if (!plan.estimate) {
    SweepOutcome outcome = sweep_scene(scene, options, out, progress);
    outcome.document["route"] = route_json(route);
    outcome.document["accuracy"] = {{"estimated", false}, {"reason", plan.reason}};
    outcome.document["wall_s"] = total.seconds();
    io::write_json(directory / "sweep.json", outcome.document);
    if (scene.has_accuracy_section) std::cerr << "crackle: note: accuracy: not estimated: " << plan.reason << "\n";
    if (!options.accuracy_start.empty()) {
      std::cerr << "crackle: note: --accuracy-start " << options.accuracy_start.string()
                << " not used: the sweep is not estimated (" << plan.reason << ")\n";
    }
    out << "wrote " << (directory / "sweep.json").string() << "\n";
    return;
  }
  io::ensure_directory(directory);
  RefinementSweeps sweeps(scene, overrides, options, out, progress);
  Setting setting;
  setting.order = scene.box.order;
  Setting start = tolerance_start(setting, options.accuracy_start, plan, sweeps.box_mesh(), out);  // checked first
  start.window = 0;  // a run's, where the file is a run.json: a sweep has no steady state to tighten
  const double run_s = sweeps.get(setting, true).wall_s;
  // The tolerance applies to accuracy.quantities: each probe's peak values and the bilinear frequency.
  setting = start;  // the scene's own sweep first all the same: the refinements' base band and penalty are its
  const std::vector<std::string>& counted = scene.accuracy.quantities;
  SettingEstimate estimate = estimate_setting(sweeps, setting, counted, plan.tolerance);
  const ToleranceOutcome outcome = reach_tolerance(
      plan.tolerance, setting, estimate.summary,
      [&](const Setting& from, std::string& blocking) {
        return refine(sweeps, from, estimate.summary, scene.accuracy.budget_s - total.seconds(), plan.tolerance, blocking);
      },
      [&](const Setting& at) {
        estimate = estimate_setting(sweeps, at, counted, plan.tolerance);
        return estimate.summary;
      },
      [&](const Setting& at) { return sweeps.describe(at); }, out);
  nlohmann::json document = sweeps.get(setting).document;
  sweeps.adopt(setting);
  for (const accuracy::Estimate& line : estimate.lines) out << "accuracy " << accuracy::estimate_line(line) << "\n";
  const double wall = total.seconds();
  nlohmann::json accuracy = accuracy_summary(sweeps.describe(setting), plan.tolerance, counted, scene.accuracy.budget_s,
                                             estimate.summary, outcome, sweeps.runs_json(), run_s,
                                             sweeps.refinement_s(), wall);
  accuracy["method"] =
      "one refinement per component from the setting swept (DETECTION.md sec. 1): mesh: the two lower element orders "
      "(Richardson with the observed rate per order, GCI safety factor 1.25, 3 where not asymptotic; the bilinear "
      "frequency Richardson in DOFs^-1/3, 3); modes: twice the band, read at order 2, and four times where that change "
      "is above a tenth of the tolerance (of 0.01 without one): three levels with the observed order (Fs 1.25 for an "
      "order in [1.33, 4], else 3); harmonics: H + 2 (the change, three times: the "
      "convergence in H is not monotone); penalty: four times it (where the crack has contact); the refinement "
      "sweeps re-solve windows of the range around the peaks at the main sweep's step (runs[].windows, fractions "
      "of the range; where the branch has no fold or period doubling and every peak stays inside its window), else "
      "the whole range at half the points. Estimated: each probe's peaks (value and frequency, the parabola through the "
      "three points around the largest, or the value at a range end), the fold and period-doubling frequencies (by "
      "kind and order along the branch) and the bilinear frequency. delta: signed relative error of the value, " +
      std::string(output::kEstimateFields);
  accuracy["reached"] = setting_json(setting);
  if (!options.accuracy_start.empty() && plan.tolerance) accuracy["started_from"] = options.accuracy_start.string();
  accuracy.update(estimate.json);  // probes, bilinear_hz, events: each number's estimate at its own place
  document["route"] = route_json(route);
  document["accuracy"] = accuracy;
  document["wall_s"] = wall;
  io::write_json(directory / "sweep.json", document);
  print_accuracy_end(out, plan.tolerance, outcome, estimate.summary, counted, sweeps.runs_json().size() - 1, "sweeps",
                     sweeps.refinement_s(), wall);
  out << "wrote " << (directory / "sweep.json").string() << "\n";
}

}  // namespace crackle::pipeline
