// The command line at the edges, on the built executable: unknown and mistyped options, values
// out of range and stray arguments are errors naming the option (with a suggestion) and exit 2;
// --help and --version exit 0; PETSc options pass only after -- or with --petsc; `crackle run`
// refuses to run as several MPI ranks.
#include <gtest/gtest.h>

#include "cli_testing.hpp"

#include <array>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>

namespace fs = std::filesystem;

namespace {

using cli_testing::crackle;
using cli_testing::data;
using cli_testing::Result;

/// A two-mode cantilever that solves in a blink.
fs::path small_scene() {
  const fs::path path = fs::temp_directory_path() / ("crackle-cli-edges-" + std::to_string(::getpid()) + ".yaml");
  std::ofstream(path) << "mesh:\n  box: {size: [0.2, 0.02, 0.01], cells: [8, 1, 1], order: 1}\n"
                         "material: {E: 210.0e9, nu: 0.3, rho: 7850.0}\n"
                         "boundary:\n  - {face: x-, fix: [x, y, z]}\n"
                         "modal: {modes: 2, variants: [uncracked]}\n";
  return path;
}

struct BadCommandLine {
  std::string arguments;
  std::string message;  ///< the whole output: one line
};

TEST(CliEdges, BadCommandLinesGiveOneLineAndExitCode2) {
  const std::string beam = data("beam.yaml"), study = data("depth-study.yaml");
  const std::vector<BadCommandLine> cases = {
      // unknown and mistyped options
      {"run " + beam + " --sett transient.periods=2",
       "crackle run: unknown option '--sett' (did you mean '--set'?); see crackle run --help"},
      {"run " + beam + " --periods 4",
       "crackle run: unknown option '--periods' (did you mean '--set transient.periods=4'?); see crackle run --help"},
      {"run " + beam + " --modes=4",
       "crackle run: unknown option '--modes' (did you mean '--set modal.modes=4'?); see crackle run --help"},
      {"modal " + beam + " --mdoes 4", "crackle modal: unknown option '--mdoes' (did you mean '--modes'?); see crackle "
                                       "modal --help"},
      {"study " + study + " -o out --jbos 2",
       "crackle study: unknown option '--jbos' (did you mean '--jobs'?); see crackle study --help"},
      {"check " + beam + " --no-assembley",
       "crackle check: unknown option '--no-assembley' (did you mean '--no-assembly'?); see crackle check --help"},
      {"modal " + beam + " -eps_view",
       "crackle modal: unknown option '-eps_view' (a PETSc option? give it after --, e.g. `crackle modal scene.yaml "
       "-- -eps_view`, or as --petsc \"-eps_view\"); see crackle modal --help"},
      {"check " + beam + " -- -eps_view",
       "crackle check: unexpected arguments after -- (only modal and run take PETSc options)"},
      {"check " + beam + " other.yaml",
       "crackle check: unexpected argument 'other.yaml' (it takes one scene file); see crackle check --help"},
      {"chekc " + beam,
       "unknown command 'chekc' (did you mean 'check'?) (commands: check, modal, run, sweep, study, identify, plan, scene-format); see "
       "crackle --help"},
      // values out of range
      {"modal " + beam + " --modes -1",
       "crackle modal: --modes: expected a positive integer, got -1; see crackle modal --help"},
      {"modal " + beam + " --modes 0",
       "crackle modal: --modes: expected a positive integer, got 0; see crackle modal --help"},
      {"modal " + beam + " --modes many",
       "crackle modal: --modes: expected a positive integer, got many; see crackle modal --help"},
      {"study " + study + " -o out --jobs 0",
       "crackle study: --jobs: expected a positive integer, got 0; see crackle study --help"},
      {"study " + study + " -o out -j -1",
       "crackle study: --jobs: expected a positive integer, got -1; see crackle study --help"},
      {"study " + study + " -o out --case-timeout -5",
       "crackle study: --case-timeout: expected a positive number of seconds, got -5; see crackle study --help"},
      // what CLI11 itself rejects exits 2 as well
      {"run", "crackle run: scene is required; see crackle run --help"},
      {"study " + study, "crackle study: --output is required; see crackle study --help"},
      {"modal " + beam + " --modes", "crackle modal: --modes: 1 required INT missing; see crackle modal --help"},
  };
  for (const BadCommandLine& bad : cases) {
    SCOPED_TRACE(bad.arguments);
    const Result result = crackle(bad.arguments);
    EXPECT_EQ(result.exit_code, 2);
    EXPECT_EQ(result.output, "crackle: error: " + bad.message + "\n");
  }
  EXPECT_EQ(crackle("").exit_code, 2);  // a command is required
  EXPECT_FALSE(fs::exists("out"));      // nothing ran
}

TEST(CliEdges, HelpAndVersionExitZeroAndDocumentTheChannels) {
  const Result version = crackle("--version");
  EXPECT_EQ(version.exit_code, 0);
  EXPECT_EQ(version.output, "crackle 0.1.0\n");
  const Result help = crackle("--help");
  EXPECT_EQ(help.exit_code, 0);
  EXPECT_NE(help.output.find("Exit codes: 0 done; 2 bad input"), std::string::npos) << help.output;
  for (const std::string command : {"modal", "run"}) {
    const Result result = crackle(command + " --help");
    EXPECT_EQ(result.exit_code, 0);
    EXPECT_NE(result.output.find("--petsc"), std::string::npos) << result.output;
    EXPECT_NE(result.output.find("PETSc/SLEPc options go after --"), std::string::npos) << result.output;
  }
  EXPECT_EQ(crackle("study --help").exit_code, 0);
}

TEST(CliEdges, QuietIsCommonToEveryCommandThatComputes) {
  for (const std::string command : {"check", "modal", "run", "sweep", "study", "identify", "plan"}) {
    const Result help = crackle(command + " --help");
    EXPECT_EQ(help.exit_code, 0) << command;
    EXPECT_NE(help.output.find("-q,--quiet"), std::string::npos) << command << ": " << help.output;
  }
  const fs::path scene = small_scene();
  const fs::path out = fs::temp_directory_path() / ("crackle-cli-edges-quiet-" + std::to_string(::getpid()));
  const Result loud = crackle("check " + scene.string());
  ASSERT_EQ(loud.exit_code, 0) << loud.output;
  EXPECT_NE(loud.output.find("dofs"), std::string::npos) << loud.output;
  const Result check = crackle("check -q " + scene.string());
  EXPECT_EQ(check.exit_code, 0);
  EXPECT_EQ(check.output, "");  // the exit code says it
  const Result bad = crackle("check -q " + scene.string() + " --set material.nu=0.7");
  EXPECT_EQ(bad.exit_code, 2);
  EXPECT_NE(bad.output.find("crackle: error: "), std::string::npos) << bad.output;  // errors still printed
  const Result modal = crackle("modal -q " + scene.string() + " -o " + out.string());
  EXPECT_EQ(modal.exit_code, 0) << modal.output;
  EXPECT_EQ(modal.output, "");
  EXPECT_TRUE(fs::exists(out / "modal.json"));  // the table is in the files
  // A study: no progress lines, the plan and the summary still said.
  const fs::path study = fs::temp_directory_path() / ("crackle-cli-edges-study-" + std::to_string(::getpid()) + ".yaml");
  std::ifstream in(scene);
  std::ofstream(study) << std::string(std::istreambuf_iterator<char>(in), {})
                       << "study:\n  vary:\n    material.E: [200.0e9, 210.0e9]\n";
  const Result loud_study = crackle("study " + study.string() + " -o " + (out / "loud").string() + " -j 1");
  EXPECT_EQ(loud_study.exit_code, 0) << loud_study.output;
  EXPECT_NE(loud_study.output.find("cases done"), std::string::npos) << loud_study.output;
  const Result quiet_study = crackle("study -q " + study.string() + " -o " + (out / "quiet").string() + " -j 1");
  EXPECT_EQ(quiet_study.exit_code, 0) << quiet_study.output;
  EXPECT_EQ(quiet_study.output.find("cases done"), std::string::npos) << quiet_study.output;
  EXPECT_NE(quiet_study.output.find("study: 2 cases, 2 ok, 0 failed"), std::string::npos) << quiet_study.output;
  fs::remove_all(out);
  fs::remove(study);
}

/// The eigen-solver modal.json says solved.
std::string backend_of(const std::string& out) {
  std::ifstream stream(fs::path(out) / "modal.json");
  const std::string text((std::istreambuf_iterator<char>(stream)), std::istreambuf_iterator<char>());
  const auto at = text.find("\"backend\"");
  return at == std::string::npos ? "" : text.substr(at, 22);
}

// modal.solver: auto (the default) is ARPACK on one process; SLEPc options, however given, are read
// and make it SLEPc (the user who tunes -eps_* wants that solver, not a silent ARPACK).
TEST(CliEdges, PetscOptionsPassAfterTheSeparatorOrWithPetsc) {
  const fs::path scene = small_scene();
  const std::string out = (fs::temp_directory_path() / ("crackle-cli-edges-out-" + std::to_string(::getpid()))).string();
  const Result plain = crackle("modal " + scene.string() + " -o " + out);
  EXPECT_EQ(plain.exit_code, 0) << plain.output;
  EXPECT_NE(backend_of(out).find("arpack"), std::string::npos) << backend_of(out);
  for (const std::string channel : {"-- -eps_view", "--petsc -eps_view", "--petsc=\"-eps_view -eps_tol 1e-9\""}) {
    SCOPED_TRACE(channel);
    const Result result = crackle("modal " + scene.string() + " -o " + out + " " + channel);
    EXPECT_EQ(result.exit_code, 0) << result.output;
    EXPECT_NE(result.output.find("EPS Object"), std::string::npos) << result.output;
    EXPECT_NE(backend_of(out).find("slepc"), std::string::npos) << backend_of(out);
  }
  const Result environment = crackle("modal " + scene.string() + " -o " + out, "PETSC_OPTIONS=-eps_view");
  EXPECT_EQ(environment.exit_code, 0) << environment.output;
  EXPECT_NE(environment.output.find("EPS Object"), std::string::npos);
  // The scene's own choice stands.
  const Result arpack = crackle("modal " + scene.string() + " -o " + out + " --solver arpack");
  EXPECT_EQ(arpack.exit_code, 0) << arpack.output;
  EXPECT_NE(backend_of(out).find("arpack"), std::string::npos) << backend_of(out);
  fs::remove_all(out);
  fs::remove(scene);
}

}  // namespace
