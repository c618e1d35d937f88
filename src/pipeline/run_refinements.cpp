#include "pipeline/run_refinements.hpp"

#include <cmath>
#include <iomanip>
#include <ostream>

#include "core/errors.hpp"
#include "pipeline/distributed_run.hpp"

namespace crackle::pipeline {

RefinementRuns::RefinementRuns(const scene::Scene& scene, const std::vector<scene::Override>& overrides,
                               const RunCommandOptions& options, std::ostream& out)
    : scene_(scene), overrides_(overrides), options_(options), out_(out),
      folders_(options.output_directory, options.modal_cache) {}

const RunOutcome& RefinementRuns::get(const Setting& setting, bool first) {
  const auto found = outcomes_.find(setting.key());
  if (found != outcomes_.end()) return found->second;
  RunCommandOptions options = options_;
  options.modal_cache = folders_.cache();
  options.output_directory = folders_.folder(setting, first);
  std::vector<scene::Override> overrides = overrides_;
  if (!first) {
    for (const scene::Override& level : level_overrides(setting)) overrides.push_back(level);
    options.progress = false;
    options.draw_plots = false;  // ~0.1 s a figure; drawn if the run's folder is adopted
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

std::vector<scene::Override> RefinementRuns::level_overrides(const Setting& setting) const {
  const RunOutcome& base = outcomes_.at(first_key_);  // the scene's own run comes first
  std::vector<scene::Override> levels = order_and_band_overrides(scene_, setting, base.max_frequency_hz);
  if (setting.steps) levels.push_back({"transient.reduced.steps_per_period", std::to_string(steps_per_period(setting))});
  if (auto penalty = penalty_override(setting, base.normal_penalty)) levels.push_back(*penalty);
  if (setting.window) {  // the start transient decays further: a tighter steady state, a longer limit
    const double tolerance = scene_.spectrum->tolerance * std::pow(10.0, -setting.window);
    levels.push_back({"spectrum.steady_state.tolerance", format_number(tolerance)});
    if (scene_.transient->periods) {
      levels.push_back({"transient.periods", format_number(*scene_.transient->periods * (1 << (2 * setting.window)))});
    }
  }
  return levels;
}

}  // namespace crackle::pipeline
