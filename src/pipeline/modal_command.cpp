#include <algorithm>
#include <array>
#include <chrono>
#include <iomanip>
#include <memory>
#include <tuple>
#include <cstdlib>
#include <iostream>
#include <string>

#include <petscsys.h>
#include <optional>

#include "pipeline/commands.hpp"
#include "core/errors.hpp"
#include "core/mpi_session.hpp"
#include "io/files.hpp"
#include "pipeline/distributed_run.hpp"
#include "pipeline/limits.hpp"
#include "pipeline/modal_accuracy.hpp"
#include "pipeline/refinement.hpp"
#include "pipeline/model.hpp"
#include "pipeline/output_folder.hpp"
#include "modal/modal.hpp"
#include "scene/scene.hpp"
#include "output/modal_json.hpp"

namespace crackle::pipeline {

namespace {

/// Processes of the MPI launcher that started this one (PETSc may not have started yet), else PETSc's.
int launched_ranks() { return std::max(launcher_world_size(), run_ranks()); }

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
  options.variants = section.variants;
  // auto: ARPACK with CHOLMOD on one process (fewer solves with the same factor than Krylov-Schur:
  // 8.9 s against 10.3 s at 86k DOFs, docs/benchmarks.md section 3), SLEPc under mpirun (distributed)
  // or when SLEPc's own options are given.
  const bool arpack = section.solver == scene::ModalSolver::arpack ||
                      (section.solver == scene::ModalSolver::automatic && launched_ranks() == 1 && !slepc_options_given());
  options.solver = arpack ? modal::Solver::arpack : modal::Solver::slepc;
  options.lumped_mass = section.mass == scene::MassMatrix::lumped;
  return options;
}

void run_modal_command(const ModalCommandOptions& options, std::ostream& out, const ModalInspect& inspect) {
  const auto started = std::chrono::steady_clock::now();
  auto seconds_since = [](std::chrono::steady_clock::time_point since) {
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - since).count();
  };
  const std::vector<scene::Override> overrides = parse_overrides(options.overrides);
  const scene::Scene scene = scene::load_scene(options.scene_path, overrides);
  scene::ModalSection section = scene.modal;
  if (options.modes > 0) section.modes = options.modes;
  if (!options.solver.empty()) section.solver = parse_word(scene::kModalSolverWords, options.solver, options.solver_option);
  const bool writer = modal::is_output_rank();
  // Fail on an unwritable or foreign output directory, or a mesh too big for the memory, before the solve.
  check_memory(scene, matrices::eigen_solve, MeshUse::modal);
  std::optional<OutputFolder> folder;
  if (writer) folder.emplace(options.output_directory, "modal", options.scene_path, options.overwrite, std::cerr);
  if (scene.has_accuracy_section && scene.accuracy.quantities != scene::AccuracySection{}.quantities) {
    out << "note: accuracy.quantities is of crackle run's and sweep's signatures; crackle modal estimates every "
           "frequency\n";
  }
  try {
    modal::ModalOptions modal_settings = modal_options(section);
    modal_settings.cache_directory = options.modal_cache;
    auto solve = [&](const scene::Scene& at) {
      const auto start = std::chrono::steady_clock::now();
      auto model = std::make_unique<Model>(build_model(at, MeshUse::modal));
      const Model& held = *model;
      modal::ModalResult result = modal::run_modal(
          [&held](mesh::Variant variant) -> const fem::System& { return *held.system(variant); }, modal_settings);
      return std::make_tuple(std::move(model), std::move(result), seconds_since(start));
    };
    auto [model, result, run_s] = solve(scene);
    if (writer) output::write_modal_outputs(options.output_directory, model->mesh, result);

    // The estimate: the plan's other orders, solved one after the other (DETECTION.md sec. 1).
    const ModalLevelPlan plan = modal_level_plan(scene, launched_ranks());
    nlohmann::json block = modal_accuracy_not_estimated(plan.reason);
    std::vector<std::string> lines;
    if (plan.estimate) {
      const auto estimate_started = std::chrono::steady_clock::now();
      std::vector<ModalLevel> levels = {modal_level(result, plan.run_order, run_s)};
      std::string lacking;
      for (int order : plan.orders) {
        if (order == plan.run_order) continue;
        std::vector<scene::Override> at_order = overrides;
        at_order.push_back({"mesh.box.order", std::to_string(order)});
        const scene::Scene level_scene = scene::load_scene(options.scene_path, at_order);
        try {
          // A lower order needs less than the solve that ran; the memory now free says little about it.
          if (order > plan.run_order) check_memory(level_scene, matrices::eigen_solve, MeshUse::modal);
        } catch (const Error& refused) {
          lacking += std::string(lacking.empty() ? "" : "; ") + "order " + std::to_string(order) + ": " + refused.what();
          continue;
        }
        auto [level_model, level_result, level_s] = solve(level_scene);
        levels.push_back(modal_level(level_result, order, level_s));
      }
      if (plan.check_cells) {
        // The check level: order 2 on the cells doubled, about the run's DOFs (its memory is checked).
        const std::array<int, 3>& cells = *plan.check_cells;
        std::vector<scene::Override> at_check = overrides;
        at_check.push_back({"mesh.box.order", std::to_string(kCheckOrder)});
        at_check.push_back({"mesh.box.cells", list_text({double(cells[0]), double(cells[1]), double(cells[2])})});
        const scene::Scene check_scene = scene::load_scene(options.scene_path, at_check);
        bool fits = true;
        try {
          check_memory(check_scene, matrices::eigen_solve, MeshUse::modal);
        } catch (const Error& refused) {
          lacking += std::string(lacking.empty() ? "" : "; ") + "the check level: " + refused.what();
          fits = false;
        }
        if (fits) {
          auto [check_model, check_result, check_s] = solve(check_scene);
          levels.push_back(modal_level(check_result, kCheckOrder, check_s));
          levels.back().check = true;
        }
      }
      const double estimate_s = seconds_since(estimate_started);
      const ModalAccuracy accuracy = modal_accuracy(plan, levels, estimate_s, seconds_since(started));
      block = accuracy.block;
      if (!lacking.empty()) block["lacking"] = lacking;
      lines = accuracy.lines;
    }
    if (!writer) return;
    output::write_modal_tables(options.output_directory, result, &block);
    folder->finish("done");
    out << modal::modal_table(result);
    for (const std::string& line : lines) out << line << "\n";
    if (!plan.estimate) out << "accuracy: not estimated (" << plan.reason << ")\n";
    if (plan.estimate && block.value("estimated", false)) {
      if (plan.tolerance) {
        out << "accuracy: tolerance " << percent(*plan.tolerance) << (block.value("met", false) ? " met" : " not met")
            << " (largest estimate " << percent(block.value("error", 0.0)) << ")\n";
      }
      out << "accuracy: orders " << nlohmann::json(plan.orders).dump()
          << (plan.check_cells ? ", checked by order 2 on cells " + nlohmann::json(*plan.check_cells).dump() : "")
          << ", " << std::setprecision(3) << block.value("estimate_s", 0.0) << " s for the other levels (" << std::setprecision(2)
          << 100.0 * block.value("share", 0.0) << " % of the " << std::setprecision(3) << seconds_since(started)
          << " s)\n";
    }
    if (inspect) inspect(*model, result);
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
