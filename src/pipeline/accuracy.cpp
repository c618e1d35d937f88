#include "pipeline/accuracy.hpp"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <iostream>
#include <limits>

#include "accuracy/estimate.hpp"
#include "core/errors.hpp"
#include "core/resources.hpp"
#include "io/files.hpp"
#include "pipeline/distributed_run.hpp"
#include "pipeline/modal_accuracy.hpp"
#include "pipeline/refinement.hpp"
#include "pipeline/run_refinements.hpp"
#include "pipeline/run_scene.hpp"

namespace crackle::pipeline {
namespace {

namespace fs = std::filesystem;

/// Whether and how the scene's signatures are estimated.
EstimatePlan accuracy_plan(const scene::Scene& scene, const RunRoute& route) {
  EstimatePlan plan;
  const std::optional<scene::ExcitationSection>& excitation = scene.transient->excitation;
  if (!scene.spectrum || !excitation || excitation->kind != scene::ExcitationKind::harmonic) {
    plan.reason = "no harmonic signature (no spectrum: section or no harmonic excitation)";
    return plan;
  }
  const scene::AccuracySection& accuracy = scene.accuracy;
  if (accuracy.estimate == scene::EstimateChoice::off) {
    plan.reason = "accuracy.estimate: off";
    return plan;
  }
  if (route.model != "reduced") {  // RunRoute::model: the word run.json writes
    if (accuracy.estimate == scene::EstimateChoice::on) {
      throw InputError(scene.where("accuracy.estimate") + ": expected auto or off with transient.model: full (each "
                       "refinement run of the full model costs as much as the run or more; transient.model: auto or "
                       "reduced estimates the signature), got on");
    }
    plan.reason = "the full model: its refinement runs would cost more than the run (transient.model: auto or reduced "
                  "estimates the signature)";
    return plan;
  }
  plan.estimate = true;
  plan.tolerance = accuracy.tolerance;
  if (!plan.tolerance && route.automatic) plan.tolerance = 0.01;
  return plan;
}

/// One signature of a run: probe quantity `q` (ProbeSignature order) or, for probe < 0, the
/// excitation mode's f_uncracked, f_open, f_bilinear (q = 0, 1, 2).
double signature(const RunOutcome& outcome, int probe, int q) {
  if (probe < 0) {
    if (!outcome.mode) return std::numeric_limits<double>::quiet_NaN();  // not paired on this level
    const ModeSignature& mode = *outcome.mode;
    return q == 0 ? mode.f_uncracked : q == 1 ? mode.f_open : mode.f_bilinear;
  }
  return outcome.probes[probe].value[q];
}

/// Whether the modes component at a setting takes its third band level (the band x4 run): where the
/// two-level component of a probe signature the tolerance counts asks for it (needs_third_band).
bool third_band_level(RefinementRuns& runs, const Setting& setting, const std::vector<std::string>& quantities,
                      std::optional<double> tolerance) {
  const RunOutcome& run = runs.get(setting);
  const RunOutcome& band = runs.get(neighbours(setting, runs.box_mesh()).band);
  for (std::size_t p = 0; p < run.probes.size(); ++p) {
    for (int q = 0; q < 4; ++q) {
      if (std::find(quantities.begin(), quantities.end(), ProbeSignature::kNames[q]) == quantities.end()) continue;
      const double value = signature(run, static_cast<int>(p), q);
      const accuracy::Component modes = modes_component(value, signature(band, static_cast<int>(p), q));
      if (std::isfinite(modes.delta) && needs_third_band(modes.delta, tolerance)) return true;
    }
  }
  return false;
}

/// The components of one signature at a setting (the modes from three band levels where `third_band`).
accuracy::Estimate estimate_of(const std::string& quantity, RefinementRuns& runs, const Setting& setting, int probe, int q,
                               bool third_band) {
  const RunOutcome& run = runs.get(setting);
  const double value = signature(run, probe, q);
  const Neighbours n = neighbours(setting, runs.box_mesh());
  std::vector<accuracy::Component> components;
  if (probe < 0 && n.coarse) {
    // A frequency: Richardson in DOFs^-1/3 with Fs = 3, as crackle modal's (docs/benchmarks.md 11.9).
    components.push_back(frequency_levels_component(n, setting, [&](const Setting& level) {
      const RunOutcome& outcome = runs.get(level);
      return std::pair{signature(outcome, probe, q), outcome.mode ? outcome.mode->dofs : 0.0};
    }));
  } else {
    components.push_back(n.coarse ? mesh_component(value, true, signature(runs.get(*n.coarser), probe, q),
                                                   signature(runs.get(*n.coarse), probe, q), runs.box_mesh())
                                  : mesh_component(value, false, 0.0, 0.0, runs.box_mesh()));
  }
  if (probe >= 0) {  // the modal stage does not depend on the reduced model's settings
    components.push_back(modes_component(value, signature(runs.get(n.band), probe, q),
                                         third_band ? signature(runs.get(n.band_twice), probe, q)
                                                    : std::numeric_limits<double>::quiet_NaN()));
    components.push_back(accuracy::one_refinement("steps", value, signature(runs.get(n.steps), probe, q), 2.0, 2.0));
    if (runs.has_contact()) {
      components.push_back(accuracy::one_refinement("penalty", value, signature(runs.get(n.penalty), probe, q), 4.0, 1.0));
    }
    // The start transient decays geometrically from window to window: the last three windows give
    // its rate and what is left of it (Richardson over windows), the rate never faster than the
    // damping's slowest decay; two windows only: their change.
    const ProbeSignature& windows = run.probes[probe];
    const double slowest_ratio = std::exp(run.slowest_decay_per_s * windows.window_s);
    components.push_back(accuracy::window_tail("window", windows.window_before[q], windows.previous_window[q], value,
                                               slowest_ratio));
  }
  return accuracy::combine(quantity, value, components);
}

/// Every signature's estimate at a setting, with the largest error among the tolerance's
/// quantities and the component that contributes most to it.
struct SettingEstimate {
  nlohmann::json probes = nlohmann::json::object();
  nlohmann::json mode;
  std::vector<std::pair<std::string, accuracy::Estimate>> lines;  ///< for the terminal
  SettingSummary summary;                                          ///< of the tolerance's quantities
};

SettingEstimate estimate_setting(RefinementRuns& runs, const Setting& setting, const std::vector<std::string>& quantities,
                                 std::optional<double> tolerance) {
  SettingEstimate result;
  const bool third_band = third_band_level(runs, setting, quantities, tolerance);
  const RunOutcome& run = runs.get(setting);
  auto counts = [&](const std::string& quantity) {
    return std::find(quantities.begin(), quantities.end(), quantity) != quantities.end();
  };
  auto take = [&](const accuracy::Estimate& estimate, bool in_tolerance) {
    if (in_tolerance) add_to_summary(estimate, result.summary);
  };
  for (std::size_t p = 0; p < run.probes.size(); ++p) {
    nlohmann::json probe_json = nlohmann::json::object();
    for (int q = 0; q < 4; ++q) {
      const std::string quantity = ProbeSignature::kNames[q];
      const accuracy::Estimate estimate = estimate_of(quantity, runs, setting, static_cast<int>(p), q, third_band);
      probe_json[quantity] = output::estimate_json(estimate);
      take(estimate, counts(quantity));
      if (q < 3) result.lines.push_back({run.probes[p].name, estimate});
    }
    result.probes[run.probes[p].name] = probe_json;
  }
  if (run.mode) {
    result.mode = {{"mode", run.mode->mode}};
    static const char* names[3] = {"f_uncracked", "f_open", "f_bilinear"};
    for (int q = 0; q < 3; ++q) {
      const accuracy::Estimate estimate = estimate_of(names[q], runs, setting, -1, q, false);
      result.mode[names[q]] = output::estimate_json(estimate);
      if (q == 2) {
        take(estimate, counts("f_b"));
        result.lines.push_back({"mode " + std::to_string(run.mode->mode), estimate});
      }
    }
  }
  return result;
}

/// The next setting the tolerance refines to: the component with the largest error per second of
/// its refinement run, or empty with `blocking` saying why none can go on.
std::optional<Setting> refine(RefinementRuns& runs, const Setting& setting, const SettingSummary& summary, double budget_left,
                              std::optional<double> tolerance, std::string& blocking) {
  const Neighbours n = neighbours(setting, runs.box_mesh());
  std::vector<RefinementChoice> choices;
  const double here = runs.get(setting).wall_s;
  if (n.coarse) {
    const double growth = here / std::max(1e-3, runs.get(*n.coarse).wall_s);
    choices.push_back(mesh_choice(setting, runs.scene(), here * growth));
  }
  choices.push_back({"modes", n.band, runs.get(n.band).wall_s, ""});
  choices.push_back({"steps", n.steps, runs.get(n.steps).wall_s, ""});
  if (runs.has_contact()) choices.push_back({"penalty", n.penalty, runs.get(n.penalty).wall_s, ""});
  // A longer run on the same mesh: the model and modal stage are shared, so it costs about what the
  // twice-the-steps run did, times two for the longer steady state.
  choices.push_back({"window", n.window, 2.0 * runs.get(n.steps).wall_s, ""});
  return choose_refinement(choices, summary, budget_left, "none (no component has an error left)", blocking, tolerance);
}

}  // namespace

nlohmann::json route_json(const RunRoute& route) {
  nlohmann::json json = {{"model", route.model}, {"automatic", route.automatic}, {"reason", route.reason}};
  if (route.own_mesh) {
    json["mesh"] = {{"cells", route.cells}, {"order", route.order}, {"grading", "always"}};
    json["scene_mesh"] = {{"cells", route.scene_cells}, {"order", route.scene_order}};
  }
  return json;
}

void run_with_accuracy(const scene::Scene& scene, const RunRoute& route, const std::vector<scene::Override>& overrides,
                       const RunCommandOptions& options, std::ostream& out) {
  Stopwatch total;
  const fs::path& directory = options.output_directory;
  const nlohmann::json route_json = pipeline::route_json(route);
  if (route.automatic) out << "route: " << route.reason << "\n";
  const EstimatePlan plan = accuracy_plan(scene, route);
  if (!plan.estimate) {
    const RunOutcome outcome = run_scene(scene, options, out);
    nlohmann::json accuracy = {{"estimated", false}, {"reason", plan.reason}};
    on_writer_rank([&] {
      if (outcome.spectrum) {
        nlohmann::json spectrum = *outcome.spectrum;
        spectrum["accuracy"] = accuracy;
        io::write_json(directory / "spectrum.json", spectrum);
      }
      write_run_json(scene, directory, outcome, route_json, accuracy, total.seconds());
    });
    // An accuracy: section that this run cannot honour is said, not ignored.
    if (scene.has_accuracy_section) std::cerr << "crackle: note: accuracy: not estimated: " << plan.reason << "\n";
    if (!options.accuracy_start.empty()) {
      std::cerr << "crackle: note: --accuracy-start " << options.accuracy_start.string()
                << " not used: the signatures are not estimated (" << plan.reason << ")\n";
    }
    out << "wrote " << (directory / "run.json").string() << "\n";
    return;
  }
  RefinementRuns runs(scene, overrides, options, out);
  Setting setting;
  setting.order = scene.box.order;
  Setting start = tolerance_start(setting, options.accuracy_start, plan, runs.box_mesh(), out);  // checked first
  start.harmonics = 0;  // a sweep's, where the file is a sweep.json: a run has no harmonics to refine
  const RunOutcome& first = runs.get(setting, true);
  const double run_s = first.wall_s;
  if (first.probes.empty()) throw SolverError(scene.file + ": accuracy: the run has no probe signatures to estimate");
  setting = start;  // the scene's own run first all the same: the refinements' base band and penalty are its
  const std::vector<std::string>& quantities = scene.accuracy.quantities;
  SettingEstimate estimate = estimate_setting(runs, setting, quantities, plan.tolerance);
  const ToleranceOutcome outcome = reach_tolerance(
      plan.tolerance, setting, estimate.summary,
      [&](const Setting& from, std::string& blocking) {
        return refine(runs, from, estimate.summary, scene.accuracy.budget_s - total.seconds(), plan.tolerance, blocking);
      },
      [&](const Setting& at) {
        estimate = estimate_setting(runs, at, quantities, plan.tolerance);
        return estimate.summary;
      },
      [&](const Setting& at) { return runs.describe(at); }, out);
  const RunOutcome& chosen = runs.get(setting);
  runs.adopt(setting);
  for (const auto& [where, line] : estimate.lines) out << "accuracy " << where << ": " << accuracy::estimate_line(line) << "\n";
  const double wall = total.seconds();
  nlohmann::json accuracy = accuracy_summary(runs.describe(setting), plan.tolerance, quantities, scene.accuracy.budget_s,
                                             estimate.summary, outcome, runs.runs_json(), run_s, runs.refinement_s(), wall);
  accuracy["method"] = "one refinement per component from the setting run (DETECTION.md sec. 1): mesh: the two lower "
                       "element orders (Richardson with the observed rate per order, GCI safety factor 1.25, 3 where "
                       "not asymptotic); modes: twice the band, read at order 2, and four times where that change "
                       "is above a tenth of the tolerance (of 0.01 without one): three levels with the observed order "
                       "(Fs 1.25 for an order in [1.33, 4], else 3); steps: twice per period; penalty: four times; window: "
                       "the start transient left in the last window, from the last three windows (Richardson over windows, "
                       "the decay ratio never faster than the damping's slowest, decay_ratio_bound). delta: signed relative "
                       "error of the value, " + std::string(output::kEstimateFields);
  accuracy["reached"] = setting_json(setting);
  if (!options.accuracy_start.empty() && plan.tolerance) accuracy["started_from"] = options.accuracy_start.string();
  accuracy["probes"] = estimate.probes;
  if (!estimate.mode.is_null()) accuracy["mode"] = estimate.mode;
  on_writer_rank([&] {
    nlohmann::json spectrum = *chosen.spectrum;
    spectrum["accuracy"] = accuracy;
    io::write_json(directory / "spectrum.json", spectrum);
    // run.json: the summary alone
    nlohmann::json summary = accuracy;
    for (const char* detail : {"method", "probes", "mode", "runs", "quantities", "budget_s", "tolerance"}) summary.erase(detail);
    write_run_json(scene, directory, chosen, route_json, summary, wall);
  });
  print_accuracy_end(out, plan.tolerance, outcome, estimate.summary, quantities, runs.runs_json().size() - 1, "runs",
                     runs.refinement_s(), wall);
  out << "wrote " << (directory / "run.json").string() << "\n";
}

}  // namespace crackle::pipeline
