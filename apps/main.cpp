/// \file The `crackle` executable: `crackle check|modal|... scene.yaml`.
///
/// The command line is strict: an unknown option or argument is an error (with a "did you mean"
/// suggestion), out-of-range values are errors naming the option, and every bad command line
/// exits 2 like any other bad input. PETSc/SLEPc options reach PETSc only through an explicit
/// channel: after `--`, as `--petsc "-opt value"`, or in the PETSC_OPTIONS environment variable.
#include <unistd.h>

#include <algorithm>
#include <CLI/CLI.hpp>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <iostream>
#include <new>
#include <sstream>

#include <nlohmann/json.hpp>

#include "pipeline/commands.hpp"
#include "pipeline/sweep.hpp"
#include "pipeline/limits.hpp"
#include "core/errors.hpp"
#include "core/mpi_session.hpp"
#include "modal/eigensolver.hpp"
#include "scene/scene.hpp"
#include "scene/yaml_text.hpp"
#include "study/plan.hpp"
#include "identify/identify.hpp"
#include "planning/planning.hpp"
#include "study/study.hpp"

namespace {

using namespace crackle;

constexpr int kExitBadInput = 2;
constexpr int kExitOutOfMemory = 3;  ///< as a solver failure: the computation could not finish

const char* const kExitCodes =
    "Exit codes: 0 done; 2 bad input (scene file or command line; nothing is written; also a scene "
    "whose mesh or outputs cannot fit in the memory or on the disk); 3 a solver failed, memory ran out "
    "during the computation, or some cases of a study failed; 4 a file could not be read or written; "
    "130 interrupted.";

const char* const kPetscChannel =
    "PETSc/SLEPc options go after --, e.g. `crackle modal s.yaml -- -eps_view`, or as --petsc \"-eps_view\" "
    "(repeatable), or in the PETSC_OPTIONS environment variable; any other unknown option is an error.";

/// A validator for an integer or a number above a bound: "expected a positive integer, got -1".
CLI::Validator above(double bound, bool integer, const std::string& phrase) {
  return CLI::Validator(
      [=](std::string& text) -> std::string {
        const std::string expected = "expected " + phrase + ", got " + (text.empty() ? "nothing" : text);
        double value = 0;
        long long whole = 0;
        if (integer ? !scene::parse_integer(text, whole) : !scene::parse_number(text, value)) return expected;
        if (integer) {
          if (whole > 1000000000LL) return expected;
          value = static_cast<double>(whole);
        }
        return value > bound ? "" : expected;
      },
      "");
}

/// The arguments before the first `--` (crackle's) and after it (PETSc's).
struct SplitArguments {
  std::vector<std::string> own;    ///< argv[0] and crackle's arguments
  std::vector<std::string> petsc;  ///< after `--`
  bool separated = false;          ///< a `--` was given
};

SplitArguments split_arguments(int argc, char** argv) {
  SplitArguments split;
  for (int i = 0; i < argc; ++i) {
    const std::string argument = argv[i];
    if (i > 0 && argument == "--" && !split.separated) {
      split.separated = true;
      continue;
    }
    (split.separated ? split.petsc : split.own).push_back(argument);
  }
  return split;
}

/// Every name of every option of `command`: "--set", "-o", "--output", ...
std::vector<std::string> option_names(const CLI::App& command) {
  std::vector<std::string> names;
  for (const CLI::Option* option : command.get_options()) {
    for (const std::string& name : option->get_lnames()) names.push_back("--" + name);
    for (const std::string& name : option->get_snames()) names.push_back("-" + name);
  }
  return names;
}

/// Scene keys whose last name is `word` (`periods` -> transient.periods).
std::vector<std::string> scene_keys_named(std::string word) {
  for (char& c : word)
    if (c == '-') c = '_';
  std::vector<std::string> keys;
  for (const std::string& path : study::leaf_key_paths()) {
    const std::size_t dot = path.find_last_of('.');
    if (path.substr(dot == std::string::npos ? 0 : dot + 1) == word) keys.push_back(path);
  }
  return keys;
}

/// The message for the first argument of `rest` that `command` does not take, or "".
std::string unexpected_argument(const CLI::App& command, const std::vector<std::string>& rest,
                                bool takes_petsc) {
  if (rest.empty()) return "";
  const std::string name = "crackle " + command.get_name();
  for (std::size_t i = 0; i < rest.size(); ++i) {
    const std::string& argument = rest[i];
    if (argument.size() < 2 || argument[0] != '-') continue;
    const std::string option = argument.substr(0, argument.find('='));
    std::string hint = scene::suggestion(option, option_names(command));
    if (hint.empty() && option.rfind("--", 0) == 0) {
      std::vector<std::string> keys = scene_keys_named(option.substr(2));
      // Several keys of that name (modal.modes, transient.reduced.modes): the shallowest one, if unique.
      const auto depth = [](const std::string& key) { return std::count(key.begin(), key.end(), '.'); };
      if (keys.size() > 1) {
        std::sort(keys.begin(), keys.end(), [&](const std::string& a, const std::string& b) { return depth(a) < depth(b); });
        if (depth(keys[0]) < depth(keys[1])) keys.resize(1);
      }
      std::string value = argument.find('=') != std::string::npos ? argument.substr(argument.find('=') + 1)
                          : i + 1 < rest.size() && rest[i + 1][0] != '-' ? rest[i + 1]
                                                                            : "VALUE";
      if (keys.size() == 1 && command.get_option_no_throw("--set"))
        hint = " (did you mean '--set " + keys[0] + "=" + value + "'?)";
    }
    if (hint.empty() && option[1] != '-' && option.find('_') != std::string::npos) {
      hint = takes_petsc ? " (a PETSc option? give it after --, e.g. `" + name + " scene.yaml -- " + argument +
                               "`, or as --petsc \"" + argument + "\")"
                         : " (" + name + " takes no PETSc options)";
    }
    return name + ": unknown option '" + option + "'" + hint + "; see " + name + " --help";
  }
  return name + ": unexpected argument '" + rest.front() + "' (it takes one scene file); see " + name + " --help";
}


/// PETSc's argv: the program name, then each `--petsc` value split at spaces, then what follows `--`.
class PetscArguments {
 public:
  PetscArguments(const std::string& program, const std::vector<std::string>& petsc_options,
                 const std::vector<std::string>& after_separator) {
    words_.push_back(program);
    for (const std::string& option : petsc_options) {
      std::istringstream words(option);
      for (std::string word; words >> word;) words_.push_back(word);
    }
    words_.insert(words_.end(), after_separator.begin(), after_separator.end());
    for (std::string& word : words_) pointers_.push_back(word.data());
    argc_ = static_cast<int>(pointers_.size());
    pointers_.push_back(nullptr);  // MPI expects argv[argc] == NULL
    argv_ = pointers_.data();
  }
  int* argc() { return &argc_; }
  char*** argv() { return &argv_; }

 private:
  std::vector<std::string> words_;
  std::vector<char*> pointers_;
  int argc_ = 0;
  char** argv_ = nullptr;
};

int bad_command_line(const std::string& message) {
  std::cerr << "crackle: error: " << message << "\n";
  return kExitBadInput;
}

/// When a command's PETSc starts: at its first SLEPc solve (a cached or ARPACK run never pays MPI's
/// start-up), or at once when PETSc options are given (--petsc, after `--`, or PETSC_OPTIONS: so that
/// they are read and checked) or under mpirun -np N > 1 (the ranks share the run).
modal::SlepcSession::Start slepc_start(const std::vector<std::string>& command_options,
                                       const std::vector<std::string>& separated_options) {
  const char* environment_options = std::getenv("PETSC_OPTIONS");
  const bool given =
      !command_options.empty() || !separated_options.empty() || (environment_options && *environment_options);
  return given || launcher_world_size() > 1 ? modal::SlepcSession::Start::now
                                            : modal::SlepcSession::Start::on_first_use;
}

}  // namespace

/// Runs crackle again with glibc's malloc asking for transparent huge pages (GLIBC_TUNABLES
/// glibc.malloc.hugetlb=1, read only at start-up): the matrices of an order-4 mesh are gigabytes, and
/// their first-touch page faults were 12 s of system time on the default route; with 2 MB pages
/// `crackle run data/beam.yaml` takes 25-27 s against 30 s, at the same peak memory
/// (docs/benchmarks.md 11.3d). Not where the tunable is set already, the kernel has no transparent
/// huge pages, valgrind runs the process (an exec would leave it), or CRACKLE_NO_HUGE_PAGES is set.
/// execv returns only when it fails; crackle then runs as it is.
void use_huge_pages(char** argv) {
  if (std::getenv("CRACKLE_NO_HUGE_PAGES")) return;
  const char* tunables = std::getenv("GLIBC_TUNABLES");
  std::string value = tunables ? tunables : "";
  if (value.find("glibc.malloc.hugetlb") != std::string::npos) return;
  const char* preload = std::getenv("LD_PRELOAD");
  if (preload && (std::strstr(preload, "vgpreload") || std::strstr(preload, "valgrind"))) return;
  std::ifstream mode("/sys/kernel/mm/transparent_hugepage/enabled");
  std::string line;
  if (!std::getline(mode, line) || line.find("[never]") != std::string::npos) return;
  value += (value.empty() ? "" : ":") + std::string("glibc.malloc.hugetlb=1");
  if (::setenv("GLIBC_TUNABLES", value.c_str(), 1) != 0) return;
  ::execv("/proc/self/exe", argv);
}

int main(int argc, char** argv) {
  using namespace crackle;
  use_huge_pages(argv);
  CLI::App cli{"crackle: nonlinear vibration of elastic bodies with a breathing crack"};
  cli.require_subcommand(1);
  cli.set_version_flag("--version", "crackle 0.1.0");
  cli.footer(kExitCodes);
  cli.allow_extras();

  pipeline::CheckOptions check;
  CLI::App* check_command = cli.add_subcommand(
      "check", "Validate a scene, mesh it, assemble K and the lumped mass, and print a summary");
  check_command->add_option("scene", check.scene_path, "Scene file (YAML)")->required();
  check_command->add_option("--set", check.overrides, "Override a scene value: --set key.path=value (repeatable)");
  check_command->add_flag("!--no-assembly", check.assemble, "Skip assembling K and M");
  bool check_quiet = false;
  check_command->add_flag("-q,--quiet", check_quiet, "Print no summary: the exit code says whether the scene is valid "
                                                     "(errors are still printed)");

  pipeline::ModalCommandOptions modal;
  std::vector<std::string> modal_petsc;
  CLI::App* modal_command = cli.add_subcommand(
      "modal", "Eigenmodes of the uncracked (faces tied) and open-crack body, paired by MAC, with the "
               "bilinear frequency of each pair. Runs under mpirun -np N (SLEPc)");
  modal_command->add_option("scene", modal.scene_path, "Scene file (YAML)")->required();
  modal_command->add_option("--set", modal.overrides, "Override a scene value: --set key.path=value (repeatable)");
  modal_command->add_option("-o,--output", modal.output_directory, "Output directory")->capture_default_str();
  modal_command->add_option("--modes", modal.modes, "Number of modes (overrides modal.modes)")
      ->check(above(0, true, "a positive integer"));
  modal_command->add_option("--solver", modal.solver, "auto, slepc or arpack (overrides modal.solver)")
      ->check(CLI::IsMember(texts_of(scene::kModalSolverWords)));
  modal_command->add_option("--modal-cache", modal.modal_cache,
                            "Folder where the modal solves (by fingerprint of K and M) and the reduced model are looked up and stored (shared by study cases)");
  modal_command->add_flag("--overwrite", modal.overwrite,
                          "Write into a folder that holds files crackle modal did not write (they are kept)");
  bool modal_quiet = false;
  modal_command->add_flag("-q,--quiet", modal_quiet, "Print no table of frequencies (the files hold it; errors are "
                                                     "still printed)");
  modal_command->add_option("--petsc", modal_petsc, "PETSc/SLEPc options, e.g. --petsc \"-eps_view\" (repeatable)");
  modal_command->footer(kPetscChannel);

  pipeline::RunCommandOptions run;
  std::vector<std::string> run_petsc;
  bool quiet = false;
  CLI::App* run_command = cli.add_subcommand(
      "run", "The scene's pipeline: modal (only if a mode is referred to or modal: is given) -> transient "
             "(explicit dynamics with crack-face contact) -> spectrum (harmonics, damage indices, plots). "
             "Under mpirun -np N the full transient is spread over the N ranks (rank 0 writes the files)");
  run_command->add_option("scene", run.scene_path, "Scene file (YAML)")->required();
  run_command->add_option("--set", run.overrides, "Override a scene value: --set key.path=value (repeatable)");
  run_command->add_option("-o,--output", run.output_directory, "Output directory")->capture_default_str();
  run_command->add_option("--modal-cache", run.modal_cache,
                          "Folder where the modal solves (by fingerprint of K and M) and the reduced model are looked up and stored (shared by study cases)");
  run_command->add_flag("-q,--quiet", quiet, "No progress line");
  run_command->add_option("--accuracy-start", run.accuracy_start,
                          "The run.json or sweep.json of an earlier estimate on the same mesh: the accuracy tolerance's "
                          "refinement starts at the setting it reached (a study passes it to the cases that share a "
                          "mesh)");
  run_command->add_flag("--overwrite", run.overwrite,
                        "Write into a folder that holds files crackle run did not write (they are kept); the files "
                        "of an earlier crackle run there are always replaced");
  run_command->add_option("--petsc", run_petsc, "PETSc/SLEPc options, e.g. --petsc \"-eps_view\" (repeatable)");
  run_command->footer(kPetscChannel);

  pipeline::SweepCommandOptions sweep;
  bool sweep_quiet = false;
  CLI::App* sweep_command = cli.add_subcommand(
      "sweep", "Frequency sweep of the scene's sweep: section on the reduced model (modal stage only for a "
               "mode-relative range): harmonic balance with arclength continuation and Hill stability, or a "
               "stepped sine (reduced transient to steady state per frequency, up then down). Writes sweep.csv "
               "(amplitude and phase of every order per probe, A2/A1, A3/A1, stability), sweep.json (settings, "
               "timings, folds and bifurcations, H-convergence warnings) and sweep_<probe>.png; progress on stderr");
  sweep_command->add_option("scene", sweep.scene_path, "Scene file (YAML) with a sweep: section")->required();
  sweep_command->add_option("--set", sweep.overrides, "Override a scene value: --set key.path=value (repeatable)");
  sweep_command->add_option("-o,--output", sweep.output_directory, "Output directory")->capture_default_str();
  sweep_command->add_option("--modal-cache", sweep.modal_cache,
                            "Folder where the modal solves (by fingerprint of K and M) and the reduced model are looked up and stored");
  sweep_command->add_flag("-q,--quiet", sweep_quiet, "No progress line");
  sweep_command->add_option("--accuracy-start", sweep.accuracy_start,
                            "The sweep.json or run.json of an earlier estimate on the same mesh: the accuracy tolerance's "
                            "refinement starts at the setting it reached (a study passes it to the cases that share a "
                            "mesh)");

  study::StudyOptions study_options;
  study_options.executable = "/proc/self/exe";
  bool no_modal_cache = false;
  CLI::App* study_command = cli.add_subcommand(
      "study", "Parameter study: every case of the scene's study: section as its own run, in parallel and "
               "resumable (rerun the same command to finish an interrupted study); writes study.csv, "
               "study.json, plots/ and cases/NNNN/. Under mpirun the cases are spread over the ranks. "
               "Exits 3 when some cases failed (they are recorded in the tables)");
  study_command->add_option("scene", study_options.scene_path, "Scene file (YAML) with a study: section")->required();
  study_command->add_option("-o,--output", study_options.output_dir, "Output directory")->required();
  study_command->add_option("-j,--jobs", study_options.jobs, "Cases at a time (default: the cores)")
      ->check(above(0, true, "a positive integer"));
  study_command->add_flag("--retry-failed", study_options.retry_failed, "Rerun cases recorded as failed");
  study_command->add_flag("--no-modal-cache", no_modal_cache, "Solve the modes (and the reduced model) in every case");
  bool study_quiet = false;
  study_command->add_flag("-q,--quiet", study_quiet, "No progress lines (cases done, running, ETA); the plan, notes, "
                                                     "the summary and errors are still printed");
  study_command->add_option("--case-timeout", study_options.case_timeout_s,
                            "Stop a case after this many seconds (default: no limit)")
      ->check(above(0, false, "a positive number of seconds"));

  identify::IdentifyOptions identify_options;
  identify_options.executable = "/proc/self/exe";
  CLI::App* identify_command = cli.add_subcommand(
      "identify", "Damage identification: the unknowns of the scene's identify: section (crack position, depth, ...) "
                  "from its measured signatures, with 95 % intervals; writes identify.json, identify_map.csv, "
                  "identify_map.png and identify_fit.png. The forward runs are study cases (parallel, resumable)");
  identify_command->add_option("scene", identify_options.scene_path, "Scene file (YAML) with an identify: section")
      ->required();
  identify_command->add_option("-o,--output", identify_options.output_dir, "Output directory")->required();
  identify_command->add_option("-j,--jobs", identify_options.jobs, "Forward runs at a time (default: the cores)")
      ->check(above(0, true, "a positive integer"));
  identify_command->add_option("--map-cache", identify_options.map_cache,
                               "Folder of the map's forward runs, kept for the next measurement set of the same design");
  bool identify_quiet = false;
  identify_command->add_flag("-q,--quiet", identify_quiet, "No progress lines of the forward runs; the stages, the "
                                                           "estimate, notes and errors are still printed");

  planning::PlanOptions plan_options;
  plan_options.executable = "/proc/self/exe";
  CLI::App* plan_command = cli.add_subcommand(
      "plan", "Test planning: which sensor, drive point and drive frequency of the scene's plan: section detect and "
              "locate the cracks of its prior (Fisher information, detectability, existence of the sub-harmonic); "
              "writes plan.json, plan_sensors.vtu and plan_log_det.png. The forward runs are study cases (parallel, "
              "resumable)");
  plan_command->add_option("scene", plan_options.scene_path, "Scene file (YAML) with a plan: section")->required();
  plan_command->add_option("-o,--output", plan_options.output_dir, "Output directory")->required();
  plan_command->add_option("-j,--jobs", plan_options.jobs, "Forward runs at a time (default: the cores)")
      ->check(above(0, true, "a positive integer"));
  bool plan_quiet = false;
  plan_command->add_flag("-q,--quiet", plan_quiet, "No progress lines of the forward runs; the stages, the best "
                                                   "test, warnings and errors are still printed");

  CLI::App* format_command =
      cli.add_subcommand("scene-format", "Print the reference of every scene key (Markdown)");
  for (CLI::App* command :
       {check_command, modal_command, run_command, sweep_command, study_command, identify_command, plan_command, format_command})
    command->allow_extras();

  // Crackle's own arguments before `--`, PETSc's after it.
  SplitArguments arguments = split_arguments(argc, argv);
  std::vector<std::string> commands;
  for (const CLI::App* command :
       {check_command, modal_command, run_command, sweep_command, study_command, identify_command, plan_command, format_command})
    commands.push_back(command->get_name());
  if (arguments.own.size() > 1 && arguments.own[1][0] != '-' &&
      std::find(commands.begin(), commands.end(), arguments.own[1]) == commands.end()) {
    std::string list;
    for (const std::string& name : commands) list += (list.empty() ? "" : ", ") + name;
    return bad_command_line("unknown command '" + arguments.own[1] + "'" + scene::suggestion(arguments.own[1], commands) +
                            " (commands: " + list + "); see crackle --help");
  }

  std::vector<std::string> reversed(arguments.own.rbegin(), arguments.own.rend() - 1);  // CLI11 takes them reversed
  const auto unexpected = [&]() -> std::string {
    for (CLI::App* command : cli.get_subcommands()) {
      const bool takes_petsc = command == modal_command || command == run_command;
      const std::string message = unexpected_argument(*command, command->remaining(), takes_petsc);
      if (!message.empty()) return message;
    }
    const std::vector<std::string> rest = cli.remaining();
    return rest.empty() ? "" : "unexpected argument '" + rest.front() + "' before the command; see crackle --help";
  };
  try {
    cli.parse(reversed);
  } catch (const CLI::ParseError& error) {
    if (error.get_exit_code() == 0) return cli.exit(error);  // --help, --version
    const std::string message = unexpected();  // an unknown option says more than what it left missing
    std::string where = "crackle";
    for (const CLI::App* command : cli.get_subcommands()) where += " " + command->get_name();
    return bad_command_line(!message.empty() ? message : where + ": " + error.what() + "; see " + where + " --help");
  }
  if (const std::string message = unexpected(); !message.empty()) return bad_command_line(message);
  const bool takes_petsc = *modal_command || *run_command;
  if (arguments.separated && !takes_petsc && !arguments.petsc.empty()) {
    return bad_command_line("crackle " + cli.get_subcommands().front()->get_name() +
                            ": unexpected arguments after -- (only modal and run take PETSc options)");
  }

  bool quiet_rank = false;  // a rank of crackle run under mpirun other than 0: its errors are rank 0's
  try {
    std::ostream discard(nullptr);  // what -q leaves unprinted
    if (*check_command) pipeline::run_check(check, check_quiet ? discard : std::cout);
    if (*modal_command) {
      PetscArguments petsc(arguments.own.front(), modal_petsc, arguments.petsc);
      // As for run: an ARPACK solve (modal.solver: auto on one process) never pays MPI's start-up, a
      // third of an identify forward run; PETSc options make auto choose SLEPc.
      modal::SlepcSession session(petsc.argc(), petsc.argv(), slepc_start(modal_petsc, arguments.petsc));
      pipeline::run_modal_command(modal, modal_quiet ? discard : std::cout);
    }
    if (*run_command) {
      run.progress = !quiet;
      PetscArguments petsc(arguments.own.front(), run_petsc, arguments.petsc);
      // Under mpirun -np N > 1 the ranks share one transient (rank 0 writes and prints, errors are
      // agreed, so every rank exits with the same code and only rank 0 says why).
      quiet_rank = launcher_world_size() > 1 && launcher_world_rank() != 0;
      modal::SlepcSession session(petsc.argc(), petsc.argv(), slepc_start(run_petsc, arguments.petsc));
      pipeline::run_run_command(run, std::cout);
    }
    if (*sweep_command) {
      sweep.progress = !sweep_quiet;
      PetscArguments petsc(arguments.own.front(), {}, {});
      modal::SlepcSession session(petsc.argc(), petsc.argv(), modal::SlepcSession::Start::on_first_use);
      pipeline::run_sweep_command(sweep, std::cout, std::cerr);
    }
    if (*study_command) {
      study_options.modal_cache = !no_modal_cache;
      study_options.progress = !study_quiet;
      return study::run_study(study_options, std::cerr);
    }
    if (*identify_command) {
      identify_options.progress = !identify_quiet;
      identify::run_identify(identify_options, std::cerr);
    }
    if (*plan_command) {
      plan_options.progress = !plan_quiet;
      planning::run_plan(plan_options, std::cerr);
    }
    if (*format_command) std::cout << scene::scene_format_markdown();
  } catch (const std::bad_alloc&) {
    if (quiet_rank) return kExitOutOfMemory;
    // The estimates refuse what surely cannot fit; what they miss (solver workspace, other
    // processes taking the memory meanwhile) ends here, with a line that says what happened.
    std::string source;
    const double available = available_memory_bytes(&source);
    std::cerr << "crackle: error: out of memory: an allocation failed (std::bad_alloc) with "
              << bytes_text(available) << " available (" << source
              << "); use a coarser mesh (mesh.box.cells, mesh.box.order), fewer modes or a shorter run\n";
    return kExitOutOfMemory;
  } catch (const std::exception& error) {
    if (!quiet_rank) std::cerr << "crackle: error: " << error.what() << "\n";
    return exit_code_for(error);
  }
  return 0;
}
