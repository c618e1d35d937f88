// Running studies with a stand-in for the crackle executable (fake_crackle.cpp): complete tables
// with a failed case recorded, identical tables for any --jobs, resuming after kill -9 or Ctrl-C
// without computing a case twice, the modal cache primed once per key, MPI ranks splitting cases.
#include <gtest/gtest.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <nlohmann/json.hpp>
#include <sstream>
#include <thread>

#include "core/errors.hpp"
#include "scene/scene.hpp"
#include "study/processes.hpp"
#include "study/results.hpp"
#include "study/study.hpp"

namespace crackle::study {
namespace {
namespace fs = std::filesystem;
using nlohmann::json;

const std::string kBase =
    "mesh:\n"
    "  box: {size: [0.2, 0.02, 0.01], cells: [20, 2, 2], order: 1}\n"
    "material: {E: 210.0e9, nu: 0.3, rho: 7850.0}\n"
    "boundary:\n"
    "  - {face: x-, fix: [x, y, z]}\n"
    "crack:\n"
    "  plane: {normal: x, at: 0.05}\n"
    "  region: {y: [0.0, 0.02], z: [0.007, 0.01]}\n"
    "modal: {modes: 3}\n";

std::string read(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  std::ostringstream text;
  text << in.rdbuf();
  return text.str();
}

std::vector<std::string> lines_of(const std::string& text) {
  std::vector<std::string> lines;
  std::istringstream in(text);
  for (std::string line; std::getline(in, line);) lines.push_back(line);
  return lines;
}

/// Fields of one CSV line (RFC 4180 quotes).
std::vector<std::string> csv_fields(const std::string& line) {
  std::vector<std::string> fields(1);
  bool quoted = false;
  for (std::size_t i = 0; i < line.size(); ++i) {
    const char c = line[i];
    if (quoted && c == '"' && i + 1 < line.size() && line[i + 1] == '"') {
      fields.back() += '"';
      ++i;
    } else if (c == '"') {
      quoted = !quoted;
    } else if (c == ',' && !quoted) {
      fields.emplace_back();
    } else {
      fields.back() += c;
    }
  }
  return fields;
}

/// A fresh folder for one test, with the scene file written into it.
struct Workspace {
  fs::path root, scene, marker;
  explicit Workspace(const std::string& name, const std::string& study) {
    root = fs::temp_directory_path() / ("crackle-study-" + name + "-" + std::to_string(::getpid()));
    fs::remove_all(root);
    fs::create_directories(root);
    scene = root / "scene.yaml";
    marker = root / "marker.txt";
    std::ofstream(scene) << kBase << study;
  }
  ~Workspace() {
    if (!::testing::Test::HasFailure()) fs::remove_all(root);
  }
  /// Lines of the fake's marker file that start with `prefix`.
  std::vector<std::string> marks(const std::string& prefix = "") const {
    std::vector<std::string> found;
    for (const std::string& line : lines_of(read(marker)))
      if (line.rfind(prefix, 0) == 0) found.push_back(line);
    return found;
  }
};

/// Sets environment variables for the fake runner (inherited by the cases) while in scope.
struct ScopedEnvironment {
  std::vector<std::string> names;
  ScopedEnvironment(std::initializer_list<std::pair<std::string, std::string>> variables) {
    for (const auto& [name, value] : variables) {
      ::setenv(name.c_str(), value.c_str(), 1);
      names.push_back(name);
    }
  }
  ~ScopedEnvironment() {
    for (const std::string& name : names) ::unsetenv(name.c_str());
  }
};

StudyOptions options_for(const Workspace& workspace, const std::string& out, int jobs) {
  StudyOptions options;
  options.scene_path = workspace.scene.string();
  options.output_dir = (workspace.root / out).string();
  options.executable = FAKE_CRACKLE;
  options.jobs = jobs;
  options.poll_interval_s = 0.01;
  return options;
}

int run_quietly(const StudyOptions& options, std::string* log_text = nullptr) {
  std::ostringstream log;
  const int code = run_study(options, log);
  if (log_text) *log_text = log.str();
  return code;
}

/// Starts study_cli as its own process (environment: the current one plus `variables`).
pid_t start_cli(const Workspace& workspace, const std::string& out, int jobs,
                const std::vector<std::pair<std::string, std::string>>& variables = {}) {
  const std::string dir = (workspace.root / out).string(), jobs_text = std::to_string(jobs);
  const std::string log = (workspace.root / (out + ".log")).string();
  const pid_t pid = ::fork();
  if (pid == 0) {
    for (const auto& [name, value] : variables) ::setenv(name.c_str(), value.c_str(), 1);
    std::FILE* err = std::freopen(log.c_str(), "a", stderr);
    (void)err;
    ::execl(STUDY_CLI, STUDY_CLI, workspace.scene.c_str(), "-o", dir.c_str(), "--exe", FAKE_CRACKLE, "--jobs",
            jobs_text.c_str(), static_cast<char*>(nullptr));
    ::_exit(127);
  }
  return pid;
}

int wait_exit_code(pid_t pid) {
  int status = 0;
  ::waitpid(pid, &status, 0);
  return WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
}

/// The index of study.csv's column `name` (a failure naming the header when it is missing).
std::size_t column_of(const std::vector<std::string>& header, const std::string& name) {
  const auto found = std::find(header.begin(), header.end(), name);
  EXPECT_NE(found, header.end()) << name << " not in the header";
  return static_cast<std::size_t>(found - header.begin());
}

int count_files(const fs::path& cases, const std::string& name) {
  int n = 0;
  std::error_code error;
  for (const auto& entry : fs::directory_iterator(cases, error))
    if (fs::exists(entry.path() / name)) ++n;
  return n;
}

TEST(StudyRun, SixCasesOneFailingAreAllTabulated) {
  // nu = 0.333 makes the fake fail like a solver failure.
  Workspace workspace("six",
                      "study:\n"
                      "  mode: zip\n"
                      "  vary:\n"
                      "    crack.region.z: {from: [0.009, 0.01], to: [0.004, 0.01], steps: 6}\n"
                      "    material.nu: [0.3, 0.3, 0.333, 0.3, 0.3, 0.3]\n"
                      "  outputs: [modal, spectrum]\n");
  const ScopedEnvironment environment({{"CRACKLE_FAKE_MARKER", workspace.marker.string()}});
  std::string log;
  ASSERT_EQ(run_quietly(options_for(workspace, "out", 2), &log), kExitFailedCases);  // a case failed
  EXPECT_NE(log.find("study: 6/6 cases done, 1 failed, 0 running"), std::string::npos) << log;
  EXPECT_NE(log.find("ETA"), std::string::npos);

  const fs::path out = workspace.root / "out";
  const auto rows = lines_of(read(out / "study.csv"));
  ASSERT_EQ(rows.size(), 7u);
  const auto header = csv_fields(rows[0]);
  const auto column = [&](const std::string& name) { return column_of(header, name); };
  for (const char* name :
       {"case", "crack.region.z [m]", "material.nu [-]", "status", "error", "f_uncracked_1 [Hz]", "f_open_1 [Hz]",
        "f_bilinear_1 [Hz]", "mac_1 [-]", "f_uncracked_3 [Hz]", "excitation [Hz]", "tip.A1/2 [m]", "tip.A1 [m]",
        "tip.A2 [m]", "tip.A3 [m]", "tip.A2/A1 [-]", "tip.A3/A1 [-]", "tip.A1/2/A1 [-]", "tip.beta [1/m]",
        "tip.A1 error [-]", "tip.A2/A1 error [-]"})
    column(name);
  // Only the signatures the runs estimated get an error column; crackle run's modal.json has no
  // estimate of the frequencies.
  EXPECT_EQ(std::find(header.begin(), header.end(), "tip.A3/A1 error [-]"), header.end());
  EXPECT_EQ(std::find(header.begin(), header.end(), "f_open_1 error [-]"), header.end());
  for (std::size_t i = 1; i < rows.size(); ++i) {
    const auto row = csv_fields(rows[i]);
    ASSERT_EQ(row.size(), header.size()) << rows[i];
    EXPECT_EQ(row[column("case")], std::to_string(i - 1));
    if (i - 1 == 2) {
      EXPECT_EQ(row[column("status")], "failed");
      EXPECT_EQ(row[column("error")], "crackle: error: fake solver failure: nu = 0.333");
      EXPECT_EQ(row[column("f_uncracked_1 [Hz]")], "");
    } else {
      EXPECT_EQ(row[column("status")], "ok");
      EXPECT_EQ(row[column("error")], "");
      EXPECT_GT(std::stod(row[column("f_uncracked_1 [Hz]")]), std::stod(row[column("f_open_1 [Hz]")]));
      EXPECT_GT(std::stod(row[column("tip.A2/A1 [-]")]), 0.0);
      // The fake's A2/A1 is 0.2 * fraction and its error 0.002 * fraction: one hundredth of it.
      EXPECT_NEAR(std::stod(row[column("tip.A2/A1 error [-]")]), 0.01 * std::stod(row[column("tip.A2/A1 [-]")]), 1e-12);
      EXPECT_DOUBLE_EQ(std::stod(row[column("tip.A1 error [-]")]), 1e-4);
    }
  }
  EXPECT_EQ(csv_fields(rows[6])[column("crack.region.z [m]")], "[0.004, 0.01]");

  const json study = json::parse(read(out / "study.json"));
  EXPECT_EQ(study["n_cases"], 6);
  EXPECT_EQ(study["n_ok"], 5);
  EXPECT_EQ(study["n_failed"], 1);
  // The scene has a modal: section, so `run` writes modal.json and no case runs `modal` (only the
  // primers of the modal cache do, in their own folders).
  EXPECT_EQ(study["cases"][2]["failed_command"], "run");
  for (const std::string& line : workspace.marks("modal ")) EXPECT_EQ(line.find("/cases/"), std::string::npos) << line;
  EXPECT_EQ(study["cases"][2]["exit"], "exit status 3");
  EXPECT_EQ(study["cases"][4]["parameters"]["crack.region.z"], json::parse("[0.005, 0.01]"));
  EXPECT_TRUE(study["cases"][4]["wall_s"].is_number());
  for (const char* file :
       {"scene.yaml", "log.txt", "stdout.txt", "modal.json", "spectrum.json", "run.json", "case.json"})
    EXPECT_TRUE(fs::exists(out / "cases/0004" / file)) << file;
  EXPECT_NE(read(out / "cases/0002/log.txt").find("$ " FAKE_CRACKLE " run"), std::string::npos);
  EXPECT_FALSE(fs::exists(out / "cases/0002/spectrum.json"));  // the case stops at its first failure

  if (std::system("command -v gnuplot > /dev/null 2>&1") == 0) {
    EXPECT_TRUE(fs::exists(out / "plots/tip.A2_A1_vs_crack.region.z.png"));
    EXPECT_TRUE(fs::exists(out / "plots/f_bilinear_1_vs_material.nu.png"));
    EXPECT_GT(study["plots"]["written"].size(), 10u);
  }
}

TEST(StudyRun, JobsOneAndTwoGiveIdenticalTables) {
  Workspace workspace("jobs",
                      "study:\n"
                      "  vary:\n"
                      "    crack.region.z: [[0.008, 0.01], [0.007, 0.01], [0.006, 0.01]]\n"
                      "    material.nu: [0.3, 0.333]\n"
                      "  outputs: [modal, spectrum]\n");
  ASSERT_EQ(run_quietly(options_for(workspace, "one", 1)), kExitFailedCases);  // the nu = 0.333 cases
  StudyOptions two = options_for(workspace, "two", 2);
  two.gnuplot = "/nonexistent/gnuplot";  // plots are skipped with a note, the tables stay the same
  std::string log;
  ASSERT_EQ(run_quietly(two, &log), kExitFailedCases);
  EXPECT_NE(
      log.find("study: note: gnuplot ('/nonexistent/gnuplot') not found: plots not drawn; data and scripts "
               "written"),
      std::string::npos)
      << log;
  EXPECT_TRUE(fs::exists(workspace.root / "two/plots/tip.beta_vs_crack.region.z.gp"));
  EXPECT_FALSE(fs::exists(workspace.root / "two/plots/tip.beta_vs_crack.region.z.png"));
  // No program named (identify's forward batches): no plots and no note about gnuplot.
  StudyOptions three = options_for(workspace, "three", 2);
  three.gnuplot = "";
  log.clear();
  ASSERT_EQ(run_quietly(three, &log), kExitFailedCases);
  EXPECT_EQ(log.find("gnuplot"), std::string::npos) << log;
  EXPECT_FALSE(fs::exists(workspace.root / "three/plots/tip.beta_vs_crack.region.z.gp"));
  const std::string one = read(workspace.root / "one/study.csv");
  EXPECT_EQ(lines_of(one).size(), 7u);
  EXPECT_EQ(one, read(workspace.root / "two/study.csv"));
  EXPECT_EQ(one, read(workspace.root / "three/study.csv"));
}

TEST(StudyRun, KilledStudyResumesWithoutComputingACaseTwice) {
  Workspace workspace("kill", "study:\n  vary:\n    material.E: {from: 200e9, to: 222e9, steps: 12}\n");
  const ScopedEnvironment environment({{"CRACKLE_FAKE_MARKER", workspace.marker.string()}});
  const fs::path cases = workspace.root / "out/cases";
  const pid_t study = start_cli(workspace, "out", 2, {{"CRACKLE_FAKE_SLEEP_MS", "250"}});
  const auto give_up = std::chrono::steady_clock::now() + std::chrono::seconds(20);
  while (count_files(cases, "case.json") < 4 && std::chrono::steady_clock::now() < give_up)
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  ::kill(study, SIGKILL);
  EXPECT_EQ(wait_exit_code(study), 128 + SIGKILL);
  std::vector<std::string> done_at_kill;
  for (const auto& entry : fs::directory_iterator(cases))
    if (fs::exists(entry.path() / "case.json")) done_at_kill.push_back(entry.path().string());
  ASSERT_GE(done_at_kill.size(), 4u);
  ASSERT_LT(done_at_kill.size(), 12u);
  // The cases in flight died with the study: nothing more appears.
  const int outputs_at_kill = count_files(cases, "modal.json");
  std::this_thread::sleep_for(std::chrono::milliseconds(600));
  EXPECT_EQ(count_files(cases, "modal.json"), outputs_at_kill);

  const pid_t rerun = start_cli(workspace, "out", 2);
  EXPECT_EQ(wait_exit_code(rerun), 0) << read(workspace.root / "out.log");
  EXPECT_NE(read(workspace.root / "out.log").find(std::to_string(done_at_kill.size()) + " already done"),
            std::string::npos);

  // Each case done before the kill ran once; the others at most twice (in flight at the kill).
  std::map<std::string, int> runs;
  for (const std::string& line : workspace.marks("modal ")) ++runs[line.substr(6, line.rfind(' ') - 6)];
  EXPECT_EQ(runs.size(), 12u);
  for (const std::string& folder : done_at_kill) EXPECT_EQ(runs[folder], 1) << folder;
  EXPECT_LE(workspace.marks("modal ").size(), 12u + 2u);

  ASSERT_EQ(run_quietly(options_for(workspace, "reference", 2)), 0);
  EXPECT_EQ(read(workspace.root / "out/study.csv"), read(workspace.root / "reference/study.csv"));
}

TEST(StudyRun, InterruptedStudyStopsItsCasesAndResumes) {
  Workspace workspace("interrupt",
                      "study:\n  vary:\n    material.E: [200e9, 201e9, 202e9, 203e9, 204e9, 205e9]\n");
  const ScopedEnvironment environment({{"CRACKLE_FAKE_MARKER", workspace.marker.string()}});
  const pid_t study = start_cli(workspace, "out", 2, {{"CRACKLE_FAKE_SLEEP_MS", "300"}});
  const auto give_up = std::chrono::steady_clock::now() + std::chrono::seconds(20);
  while (count_files(workspace.root / "out/cases", "case.json") < 1 &&
         std::chrono::steady_clock::now() < give_up)
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  ::kill(study, SIGINT);
  EXPECT_EQ(wait_exit_code(study), 130);
  EXPECT_NE(read(workspace.root / "out.log").find("study: interrupted (signal 2)"), std::string::npos);
  EXPECT_FALSE(fs::exists(workspace.root / "out/study.csv"));
  for (const auto& entry : fs::directory_iterator(workspace.root / "out/cases"))
    if (fs::exists(entry.path() / "case.json"))
      EXPECT_EQ(json::parse(read(entry.path() / "case.json"))["status"], "ok")
          << "an interrupted case was recorded";
  EXPECT_EQ(wait_exit_code(start_cli(workspace, "out", 2)), 0);
  EXPECT_EQ(read(workspace.root / "out/study.csv").find("failed"), std::string::npos);
}

TEST(StudyRun, ModalCacheIsPrimedOncePerKey) {
  // 4 gaps x 2 masses: the gap does not change the uncracked modes, the mass matrix does.
  Workspace workspace(
      "cache",
      "study:\n  vary:\n    modal.mass: [consistent, lumped]\n    crack.gap: [0, 1e-6, 2e-6, 3e-6]\n");
  const ScopedEnvironment environment({{"CRACKLE_FAKE_MARKER", workspace.marker.string()}});
  ASSERT_EQ(run_quietly(options_for(workspace, "out", 2)), 0);
  EXPECT_EQ(workspace.marks("cache-solve").size(), 2u);
  EXPECT_EQ(workspace.marks("cache-hit").size(), 8u);
  EXPECT_EQ(workspace.marks("modal " + (workspace.root / "out/modal-cache").string()).size(), 2u);  // primers
  const json study = json::parse(read(workspace.root / "out/study.json"));
  EXPECT_EQ(study["cases"][0]["modal_cache_key"], study["cases"][3]["modal_cache_key"]);
  EXPECT_NE(study["cases"][0]["modal_cache_key"], study["cases"][4]["modal_cache_key"]);
  // A rerun of a finished study runs nothing and writes the same table.
  const std::string table = read(workspace.root / "out/study.csv");
  const std::size_t n_marks = workspace.marks().size();
  ASSERT_EQ(run_quietly(options_for(workspace, "out", 2)), 0);
  EXPECT_EQ(workspace.marks().size(), n_marks);
  EXPECT_EQ(read(workspace.root / "out/study.csv"), table);
  // Without the cache, no --modal-cache and no primers.
  StudyOptions uncached = options_for(workspace, "uncached", 2);
  uncached.modal_cache = false;
  ASSERT_EQ(run_quietly(uncached), 0);
  EXPECT_EQ(workspace.marks("cache-").size(), 10u);
  EXPECT_EQ(read(workspace.root / "uncached/study.csv"), table);
}

// The cases of one mesh with an accuracy tolerance (three drive amplitudes per crack) refine once:
// the first case of each crack runs its tolerance loop from the scene's setting, the others wait for
// it and start theirs where it ended (`--accuracy-start` its run.json, which must exist when they
// start: the fake reads it). A rerun after a lost follower still starts it from its leader.
TEST(StudyRun, TheCasesOfOneMeshRefineOnceAndTheOthersStartWhereTheFirstEnded) {
  Workspace workspace("accuracy",
                      "transient:\n  model: reduced\n"
                      "  excitation: {point: [0.2, 0.01, 0.01], direction: z, amplitude: 10.0, frequency: 100}\n"
                      "  periods: 4\n  probes:\n    - {name: tip, point: [0.2, 0.01, 0.01]}\n"
                      "spectrum: {harmonics: 3}\n"
                      "accuracy: {tolerance: 0.01}\n"
                      "study:\n  vary:\n    crack.region.z: [[0.007, 0.01], [0.005, 0.01]]\n"
                      "    transient.excitation.amplitude: [10, 20, 30]\n  outputs: [spectrum]\n");
  const ScopedEnvironment environment({{"CRACKLE_FAKE_MARKER", workspace.marker.string()}});
  ASSERT_EQ(run_quietly(options_for(workspace, "out", 2)), 0);
  const fs::path cases = workspace.root / "out/cases";
  std::map<double, int> leaders;  // crack's lower edge -> its leader case
  std::vector<std::pair<int, double>> followers;
  for (int index = 0; index < 6; ++index) {
    char name[8];
    std::snprintf(name, sizeof name, "%04d", index);
    const json record = json::parse(read(cases / name / "case.json"));
    ASSERT_EQ(record["status"], "ok") << record.dump();
    const double edge = scene::load_scene((cases / name / "scene.yaml").string()).crack->region[2][0];
    if (record.contains("accuracy_start")) {
      followers.push_back({index, edge});
    } else {
      EXPECT_EQ(leaders.count(edge), 0u) << "two cases of one mesh refined from the scene's setting";
      leaders[edge] = index;
    }
  }
  ASSERT_EQ(leaders.size(), 2u);
  ASSERT_EQ(followers.size(), 4u);
  for (const auto& [index, edge] : followers) {
    char name[8], leader[8];
    std::snprintf(name, sizeof name, "%04d", index);
    std::snprintf(leader, sizeof leader, "%04d", leaders.at(edge));
    const json record = json::parse(read(cases / name / "case.json"));
    const fs::path start = cases / leader / "run.json";
    EXPECT_EQ(record["accuracy_start"]["run"], start.string());
    // It reached the setting its leader reached (the fake's leader: one order above the scene's).
    EXPECT_EQ(json::parse(read(cases / name / "run.json"))["accuracy"]["reached"]["order"], 2);
  }
  EXPECT_EQ(workspace.marks("accuracy-start").size(), 4u);
  // A follower lost (its case.json removed) reruns from its leader, which a rerun does not redo.
  const auto [lost, lost_edge] = followers.front();
  char lost_name[8];
  std::snprintf(lost_name, sizeof lost_name, "%04d", lost);
  fs::remove(cases / lost_name / "case.json");
  const std::size_t before = workspace.marks("run").size();
  ASSERT_EQ(run_quietly(options_for(workspace, "out", 2)), 0);
  EXPECT_EQ(workspace.marks("run").size(), before + 1);
  EXPECT_TRUE(json::parse(read(cases / lost_name / "case.json")).contains("accuracy_start"));
  EXPECT_EQ(workspace.marks("accuracy-start").size(), 5u);
}

TEST(StudyRun, ChangedStudyRerunsOnlyTheChangedCases) {
  Workspace workspace("changed", "study:\n  vary:\n    material.E: [200e9, 210e9, 220e9]\n");
  const ScopedEnvironment environment({{"CRACKLE_FAKE_MARKER", workspace.marker.string()}});
  ASSERT_EQ(run_quietly(options_for(workspace, "out", 2)), 0);
  EXPECT_EQ(workspace.marks("modal ").size(), 3u);
  std::ofstream(workspace.scene) << kBase << "study:\n  vary:\n    material.E: [200e9, 215e9, 220e9]\n";
  ASSERT_EQ(run_quietly(options_for(workspace, "out", 2)), 0);
  const auto runs = workspace.marks("modal ");
  ASSERT_EQ(runs.size(), 4u);
  EXPECT_NE(runs[3].find("cases/0001"), std::string::npos);
  EXPECT_NE(read(workspace.root / "out/study.csv").find(",215e9,"), std::string::npos);
}

TEST(StudyRun, MpiRanksSplitTheCasesAndRankZeroWritesTheTables) {
  Workspace workspace("mpi",
                      "study:\n  vary:\n    material.E: [200e9, 201e9, 202e9, 203e9, 204e9, 205e9, 206e9]\n");
  const ScopedEnvironment environment({{"CRACKLE_FAKE_MARKER", workspace.marker.string()}});
  std::vector<pid_t> ranks;
  for (int rank = 0; rank < 2; ++rank) {
    ranks.push_back(start_cli(workspace, "out", 1,
                              {{"OMPI_COMM_WORLD_SIZE", "2"},
                               {"OMPI_COMM_WORLD_RANK", std::to_string(rank)},
                               {"OMPI_COMM_WORLD_LOCAL_SIZE", "2"},
                               {"CRACKLE_FAKE_SLEEP_MS", "50"}}));
  }
  for (pid_t rank : ranks) EXPECT_EQ(wait_exit_code(rank), 0) << read(workspace.root / "out.log");
  // Case i ran under rank i % 2 (the fake records its parent's pid), with the launcher's variables removed.
  for (const std::string& line : workspace.marks("modal ")) {
    const int index = std::stoi(line.substr(line.find("cases/") + 6, 4));
    EXPECT_EQ(std::stoi(line.substr(line.rfind(' ') + 1)), ranks[index % 2]) << line;
  }
  EXPECT_EQ(workspace.marks("modal ").size(), 7u);
  ASSERT_EQ(run_quietly(options_for(workspace, "reference", 2)), 0);
  EXPECT_EQ(read(workspace.root / "out/study.csv"), read(workspace.root / "reference/study.csv"));
}

// A case process gets one OpenMP and one OpenBLAS thread unless the user's environment says
// otherwise (OpenBLAS's pthreads build would start one per core in each case run side by side), and
// no MPI launcher variables.
TEST(StudyRun, CaseProcessesGetTheirThreadCountsUnlessTheEnvironmentSetsThem) {
  const auto has = [](const std::vector<std::string>& environment, const std::string& entry) {
    return std::find(environment.begin(), environment.end(), entry) != environment.end();
  };
  const auto count = [](const std::vector<std::string>& environment, const std::string& prefix) {
    return std::count_if(environment.begin(), environment.end(),
                         [&](const std::string& e) { return e.rfind(prefix, 0) == 0; });
  };
  std::map<std::string, std::string> saved;
  for (const char* name : {"OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "OMPI_COMM_WORLD_SIZE"}) {
    if (const char* value = std::getenv(name)) saved[name] = value;
  }
  ::unsetenv("OMP_NUM_THREADS");
  ::unsetenv("OPENBLAS_NUM_THREADS");
  ::setenv("OMPI_COMM_WORLD_SIZE", "2", 1);
  const std::vector<std::string> unset = crackle::study::child_environment(1);
  EXPECT_TRUE(has(unset, "OMP_NUM_THREADS=1"));
  EXPECT_TRUE(has(unset, "OPENBLAS_NUM_THREADS=1"));
  EXPECT_EQ(count(unset, "OMPI_"), 0);
  ::setenv("OPENBLAS_NUM_THREADS", "3", 1);
  ::setenv("OMP_NUM_THREADS", "4", 1);
  const std::vector<std::string> given = crackle::study::child_environment(1);
  EXPECT_TRUE(has(given, "OPENBLAS_NUM_THREADS=3"));
  EXPECT_TRUE(has(given, "OMP_NUM_THREADS=4"));
  EXPECT_EQ(count(given, "OPENBLAS_NUM_THREADS="), 1);
  EXPECT_EQ(count(given, "OMP_NUM_THREADS="), 1);
  const std::vector<std::string> left = crackle::study::child_environment(0);
  ::unsetenv("OMP_NUM_THREADS");
  ::unsetenv("OPENBLAS_NUM_THREADS");
  EXPECT_EQ(count(crackle::study::child_environment(0), "OPENBLAS_NUM_THREADS="), 0);
  EXPECT_EQ(count(left, "OPENBLAS_NUM_THREADS="), 1);  // the user's, kept
  ::unsetenv("OMPI_COMM_WORLD_SIZE");
  for (const auto& [name, value] : saved) ::setenv(name.c_str(), value.c_str(), 1);
}

TEST(StudyRun, BadOverrideFailsBeforeAnythingRuns) {
  Workspace workspace("bad",
                      "study:\n  vary:\n    material.E: [200e9, 210e9]\n    material.nu: [0.3, 0.6]\n");
  const ScopedEnvironment environment({{"CRACKLE_FAKE_MARKER", workspace.marker.string()}});
  EXPECT_EQ(wait_exit_code(start_cli(workspace, "out", 2)), 2);
  const std::string message = read(workspace.root / "out.log");
  EXPECT_NE(
      message.find("scene.yaml:13: study.vary.material.nu: case 1 (material.E = 200e9, material.nu = 0.6): "
                   "material.nu: expected a number in (-1, 0.5), got 0.6"),
      std::string::npos)
      << message;
  EXPECT_FALSE(fs::exists(workspace.root / "out"));
  EXPECT_FALSE(fs::exists(workspace.marker));
  std::ofstream(workspace.scene) << kBase << "study:\n  vary:\n    material.young: [200e9]\n";
  EXPECT_THROW(run_quietly(options_for(workspace, "out", 2)), InputError);
  EXPECT_FALSE(fs::exists(workspace.root / "out"));
}

TEST(StudyResults, UnpairedModesLeaveRatioAndBilinearFrequencyEmpty) {
  const json modal = json::parse(R"({"variants": {"uncracked": {"frequencies_hz": [100, 200]},
                                                  "open": {"frequencies_hz": [90, 150]}},
    "pairs": [{"uncracked_mode": 1, "open_mode": 1, "f_uncracked_hz": 100, "f_open_hz": 90, "ratio": 0.9,
               "mac": 0.99, "f_bilinear_hz": 94.7, "paired": true},
              {"uncracked_mode": 2, "open_mode": 2, "f_uncracked_hz": 200, "f_open_hz": 150, "ratio": 0.75,
               "mac": 0.08, "f_bilinear_hz": 171.4, "paired": false}]})");
  const json summary = summarize_modal(modal);
  ASSERT_EQ(summary["pairs"].size(), 2u);
  EXPECT_EQ(summary["pairs"][0]["bilinear_hz"], 94.7);
  EXPECT_EQ(summary["pairs"][0]["ratio"], 0.9);
  EXPECT_TRUE(summary["pairs"][1]["bilinear_hz"].is_null());
  EXPECT_TRUE(summary["pairs"][1]["ratio"].is_null());
  EXPECT_EQ(summary["pairs"][1]["mac"], 0.08);  // the MAC says why
  EXPECT_FALSE(summary["pairs"][1]["paired"].get<bool>());
  EXPECT_FALSE(summary.contains("open_error"));  // no accuracy block: no errors
}

// crackle modal's frequency estimates (modal.json accuracy) become error columns beside each
// frequency; a study without them has none (SixCasesOneFailingAreAllTabulated).
TEST(StudyRun, ModalCasesEstimatesAreErrorColumnsBesideTheirFrequencies) {
  Workspace workspace("modal-errors",
                      "study:\n"
                      "  vary:\n"
                      "    crack.region.z: [[0.008, 0.01], [0.006, 0.01]]\n"
                      "  outputs: [modal]\n");
  std::string log;
  ASSERT_EQ(run_quietly(options_for(workspace, "out", 2), &log), 0) << log;
  const auto rows = lines_of(read(workspace.root / "out" / "study.csv"));
  ASSERT_EQ(rows.size(), 3u);
  const auto header = csv_fields(rows[0]);
  const auto column = [&](const std::string& name) { return column_of(header, name); };
  // Each error column follows its frequency.
  EXPECT_EQ(column("f_open_2 error [-]"), column("f_open_2 [Hz]") + 1);
  for (std::size_t i = 1; i < rows.size(); ++i) {
    const auto row = csv_fields(rows[i]);
    EXPECT_DOUBLE_EQ(std::stod(row[column("f_uncracked_1 error [-]")]), 1e-3);
    EXPECT_DOUBLE_EQ(std::stod(row[column("f_open_2 error [-]")]), 4e-3);
    EXPECT_DOUBLE_EQ(std::stod(row[column("f_bilinear_3 error [-]")]), 4.5e-3);
  }
}

TEST(StudyRun, FailedCaseRecordsItsErrorLineAndTheStudyExitsThree) {
  // The failing case writes progress lines ('\r'), then its error line, then one more line.
  Workspace workspace("failing",
                      "study:\n"
                      "  vary:\n"
                      "    material.nu: [0.3, 0.333]\n"
                      "  outputs: [spectrum]\n");
  const ScopedEnvironment environment({{"CRACKLE_FAKE_TRAILER", "WARNING! There are options you set that were not used!"}});
  std::string log;
  ASSERT_EQ(run_quietly(options_for(workspace, "out", 2), &log), kExitFailedCases) << log;
  const json failed = json::parse(read(workspace.root / "out/cases/0001/case.json"));
  EXPECT_EQ(failed["status"], "failed");
  EXPECT_EQ(failed["error"], "crackle: error: fake solver failure: nu = 0.333");
  EXPECT_EQ(failed["exit"], "exit status 3");
  EXPECT_NE(log.find("study: cases/0001 failed: crackle: error: fake solver failure: nu = 0.333\n"), std::string::npos)
      << log;
  // A rerun finds every case done, one of them failed: the study still says so.
  ASSERT_EQ(run_quietly(options_for(workspace, "out", 2), &log), kExitFailedCases) << log;
  EXPECT_NE(log.find("2 cases, 1 ok, 1 failed"), std::string::npos) << log;
}

TEST(StudyRun, RealCrackleWhenItHasTheModalCommand) {
  // The real executable slots in where the fake stands: skipped until `crackle modal` exists.
  const std::string crackle = CRACKLE_BINARY_DIR "/apps/crackle";
  if (!fs::exists(crackle) || std::system((crackle + " modal --help > /dev/null 2>&1").c_str()) != 0)
    GTEST_SKIP() << crackle << " has no modal command yet";
  Workspace workspace("real", "study:\n  vary:\n    crack.region.z: [[0.008, 0.01], [0.006, 0.01]]\n");
  StudyOptions options = options_for(workspace, "out", 2);
  options.executable = crackle;
  options.modal_cache = std::system((crackle + " modal --help 2>&1 | grep -q -- --modal-cache").c_str()) == 0;
  std::string log;
  ASSERT_EQ(run_quietly(options, &log), 0);
  const json study = json::parse(read(workspace.root / "out/study.json"));
  ASSERT_EQ(study["n_ok"], 2) << log << study.dump(2);
  for (const json& c : study["cases"]) {
    const double f_uncracked = c["modal"]["uncracked_hz"][0], f_open = c["modal"]["open_hz"][0];
    EXPECT_GT(f_uncracked, 0.0);
    EXPECT_LE(f_open, f_uncracked * (1 + 1e-9));
  }
  // The deeper crack lowers the open frequency more.
  EXPECT_LT(study["cases"][1]["modal"]["open_hz"][0].get<double>(),
            study["cases"][0]["modal"]["open_hz"][0].get<double>());
}

}  // namespace
}  // namespace crackle::study
