/// \file `crackle run`: the whole pipeline of a scene, each stage only if the scene needs it:
/// modal (only when something refers to a mode or the scene asks for modal output) -> transient
/// (with contact only when there is a crack) -> spectrum (harmonics, damage indices, plots).
#include <cmath>
#include <iomanip>
#include <iostream>

#include "core/errors.hpp"
#include "core/resources.hpp"
#include "io/files.hpp"
#include "modal/modal.hpp"
#include "pipeline/accuracy.hpp"
#include "pipeline/commands.hpp"
#include "pipeline/distributed_run.hpp"
#include "pipeline/limits.hpp"
#include "pipeline/model.hpp"
#include "pipeline/output_folder.hpp"
#include "pipeline/route.hpp"
#include "pipeline/run_scene.hpp"
#include "pipeline/run_stages.hpp"
#include "pipeline/stages.hpp"
#include "transient/solver.hpp"

namespace crackle::pipeline {

namespace fs = std::filesystem;

/// The frequencies of the mode the excitation refers to, when it is paired.
namespace {

std::optional<ModeSignature> excitation_mode(const scene::Scene& scene, const std::optional<modal::ModalResult>& modes) {
  const std::optional<scene::ExcitationSection>& excitation = scene.transient->excitation;
  if (!modes || !excitation || excitation->mode <= 0) return std::nullopt;
  for (const modal::ModePair& pair : modes->pairs) {
    if (!pair.paired || pair.uncracked_mode + 1 != excitation->mode) continue;
    return ModeSignature{excitation->mode, pair.f_uncracked_hz, pair.f_open_hz, pair.f_bilinear_hz,
                         static_cast<double>(modes->free_dofs())};
  }
  return std::nullopt;
}

}  // namespace

RunOutcome run_scene(const scene::Scene& scene, const RunCommandOptions& options, std::ostream& out, RunReuse* reuse) {
  Stopwatch total;
  RunOutcome outcome;
  const fs::path& directory = options.output_directory;
  std::unique_ptr<Model> own_model;
  const bool shared = reuse && reuse->models.count(reuse->key);
  if (!shared) own_model = std::make_unique<Model>(build_model(scene, MeshUse::transient));
  const Model& model = shared ? *reuse->models.at(reuse->key) : *own_model;
  std::vector<Stage>& stages = outcome.stages;

  Stage modal_stage{"modal", false, "", 0.0};
  // The modes of a shared mesh are read where the first run left them (a copy would hold both
  // variants' shapes and mass matrices again).
  std::optional<modal::ModalResult> own_modes;
  const bool shared_modes = shared && reuse->modes.count(reuse->key);
  if (shared_modes) {
    modal_stage = {"modal", reuse->modes.at(reuse->key).has_value(), "shared with the run of the same mesh in this process", 0.0};
  } else {
    own_modes = run_modal_stage(scene, model, directory, options.modal_cache, modal_stage, out,
                                scene.transient->model == scene::TransientModel::reduced);
  }
  const std::optional<modal::ModalResult>& modes = shared_modes ? reuse->modes.at(reuse->key) : own_modes;
  stages.push_back(modal_stage);
  outcome.mode = excitation_mode(scene, modes);

  Stage transient_stage{"transient", true, "the scene has a transient: section (model: " + scene::model_name(scene.transient->model) + ")"};
  Stopwatch transient_clock;
  TransientSetup setup = transient_setup(scene, model, modes, options);
  std::optional<SpectrumMonitor> spectrum;
  std::unique_ptr<transient::TransientSolver> solver;
  transient::ProbeHistory reduced_probes;
  double dt = 0.0;
  if (scene.transient->model == scene::TransientModel::reduced) {
    reduced_probes = run_reduced_stage(scene, model, setup, options, spectrum, dt, outcome, out);
  } else {
    solver = run_transient_stage(scene, model, setup, directory, spectrum);
    dt = solver->dt();
  }
  transient_stage.seconds = transient_clock.seconds();
  stages.push_back(transient_stage);
  if (setup.release) {
    out << "release (" << text_of(scene::kReleaseKindWords, setup.release->kind) << "): largest displacement " << setup.release->largest_displacement
        << " m";
    if (setup.release->n_pairs > 0) {
      out << ", " << setup.release->n_closed << " of " << setup.release->n_pairs << " crack pairs closed after "
          << setup.release->iterations << " active-set iterations";
    }
    out << "\n";
  }
  if (solver) {
    const transient::TransientSummary& summary = solver->summary();
    out << "transient: " << summary.steps << " steps of " << summary.dt << " s (dt_critical " << summary.dt_critical
        << " s), " << summary.status << ", energy error " << summary.energy_error << ", " << std::setprecision(3)
        << summary.wall_s << " s\n";
  }

  Stage spectrum_stage{"spectrum", false, "the scene has no spectrum: section", 0.0};
  if (spectrum) {
    Stopwatch clock;
    spectrum_stage.ran = true;
    spectrum_stage.reason = "the scene has a spectrum: section";
    on_writer_rank([&] { outcome.spectrum = spectrum->write(scene, directory, dt, outcome.probes, out, options.draw_plots); });
    spectrum_stage.seconds = clock.seconds();
  } else if (scene.spectrum) {
    Stopwatch clock;
    spectrum_stage.ran = true;
    spectrum_stage.reason = "the scene has a spectrum: section; no harmonic excitation: ring-down analysis";
    on_writer_rank([&] {
      write_ringdown_spectrum(scene, directory, solver ? solver->probes() : reduced_probes, setup, modes, out,
                              options.draw_plots);
    });
    spectrum_stage.seconds = clock.seconds();
  }
  stages.push_back(spectrum_stage);
  if (reuse && !shared) {
    reuse->modes[reuse->key] = std::move(own_modes);  // `modes` is not used below
    reuse->models[reuse->key] = std::move(own_model);
  }
  outcome.frequency = setup.frequency;
  outcome.wall_s = total.seconds();
  return outcome;
}

void write_run_json(const scene::Scene& scene, const fs::path& directory, const RunOutcome& outcome,
                    const nlohmann::json& route, const nlohmann::json& accuracy, double wall_s) {
  output::write_run_json(directory, scene.file, outcome.stages, outcome.frequency, route, accuracy, wall_s);
}


void run_run_command(const RunCommandOptions& options, std::ostream& out) {
  std::vector<scene::Override> overrides = parse_overrides(options.overrides);
  const scene::Scene written = scene::load_scene(options.scene_path, overrides);
  if (!written.transient) {
    throw InputError(written.file + ": transient: expected a transient section for crackle run (crackle modal "
                     "computes modes alone), got none");
  }
  const int ranks = run_ranks();
  // transient.model: auto becomes full or reduced (and the reduced route's own mesh) by overrides
  // after the user's, so every later check and message sees the scene that runs.
  const RunRoute route = choose_route(written, ranks);
  overrides.insert(overrides.end(), route.overrides.begin(), route.overrides.end());
  const scene::Scene scene = route.overrides.empty() ? written : scene::load_scene(options.scene_path, overrides);
  if (ranks > 1 && scene.transient->model == scene::TransientModel::reduced) {
    throw InputError(scene.where("transient.model") + ": expected full under mpirun -np " + std::to_string(ranks) +
                     " (one transient over several processes is the full explicit model), got reduced; run the "
                     "reduced model without mpirun (it takes seconds on one process)");
  }
  const fs::path& directory = options.output_directory;
  // Before anything is computed: the folder can be written and is ours (leftovers of an earlier run
  // removed), and the mesh fits in memory. Under mpirun rank 0 owns the folder and prints.
  std::string modal_reason;
  on_every_rank([&] {
    check_memory(scene, !needed_variants(scene, modal_reason).empty() ? matrices::eigen_solve
                        : scene.transient->model == scene::TransientModel::reduced ? matrices::static_solve
                        : !scene.gmsh_file.empty()                  ? matrices::stiffness
                                                                    : matrices::none);
  });
  std::optional<OutputFolder> folder;
  on_writer_rank([&] { folder.emplace(directory, "run", options.scene_path, options.overwrite, std::cerr); });
  NullStream silent;
  std::exception_ptr error;
  try {
    run_with_accuracy(scene, route, overrides, options, is_writer_rank() ? out : silent);
  } catch (...) {
    error = std::current_exception();
  }
  if (ranks > 1) {  // the same error (and exit code) on every rank
    try {
      distributed::agree(error);
    } catch (...) {
      error = std::current_exception();
    }
  }
  if (error) {
    try {
      if (folder) folder->finish("failed");
    } catch (const std::exception&) {
      // The run's own error says more than a failure to record it.
    }
    std::rethrow_exception(error);
  }
  if (folder) folder->finish("done");
}

}  // namespace crackle::pipeline
