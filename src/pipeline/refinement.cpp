#include "pipeline/refinement.hpp"

#include <unistd.h>

#include <cmath>
#include <cstdio>
#include <iomanip>
#include <ostream>
#include <set>

#include "core/errors.hpp"
#include "io/files.hpp"
#include "mesh/box.hpp"
#include "pipeline/modal_accuracy.hpp"
#include "plot/gnuplot.hpp"

namespace crackle::pipeline {

namespace fs = std::filesystem;

std::string Setting::key() const {
  return "p" + std::to_string(order) + "-l" + std::to_string(layers) + "-b" + std::to_string(band) + "-s" +
         std::to_string(steps) + "-k" + std::to_string(penalty) + "-h" + std::to_string(harmonics) + "-w" +
         std::to_string(window);
}

Setting finer_mesh(const Setting& setting) {
  Setting finer = setting;
  if (finer.order < kHighestOrder) finer.order += 1;
  else finer.layers += 1;
  return finer;
}

Neighbours neighbours(const Setting& setting, bool box_mesh) {
  Neighbours n;
  if (box_mesh && setting.order >= 3) {
    n.coarse = setting;
    n.coarse->order -= 1;
    n.coarser = setting;
    n.coarser->order -= 2;
  }
  n.band = n.steps = n.penalty = n.harmonics = n.window = setting;
  n.window.window += 1;
  n.band.band += 1;
  n.band_twice = n.band;
  n.band_twice.band += 1;
  n.steps.steps += 1;
  n.penalty.penalty += 1;
  n.harmonics.harmonics += 1;
  return n;
}

std::optional<scene::Override> penalty_override(const Setting& setting, double base_penalty) {
  if (!setting.penalty) return std::nullopt;
  return scene::Override{"crack.contact.penalty", format_number(base_penalty * (1 << (2 * setting.penalty)))};
}

std::string describe_setting(const Setting& setting, bool box_mesh) {
  std::string text = box_mesh ? "order " + std::to_string(setting.order) : std::string("the Gmsh mesh");
  if (setting.layers) text += ", front layers +" + std::to_string(setting.layers);
  if (setting.band) text += ", band x" + std::to_string(1 << setting.band);
  if (setting.steps) text += ", steps x" + std::to_string(1 << setting.steps);
  if (setting.penalty) text += ", penalty x" + std::to_string(1 << (2 * setting.penalty));
  if (setting.window) text += ", steady state / " + format_number(std::pow(10.0, setting.window));
  return text;
}

std::vector<scene::Override> order_and_band_overrides(const scene::Scene& scene, const Setting& setting,
                                                      double base_max_frequency_hz) {
  std::vector<scene::Override> levels;
  if (scene.gmsh_file.empty()) {
    levels.push_back({"mesh.box.order", std::to_string(setting.order)});
    if (setting.layers > 0 && scene.crack) {
      mesh::BoxSpec box = scene.box;
      box.order = setting.order;
      box.grading = scene.grading.grading;
      const int layers = mesh::resolve_grading(box, *scene.crack).layers;
      levels.push_back({"mesh.box.grading.layers", std::to_string(layers + setting.layers)});
    }
  }
  if (setting.band) {
    const int modes = scene.transient->reduced.modes;
    if (modes > 0) levels.push_back({"transient.reduced.modes", std::to_string(modes << setting.band)});
    else levels.push_back({"transient.reduced.max_frequency", format_number(base_max_frequency_hz * (1 << setting.band))});
  }
  return levels;
}

accuracy::Component frequency_levels_component(const Neighbours& n, const Setting& setting,
                                               const std::function<std::pair<double, double>(const Setting&)>& value_and_dofs) {
  std::vector<double> values, dofs;
  for (const Setting& level : {*n.coarser, *n.coarse, setting}) {
    const auto [value, free_dofs] = value_and_dofs(level);
    values.push_back(value);
    dofs.push_back(free_dofs);
  }
  return frequency_mesh_component({n.coarser->order, n.coarse->order, setting.order}, values, dofs, setting.order);
}

accuracy::Component missing_component(const std::string& name, double value) {
  accuracy::Component component;
  component.name = name;
  component.value = component.refined = value;
  component.verified = component.asymptotic = false;
  component.reason = name + ": the refinement lacks this quantity (a peak or event that moved out of the range "
                            "or changed its kind)";
  return component;
}

bool needs_third_band(double two_level_delta, std::optional<double> tolerance) {
  return std::abs(two_level_delta) > kThirdBandShare * tolerance.value_or(0.01);
}

accuracy::Component modes_component(double value, double band, double band_twice) {
  if (!std::isfinite(band)) return missing_component("modes", value);
  if (!std::isfinite(band_twice)) return accuracy::one_refinement("modes", value, band, 2.0, kModesOrder);
  const double first = band - value, last = band_twice - band;
  if (first * last < 0.0 && std::abs(first) >= kSettledRatio * std::abs(last)) {
    accuracy::Component settled = accuracy::one_refinement("modes", value, band_twice, 4.0, 0.0);  // Fs 3
    settled.ratio = first / last;
    settled.asymptotic = false;
    settled.reason = "modes (band, x2, x4): settled with a wiggle (the last change " + format_number(last / first) +
                     " of the first): three times the change to the band x4";
    return settled;
  }
  accuracy::Component modes =
      accuracy::three_level_at("modes", value, band, band_twice, 1, 2.0, kModesOrderMin, kModesOrderMax);
  modes.refined = band_twice;
  if (!modes.reason.empty()) modes.reason = "modes (band, x2, x4): " + modes.reason;
  return modes;
}

accuracy::Component mesh_component(double value, bool levels, double q1, double q2, bool box_mesh) {
  if (levels) {
    if (std::isfinite(q1) && std::isfinite(q2)) {
      return accuracy::three_level("mesh", q1, q2, value, kOrderLevelRatio, kRateMin, kRateMax);
    }
    return missing_component("mesh", value);
  }
  accuracy::Component mesh = missing_component("mesh", value);
  mesh.reason = box_mesh ? "not estimated below element order 3 (the levels are the two lower orders)"
                         : "not estimated on a Gmsh mesh (no refinement family)";
  return mesh;
}

RefinementFolders::RefinementFolders(const fs::path& output_directory, const fs::path& modal_cache)
    : output_(output_directory), scratch_(output_directory / ("accuracy.tmp." + std::to_string(::getpid()))) {
  cache_ = modal_cache.empty() ? scratch_ / "cache" : modal_cache;
}

RefinementFolders::~RefinementFolders() {
  std::error_code ignored;
  fs::remove_all(scratch_, ignored);
}

fs::path RefinementFolders::folder(const Setting& setting, bool first) {
  const fs::path folder = first ? output_ : scratch_ / setting.key();
  if (!first) fs::create_directories(folder);
  folders_[setting.key()] = folder;
  return folder;
}

void RefinementFolders::adopt(const Setting& setting) const {
  const fs::path from = folders_.at(setting.key());
  if (from == output_) return;
  std::set<fs::path> moved;
  for (const fs::directory_entry& entry : fs::directory_iterator(from)) {
    if (!entry.is_regular_file()) continue;
    fs::rename(entry.path(), output_ / entry.path().filename());
    moved.insert(entry.path().filename());
  }
  // A refinement run writes its figures' data and scripts without drawing them (draw_plots): drawn
  // now, over the PNGs of the scene's own run, which are of other data.
  for (const fs::path& name : moved) {
    if (name.extension() != ".gp") continue;
    const fs::path png = fs::path(name).replace_extension(".png");
    if (!moved.count(png)) plot::run_gnuplot(output_ / png, output_ / name, plot::PlotOptions{});
  }
}

namespace {

/// The fields of `accuracy.reached`, as setting_json writes them and read_reached_setting reads them.
constexpr std::pair<const char*, int Setting::*> kSettingFields[] = {
    {"order", &Setting::order}, {"layers", &Setting::layers},     {"band", &Setting::band},
    {"steps", &Setting::steps}, {"penalty", &Setting::penalty}, {"harmonics", &Setting::harmonics},
    {"window", &Setting::window}};

}  // namespace

nlohmann::json setting_json(const Setting& setting) {
  nlohmann::json json = nlohmann::json::object();
  for (const auto& [name, field] : kSettingFields) json[name] = setting.*field;
  return json;
}

namespace {

/// The setting of a run.json or sweep.json `accuracy.reached`.
Setting read_reached_setting(const fs::path& file) {
  nlohmann::json document;
  try {
    document = nlohmann::json::parse(io::read_file(file));
  } catch (const nlohmann::json::exception& error) {
    throw InputError(file.string() + ": expected the JSON of an earlier crackle run or sweep (run.json or "
                     "sweep.json), got a file that does not parse (" + error.what() + ")");
  }
  const nlohmann::json* reached = nullptr;
  if (document.is_object() && document.contains("accuracy") && document["accuracy"].is_object() &&
      document["accuracy"].contains("reached"))
    reached = &document["accuracy"]["reached"];
  if (!reached || !reached->is_object()) {
    throw InputError(file.string() + ": accuracy.reached: expected the setting an estimate reached (the run.json or "
                     "sweep.json of a crackle run or sweep whose signatures were estimated), not found");
  }
  Setting setting;
  for (const auto& [name, field] : kSettingFields) {
    const nlohmann::json& value = reached->contains(name) ? (*reached)[name] : nlohmann::json();
    if (!value.is_number_integer() || value.get<int>() < 0 || value.get<int>() > 16) {
      throw InputError(file.string() + ": accuracy.reached." + name + ": expected an integer from 0 to 16, got " +
                       (value.is_null() ? std::string("nothing") : value.dump()));
    }
    setting.*field = value.get<int>();
  }
  return setting;
}

}  // namespace

Setting tolerance_start(const Setting& own, const fs::path& start_file, const EstimatePlan& plan, bool box_mesh,
                        std::ostream& out) {
  if (start_file.empty()) return own;
  if (!plan.tolerance) {
    out << "accuracy: note: --accuracy-start " << start_file.string()
        << " not used: the estimate has no tolerance to reach (accuracy.tolerance)\n";
    return own;
  }
  Setting start = read_reached_setting(start_file);
  if (start.order < own.order) {
    throw InputError(start_file.string() + ": accuracy.reached.order: expected at least the scene's element order " +
                     std::to_string(own.order) + " (an estimate on the same mesh), got " + std::to_string(start.order));
  }
  if (!box_mesh && (start.order != own.order || start.layers != 0)) {
    throw InputError(start_file.string() + ": accuracy.reached: expected a setting of this Gmsh mesh (order " +
                     std::to_string(own.order) + ", no front layers), got order " + std::to_string(start.order) +
                     " with " + std::to_string(start.layers) + " front layers");
  }
  if (start.key() != own.key()) {
    out << "accuracy: the tolerance starts at " << describe_setting(start, box_mesh) << " (reached by "
        << start_file.string() << ")\n";
  }
  return start;
}

void add_to_summary(const accuracy::Estimate& estimate, SettingSummary& summary) {
  summary.worst = std::max(summary.worst, estimate.error);
  summary.verified = summary.verified && estimate.verified;
  for (const accuracy::Component& component : estimate.components) {
    double& largest = summary.largest[component.name];
    largest = std::max(largest, std::abs(component.delta));
  }
}

RefinementChoice mesh_choice(const Setting& setting, const scene::Scene& scene, double cost) {
  RefinementChoice choice{"mesh", finer_mesh(setting), cost, ""};
  if (choice.next.layers > 0 && scene.grading.mode != scene::GradingMode::always) {
    choice.blocked = "mesh (the highest element order, " + std::to_string(kHighestOrder) +
                     ", is reached on a mesh that is not graded: finer cells, mesh.box.cells, or mesh.box.grading: "
                     "always, whose front layers the refinement adds)";
  } else if (choice.next.layers > kMostExtraLayers) {
    choice.blocked = "mesh (the highest element order, " + std::to_string(kHighestOrder) + ", and " +
                     std::to_string(kMostExtraLayers) + " more front layers are reached; finer cells: mesh.box.cells "
                     "with transient.model: reduced)";
  }
  return choice;
}

std::optional<Setting> choose_refinement(const std::vector<RefinementChoice>& choices, const SettingSummary& summary,
                                         double budget_left, const std::string& nothing_left, std::string& blocking,
                                         std::optional<double> tolerance) {
  const auto part = [&](const RefinementChoice& choice) {
    const auto found = summary.largest.find(choice.name);
    return found == summary.largest.end() ? 0.0 : found->second;
  };
  const RefinementChoice* best = nullptr;
  double best_rate = -1.0;
  // A component too small to meet the tolerance by itself is not refined first however cheap it is
  // (a band at 0.007 % of an estimate of 0.29 % against 0.2 %: its run and its neighbours' bought
  // nothing, and the loop's path followed the run times).
  if (tolerance) {
    for (const RefinementChoice& choice : choices) {
      if (part(choice) > 0.0 && summary.worst - part(choice) <= *tolerance && (!best || choice.cost < best->cost))
        best = &choice, best_rate = part(choice) / std::max(1e-3, choice.cost);
    }
  }
  if (!best) {
    for (const RefinementChoice& choice : choices) {
      const double rate = part(choice) / std::max(1e-3, choice.cost);
      if (rate > best_rate) best_rate = rate, best = &choice;
    }
  }
  if (!best || best_rate <= 0.0) {
    blocking = nothing_left;
    return std::nullopt;
  }
  if (!best->blocked.empty()) {
    blocking = best->blocked;
    return std::nullopt;
  }
  if (best->name == "window" && best->next.window > kMostWindowRefinements) {
    blocking = "window (the steady state tightened " + std::to_string(kMostWindowRefinements) +
               " times; raise spectrum.steady_state.min_periods or transient.periods)";
    return std::nullopt;
  }
  if (best->cost > budget_left) {
    blocking = best->name + " (its refinement run, about " + format_number(std::round(best->cost)) +
               " s, exceeds what is left of accuracy.budget)";
    return std::nullopt;
  }
  return best->next;
}

ToleranceOutcome reach_tolerance(std::optional<double> tolerance, Setting& setting, SettingSummary& summary,
                                 const std::function<std::optional<Setting>(const Setting&, std::string&)>& refine,
                                 const std::function<SettingSummary(const Setting&)>& summarize,
                                 const std::function<std::string(const Setting&)>& describe, std::ostream& out) {
  ToleranceOutcome outcome;
  if (!tolerance) return outcome;
  while (true) {
    if (summary.worst <= *tolerance && summary.verified) {
      outcome.met = true;
      return outcome;
    }
    outcome.met = false;
    if (!summary.verified) {
      outcome.blocking = "an estimate that is not verified (see reasons)";
      return outcome;
    }
    const std::optional<Setting> next = refine(setting, outcome.blocking);
    if (!next) return outcome;
    out << "accuracy: largest estimate " << percent(summary.worst) << " > tolerance " << percent(*tolerance)
        << ": refining to " << describe(*next) << "\n";
    setting = *next;
    summary = summarize(setting);
  }
}

nlohmann::json accuracy_summary(const std::string& setting, std::optional<double> tolerance,
                                const std::vector<std::string>& quantities, double budget_s,
                                const SettingSummary& summary, const ToleranceOutcome& outcome,
                                const nlohmann::json& runs, double run_s, double estimate_s, double wall_s) {
  return output::accuracy_json({setting, tolerance, quantities, budget_s, summary.worst, summary.verified, outcome.met,
                                outcome.blocking, runs, run_s, estimate_s, wall_s});
}

void print_accuracy_end(std::ostream& out, std::optional<double> tolerance, const ToleranceOutcome& outcome,
                        const SettingSummary& summary, const std::vector<std::string>& quantities, std::size_t runs,
                        const std::string& noun, double estimate_s, double wall_s) {
  if (tolerance) {
    out << "accuracy: tolerance " << percent(*tolerance) << (*outcome.met ? " met" : " not met")
        << " (largest estimate " << percent(summary.worst) << " on " << nlohmann::json(quantities).dump() << ")";
    if (!outcome.blocking.empty()) out << ", blocked by " << outcome.blocking;
    out << "\n";
  }
  out << "accuracy: " << runs << " refinement " << noun << ", " << std::setprecision(3) << estimate_s << " s ("
      << std::setprecision(2) << 100.0 * estimate_s / wall_s << " % of the " << std::setprecision(3) << wall_s
      << " s)\n";
}

std::string percent(double value) {
  char text[32];
  std::snprintf(text, sizeof text, "%.2g %%", 100.0 * value);
  return text;
}

}  // namespace crackle::pipeline
