/// \file `crackle run`: the whole pipeline of a scene, each stage only if the scene needs it:
/// modal (only when something refers to a mode or the scene asks for modal output) -> transient
/// (with contact only when there is a crack) -> spectrum (harmonics, damage indices, plots).
#include <cmath>
#include <iomanip>
#include <iostream>
#include <set>

#include "commands.hpp"
#include "core/errors.hpp"
#include "core/resources.hpp"
#include "io/csv.hpp"
#include "io/files.hpp"
#include "io/vtu.hpp"
#include "model.hpp"
#include "modal/modal.hpp"
#include "spectral/harmonics.hpp"
#include "spectral/plot.hpp"
#include "spectral/signature.hpp"
#include "spectral/spectrum.hpp"
#include "transient/damping.hpp"
#include "transient/excitation.hpp"
#include "transient/solver.hpp"

namespace crackle::app {
namespace {

namespace fs = std::filesystem;

/// One line of run.json: a stage, whether it ran, why, and its time.
struct Stage {
  std::string name;
  bool ran = false;
  std::string reason;
  double seconds = 0.0;
};

/// The modal variants the scene needs (empty: no modal stage).
std::vector<mesh::Variant> needed_variants(const scene::Scene& scene, std::string& reason) {
  std::set<mesh::Variant> variants;
  const scene::TransientSection& transient = *scene.transient;
  if (transient.excitation && transient.excitation->mode > 0) {
    const std::string& of = transient.excitation->of;
    if (of != "open") variants.insert(mesh::Variant::uncracked);
    if (of != "uncracked") variants.insert(mesh::Variant::open);
    reason = "transient.excitation.frequency refers to mode " + std::to_string(transient.excitation->mode);
  }
  if (transient.damping.at_mode > 0) {
    variants.insert(mesh::Variant::uncracked);
    if (reason.empty()) reason = "transient.damping.at refers to mode " + std::to_string(transient.damping.at_mode);
  }
  if (scene.has_modal_section) {
    for (const std::string& name : scene.modal.variants) {
      variants.insert(name == "open" ? mesh::Variant::open : mesh::Variant::uncracked);
    }
    if (reason.empty()) reason = "the scene has a modal: section";
  }
  // Keep the uncracked limit first, as the modal module lists it.
  std::vector<mesh::Variant> ordered;
  for (mesh::Variant variant : {mesh::Variant::uncracked, mesh::Variant::open}) {
    if (variants.count(variant)) ordered.push_back(variant);
  }
  return ordered;
}

/// Frequency [Hz] of elastic mode `mode` (1-based) of the given kind from a modal result.
double mode_frequency(const modal::ModalResult& result, int mode, const std::string& of, const std::string& key) {
  const int index = mode - 1;
  if (of == "bilinear") {
    if (index >= static_cast<int>(result.pairs.size())) {
      throw InputError(key + ": mode " + std::to_string(mode) + " asked, but only " +
                       std::to_string(result.pairs.size()) + " modes were paired (raise modal.modes)");
    }
    const modal::ModePair& pair = result.pairs[index];
    if (!pair.paired) {
      throw InputError(key + ": mode " + std::to_string(mode) + " has no open partner among the " +
                       std::to_string(result.mac.cols()) + " open modes computed (best MAC " +
                       format_number(pair.mac) + " < " + format_number(modal::kPairingMac) +
                       "), so its bilinear frequency is undefined (raise modal.modes)");
    }
    return pair.f_bilinear_hz;
  }
  const modal::VariantResult* variant =
      result.find(of == "open" ? mesh::Variant::open : mesh::Variant::uncracked);
  if (!variant || index >= variant->modes.n_modes()) {
    throw InputError(key + ": mode " + std::to_string(mode) + " of the " + of + " body asked, but only " +
                     std::to_string(variant ? variant->modes.n_modes() : 0) + " modes were computed");
  }
  return variant->modes.frequencies_hz[index];
}

std::vector<Index> nodes_in_range(const mesh::Mesh& mesh, const scene::InitialSection& initial) {
  std::vector<Index> nodes;
  for (Index node = 0; node < mesh.n_nodes(); ++node) {
    bool inside = true;
    for (int axis = 0; axis < 3; ++axis) {
      if (!initial.range[axis]) continue;
      const double x = mesh.nodes[node][axis];
      inside = inside && x >= (*initial.range[axis])[0] && x <= (*initial.range[axis])[1];
    }
    if (inside) nodes.push_back(node);
  }
  return nodes;
}

/// Per probe: the analysed component's accumulator.
struct ProbeSpectrum {
  std::string name;
  int component = 2;
  std::unique_ptr<spectral::HarmonicAccumulator> accumulator;
};

}  // namespace

void run_run_command(const RunCommandOptions& options, std::ostream& out) {
  Stopwatch total;
  const scene::Scene scene = scene::load_scene(options.scene_path, parse_overrides(options.overrides));
  if (!scene.transient) {
    throw InputError(scene.file + ": transient: expected a transient section for crackle run (crackle modal "
                     "computes modes alone), got none");
  }
  const scene::TransientSection& section = *scene.transient;
  const fs::path directory = options.output_directory;
  io::ensure_directory(directory);
  Model model = build_model(scene);
  std::vector<Stage> stages;
  nlohmann::json run_json = {{"scene", scene.file}, {"output", directory.string()}};

  // ---- Stage 1: modal, only if something needs it.
  Stage modal_stage{"modal", false, "", 0.0};
  std::optional<modal::ModalResult> modes;
  const std::vector<mesh::Variant> variants = needed_variants(scene, modal_stage.reason);
  if (!variants.empty()) {
    Stopwatch clock;
    modal::ModalOptions modal_settings = modal_options(scene.modal);
    modal_settings.variants = variants;
    int highest = scene.has_modal_section ? scene.modal.modes : 1;
    if (section.excitation) highest = std::max(highest, section.excitation->mode);
    modal_settings.modes = std::max(highest, section.damping.at_mode);
    modal_settings.cache_directory = options.modal_cache;
    modes = modal::run_modal(model.mesh, model.materials, model.dirichlet, modal_settings);
    modal::write_modal_outputs(directory, model.mesh, *modes);
    modal_stage.ran = true;
    modal_stage.seconds = clock.seconds();
    out << modal::modal_table(*modes);
  } else {
    modal_stage.reason = "nothing refers to a mode";
  }
  stages.push_back(modal_stage);

  // ---- Excitation frequency and damping from the scene (and the modes).
  double frequency = 0.0;
  transient::TransientProblem problem;
  problem.materials = model.materials;
  problem.dirichlet = model.dirichlet;
  if (section.excitation) {
    const scene::ExcitationSection& excitation = *section.excitation;
    transient::ExternalLoad load;
    load.name = "transient.excitation";
    if (!excitation.face.empty()) load.faces = model.mesh.face_sets.at(excitation.face);
    if (!excitation.group.empty()) load.nodes = model.mesh.node_sets.at(excitation.group);  // checked by build_model
    if (excitation.point) load.nodes = {transient::nearest_node(model.mesh, *excitation.point)};
    load.direction = Vec3::Unit(excitation.direction);
    load.amplitude = excitation.amplitude;
    if (excitation.kind == "harmonic") {
      frequency = excitation.frequency_hz
                      ? *excitation.frequency_hz
                      : excitation.ratio * mode_frequency(*modes, excitation.mode, excitation.of,
                                                          scene.file + ": transient.excitation.frequency.mode");
      load.signal.kind = transient::SignalKind::harmonic;
      load.signal.frequency = frequency;
      load.signal.ramp_periods = excitation.ramp_periods;
    } else {
      load.signal.kind = transient::SignalKind::pulse;
      load.signal.duration = excitation.duration;
    }
    problem.loads.push_back(load);
  }
  transient::TransientOptions settings;
  if (section.damping.ratio) {
    const double at_hz = section.damping.at_hz ? *section.damping.at_hz
                                               : mode_frequency(*modes, section.damping.at_mode, "uncracked",
                                                                scene.file + ": transient.damping.at.mode");
    const double omega = 2.0 * M_PI * at_hz;
    settings.damping = section.damping.type == "stiffness"
                           ? transient::stiffness_proportional_damping(*section.damping.ratio, omega)
                           : transient::mass_proportional_damping(*section.damping.ratio, omega);
  } else {
    settings.damping.alpha = section.damping.alpha;
    settings.damping.beta = section.damping.beta;
  }
  settings.variant = section.variant == "open" ? mesh::Variant::open : mesh::Variant::uncracked;
  if (settings.variant == mesh::Variant::open && model.mesh.has_crack()) {
    contact::ContactOptions contact;
    contact.initial_gap = scene.crack ? scene.crack->gap : (scene.crack_group ? scene.crack_group->gap : 0.0);
    contact.normal_penalty = scene.contact.penalty.value_or(0.0);
    contact.friction_coefficient = scene.contact.friction;
    contact.integration = scene.contact.integration == "explicit" ? contact::ContactIntegration::explicit_forces
                                                                  : contact::ContactIntegration::implicit;
    problem.contact = contact;
  }
  const mesh::DofMap run_dofs = mesh::make_dof_map(model.mesh, settings.variant);
  for (const scene::InitialSection& initial : section.initial) {
    const std::vector<Index> nodes = nodes_in_range(model.mesh, initial);
    const VectorX velocity = transient::uniform_on_nodes(run_dofs, nodes, initial.velocity);
    const VectorX displacement = transient::uniform_on_nodes(run_dofs, nodes, initial.displacement);
    if (problem.initial.velocity.size() == 0) problem.initial.velocity = VectorX::Zero(run_dofs.n_dofs());
    if (problem.initial.displacement.size() == 0) problem.initial.displacement = VectorX::Zero(run_dofs.n_dofs());
    problem.initial.velocity += velocity;
    problem.initial.displacement += displacement;
  }
  for (const scene::ProbeSection& probe : section.probes) {
    problem.probes.push_back({probe.name, transient::nearest_node(model.mesh, probe.point)});
  }
  // A hair beyond the last period, so that rounding in n dt cannot leave it one step short.
  settings.end_time = section.periods ? *section.periods / frequency * (1.0 + 1e-9) : *section.duration;
  settings.time_step = section.time_step.value_or(0.0);
  settings.time_step_options.safety_factor = section.safety_factor;
  settings.force_time_step = section.force_time_step;
  if (frequency > 0.0) settings.whole_steps_per_period = 1.0 / frequency;
  settings.progress = section.progress && options.progress;
  settings.output_directory = directory;

  // ---- Stage 2: transient, with the harmonic accumulators fed every step when a spectrum is asked.
  Stage transient_stage{"transient", true, "the scene has a transient: section"};
  Stopwatch transient_clock;
  transient::TransientSolver solver(model.mesh, problem, settings);
  std::vector<ProbeSpectrum> spectra;
  spectral::HarmonicOptions harmonic_options;
  spectral::SteadyStateCriterion criterion;
  std::optional<spectral::SteadyState> steady;
  int window_periods = 0;
  if (scene.spectrum) {
    harmonic_options.excitation_frequency_hz = frequency;
    harmonic_options.max_order = scene.spectrum->harmonics;
    harmonic_options.subharmonics = scene.spectrum->subharmonics;
    window_periods = scene.spectrum->window_periods + (scene.spectrum->subharmonics && scene.spectrum->window_periods % 2);
    criterion.window_periods = window_periods;
    criterion.tolerance = scene.spectrum->tolerance > 0.0 ? scene.spectrum->tolerance : 1e-300;
    for (const scene::ProbeSection& probe : section.probes) {
      ProbeSpectrum spectrum;
      spectrum.name = probe.name;
      spectrum.component = probe.component >= 0 ? probe.component : section.excitation->direction;
      spectrum.accumulator =
          std::make_unique<spectral::HarmonicAccumulator>(harmonic_options, solver.dt(), 0.0);
      spectra.push_back(std::move(spectrum));
    }
  }
  transient::TransientCallbacks callbacks;
  // Displacement snapshots (VTU) at evenly spaced steps, only when asked.
  std::vector<Index> snapshot_steps;
  for (int k = 1; k <= section.snapshots; ++k) {
    snapshot_steps.push_back(std::max<Index>(1, solver.n_steps() * k / section.snapshots) - 1);
  }
  std::size_t next_snapshot = 0;
  const mesh::DofMap& dofs = solver.dofs();
  auto write_snapshot = [&](const transient::StepView& view) {
    io::PointField field{"displacement", 3, std::vector<double>(3 * static_cast<std::size_t>(model.mesh.n_nodes()))};
    for (Index node = 0; node < model.mesh.n_nodes(); ++node) {
      for (int c = 0; c < 3; ++c) field.values[3 * node + c] = view.displacement[dofs.dof(node, c)];
    }
    char name[32];
    std::snprintf(name, sizeof name, "snapshot_%04zu.vtu", next_snapshot);
    io::write_vtu(directory / name, model.mesh, {field});
  };
  std::function<bool(const transient::StepView&)> spectrum_step;
  callbacks.on_step = [&](const transient::StepView& view) {
    if (next_snapshot < snapshot_steps.size() && view.step >= snapshot_steps[next_snapshot]) {
      write_snapshot(view);
      ++next_snapshot;
    }
    return spectrum_step ? spectrum_step(view) : false;
  };
  if (!spectra.empty()) {
    const int min_periods = std::max(scene.spectrum->min_periods, 2 * window_periods);
    spectrum_step = [&](const transient::StepView& view) {
      int completed = 0;
      for (std::size_t p = 0; p < spectra.size(); ++p) {
        completed = spectra[p].accumulator->add(view.time, view.probe_sample[9 * p + spectra[p].component]);
      }
      if (completed == 0 || scene.spectrum->tolerance <= 0.0) return false;
      const int periods = spectra.front().accumulator->n_periods();
      if (periods < min_periods) return false;
      // Settled when every probe's table has settled.
      spectral::SteadyState verdict;
      verdict.settled = true;
      verdict.periods_used = periods;
      verdict.change = 0.0;
      for (const ProbeSpectrum& spectrum : spectra) {
        const spectral::SteadyState state = spectrum.accumulator->steady_state(criterion);
        verdict.settled = verdict.settled && state.settled;
        verdict.change = std::max(verdict.change, state.change);
      }
      steady = verdict;
      return verdict.settled;
    };
  }
  const transient::TransientSummary& summary = solver.run(callbacks);
  transient::write_transient_outputs(directory, solver);
  transient_stage.seconds = transient_clock.seconds();
  stages.push_back(transient_stage);
  out << "transient: " << summary.steps << " steps of " << summary.dt << " s (dt_critical " << summary.dt_critical
      << " s), " << summary.status << ", energy error " << summary.energy_error << ", " << std::setprecision(3)
      << summary.wall_s << " s\n";

  // ---- Stage 3: spectrum.
  Stage spectrum_stage{"spectrum", false, "", 0.0};
  if (scene.spectrum) {
    Stopwatch clock;
    spectrum_stage.ran = true;
    spectrum_stage.reason = "the scene has a spectrum: section";
    nlohmann::json spectrum_json = {{"excitation_hz", frequency}, {"amplitude_convention",
                                    "peak amplitude A_k of x(t) = A_0 + sum A_k cos(2 pi k f t + phi_k), t from the start of the run"}};
    // Close the record: grid points of the last period still waiting for stencil samples.
    for (ProbeSpectrum& spectrum : spectra) spectrum.accumulator->finish();
    const int periods = spectra.front().accumulator->n_periods();
    const int used = std::min(window_periods, periods - (harmonic_options.subharmonics ? periods % 2 : 0));
    if (used < 1) {
      throw SolverError(scene.file + ": spectrum: the run completed " + std::to_string(periods) +
                        " excitation periods, too few for a harmonic table (raise transient.periods)");
    }
    spectral::SteadyState state = steady.value_or(spectral::SteadyState{});
    state.periods_used = periods;
    state.limit_reached = !state.settled;
    nlohmann::json probes_json = nlohmann::json::object();
    const transient::ProbeHistory& history = solver.probes();
    const double sample_step = history.time.size() > 1 ? history.time[1] - history.time[0] : solver.dt();
    spectral::SpectrumAnalyzer analyzer;
    spectral::PlotOptions plot;
    for (std::size_t p = 0; p < spectra.size(); ++p) {
      const spectral::HarmonicTable table = spectra[p].accumulator->last_table(used);
      const std::string component = axis_name(spectra[p].component);
      probes_json[spectra[p].name] = spectral::probe_json(component, table);
      const std::vector<double>& values = history.values[9 * p + spectra[p].component];
      spectral::SpectrumOptions spectrum_options;
      spectrum_options.excitation_frequency_hz = frequency;
      spectrum_options.periods = used;
      spectrum_options.subharmonics = harmonic_options.subharmonics;
      const spectral::Sampling sampling{sample_step, history.time.empty() ? 0.0 : history.time.front()};
      const spectral::AmplitudeSpectrum amplitude = analyzer.amplitude_spectrum(values, sampling, spectrum_options);
      io::write_file_atomic(directory / ("spectrum_" + spectra[p].name + ".csv"), spectral::spectrum_csv(amplitude, "m"));
      if (scene.spectrum->plots) {
        plot.title = spectra[p].name + " u_" + component;
        const auto history_plot = spectral::plot_time_history(directory / ("history_" + spectra[p].name + ".png"), values, sampling, plot);
        const auto spectrum_plot = spectral::plot_spectrum(directory / ("spectrum_" + spectra[p].name + ".png"), amplitude, frequency,
                                                           spectral::harmonic_orders(harmonic_options), plot);
        if (!history_plot.written) out << "note: no plots (" << history_plot.note << ")\n";
        (void)spectrum_plot;
      }
      const spectral::DamageIndices indices = spectral::damage_indices(table);
      out << "spectrum " << spectra[p].name << " (u_" << component << "): A1 = " << table.amplitude(1) << " m, A2/A1 = "
          << indices.a2_over_a1 << ", A3/A1 = " << indices.a3_over_a1;
      if (harmonic_options.subharmonics) out << ", A1/2/A1 = " << indices.a_half_over_a1;
      out << "\n";
    }
    spectrum_json["probes"] = probes_json;
    spectrum_json["steady_state"] = spectral::steady_state_json(state);
    spectrum_json["steady_state"]["window_periods"] = used;
    io::write_json(directory / "spectrum.json", spectrum_json);
    spectrum_stage.seconds = clock.seconds();
  } else {
    spectrum_stage.reason = "the scene has no spectrum: section";
  }
  stages.push_back(spectrum_stage);

  nlohmann::json stage_list = nlohmann::json::array();
  for (const Stage& stage : stages) {
    stage_list.push_back({{"name", stage.name}, {"ran", stage.ran}, {"reason", stage.reason}, {"seconds", stage.seconds}});
  }
  run_json["stages"] = stage_list;
  run_json["excitation_hz"] = frequency;
  run_json["wall_s"] = total.seconds();
  io::write_json(directory / "run.json", run_json);
  out << "wrote " << (directory / "run.json").string() << "\n";
}

}  // namespace crackle::app
