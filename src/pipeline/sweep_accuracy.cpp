#include "pipeline/sweep_accuracy.hpp"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <iomanip>
#include <iostream>
#include <limits>
#include <map>
#include <optional>

#include "accuracy/estimate.hpp"
#include "core/errors.hpp"
#include "core/resources.hpp"
#include "io/files.hpp"
#include "pipeline/accuracy.hpp"
#include "pipeline/distributed_run.hpp"
#include "pipeline/modal_accuracy.hpp"
#include "pipeline/refinement.hpp"
#include "pipeline/sweep_windows.hpp"

namespace crackle::pipeline {
namespace {

namespace fs = std::filesystem;

/// Harmonics added per level of the harmonics refinement (H against H + 2, HYBRID.md sec. 4).
constexpr int kHarmonicsStep = 2;
/// The harmonic-balance truncation error is taken as the change from H to H + 2, three times (an
/// order unknown, Fs = 3): on data/beam.yaml's route the peak A2/A1 at H = 15, 17, 21, 31 is
/// 0.154913, 0.154993, 0.154952, 0.154881, not monotone, so no rate can be fitted to it
/// (docs/benchmarks.md section 11.6).
constexpr double kHarmonicsOrder = 0.0;

EstimatePlan sweep_plan(const scene::Scene& scene, const RunRoute& route) {
  EstimatePlan plan;
  const scene::AccuracySection& accuracy = scene.accuracy;
  if (accuracy.estimate == "off") {
    plan.reason = "accuracy.estimate: off";
    return plan;
  }
  if (accuracy.estimate == "auto" && !route.automatic && !accuracy.tolerance) {
    plan.reason = "the sweep of the scene's mesh as written (" + route.reason.substr(0, route.reason.find(':')) +
                  " not auto): accuracy.estimate: on or an accuracy.tolerance estimates it";
    return plan;
  }
  plan.estimate = true;
  plan.tolerance = accuracy.tolerance;
  if (!plan.tolerance && route.automatic) plan.tolerance = 0.01;
  return plan;
}

/// The peaks of sweep.json `probes` that are estimated, with the quantity each one's value is.
const std::vector<std::pair<std::string, std::string>>& peak_keys() {
  static const std::vector<std::pair<std::string, std::string>> keys = {
      {"peak_a1", "A1"}, {"peak_a2_over_a1", "A2/A1"}, {"peak_a3_over_a1", "A3/A1"}, {"peak_a_half_over_a1", "A1/2/A1"}};
  return keys;
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
    for (const auto& [key, quantity] : peak_keys()) {
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

/// The sweeps of one `crackle sweep` with its estimate: each setting swept once, the first (the
/// scene's own) into the output folder with its progress, the others silent in temporary folders.
class Sweeps {
 public:
  Sweeps(const scene::Scene& scene, const std::vector<scene::Override>& overrides, const SweepCommandOptions& options,
         std::ostream& out, std::ostream& progress)
      : scene_(scene), overrides_(overrides), options_(options), out_(out), progress_(progress),
        folders_(options.output_directory, options.modal_cache) {}

  /// The sweep of a setting over the whole range (the scene's own when `first`).
  const SweepOutcome& get(const Setting& setting, bool first = false) {
    const auto found = outcomes_.find(setting.key());
    if (found != outcomes_.end()) return found->second;
    SweepOutcome outcome = sweep(setting, first, nullptr);
    if (first) first_key_ = setting.key();
    return outcomes_.emplace(setting.key(), std::move(outcome)).first->second;
  }

  /// A refinement of the setting estimated, for its estimate: over the windows around the first
  /// sweep's peaks where every peak stays inside its window (sweep_windows.hpp), else the whole range.
  const SweepOutcome& near(const Setting& setting) {
    const auto full = outcomes_.find(setting.key());
    if (full != outcomes_.end()) return full->second;
    const auto found = windowed_.find(setting.key());
    if (found != windowed_.end()) return found->second;
    if (!windows_) {
      windows_ = sweep_windows(outcomes_.at(first_key_).document, peak_names());
      if (windows_->windows.empty()) {
        out_ << "accuracy: refinement sweeps over the whole range: " << windows_->reason << "\n";
      } else {
        out_ << "accuracy: refinement sweeps over " << windows_->windows.size() << " windows around the peaks ("
             << std::setprecision(3) << 100.0 * windows_->covered << " % of the range)\n";
      }
    }
    if (windows_->windows.empty()) return get(setting);
    SweepOutcome outcome = sweep(setting, false, &*windows_);
    std::string why;
    if (!windows_hold(*windows_, outcome.document, why)) {
      out_ << "accuracy: refinement sweep " << describe(setting) << ": " << why << ": swept again over the whole range\n";
      return get(setting);
    }
    return windowed_.emplace(setting.key(), std::move(outcome)).first->second;
  }

  /// What a sweep of the whole range at a setting costs [s]: its own wall time, or a windowed one's
  /// with its solve scaled to the first sweep's points.
  double cost_s(const Setting& setting) {
    const SweepOutcome& outcome = near(setting);
    if (outcomes_.count(setting.key())) return outcome.wall_s;
    const nlohmann::json& document = outcome.document;
    const double solve = document.at("solve_s"), points = std::max(1.0, document.at("points").get<double>());
    return outcome.wall_s - solve + solve * outcomes_.at(first_key_).document.at("points").get<double>() / points;
  }

  void adopt(const Setting& setting) const { folders_.adopt(setting); }

  std::string describe(const Setting& setting) const {
    return describe_setting(setting, box_mesh()) + ", H = " + std::to_string(harmonics(setting));
  }
  /// The scene's sweep has contact pairs whose penalty can be refined.
  bool has_contact() const { return base_penalty() > 0.0; }
  int harmonics(const Setting& setting) const { return scene_.sweep->harmonics + kHarmonicsStep * setting.harmonics; }
  const nlohmann::json& runs_json() const { return runs_; }
  double refinement_s() const { return refinement_s_; }
  bool box_mesh() const { return scene_.gmsh_file.empty(); }

 private:
  SweepOutcome sweep(const Setting& setting, bool first, const SweepWindows* windows) {
    SweepCommandOptions options = options_;
    options.modal_cache = folders_.cache();
    options.output_directory = folders_.folder(setting, first);
    std::vector<scene::Override> overrides = overrides_;
    if (!first) {
      for (const scene::Override& level : level_overrides(setting, windows != nullptr)) overrides.push_back(level);
      options.progress = false;
      if (windows) {
        options.windows = windows->windows;
        // each window starts from the first sweep's branch there (the same pair rows: band, H, penalty)
        const SweepOutcome& main = outcomes_.at(first_key_);
        const nlohmann::json& at = main.document.at("settings");
        options.window_starts = window_starts(main.result, at.at("from_hz"), at.at("to_hz"), at.at("harmonics"),
                                              windows->windows);
      }
    }
    const scene::Scene scene = first ? scene_ : scene::load_scene(options_.scene_path, overrides);
    NullStream silent;
    SweepOutcome outcome = sweep_scene(scene, options, first ? out_ : silent, first ? progress_ : silent);
    if (!first) {
      out_ << "accuracy: refinement sweep " << describe(setting) << (windows ? " (windows)" : "") << ": "
           << std::setprecision(3) << outcome.wall_s << " s (" << outcome.document.at("points") << " points in "
           << outcome.document.at("solve_s").get<double>() << " s)\n";
      refinement_s_ += outcome.wall_s;
    }
    const nlohmann::json& model = outcome.document.at("model");
    nlohmann::json windows_json = nullptr;
    if (windows) windows_json = outcome.document.at("settings").at("windows");
    runs_.push_back({{"setting", describe(setting)},
                     {"order", setting.order},
                     {"harmonics", harmonics(setting)},
                     {"max_frequency_hz", model.at("max_frequency_hz")},
                     {"penalty", model.value("normal_penalty", 0.0)},
                     {"modes", model.at("modes")},
                     {"pairs", model.at("pairs")},
                     {"points", outcome.document.at("points")},
                     {"windows", windows_json},
                     {"solve_s", outcome.document.at("solve_s")},
                     {"wall_s", outcome.wall_s},
                     {"main", first}});
    return outcome;
  }

  static std::vector<std::string> peak_names() {
    std::vector<std::string> names;
    for (const auto& [key, quantity] : peak_keys()) names.push_back(key);
    return names;
  }

  double base_penalty() const { return outcomes_.at(first_key_).document.at("model").value("normal_penalty", 0.0); }

  std::vector<scene::Override> level_overrides(const Setting& setting, bool windowed) const {
    const double base = outcomes_.at(first_key_).document.at("model").at("max_frequency_hz").get<double>();
    std::vector<scene::Override> levels = order_and_band_overrides(scene_, setting, base);
    levels.push_back({"sweep.harmonics", std::to_string(harmonics(setting))});
    if (auto penalty = penalty_override(setting, base_penalty())) levels.push_back(*penalty);
    // Half the points: the peaks are read off a parabola through the three points around them, which
    // moves them by less than 1e-6 between 200 and 100 points on the beam (docs/benchmarks.md 11.6),
    // far below the changes the refinements measure; the continuation costs about half.
    // A windowed sweep keeps the scene's points: its windows are short, and the same step as the
    // main sweep's leaves the parabola's sampling out of the difference.
    if (scene_.sweep->method == "harmonic_balance" && !windowed) {
      levels.push_back({"sweep.points", std::to_string(std::max(10, scene_.sweep->points / 2))});
    }
    // The Floquet multipliers only find period doublings (folds come from the tangent): without one
    // in the scene's sweep, and without a period-two branch to switch to, the refinements skip them.
    const bool doubling = std::any_of(base_events().begin(), base_events().end(), [](const nlohmann::json& event) {
      return event.at("kind") == "period_doubling";
    });
    if (scene_.sweep->stability && !doubling && scene_.sweep->subharmonic != 2) {
      levels.push_back({"sweep.stability", "false"});
    }
    return levels;
  }

  const nlohmann::json& base_events() const { return outcomes_.at(first_key_).document.at("events"); }

  const scene::Scene& scene_;
  std::vector<scene::Override> overrides_;
  SweepCommandOptions options_;
  std::ostream& out_;
  std::ostream& progress_;
  RefinementFolders folders_;
  std::map<std::string, SweepOutcome> outcomes_;   ///< whole-range sweeps
  std::map<std::string, SweepOutcome> windowed_;   ///< refinement sweeps over windows
  std::optional<SweepWindows> windows_;
  std::string first_key_;
  nlohmann::json runs_ = nlohmann::json::array();
  double refinement_s_ = 0.0;
};

accuracy::Estimate estimate_of(const Quantity& quantity, Sweeps& sweeps, const Setting& setting) {
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
    components.push_back(std::isfinite(band) ? accuracy::one_refinement("modes", value, band, 2.0, 2.0)
                                             : missing_component("modes", value));
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

SettingEstimate estimate_setting(Sweeps& sweeps, const Setting& setting, const std::vector<std::string>& counted) {
  SettingEstimate result;
  for (const Quantity& quantity : quantities_of(sweeps.get(setting).document)) {
    const accuracy::Estimate estimate = estimate_of(quantity, sweeps, setting);
    result.json[nlohmann::json::json_pointer(quantity.pointer)] = estimate_json(estimate);
    if (std::find(counted.begin(), counted.end(), quantity.tolerance_quantity) == counted.end()) continue;
    result.lines.push_back(estimate);
    add_to_summary(estimate, result.summary);
  }
  return result;
}

/// The next setting the tolerance refines to: the component with the largest error per second of
/// its refinement sweep, or empty with `blocking` saying why none can go on.
std::optional<Setting> refine(Sweeps& sweeps, const Setting& setting, const SettingSummary& summary,
                              double budget_left, std::string& blocking) {
  const Neighbours n = neighbours(setting, sweeps.box_mesh());
  std::vector<RefinementChoice> choices;
  const double here = sweeps.get(setting).wall_s;
  if (n.coarse) {
    const Setting finer = finer_mesh(setting);
    choices.push_back({"mesh", finer, here * here / std::max(1e-3, sweeps.cost_s(*n.coarse))});
  }
  choices.push_back({"modes", n.band, sweeps.cost_s(n.band)});
  choices.push_back({"harmonics", n.harmonics, sweeps.cost_s(n.harmonics)});
  if (sweeps.has_contact()) choices.push_back({"penalty", n.penalty, sweeps.cost_s(n.penalty)});
  return choose_refinement(choices, summary, budget_left,
                           sweeps.box_mesh() && !n.coarse ? "mesh (not estimated below element order 3)"
                                                          : "none (no component has an error left)",
                           blocking);
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
    out << "wrote " << (directory / "sweep.json").string() << "\n";
    return;
  }
  io::ensure_directory(directory);
  Sweeps sweeps(scene, overrides, options, out, progress);
  Setting setting;
  setting.order = scene.box.order;
  const double run_s = sweeps.get(setting, true).wall_s;
  // The tolerance applies to accuracy.quantities: each probe's peak values and the bilinear frequency.
  const std::vector<std::string>& counted = scene.accuracy.quantities;
  SettingEstimate estimate = estimate_setting(sweeps, setting, counted);
  const ToleranceOutcome outcome = reach_tolerance(
      plan.tolerance, setting, estimate.summary,
      [&](const Setting& from, std::string& blocking) {
        return refine(sweeps, from, estimate.summary, scene.accuracy.budget_s - total.seconds(), blocking);
      },
      [&](const Setting& at) {
        estimate = estimate_setting(sweeps, at, counted);
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
      "frequency Richardson in DOFs^-1/3, 3); modes: twice the band; harmonics: H + 2 (the change, three times: the "
      "convergence in H is not monotone); penalty: four times it (where the crack has contact); the refinement "
      "sweeps re-solve windows of the range around the peaks at the main sweep's step (runs[].windows, fractions "
      "of the range; where the branch has no fold or period doubling and every peak stays inside its window), else "
      "the whole range at half the points. Estimated: each probe's peaks (value and frequency, the parabola through the "
      "three points around the largest, or the value at a range end), the fold and period-doubling frequencies (by "
      "kind and order along the branch) and the bilinear frequency. delta: signed relative error of the value, "
      "error: sum of |delta|, rss: root-sum-square";
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
