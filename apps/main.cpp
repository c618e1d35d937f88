/// \file The `crackle` executable: `crackle check|modal|... scene.yaml`.
#include <CLI/CLI.hpp>
#include <iostream>

#include "pipeline/commands.hpp"
#include "modal/eigensolver.hpp"
#include "core/errors.hpp"
#include "scene/scene.hpp"
#include "study/study.hpp"

int main(int argc, char** argv) {
  using namespace crackle;
  CLI::App cli{"crackle: nonlinear vibration of elastic bodies with a breathing crack"};
  cli.require_subcommand(1);
  cli.set_version_flag("--version", "crackle 0.1.0");

  pipeline::CheckOptions check;
  CLI::App* check_command = cli.add_subcommand(
      "check", "Validate a scene, mesh it, assemble K and the lumped mass, and print a summary");
  check_command->add_option("scene", check.scene_path, "Scene file (YAML)")->required();
  check_command->add_option("--set", check.overrides, "Override a scene value: --set key.path=value (repeatable)");
  check_command->add_flag("!--no-assembly", check.assemble, "Skip assembling K and M");

  pipeline::ModalCommandOptions modal;
  CLI::App* modal_command = cli.add_subcommand(
      "modal", "Eigenmodes of the uncracked (faces tied) and open-crack body, paired by MAC, with the "
               "bilinear frequency of each pair. PETSc/SLEPc options may follow, e.g. -eps_view");
  modal_command->add_option("scene", modal.scene_path, "Scene file (YAML)")->required();
  modal_command->add_option("--set", modal.overrides, "Override a scene value: --set key.path=value (repeatable)");
  modal_command->add_option("-o,--output", modal.output_directory, "Output directory")->capture_default_str();
  modal_command->add_option("--modes", modal.modes, "Number of modes (overrides modal.modes)");
  modal_command->add_option("--solver", modal.solver, "slepc or arpack (overrides modal.solver)")
      ->check(CLI::IsMember({"slepc", "arpack"}));
  modal_command->add_option("--modal-cache", modal.modal_cache,
                            "Folder where the uncracked solve is looked up and stored (shared by study cases)");
  modal_command->allow_extras();

  pipeline::RunCommandOptions run;
  bool quiet = false;
  CLI::App* run_command = cli.add_subcommand(
      "run", "The scene's pipeline: modal (only if a mode is referred to or modal: is given) -> transient "
             "(explicit dynamics with crack-face contact) -> spectrum (harmonics, damage indices, plots)");
  run_command->add_option("scene", run.scene_path, "Scene file (YAML)")->required();
  run_command->add_option("--set", run.overrides, "Override a scene value: --set key.path=value (repeatable)");
  run_command->add_option("-o,--output", run.output_directory, "Output directory")->capture_default_str();
  run_command->add_option("--modal-cache", run.modal_cache,
                          "Folder where the uncracked solve is looked up and stored (shared by study cases)");
  run_command->add_flag("-q,--quiet", quiet, "No progress line");
  run_command->allow_extras();

  study::StudyOptions study_options;
  study_options.executable = "/proc/self/exe";
  bool no_modal_cache = false;
  CLI::App* study_command = cli.add_subcommand(
      "study", "Parameter study: every case of the scene's study: section as its own run, in parallel and "
               "resumable (rerun the same command to finish an interrupted study); writes study.csv, "
               "study.json, plots/ and cases/NNNN/. Under mpirun the cases are spread over the ranks");
  study_command->add_option("scene", study_options.scene_path, "Scene file (YAML) with a study: section")->required();
  study_command->add_option("-o,--output", study_options.output_dir, "Output directory")->required();
  study_command->add_option("-j,--jobs", study_options.jobs, "Cases at a time (default: the cores)");
  study_command->add_flag("--retry-failed", study_options.retry_failed, "Rerun cases recorded as failed");
  study_command->add_flag("--no-modal-cache", no_modal_cache, "Solve the uncracked modes in every case");
  study_command->add_option("--case-timeout", study_options.case_timeout_s, "Stop a case after this many seconds");

  CLI::App* format_command =
      cli.add_subcommand("scene-format", "Print the reference of every scene key (Markdown)");

  try {
    cli.parse(argc, argv);
  } catch (const CLI::ParseError& error) {
    return cli.exit(error);
  }
  try {
    if (*check_command) pipeline::run_check(check, std::cout);
    if (*modal_command) {
      // PETSc sees only the arguments CLI11 did not take (e.g. -eps_view), and PETSC_OPTIONS.
      std::vector<std::string> extras = modal_command->remaining();
      std::vector<char*> petsc_argv{argv[0]};
      for (std::string& extra : extras) petsc_argv.push_back(extra.data());
      int petsc_argc = static_cast<int>(petsc_argv.size());
      petsc_argv.push_back(nullptr);  // MPI expects argv[argc] == NULL
      char** petsc_args = petsc_argv.data();
      modal::SlepcSession session(&petsc_argc, &petsc_args);
      pipeline::run_modal_command(modal, std::cout);
    }
    if (*run_command) {
      run.progress = !quiet;
      std::vector<std::string> extras = run_command->remaining();
      std::vector<char*> petsc_argv{argv[0]};
      for (std::string& extra : extras) petsc_argv.push_back(extra.data());
      int petsc_argc = static_cast<int>(petsc_argv.size());
      petsc_argv.push_back(nullptr);
      char** petsc_args = petsc_argv.data();
      modal::SlepcSession session(&petsc_argc, &petsc_args);
      pipeline::run_run_command(run, std::cout);
    }
    if (*study_command) {
      study_options.modal_cache = !no_modal_cache;
      return study::run_study(study_options, std::cerr);
    }
    if (*format_command) std::cout << scene::scene_format_markdown();
  } catch (const std::exception& error) {
    std::cerr << "crackle: error: " << error.what() << "\n";
    return exit_code_for(error);
  }
  return 0;
}
