#include <algorithm>
#include <cstdlib>
#include <iostream>
#include <string>

#include <petscsys.h>
#include <optional>

#include "pipeline/commands.hpp"
#include "core/errors.hpp"
#include "io/files.hpp"
#include "pipeline/distributed_run.hpp"
#include "pipeline/limits.hpp"
#include "pipeline/model.hpp"
#include "pipeline/output_folder.hpp"
#include "modal/modal.hpp"
#include "scene/scene.hpp"

namespace crackle::pipeline {

namespace {

/// Processes of the MPI launcher that started this one (1 without one), from its environment: PETSc
/// may not have started yet.
int launched_ranks() {
  for (const char* name : {"OMPI_COMM_WORLD_SIZE", "PMI_SIZE"}) {
    const char* value = std::getenv(name);
    if (value && *value) return std::max(1, std::atoi(value));
  }
  return run_ranks();
}

/// PETSc options that speak to SLEPc's eigen-solve (-eps_*, -st_* and the KSP/PC of its spectral
/// transformation), from the command line or PETSC_OPTIONS: a user who gives them wants SLEPc.
bool slepc_options_given() {
  PetscBool started = PETSC_FALSE;
  PetscInitialized(&started);
  char* all = nullptr;
  if (!started || PetscOptionsGetAll(nullptr, &all) != 0 || !all) return false;
  const std::string text = std::string(" ") + all;
  PetscFree(all);
  for (const char* prefix : {" -eps_", " -st_", " -ksp_", " -pc_", " -mat_mumps"}) {
    if (text.find(prefix) != std::string::npos) return true;
  }
  return false;
}

}  // namespace

modal::ModalOptions modal_options(const scene::ModalSection& section) {
  modal::ModalOptions options;
  options.modes = section.modes;
  for (const std::string& name : section.variants) {
    options.variants.push_back(name == "open" ? mesh::Variant::open : mesh::Variant::uncracked);
  }
  // auto: ARPACK with CHOLMOD on one process (fewer solves with the same factor than Krylov-Schur:
  // 8.9 s against 10.3 s at 86k DOFs, docs/benchmarks.md section 3), SLEPc under mpirun (distributed)
  // or when SLEPc's own options are given.
  const bool arpack = section.solver == "arpack" ||
                      (section.solver == "auto" && launched_ranks() == 1 && !slepc_options_given());
  options.solver = arpack ? modal::Solver::arpack : modal::Solver::slepc;
  options.lumped_mass = section.mass == "lumped";
  return options;
}

void run_modal_command(const ModalCommandOptions& options, std::ostream& out, const ModalInspect& inspect) {
  const scene::Scene scene = scene::load_scene(options.scene_path, parse_overrides(options.overrides));
  scene::ModalSection section = scene.modal;
  if (options.modes > 0) section.modes = options.modes;
  if (!options.solver.empty()) section.solver = options.solver;
  const bool writer = modal::is_output_rank();
  // Fail on an unwritable or foreign output directory, or a mesh too big for the memory, before the solve.
  check_memory(scene, matrices::eigen_solve, MeshUse::modal);
  std::optional<OutputFolder> folder;
  if (writer) folder.emplace(options.output_directory, "modal", options.scene_path, options.overwrite, std::cerr);
  try {
    const Model model = build_model(scene, MeshUse::modal);
    modal::ModalOptions modal_settings = modal_options(section);
    modal_settings.cache_directory = options.modal_cache;
    const modal::ModalResult result = modal::run_modal(
        [&model](mesh::Variant variant) -> const fem::System& { return *model.system(variant); }, modal_settings);
    if (!writer) return;
    modal::write_modal_outputs(options.output_directory, model.mesh, result);
    folder->finish("done");
    out << modal::modal_table(result);
    if (inspect) inspect(model, result);
  } catch (...) {
    try {
      if (folder) folder->finish("failed");
    } catch (const std::exception&) {
      // The solve's own error says more than a failure to record it.
    }
    throw;
  }
  out << "wrote " << (options.output_directory / "modal.json").string() << ", modes.csv and the mode shapes (VTU)\n";
}

}  // namespace crackle::pipeline
