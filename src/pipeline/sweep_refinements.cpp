#include "pipeline/sweep_refinements.hpp"

#include <algorithm>
#include <iomanip>
#include <ostream>

#include "core/resources.hpp"
#include "pipeline/distributed_run.hpp"

namespace crackle::pipeline {

const std::vector<std::pair<std::string, std::string>>& sweep_peak_keys() {
  static const std::vector<std::pair<std::string, std::string>> keys = {
      {"peak_a1", "A1"}, {"peak_a2_over_a1", "A2/A1"}, {"peak_a3_over_a1", "A3/A1"}, {"peak_a_half_over_a1", "A1/2/A1"}};
  return keys;
}

RefinementSweeps::RefinementSweeps(const scene::Scene& scene, const std::vector<scene::Override>& overrides,
                                   const SweepCommandOptions& options, std::ostream& out, std::ostream& progress)
    : scene_(scene), overrides_(overrides), options_(options), out_(out), progress_(progress),
      folders_(options.output_directory, options.modal_cache) {}

const SweepOutcome& RefinementSweeps::get(const Setting& setting, bool first) {
  const auto found = outcomes_.find(setting.key());
  if (found != outcomes_.end()) return found->second;
  SweepOutcome outcome = sweep(setting, first, nullptr);
  if (first) first_key_ = setting.key();
  return outcomes_.emplace(setting.key(), std::move(outcome)).first->second;
}

const SweepOutcome& RefinementSweeps::near(const Setting& setting) {
  const auto full = outcomes_.find(setting.key());
  if (full != outcomes_.end()) return full->second;
  const auto found = windowed_.find(setting.key());
  if (found != windowed_.end()) return found->second;
  if (windows_.windows.empty()) return get(setting);
  SweepOutcome outcome = sweep(setting, false, &windows_);
  std::string why;
  if (!windows_hold(windows_, outcome.document, why)) {
    out_ << "accuracy: refinement sweep " << describe(setting) << ": " << why << ": swept again over the whole range\n";
    return get(setting);
  }
  return windowed_.emplace(setting.key(), std::move(outcome)).first->second;
}

double RefinementSweeps::cost_s(const Setting& setting) {
  const SweepOutcome& outcome = near(setting);
  if (outcomes_.count(setting.key())) return outcome.wall_s;
  const nlohmann::json& document = outcome.document;
  const double solve = document.at("solve_s"), points = std::max(1.0, document.at("points").get<double>());
  return outcome.wall_s - solve + solve * outcomes_.at(first_key_).document.at("points").get<double>() / points;
}

std::string RefinementSweeps::describe(const Setting& setting) const {
  return describe_setting(setting, box_mesh()) + ", H = " + std::to_string(harmonics(setting));
}

SweepOutcome RefinementSweeps::sweep(const Setting& setting, bool first, const SweepWindows* windows) {
  SweepCommandOptions options = options_;
  options.modal_cache = folders_.cache();
  options.output_directory = folders_.folder(setting, first);
  std::vector<scene::Override> overrides = overrides_;
  if (!first) {
    for (const scene::Override& level : level_overrides(setting, windows != nullptr)) overrides.push_back(level);
    options.progress = false;
    options.draw_plots = false;  // drawn if the sweep's folder is adopted (RefinementFolders::adopt)
    if (windows) {
      options.windows = windows->windows;
      options.window_starts = starts_;
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
  if (first) {
    // The refinements' windows, each started from this sweep's branch there (the same pair rows:
    // band, H, penalty). Only those gaps are kept: the branch's points hold pair rows x (2H + 1)
    // values each.
    std::vector<std::string> peaks;
    for (const auto& [key, quantity] : sweep_peak_keys()) peaks.push_back(key);
    windows_ = sweep_windows(outcome.document, peaks);
    const nlohmann::json& at = outcome.document.at("settings");
    starts_ = window_starts(outcome.result, at.at("from_hz"), at.at("to_hz"), at.at("harmonics"), windows_.windows);
    if (windows_.windows.empty()) {
      out_ << "accuracy: refinement sweeps over the whole range: " << windows_.reason << "\n";
    } else {
      out_ << "accuracy: refinement sweeps over " << windows_.windows.size() << " windows around the peaks ("
           << std::setprecision(3) << 100.0 * windows_.covered << " % of the range)\n";
    }
  }
  outcome.result = SweepResult();
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

double RefinementSweeps::base_penalty() const {
  return outcomes_.at(first_key_).document.at("model").value("normal_penalty", 0.0);
}

std::vector<scene::Override> RefinementSweeps::level_overrides(const Setting& setting, bool windowed) const {
  const double base = outcomes_.at(first_key_).document.at("model").at("max_frequency_hz").get<double>();
  std::vector<scene::Override> levels = order_and_band_overrides(scene_, setting, base);
  levels.push_back({"sweep.harmonics", std::to_string(harmonics(setting))});
  if (auto penalty = penalty_override(setting, base_penalty())) levels.push_back(*penalty);
  // Half the points: the peaks are read off a parabola through the three points around them, which
  // moves them by less than 1e-6 between 200 and 100 points on the beam (docs/benchmarks.md 11.6),
  // far below the changes the refinements measure; the continuation costs about half.
  // A windowed sweep keeps the scene's points: its windows are short, and the same step as the
  // main sweep's leaves the parabola's sampling out of the difference.
  if (scene_.sweep->method == scene::SweepMethod::harmonic_balance && !windowed) {
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

const nlohmann::json& RefinementSweeps::base_events() const {
  return outcomes_.at(first_key_).document.at("events");
}

}  // namespace crackle::pipeline
