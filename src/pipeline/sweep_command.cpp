/// \file `crackle sweep`: scene -> model -> modal stage (only for mode-relative ranges or a modal:
/// section) -> reduced model -> harmonic balance or stepped sine -> sweep.csv, sweep.json, plots.
#include <cmath>
#include <iomanip>
#include <iostream>

#include "core/errors.hpp"
#include "core/resources.hpp"
#include "io/csv.hpp"
#include "io/files.hpp"
#include "pipeline/commands.hpp"
#include "pipeline/limits.hpp"
#include "pipeline/placement.hpp"
#include "pipeline/reduced_model.hpp"
#include "pipeline/stages.hpp"
#include "pipeline/sweep.hpp"
#include "pipeline/sweep_accuracy.hpp"

namespace crackle::pipeline {
namespace {

namespace fs = std::filesystem;

/// One end of the range in Hz; the bilinear frequency of its mode in `bilinear_hz` when it names one.
double end_frequency(const scene::Scene& scene, const scene::SweepFrequencySection& end,
                     const std::optional<modal::ModalResult>& modes, const std::string& key, double& bilinear_hz) {
  if (end.hz) return *end.hz;
  const std::string where = scene.file + ": " + key + ".mode";
  if (bilinear_hz == 0.0 && scene.has_crack()) bilinear_hz = mode_frequency(*modes, end.mode, scene::ModeOf::bilinear, where);
  return end.ratio * mode_frequency(*modes, end.mode, end.of, where);
}

SweepSettings resolve_settings(const scene::Scene& scene, const std::optional<modal::ModalResult>& modes) {
  SweepSettings settings;
  settings.section = *scene.sweep;
  settings.from_hz = end_frequency(scene, scene.sweep->from, modes, "sweep.frequency.from", settings.bilinear_hz);
  settings.to_hz = end_frequency(scene, scene.sweep->to, modes, "sweep.frequency.to", settings.bilinear_hz);
  if (settings.from_hz == settings.to_hz) {
    throw InputError(scene.file + ": sweep.frequency: expected two different frequencies, got " +
                     format_number(settings.from_hz) + " Hz for both");
  }
  settings.probes = sweep_probes(scene);
  return settings;
}

/// A progress line on stderr, rewritten in place.
SweepProgress progress_line(std::ostream& progress, bool enabled) {
  if (!enabled) return SweepProgress();
  return [&progress](const SweepResult& result, double fraction) {
    const SweepPoint& point = result.points.back();
    progress << "\rsweep: " << std::setw(5) << result.points.size() << " points, " << std::setprecision(6)
             << point.frequency_hz() << " Hz, " << std::setw(3) << std::lround(100.0 * std::clamp(fraction, 0.0, 1.0))
             << " %, " << (point.stability_known ? (point.stable ? "stable  " : "unstable") : "") << std::flush;
  };
}

/// sweep.csv and the plots (sweep.json is written by the caller, with the route and accuracy).
void write_outputs(const fs::path& directory, const SweepResult& result, const SweepSettings& settings,
                   bool draw_plots, std::ostream& out) {
  io::write_csv(directory / "sweep.csv", output::sweep_table(result, file_settings(settings)));
  if (!settings.section.plots) return;
  for (std::size_t p = 0; p < settings.probes.size(); ++p) {
    plot::PlotOptions plot;
    plot.draw = draw_plots;
    plot.title = settings.probes[p].name + " u_" + axis_name(settings.probes[p].component) + ", " +
                 scene::method_name(settings.section.method);
    const plot::PlotResult drawn = plot_sweep(directory / ("sweep_" + settings.probes[p].name + ".png"), result,
                                                  settings, p, plot);
    if (!drawn.written && draw_plots) out << "note: no plot (" << drawn.note << ")\n";
  }
}

void print_summary(const SweepResult& result, const nlohmann::json& document, std::ostream& out) {
  out << "sweep: " << result.points.size() << " points in " << std::setprecision(3) << result.solve_s << " s";
  out << (result.completed ? "" : " (incomplete)") << "\n";
  for (const SweepEvent& event : result.events) out << "  " << event.kind << " at " << event.frequency_hz << " Hz\n";
  for (const auto& [name, probe] : document["probes"].items()) {
    out << "  " << name << ": A2/A1 peaks at " << std::setprecision(6)
        << probe["peak_a2_over_a1"].value("frequency_hz", 0.0) << " Hz ("
        << probe["peak_a2_over_a1"].value("value", 0.0) << ")\n";
  }
  for (const std::string& warning : result.warnings) out << "warning: " << warning << "\n";
}

}  // namespace

/// Pair rows above which a harmonic-balance sweep runs without stability (see run_sweep_command).
constexpr Index kStabilityRowLimit = 1000;

SweepOutcome sweep_scene(const scene::Scene& scene, const SweepCommandOptions& options, std::ostream& out,
                         std::ostream& progress) {
  Stopwatch total;
  const fs::path& directory = options.output_directory;
  // The modal stage (mode-relative ranges) and the reduction's static solves hold K, M and copies.
  check_memory(scene, matrices::eigen_solve);
  io::ensure_directory(directory);
  const Model model = build_model(scene, MeshUse::transient);
  check_points(scene, model);  // a probe outside the body is refused, not read at its nearest node
  Stage modal_stage{"modal", false, "", 0.0};
  const std::optional<modal::ModalResult> modes =
      run_modal_stage(scene, model, directory, options.modal_cache, modal_stage, out, true);
  SweepSettings settings = resolve_settings(scene, modes);
  settings.windows = options.windows;
  settings.window_starts = options.window_starts;

  Stopwatch reduction_clock;
  ReducedModel reduced = build_reduced_model(scene, model, std::max(settings.from_hz, settings.to_hz),
                                                   options.modal_cache);
  check_sweep_memory(scene, reduced.system.n_rows(), reduced.system.n_modes());
  const transient::RayleighDamping damping = scene_damping(scene, modes);
  reduced.system.rayleigh_alpha = damping.alpha;
  reduced.system.rayleigh_beta = damping.beta;
  Stage reduction_stage{"reduction", true, reduced.from_cache ? "reduced model read from the cache" : "built",
                        reduction_clock.seconds()};
  // The monodromy's condensed stiffness factorises the closed rows' flexibility block once per run of
  // samples with one active set (tens per period, n_a^3 / 3 each): beyond kStabilityRowLimit rows that
  // outweighs the solve, so the stability is switched off with a note.
  std::string stability_note;
  if (settings.section.method == scene::SweepMethod::harmonic_balance && settings.section.stability &&
      reduced.system.n_rows() > kStabilityRowLimit) {
    settings.section.stability = false;
    stability_note = "stability switched off: " + std::to_string(reduced.system.n_rows()) +
                     " pair rows, more than the " + std::to_string(kStabilityRowLimit) +
                     " up to which the Floquet multipliers are computed (their condensed contact stiffness costs "
                     "pair rows^3 per active set); the points are not classified stable or unstable";
  }
  const SweepProgress line = progress_line(progress, options.progress);
  SweepResult result = settings.section.method == scene::SweepMethod::stepped_sine
                                 ? stepped_sine_sweep(reduced.system, settings, line)
                                 : harmonic_balance_sweep(reduced.system, settings, line);
  if (options.progress) progress << "\n";
  if (!stability_note.empty()) result.warnings.insert(result.warnings.begin(), stability_note);

  nlohmann::json document = output::sweep_json(result, file_settings(settings));
  const nlohmann::json stages =
      output::stages_json({modal_stage, reduction_stage, Stage{"sweep", true, scene::method_name(settings.section.method), result.solve_s}});
  const Index unknowns = reduced.system.n_rows() * (2 * settings.section.harmonics + 1);
  if (!stability_note.empty()) document["stability_note"] = stability_note;
  document["scene"] = scene.file;
  document["stages"] = stages;
  document["model"] = {{"modes", reduced.modes}, {"pairs", reduced.pairs}, {"pair_rows", reduced.system.n_rows()},
                       {"unknowns", unknowns}, {"max_frequency_hz", reduced.max_frequency_hz},
                       {"normal_penalty", reduced.system.normal_penalty}};
  // the modal stage's size: the frequencies' estimate is Richardson in DOFs^-1/3
  if (modes) document["model"]["free_dofs"] = modes->free_dofs();
  document["seconds_per_point"] = result.points.empty() ? 0.0 : result.solve_s / double(result.points.size());
  write_outputs(directory, result, settings, options.draw_plots, out);
  print_summary(result, document, out);
  document["wall_s"] = total.seconds();
  return {std::move(document), total.seconds(), std::move(result)};
}

void run_sweep_command(const SweepCommandOptions& options, std::ostream& out, std::ostream& progress) {
  std::vector<scene::Override> overrides = parse_overrides(options.overrides);
  const scene::Scene written = scene::load_scene(options.scene_path, overrides);
  if (!written.sweep) {
    throw InputError(written.file + ": sweep: expected a sweep section for crackle sweep (frequency: {from, to}), got none");
  }
  // transient.model: auto gives the sweep's reduced model the automatic route's own mesh, by
  // overrides after the user's, so every later check and message sees the scene that runs.
  const RunRoute route = choose_sweep_route(written);
  overrides.insert(overrides.end(), route.overrides.begin(), route.overrides.end());
  const scene::Scene scene = route.overrides.empty() ? written : scene::load_scene(options.scene_path, overrides);
  sweep_with_accuracy(scene, route, overrides, options, out, progress);
}

}  // namespace crackle::pipeline
