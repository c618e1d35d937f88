#pragma once
/// \file The subcommands of the `crackle` executable, callable from tests.
#include <filesystem>
#include <functional>
#include <iosfwd>
#include <string>
#include <vector>

#include "modal/modal.hpp"
#include "scene/scene.hpp"

namespace crackle::pipeline {

struct Model;

/// `--set key.path=value` arguments: scene overrides (validated like the file's own values).
std::vector<scene::Override> parse_overrides(const std::vector<std::string>& assignments);

struct CheckOptions {
  std::string scene_path;
  std::vector<std::string> overrides;  ///< `key.path=value`
  bool assemble = true;  ///< assemble K and the lumped M to report mass and assembly time
};

/// `crackle check`: validates a scene and prints a summary (nodes, elements, DOFs, crack pairs,
/// total mass, assembly time). Throws InputError on a bad scene.
void run_check(const CheckOptions& options, std::ostream& out);

struct ModalCommandOptions {
  std::string scene_path;
  std::vector<std::string> overrides;  ///< `key.path=value`
  std::filesystem::path output_directory = "out";
  int modes = 0;       ///< overrides modal.modes when > 0
  std::string solver;  ///< overrides modal.solver when not empty
  std::string solver_option = "--solver";  ///< how the caller spells that override in messages (Python: "solver")
  std::filesystem::path modal_cache;  ///< folder sharing the modal solves and reduced models between runs
  bool overwrite = false;  ///< write into a folder that holds files of others (they are kept)
};

struct RunCommandOptions {
  std::string scene_path;
  std::vector<std::string> overrides;  ///< `key.path=value`
  std::filesystem::path output_directory = "out";
  std::filesystem::path modal_cache;  ///< folder sharing the modal solves and reduced models between runs
  bool progress = true;               ///< progress line (also needs transient.progress)
  bool overwrite = false;  ///< write into a folder that holds files of others (they are kept)
  /// run.json or sweep.json of an earlier estimate on the same mesh: the tolerance loop starts at the
  /// setting it reached (pipeline/refinement.hpp, tolerance_start); empty: at the scene's own.
  std::filesystem::path accuracy_start;
  /// false: the figures' data and scripts only, gnuplot not run (the accuracy's refinement runs,
  /// whose figures are drawn when their folder is adopted: RefinementFolders::adopt).
  bool draw_plots = true;
};

/// `crackle run`: modal (only if needed) -> transient -> spectrum; writes run.json (the stages
/// that ran, and why, with their times) and each stage's outputs into the output directory.
void run_run_command(const RunCommandOptions& options, std::ostream& out);

/// The scene's `modal:` section as options of the modal module.
modal::ModalOptions modal_options(const scene::ModalSection& section);

/// `crackle modal`: eigenmodes of the uncracked and open-crack body; writes modal.json,
/// modes.csv and the mode shapes (VTU) into the output directory, prints the pairing table.
/// Needs SLEPc initialised (modal::SlepcSession). Under MPI only rank 0 writes and prints.
/// `inspect`, when given, sees the model and the result once the files are written (the Python
/// module takes its arrays from them).
using ModalInspect = std::function<void(const Model& model, const modal::ModalResult& result)>;
void run_modal_command(const ModalCommandOptions& options, std::ostream& out, const ModalInspect& inspect = {});

}  // namespace crackle::pipeline
