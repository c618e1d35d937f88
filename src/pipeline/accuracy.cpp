#include "pipeline/accuracy.hpp"

#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <iostream>
#include <iomanip>
#include <limits>
#include <map>

#include "accuracy/estimate.hpp"
#include "core/errors.hpp"
#include "core/resources.hpp"
#include "io/files.hpp"
#include "pipeline/distributed_run.hpp"
#include "pipeline/run_scene.hpp"

namespace crackle::pipeline {
namespace {

namespace fs = std::filesystem;

/// Rate of the mesh levels: the element order is raised by one per level, so the observed "order"
/// is the rate ln((Q1 - Q2)/(Q2 - Q3)) per order; sane when the error at least halves per order.
constexpr double kOrderLevelRatio = 2.718281828459045;
const double kRateMin = std::log(2.0), kRateMax = 20.0;

/// One setting of the numerical parameters: the element order, and how many times the reduced
/// model's band, the steps per period (each x2) and the penalty (x4) were refined.
struct Setting {
  int order = 0;
  int band = 0, steps = 0, penalty = 0;
  std::string key() const {
    return "p" + std::to_string(order) + "-b" + std::to_string(band) + "-s" + std::to_string(steps) + "-k" +
           std::to_string(penalty);
  }
};

/// Whether and how the scene's signatures are estimated.
struct Plan {
  bool estimate = false;
  std::string reason;  ///< why not
  std::optional<double> tolerance;
};

Plan accuracy_plan(const scene::Scene& scene, const RunRoute& route) {
  Plan plan;
  const std::optional<scene::ExcitationSection>& excitation = scene.transient->excitation;
  if (!scene.spectrum || !excitation || excitation->kind != "harmonic") {
    plan.reason = "no harmonic signature (no spectrum: section or no harmonic excitation)";
    return plan;
  }
  const scene::AccuracySection& accuracy = scene.accuracy;
  if (accuracy.estimate == "off") {
    plan.reason = "accuracy.estimate: off";
    return plan;
  }
  if (route.model != "reduced") {
    if (accuracy.estimate == "on") {
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

/// The runs of one `crackle run` with its estimate: each setting run once, the first (the scene's
/// own) into the output folder with its progress, the others silent in temporary folders.
class Runs {
 public:
  Runs(const scene::Scene& scene, const std::vector<scene::Override>& overrides, const RunCommandOptions& options,
       std::ostream& out)
      : scene_(scene), overrides_(overrides), options_(options), out_(out) {
    scratch_ = options.output_directory / ("accuracy.tmp." + std::to_string(::getpid()));
    cache_ = options.modal_cache.empty() ? scratch_ / "cache" : options.modal_cache;
  }
  ~Runs() {
    std::error_code ignored;
    fs::remove_all(scratch_, ignored);
  }

  /// The outcome of a setting (run now unless it ran before); `first` runs into the output folder.
  const RunOutcome& get(const Setting& setting, bool first = false) {
    const auto found = outcomes_.find(setting.key());
    if (found != outcomes_.end()) return found->second;
    RunCommandOptions options = options_;
    options.modal_cache = cache_;
    std::vector<scene::Override> overrides = overrides_;
    if (!first) {
      for (const scene::Override& level : level_overrides(setting)) overrides.push_back(level);
      options.output_directory = scratch_ / setting.key();
      options.progress = false;
      fs::create_directories(options.output_directory);
    }
    const scene::Scene scene = first ? scene_ : scene::load_scene(options_.scene_path, overrides);
    NullStream silent;
    // Runs that differ only in the reduced model's band, steps or penalty share the model and the
    // modal stage (keyed by the element order, the only mesh setting the levels change).
    reuse_.key = "order " + std::to_string(setting.order);
    RunOutcome outcome = run_scene(scene, options, first ? out_ : silent, &reuse_);
    if (!first) {
      out_ << "accuracy: refinement run " << describe(setting) << ": " << std::setprecision(3) << outcome.wall_s << " s\n";
      refinement_s_ += outcome.wall_s;
    }
    directories_[setting.key()] = options.output_directory;
    runs_.push_back({{"setting", describe(setting)},
                     {"order", setting.order},
                     {"max_frequency_hz", outcome.max_frequency_hz},
                     {"modes", outcome.modes},
                     {"pairs", outcome.pairs},
                     {"steps_per_period", steps_per_period(setting)},
                     {"penalty", outcome.normal_penalty},
                     {"wall_s", outcome.wall_s},
                     {"main", first}});
    if (first) first_key_ = setting.key();
    return outcomes_.emplace(setting.key(), std::move(outcome)).first->second;
  }

  /// Moves the files of a setting's run into the output folder (the setting the tolerance settled on).
  void adopt(const Setting& setting) {
    const fs::path from = directories_.at(setting.key());
    if (from == options_.output_directory) return;
    for (const fs::directory_entry& entry : fs::directory_iterator(from)) {
      if (!entry.is_regular_file()) continue;
      fs::rename(entry.path(), options_.output_directory / entry.path().filename());
    }
  }

  std::string describe(const Setting& setting) const {
    std::string text = "order " + std::to_string(setting.order);
    if (setting.band) text += ", band x" + std::to_string(1 << setting.band);
    if (setting.steps) text += ", steps x" + std::to_string(1 << setting.steps);
    if (setting.penalty) text += ", penalty x" + std::to_string(1 << (2 * setting.penalty));
    return text;
  }
  const nlohmann::json& runs_json() const { return runs_; }
  double refinement_s() const { return refinement_s_; }
  bool box_mesh() const { return scene_.gmsh_file.empty(); }
  /// Whether the run has contact pairs whose penalty can be refined.
  bool has_contact() const { return outcomes_.at(first_key_).normal_penalty > 0.0; }
  const scene::Scene& scene() const { return scene_; }

 private:
  int steps_per_period(const Setting& setting) const {
    return scene_.transient->reduced.steps_per_period << setting.steps;
  }
  std::vector<scene::Override> level_overrides(const Setting& setting) const {
    std::vector<scene::Override> levels;
    const RunOutcome& base = outcomes_.at(first_key_);  // the scene's own run comes first
    if (box_mesh()) levels.push_back({"mesh.box.order", std::to_string(setting.order)});
    if (setting.band) {
      const int modes = scene_.transient->reduced.modes;
      if (modes > 0) levels.push_back({"transient.reduced.modes", std::to_string(modes << setting.band)});
      else levels.push_back({"transient.reduced.max_frequency", format_number(base.max_frequency_hz * (1 << setting.band))});
    }
    if (setting.steps) levels.push_back({"transient.reduced.steps_per_period", std::to_string(steps_per_period(setting))});
    if (setting.penalty) {
      levels.push_back({"crack.contact.penalty", format_number(base.normal_penalty * (1 << (2 * setting.penalty)))});
    }
    return levels;
  }

  const scene::Scene& scene_;
  std::vector<scene::Override> overrides_;
  RunCommandOptions options_;
  std::ostream& out_;
  fs::path scratch_, cache_;
  std::map<std::string, RunOutcome> outcomes_;
  std::string first_key_;
  RunReuse reuse_;
  std::map<std::string, fs::path> directories_;
  nlohmann::json runs_ = nlohmann::json::array();
  double refinement_s_ = 0.0;
};

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

/// The runs each component of a setting's estimate needs.
struct Neighbours {
  std::optional<Setting> coarse, coarser;  ///< the two lower orders (mesh)
  Setting band, steps, penalty;
};

Neighbours neighbours(const Setting& setting, bool box_mesh) {
  Neighbours n;
  if (box_mesh && setting.order >= 3) {
    n.coarse = setting;
    n.coarse->order -= 1;
    n.coarser = setting;
    n.coarser->order -= 2;
  }
  n.band = n.steps = n.penalty = setting;
  n.band.band += 1;
  n.steps.steps += 1;
  n.penalty.penalty += 1;
  return n;
}

/// The components of one signature at a setting.
accuracy::Estimate estimate_of(const std::string& quantity, Runs& runs, const Setting& setting, int probe, int q) {
  const RunOutcome& run = runs.get(setting);
  const double value = signature(run, probe, q);
  const Neighbours n = neighbours(setting, runs.box_mesh());
  std::vector<accuracy::Component> components;
  if (n.coarse) {
    components.push_back(accuracy::three_level("mesh", signature(runs.get(*n.coarser), probe, q),
                                               signature(runs.get(*n.coarse), probe, q), value, kOrderLevelRatio,
                                               kRateMin, kRateMax));
  } else {
    accuracy::Component mesh;
    mesh.name = "mesh";
    mesh.value = mesh.refined = value;
    mesh.verified = mesh.asymptotic = false;
    mesh.reason = runs.box_mesh() ? "not estimated below element order 3 (the levels are the two lower orders)"
                                  : "not estimated on a Gmsh mesh (no refinement family)";
    components.push_back(mesh);
  }
  if (probe >= 0) {  // the modal stage does not depend on the reduced model's settings
    components.push_back(accuracy::one_refinement("modes", value, signature(runs.get(n.band), probe, q), 2.0, 2.0));
    components.push_back(accuracy::one_refinement("steps", value, signature(runs.get(n.steps), probe, q), 2.0, 2.0));
    if (runs.has_contact()) {
      components.push_back(accuracy::one_refinement("penalty", value, signature(runs.get(n.penalty), probe, q), 4.0, 1.0));
    }
    // The start transient decays geometrically from window to window: the last three windows give
    // its rate and what is left of it (Richardson over windows); two windows only: their change.
    const double previous = run.probes[probe].previous_window[q], before = run.probes[probe].window_before[q];
    accuracy::Component window;
    if (std::isfinite(before)) {
      window = accuracy::three_level("window", before, previous, value, kOrderLevelRatio, kRateMin, kRateMax);
    } else {
      window = accuracy::one_refinement("window", value, std::isfinite(previous) ? 2.0 * value - previous : value, 1.0, 0.0);
      window.asymptotic = false;
      window.reason = "fewer than three analysis windows (the change from the window before, three times)";
    }
    // A decay that is not geometric over the last windows (beats) is bounded by three times the last
    // change (Fs = 3), not a failed refinement: counted as verified, marked not asymptotic.
    if (!window.verified) {
      window.verified = true;
      window.reason = "the start transient's decay is not geometric over the last three windows (" + window.reason +
                      "): three times the last change";
    }
    components.push_back(window);
  }
  return accuracy::combine(quantity, value, components);
}

nlohmann::json component_json(const accuracy::Component& component) {
  nlohmann::json json = {{"delta", component.delta},
                         {"refined", component.refined},
                         {"safety_factor", component.safety_factor},
                         {"verified", component.verified},
                         {"asymptotic", component.asymptotic}};
  if (component.ratio != 0.0) {
    json["levels_ratio"] = component.ratio;
    json["observed_rate"] = component.observed_order;
  }
  if (!component.reason.empty()) json["reason"] = component.reason;
  return json;
}

nlohmann::json estimate_json(const accuracy::Estimate& estimate) {
  nlohmann::json components = nlohmann::json::object();
  for (const accuracy::Component& component : estimate.components) components[component.name] = component_json(component);
  return {{"value", estimate.value},   {"error", estimate.sum},         {"rss", estimate.rss},
          {"verified", estimate.verified}, {"asymptotic", estimate.asymptotic}, {"reasons", estimate.reasons},
          {"components", components}};
}

/// Every signature's estimate at a setting, with the largest error among the tolerance's
/// quantities and the component that contributes most to it.
struct SettingEstimate {
  nlohmann::json probes = nlohmann::json::object();
  nlohmann::json mode;
  std::vector<std::pair<std::string, accuracy::Estimate>> lines;  ///< for the terminal
  double worst = 0.0;                                              ///< largest sum among the tolerance's quantities
  bool verified = true;                                            ///< of those quantities
  std::map<std::string, double> largest;                           ///< per component, largest |delta| among them
};

SettingEstimate estimate_setting(Runs& runs, const Setting& setting, const std::vector<std::string>& quantities) {
  SettingEstimate result;
  const RunOutcome& run = runs.get(setting);
  auto counts = [&](const std::string& quantity) {
    return std::find(quantities.begin(), quantities.end(), quantity) != quantities.end();
  };
  auto take = [&](const accuracy::Estimate& estimate, bool in_tolerance) {
    if (!in_tolerance) return;
    result.worst = std::max(result.worst, estimate.sum);
    result.verified = result.verified && estimate.verified;
    for (const accuracy::Component& component : estimate.components) {
      double& largest = result.largest[component.name];
      largest = std::max(largest, std::abs(component.delta));
    }
  };
  for (std::size_t p = 0; p < run.probes.size(); ++p) {
    nlohmann::json probe_json = nlohmann::json::object();
    for (int q = 0; q < 4; ++q) {
      const std::string quantity = ProbeSignature::kNames[q];
      const accuracy::Estimate estimate = estimate_of(quantity, runs, setting, static_cast<int>(p), q);
      probe_json[quantity] = estimate_json(estimate);
      take(estimate, counts(quantity));
      if (q < 3) result.lines.push_back({run.probes[p].name, estimate});
    }
    result.probes[run.probes[p].name] = probe_json;
  }
  if (run.mode) {
    result.mode = {{"mode", run.mode->mode}};
    static const char* names[3] = {"f_uncracked", "f_open", "f_bilinear"};
    for (int q = 0; q < 3; ++q) {
      const accuracy::Estimate estimate = estimate_of(names[q], runs, setting, -1, q);
      result.mode[names[q]] = estimate_json(estimate);
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
std::optional<Setting> refine(Runs& runs, const Setting& setting, const SettingEstimate& estimate, double budget_left,
                              std::string& blocking) {
  const Neighbours n = neighbours(setting, runs.box_mesh());
  struct Choice {
    std::string name;
    Setting next;
    double cost;
  };
  std::vector<Choice> choices;
  const double here = runs.get(setting).wall_s;
  if (n.coarse) {
    Setting finer = setting;
    finer.order += 1;
    const double growth = here / std::max(1e-3, runs.get(*n.coarse).wall_s);
    choices.push_back({"mesh", finer, here * growth});
  }
  choices.push_back({"modes", n.band, runs.get(n.band).wall_s});
  choices.push_back({"steps", n.steps, runs.get(n.steps).wall_s});
  if (runs.has_contact()) choices.push_back({"penalty", n.penalty, runs.get(n.penalty).wall_s});
  const Choice* best = nullptr;
  double best_rate = -1.0;
  for (const Choice& choice : choices) {
    const auto found = estimate.largest.find(choice.name);
    const double rate = (found == estimate.largest.end() ? 0.0 : found->second) / std::max(1e-3, choice.cost);
    if (rate > best_rate) best_rate = rate, best = &choice;
  }
  if (!best || best_rate <= 0.0) {
    blocking = "window (the steady-state window change; raise spectrum.steady_state.min_periods or lower its tolerance)";
    return std::nullopt;
  }
  if (best->name == "mesh" && best->next.order > 4) {
    blocking = "mesh (the highest element order, 4, is reached; finer cells: mesh.box.cells with transient.model: reduced)";
    return std::nullopt;
  }
  if (best->cost > budget_left) {
    blocking = best->name + " (its refinement run, about " + format_number(std::round(best->cost)) +
               " s, exceeds what is left of accuracy.budget)";
    return std::nullopt;
  }
  return best->next;
}

std::string percent(double value) {
  char text[32];
  std::snprintf(text, sizeof text, "%.2g %%", 100.0 * value);
  return text;
}

}  // namespace

void run_with_accuracy(const scene::Scene& scene, const RunRoute& route, const std::vector<scene::Override>& overrides,
                       const RunCommandOptions& options, std::ostream& out) {
  Stopwatch total;
  const fs::path& directory = options.output_directory;
  nlohmann::json route_json = {{"model", route.model}, {"automatic", route.automatic}, {"reason", route.reason}};
  if (route.own_mesh) {
    route_json["mesh"] = {{"cells", route.cells}, {"order", route.order}, {"grading", "always"}};
    route_json["scene_mesh"] = {{"cells", route.scene_cells}, {"order", route.scene_order}};
  }
  if (route.automatic) out << "route: " << route.reason << "\n";
  const Plan plan = accuracy_plan(scene, route);
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
    out << "wrote " << (directory / "run.json").string() << "\n";
    return;
  }
  Runs runs(scene, overrides, options, out);
  Setting setting;
  setting.order = scene.box.order;
  const RunOutcome& first = runs.get(setting, true);
  const double run_s = first.wall_s;
  if (first.probes.empty()) throw SolverError(scene.file + ": accuracy: the run has no probe signatures to estimate");
  SettingEstimate estimate = estimate_setting(runs, setting, scene.accuracy.quantities);
  std::optional<bool> met;
  std::string blocking;
  if (plan.tolerance) {
    while (true) {
      if (estimate.worst <= *plan.tolerance && estimate.verified) {
        met = true;
        break;
      }
      met = false;
      if (!estimate.verified) {
        blocking = "an estimate that is not verified (see reasons)";
        break;
      }
      const double left = scene.accuracy.budget_s - total.seconds();
      const std::optional<Setting> next = refine(runs, setting, estimate, left, blocking);
      if (!next) break;
      setting = *next;
      out << "accuracy: largest estimate " << percent(estimate.worst) << " > tolerance " << percent(*plan.tolerance)
          << ": refining to " << runs.describe(setting) << "\n";
      estimate = estimate_setting(runs, setting, scene.accuracy.quantities);
    }
  }
  const RunOutcome& chosen = runs.get(setting);
  runs.adopt(setting);
  for (const auto& [where, line] : estimate.lines) out << "accuracy " << where << ": " << accuracy::estimate_line(line) << "\n";
  const double wall = total.seconds();
  nlohmann::json accuracy = {{"estimated", true},
                             {"method", "one refinement per component from the setting run (DETECTION.md sec. 1): mesh: "
                                        "the two lower element orders (Richardson with the observed rate per order, "
                                        "GCI safety factor 1.25, 3 where not asymptotic); modes: twice the band; "
                                        "steps: twice per period; penalty: four times; window: the change from the "
                                        "window before. delta: signed relative error of the value, error: sum of "
                                        "|delta|, rss: root-sum-square"},
                             {"setting", runs.describe(setting)},
                             {"tolerance", plan.tolerance ? nlohmann::json(*plan.tolerance) : nlohmann::json(nullptr)},
                             {"quantities", scene.accuracy.quantities},
                             {"budget_s", scene.accuracy.budget_s},
                             {"error", estimate.worst},
                             {"verified", estimate.verified},
                             {"probes", estimate.probes},
                             {"runs", runs.runs_json()},
                             {"run_s", run_s},
                             {"estimate_s", runs.refinement_s()},
                             {"share", wall > 0.0 ? runs.refinement_s() / wall : 0.0}};
  if (met) accuracy["met"] = *met;
  if (!blocking.empty()) accuracy["blocking"] = blocking;
  if (!estimate.mode.is_null()) accuracy["mode"] = estimate.mode;
  on_writer_rank([&] {
    nlohmann::json spectrum = *chosen.spectrum;
    spectrum["accuracy"] = accuracy;
    io::write_json(directory / "spectrum.json", spectrum);
    nlohmann::json summary = {{"estimated", true}, {"setting", runs.describe(setting)}, {"error", estimate.worst},
                              {"verified", estimate.verified}, {"run_s", run_s}, {"estimate_s", runs.refinement_s()},
                              {"share", accuracy["share"]}};
    if (met) summary["met"] = *met;
    if (!blocking.empty()) summary["blocking"] = blocking;
    write_run_json(scene, directory, chosen, route_json, summary, wall);
  });
  if (plan.tolerance) {
    out << "accuracy: tolerance " << percent(*plan.tolerance) << (*met ? " met" : " not met") << " (largest estimate "
        << percent(estimate.worst) << " on " << nlohmann::json(scene.accuracy.quantities).dump() << ")";
    if (!blocking.empty()) out << ", blocked by " << blocking;
    out << "\n";
  }
  out << "accuracy: " << runs.runs_json().size() - 1 << " refinement runs, " << std::setprecision(3)
      << runs.refinement_s() << " s (" << std::setprecision(2) << 100.0 * runs.refinement_s() / wall
      << " % of the " << std::setprecision(3) << wall << " s)\n";
  out << "wrote " << (directory / "run.json").string() << "\n";
}

}  // namespace crackle::pipeline
