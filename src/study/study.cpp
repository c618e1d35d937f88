#include "study/study.hpp"

#include <fcntl.h>
#include <sys/file.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <csignal>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <deque>
#include <filesystem>
#include <fstream>
#include <map>
#include <ostream>
#include <thread>
#include <nlohmann/json.hpp>

#include "core/errors.hpp"
#include "core/mpi_session.hpp"
#include "io/files.hpp"
#include "study/plan.hpp"
#include "study/plot.hpp"
#include "study/processes.hpp"
#include "study/results.hpp"

namespace crackle::study {
namespace fs = std::filesystem;
using Clock = std::chrono::steady_clock;
using nlohmann::json;

namespace {

/// Set by the signal handler: the one piece of global state, since a handler can reach nothing else.
volatile std::sig_atomic_t interrupted_by = 0;

void on_interrupt(int signal) { interrupted_by = signal; }

/// Catches SIGINT, SIGTERM and SIGHUP while a study runs; restores the previous handlers.
class InterruptGuard {
 public:
  InterruptGuard() {
    interrupted_by = 0;
    struct sigaction action {};
    action.sa_handler = on_interrupt;
    sigemptyset(&action.sa_mask);
    for (std::size_t i = 0; i < std::size(kSignals); ++i) ::sigaction(kSignals[i], &action, &previous_[i]);
  }
  ~InterruptGuard() {
    for (std::size_t i = 0; i < std::size(kSignals); ++i) ::sigaction(kSignals[i], &previous_[i], nullptr);
  }
  InterruptGuard(const InterruptGuard&) = delete;
  InterruptGuard& operator=(const InterruptGuard&) = delete;

 private:
  static constexpr int kSignals[3] = {SIGINT, SIGTERM, SIGHUP};
  struct sigaction previous_[3]{};
};

/// An exclusive lock on a file in the output directory, held while the study runs (released by
/// the kernel however the process ends).
class DirectoryLock {
 public:
  explicit DirectoryLock(const fs::path& path) {
    fd_ = ::open(path.c_str(), O_RDWR | O_CREAT | O_CLOEXEC, 0644);
    if (fd_ < 0)
      throw IoError(path.string() + ": cannot create the study lock (" + std::strerror(errno) + ")");
    if (::flock(fd_, LOCK_EX | LOCK_NB) != 0) {
      ::close(fd_);
      throw IoError(path.parent_path().string() + ": in use by another crackle study (lock " + path.string() +
                    ")");
    }
  }
  ~DirectoryLock() { ::close(fd_); }
  DirectoryLock(const DirectoryLock&) = delete;
  DirectoryLock& operator=(const DirectoryLock&) = delete;

 private:
  int fd_ = -1;
};


std::string duration_text(double seconds) {
  const long total = std::lround(std::max(0.0, seconds));
  char buffer[32];
  if (total >= 3600)
    std::snprintf(buffer, sizeof buffer, "%ldh%02ldm%02lds", total / 3600, total / 60 % 60, total % 60);
  else if (total >= 60)
    std::snprintf(buffer, sizeof buffer, "%ldm%02lds", total / 60, total % 60);
  else
    std::snprintf(buffer, sizeof buffer, "%lds", total);
  return buffer;
}

double seconds_since(Clock::time_point start) {
  return std::chrono::duration<double>(Clock::now() - start).count();
}

/// What a failed command said, from its stderr (a file, from byte `offset` on): the last
/// `crackle: error: ...` line, else the last non-empty line, else "". Lines end at '\n' or '\r'
/// (a progress line is rewritten in place with '\r').
std::string error_line(const fs::path& path, std::uintmax_t offset) {
  std::ifstream in(path, std::ios::binary);
  if (!in) return "";
  in.seekg(static_cast<std::streamoff>(offset));
  const std::string text{std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
  std::string last, error;
  std::size_t start = 0;
  while (start < text.size()) {
    std::size_t end = text.find_first_of("\r\n", start);
    if (end == std::string::npos) end = text.size();
    std::string line = text.substr(start, end - start);
    while (!line.empty() && line.back() == ' ') line.pop_back();
    if (!line.empty()) last = line;
    const std::size_t found = line.find("crackle: error: ");
    if (found != std::string::npos) error = line.substr(found);
    start = end + 1;
  }
  return error.empty() ? last : error;
}

std::string command_line(const std::vector<std::string>& argv) {
  std::string text;
  for (const std::string& a : argv) text += (text.empty() ? "" : " ") + a;
  return text;
}

/// A primer or a case: commands run one after the other in one folder.
struct Job {
  bool primer = false;
  int case_index = -1;
  std::string key;  ///< modal cache key
  fs::path folder;
  std::vector<std::pair<std::string, std::vector<std::string>>> commands;  ///< name, argv
  std::size_t next = 0;  ///< the command running is commands[next - 1]
  ChildProcess child;
  std::uintmax_t log_offset = 0;  ///< size of log.txt when the running command started
  json accuracy_start = json::object();  ///< command -> the --accuracy-start file it was given
  Clock::time_point start;
};

/// Scheduling state of the cases that share a modal cache key.
struct Group {
  enum class State { needs_primer, priming, primed } state = State::primed;
  int first_case = -1;
};

class StudyRun {
 public:
  StudyRun(const StudyOptions& options, const StudyPlan& plan, std::ostream& log)
      : options_(options), plan_(plan), log_(log), finished_(plan.cases.size()) {}

  int run();

 private:
  void detect_ranks();
  bool mine(int index) const { return index % n_ranks_ == rank_; }
  fs::path case_path(int index) const { return directory_ / case_folder(index); }
  fs::path cache_path(const std::string& key) const { return directory_ / "modal-cache" / key; }

  void scan_finished(bool initial);
  bool start_next();
  Job case_job(int index);
  /// The case's `--accuracy-start FILE` arguments for `command` (run or sweep): its group leader's
  /// run.json or sweep.json where that estimate reached a setting under a tolerance, else none.
  std::vector<std::string> accuracy_start(int index, const std::string& command) const;
  Job primer_job(const std::string& key, int index);
  void start_command(Job& job);
  /// Polls the running jobs; true when one finished.
  bool poll_jobs();
  void finish_case(Job& job, const std::string& failed_command, const std::string& error,
                   const std::string& exit);
  void finish_primer(Job& job, bool ok);
  int stop_all();
  void progress(bool force);
  void write_tables();

  const StudyOptions& options_;
  const StudyPlan& plan_;
  std::ostream& log_;
  fs::path directory_, executable_;
  int rank_ = 0, n_ranks_ = 1, jobs_ = 1;
  std::vector<std::string> environment_;
  std::vector<json> finished_;  ///< case.json of each done case, null while not done
  std::deque<int> pending_;     ///< this rank's cases to run, in order
  std::map<std::string, Group> groups_;
  /// The leader of each accuracy key (StudyCase::accuracy_key): the first case of it refines to its
  /// tolerance alone; the others wait until it is done and start where it ended.
  std::map<std::string, int> accuracy_leaders_;
  std::vector<Job> running_;
  std::map<int, fs::file_time_type> failed_before_;  ///< retry_failed: when the old failure was written
  Clock::time_point start_;
  int own_total_ = 0;  ///< cases of this rank
  int done_before_ = 0, done_now_ = 0, n_done_ = 0, n_failed_ = 0, last_reported_ = -1;
  Clock::time_point last_scan_;
};

void StudyRun::detect_ranks() {
  n_ranks_ =
      options_.n_ranks > 0 ? options_.n_ranks : launcher_world_size();
  rank_ = options_.rank >= 0 ? options_.rank : launcher_world_rank();
  if (n_ranks_ < 1 || rank_ < 0 || rank_ >= n_ranks_)
    throw InputError("study: rank " + std::to_string(rank_) + " of " + std::to_string(n_ranks_) +
                     " ranks is not valid");
  const int on_node = launcher_local_size();
  const int cores = std::max(1u, std::thread::hardware_concurrency());
  jobs_ = options_.jobs > 0 ? options_.jobs : std::max(1, cores / std::min(on_node, n_ranks_));
}

void StudyRun::scan_finished(bool initial) {
  for (std::size_t i = 0; i < plan_.cases.size(); ++i) {
    if (!finished_[i].is_null()) continue;
    const int index = static_cast<int>(i);
    if (!initial && mine(index)) continue;     // this rank records its own cases as they finish
    if (rank_ != 0 && !mine(index)) continue;  // only rank 0 follows the other ranks' cases
    json done = read_finished_case(case_path(index), plan_.cases[i].hash);
    if (done.is_null()) continue;
    if (options_.retry_failed && done.value("status", "") == "failed") {
      // A failed case counts only once redone in this run (by whichever rank owns it).
      std::error_code error;
      const auto written = fs::last_write_time(case_path(index) / "case.json", error);
      if (initial) {
        failed_before_[index] = written;
        continue;
      }
      const auto before = failed_before_.find(index);
      if (error || (before != failed_before_.end() && before->second == written)) continue;
    }
    finished_[i] = done;
    ++n_done_;
    n_failed_ += done.value("status", "") == "failed";
    if (initial)
      ++done_before_;
    else
      ++done_now_;
  }
}

Job StudyRun::case_job(int index) {
  const StudyCase& study_case = plan_.cases[index];
  Job job;
  job.case_index = index;
  job.key = study_case.modal_key;
  job.folder = case_path(index);
  std::error_code error;
  fs::remove_all(job.folder, error);  // what an interrupted or changed run left
  if (error) throw IoError(job.folder.string() + ": cannot clear the case folder (" + error.message() + ")");
  io::ensure_directory(job.folder);
  const fs::path scene = job.folder / "scene.yaml";
  io::write_file_atomic(scene, study_case.scene_text);
  // `crackle run` writes modal.json itself when the scene has a modal: section (the same variants,
  // at least as many modes), so a case that asks for both runs only `run`: one modal solve less.
  const auto& outputs = plan_.spec.outputs;
  // `crackle sweep` runs the same modal stage.
  const bool run_writes_modal =
      study_case.has_modal_section && (std::count(outputs.begin(), outputs.end(), "spectrum") > 0 ||
                                       std::count(outputs.begin(), outputs.end(), "sweep") > 0);
  for (const std::string& output : outputs) {
    if (output == "modal" && run_writes_modal) continue;
    const std::string command = output == "spectrum" ? "run" : output == "sweep" ? "sweep" : "modal";
    std::vector<std::string> argv = {executable_.string(), command, scene.string(), "-o",
                                     job.folder.string()};
    if (options_.modal_cache) {
      argv.push_back("--modal-cache");
      argv.push_back(options_.modal_cache_directory.empty() ? cache_path(study_case.modal_key).string()
                                                            : options_.modal_cache_directory);
    }
    // The case folder holds the study's scene.yaml and log.txt: modal and run refuse such a folder
    // without --overwrite; sweep writes into any folder (it has no such flag).
    if (command != "sweep") argv.push_back("--overwrite");
    if (const std::vector<std::string> start = command == "modal" ? std::vector<std::string>()
                                                                  : accuracy_start(index, command);
        !start.empty()) {
      argv.insert(argv.end(), start.begin(), start.end());
      job.accuracy_start[command] = start.back();
    }
    job.commands.push_back({command, argv});
  }
  return job;
}

std::vector<std::string> StudyRun::accuracy_start(int index, const std::string& command) const {
  const std::string& key = plan_.cases[index].accuracy_key;
  if (key.empty()) return {};
  const auto leader = accuracy_leaders_.find(key);
  if (leader == accuracy_leaders_.end() || leader->second == index) return {};
  const fs::path file = case_path(leader->second) / (command == "sweep" ? "sweep.json" : "run.json");
  std::error_code error;
  if (!fs::exists(file, error)) return {};
  try {
    const json document = json::parse(io::read_file(file));
    const json accuracy = document.value("accuracy", json::object());
    // `met` is there exactly when the estimate had a tolerance to reach (run.json, sweep.json).
    if (!accuracy.is_object() || !accuracy.contains("reached") || !accuracy.contains("met")) return {};
  } catch (const std::exception&) {
    return {};  // the leader's file is its own case's concern; this case refines from its own setting
  }
  return {"--accuracy-start", file.string()};
}

Job StudyRun::primer_job(const std::string& key, int index) {
  Job job;
  job.primer = true;
  job.case_index = index;
  job.key = key;
  job.folder = cache_path(key) / "primer";
  std::error_code error;
  fs::remove_all(job.folder, error);
  io::ensure_directory(job.folder);
  const fs::path scene = job.folder / "scene.yaml";
  io::write_file_atomic(scene, plan_.cases[index].primer_text);
  job.commands.push_back({"modal",
                          {executable_.string(), "modal", scene.string(), "-o", job.folder.string(),
                           "--modal-cache", cache_path(key).string(), "--overwrite"}});
  return job;
}

void StudyRun::start_command(Job& job) {
  const auto& [name, argv] = job.commands[job.next++];
  const fs::path log_file = job.folder / "log.txt";
  {
    std::ofstream header(log_file, std::ios::app);
    header << "$ " << command_line(argv) << "\n";
  }
  std::error_code error;
  job.log_offset = fs::exists(log_file, error) ? fs::file_size(log_file, error) : 0;
  job.child = start_process(argv, environment_, job.folder / "stdout.txt", log_file);
}

bool StudyRun::start_next() {
  // A case whose modal cache key is primed (or needs no primer) and whose accuracy group's leader
  // is done (or which leads it), else a primer for a key.
  for (auto it = pending_.begin(); it != pending_.end(); ++it) {
    if (groups_[plan_.cases[*it].modal_key].state != Group::State::primed) continue;
    if (const std::string& key = plan_.cases[*it].accuracy_key; !key.empty()) {
      const auto [leader, first] = accuracy_leaders_.emplace(key, *it);
      if (!first && finished_[leader->second].is_null()) continue;  // its leader is running
    }
    Job job = case_job(*it);
    pending_.erase(it);
    job.start = Clock::now();
    start_command(job);
    running_.push_back(std::move(job));
    return true;
  }
  for (auto& [key, group] : groups_) {
    if (group.state != Group::State::needs_primer) continue;
    group.state = Group::State::priming;
    Job job = primer_job(key, group.first_case);
    job.start = Clock::now();
    start_command(job);
    running_.push_back(std::move(job));
    return true;
  }
  return false;
}

void StudyRun::finish_case(Job& job, const std::string& failed_command, const std::string& error,
                           const std::string& exit) {
  const StudyCase& study_case = plan_.cases[job.case_index];
  json record = json::object();
  record["case"] = study_case.index;
  record["scene_hash"] = study_case.hash;
  record["outputs"] = plan_.spec.outputs;
  if (options_.modal_cache) record["modal_cache_key"] = study_case.modal_key;
  std::string problem;
  json kept =
      failed_command.empty() ? read_case_outputs(job.folder, plan_.spec.outputs, problem) : json::object();
  const bool ok = failed_command.empty() && problem.empty();
  record["status"] = ok ? "ok" : "failed";
  record["error"] = ok ? "" : failed_command.empty() ? problem : error;
  if (!failed_command.empty()) {
    record["failed_command"] = failed_command;
    record["exit"] = exit;
  }
  record["wall_s"] = seconds_since(job.start);
  for (const auto& [name, value] : kept.items()) record[name] = value;
  if (!job.accuracy_start.empty()) record["accuracy_start"] = job.accuracy_start;  // where its tolerance loops started
  io::write_json(job.folder / "case.json", record);  // last, atomically: the case is done
  finished_[job.case_index] = record;
  ++n_done_;
  ++done_now_;
  if (!ok) {
    ++n_failed_;
    log_ << "study: " << case_folder(job.case_index) << " failed: " << record["error"].get<std::string>()
         << "\n";
  }
}

void StudyRun::finish_primer(Job& job, bool ok) {
  groups_[job.key].state = Group::State::primed;
  if (ok) {
    io::write_file_atomic(cache_path(job.key) / "primed", job.key + "\n");
  } else {
    log_ << "study: note: priming the modal cache " << job.key << " failed (see "
         << (job.folder / "log.txt").string() << "); its cases solve the uncracked modes themselves\n";
  }
}

bool StudyRun::poll_jobs() {
  bool finished_any = false;
  for (std::size_t j = 0; j < running_.size();) {
    Job& job = running_[j];
    std::optional<ExitStatus> status = poll_process(job.child);
    bool timed_out = false;
    if (!status && !job.primer && options_.case_timeout_s > 0 &&
        seconds_since(job.start) > options_.case_timeout_s) {
      signal_process(job.child, SIGKILL);
      status = wait_process(job.child);
      timed_out = true;
    }
    if (!status) {
      ++j;
      continue;
    }
    // A child that died of an interruption signal belongs to an interrupted study: not recorded.
    if (interrupted_by != 0 || status->signal == SIGINT || status->signal == SIGTERM ||
        status->signal == SIGHUP) {
      if (interrupted_by == 0) interrupted_by = status->signal;
      ++j;
      job.child.pid = -1;
      continue;
    }
    const std::string name = job.commands[job.next - 1].first;
    if (status->ok() && job.next < job.commands.size()) {
      start_command(job);
      ++j;
      continue;
    }
    if (job.primer) {
      finish_primer(job, status->ok());
    } else if (status->ok()) {
      finish_case(job, "", "", "");
    } else {
      std::string error = timed_out ? "timed out after " + duration_text(options_.case_timeout_s)
                                    : error_line(job.folder / "log.txt", job.log_offset);
      if (error.empty()) error = "crackle " + name + ": " + status->describe() + " without a message";
      finish_case(job, name, error, timed_out ? "timed out" : status->describe());
    }
    finished_any = finished_any || !job.primer;
    running_.erase(running_.begin() + static_cast<std::ptrdiff_t>(j));
  }
  return finished_any;
}

int StudyRun::stop_all() {
  for (Job& job : running_)
    if (job.child.pid > 0) signal_process(job.child, SIGTERM);
  const Clock::time_point asked = Clock::now();
  for (Job& job : running_) {
    if (job.child.pid <= 0) continue;
    while (!poll_process(job.child)) {
      if (seconds_since(asked) > 2.0) {
        signal_process(job.child, SIGKILL);
        wait_process(job.child);
        break;
      }
      std::this_thread::sleep_for(std::chrono::milliseconds(20));
    }
  }
  const int in_flight = static_cast<int>(
      std::count_if(running_.begin(), running_.end(), [](const Job& j) { return !j.primer; }));
  running_.clear();
  log_ << "study: interrupted (signal " << interrupted_by << "): " << n_done_ << "/" << plan_.cases.size()
       << " cases done, " << in_flight << " in flight stopped; rerun the same command to finish the rest\n";
  return 130;
}

void StudyRun::progress(bool force) {
  if (!options_.progress || (!force && n_done_ == last_reported_)) return;
  last_reported_ = n_done_;
  // Rank 0 counts every case; the other ranks their own.
  const int total = rank_ == 0 ? static_cast<int>(plan_.cases.size()) : own_total_;
  const double elapsed = seconds_since(start_);
  std::string eta = "?";
  if (n_done_ == total)
    eta = "0s";
  else if (done_now_ > 0)
    eta = duration_text(elapsed / done_now_ * (total - n_done_));
  const int in_flight = static_cast<int>(
      std::count_if(running_.begin(), running_.end(), [](const Job& j) { return !j.primer; }));
  log_ << "study" << (n_ranks_ > 1 ? " [rank " + std::to_string(rank_) + "]" : "") << ": " << n_done_ << "/"
       << total << " cases done, " << n_failed_ << " failed, " << in_flight << " running, "
       << duration_text(elapsed) << " elapsed, ETA " << eta << "\n";
}

void StudyRun::write_tables() {
  const StudyTable table = build_table(plan_, finished_);
  io::write_file_atomic(directory_ / "study.csv", table_csv(table));
  // No gnuplot program named: a caller that reads only the tables (identify's forward batches).
  const PlotReport plots =
      options_.gnuplot.empty() ? PlotReport{} : plot_study(plan_, table, directory_ / "plots", options_.gnuplot);
  json document = study_json(plan_, table, finished_);
  document["plots"] = {{"folder", "plots"}, {"written", plots.written}, {"notes", plots.notes}};
  io::write_json(directory_ / "study.json", document);
  for (const std::string& note : plots.notes) log_ << "study: note: " << note << "\n";

  std::vector<std::string> stale;
  std::error_code error;
  for (const auto& entry : fs::directory_iterator(directory_ / "cases", error)) {
    const std::string name = entry.path().filename().string();
    char* end = nullptr;
    const long index = std::strtol(name.c_str(), &end, 10);
    if (*end == '\0' && index >= static_cast<long>(plan_.cases.size())) stale.push_back(name);
  }
  std::sort(stale.begin(), stale.end());
  if (!stale.empty())
    log_ << "study: note: " << stale.size() << " case folder(s) from an earlier, larger study (cases/"
         << stale.front() << " ...) are not part of the tables\n";
  log_ << "study: " << plan_.cases.size() << " cases, " << n_done_ - n_failed_ << " ok, " << n_failed_
       << " failed; tables " << (directory_ / "study.csv").string() << ", "
       << (directory_ / "study.json").string() << "; " << plots.written.size() << " plots in "
       << (directory_ / "plots").string() << "\n";
}

int StudyRun::run() {
  detect_ranks();
  directory_ = fs::absolute(options_.output_dir);
  std::error_code error;
  executable_ = fs::canonical(options_.executable, error);  // /proc/self/exe -> the file it names
  if (error) executable_ = fs::absolute(options_.executable);
  if (options_.executable.empty() || !fs::is_regular_file(executable_, error) ||
      ::access(executable_.c_str(), X_OK) != 0)
    throw InputError("study: the case executable '" + options_.executable + "' is not an executable file");
  io::check_writable_directory(directory_);  // before any case runs, not when the tables are written
  io::ensure_directory(directory_ / "cases");
  const DirectoryLock lock(directory_ /
                           (n_ranks_ > 1 ? ".study-rank" + std::to_string(rank_) + ".lock" : ".study.lock"));
  environment_ = child_environment(options_.threads_per_case);
  start_ = Clock::now();
  last_scan_ = start_;

  scan_finished(true);
  if (rank_ == 0 && n_done_ < static_cast<int>(plan_.cases.size())) {
    // Tables of an earlier run would describe a study that is about to change.
    fs::remove(directory_ / "study.csv", error);
    fs::remove(directory_ / "study.json", error);
  }
  for (const StudyCase& study_case : plan_.cases) {
    // A case done before leads its accuracy group: the others start where its tolerance loop ended.
    if (!study_case.accuracy_key.empty() && !finished_[study_case.index].is_null() &&
        finished_[study_case.index].value("status", "") == "ok")
      accuracy_leaders_.emplace(study_case.accuracy_key, study_case.index);
  }
  for (const StudyCase& study_case : plan_.cases) {
    if (!mine(study_case.index) || !finished_[study_case.index].is_null()) continue;
    pending_.push_back(study_case.index);
    Group& group = groups_[study_case.modal_key];
    if (group.first_case < 0) {
      group.first_case = study_case.index;
    } else if (options_.modal_cache && options_.modal_cache_directory.empty() && !study_case.primer_text.empty()) {
      group.state = Group::State::needs_primer;  // two or more cases share the key
    }
  }
  for (auto& [key, group] : groups_) {
    if (group.state != Group::State::needs_primer) continue;
    std::ifstream marker(cache_path(key) / "primed");
    std::string primed;
    std::getline(marker, primed);
    if (primed == key) group.state = Group::State::primed;  // an earlier run primed this key
  }
  own_total_ = static_cast<int>(std::count_if(plan_.cases.begin(), plan_.cases.end(),
                                              [&](const StudyCase& c) { return mine(c.index); }));
  const int own = own_total_;
  log_ << "study: " << plan_.cases.size() << " cases (" << plan_.spec.outputs.size() << " command"
       << (plan_.spec.outputs.size() == 1 ? "" : "s") << " each)"
       << (n_ranks_ > 1 ? ", rank " + std::to_string(rank_) + " of " + std::to_string(n_ranks_) + " runs " +
                              std::to_string(own)
                        : "")
       << ", " << done_before_ << " already done, " << pending_.size() << " to run with " << jobs_ << " job"
       << (jobs_ == 1 ? "" : "s") << " -> " << directory_.string() << "\n";

  const auto pause = std::chrono::duration<double>(std::max(0.001, options_.poll_interval_s));
  while (!pending_.empty() || !running_.empty()) {
    if (interrupted_by != 0) return stop_all();
    while (static_cast<int>(running_.size()) < jobs_ && start_next()) {
    }
    const bool finished_any = poll_jobs();
    if (interrupted_by != 0) return stop_all();
    if (rank_ == 0 && n_ranks_ > 1 && seconds_since(last_scan_) > 0.5) {
      scan_finished(false);
      last_scan_ = Clock::now();
    }
    if (finished_any || (rank_ == 0 && n_done_ != last_reported_)) progress(false);
    if (!finished_any) std::this_thread::sleep_for(pause);
  }
  if (rank_ != 0) {
    log_ << "study [rank " << rank_ << "]: its cases are done; rank 0 writes the tables\n";
    return 0;
  }
  // Rank 0 waits for the other ranks' cases.
  while (n_done_ < static_cast<int>(plan_.cases.size())) {
    if (interrupted_by != 0) return stop_all();
    std::this_thread::sleep_for(std::chrono::duration<double>(std::max(0.1, options_.poll_interval_s)));
    scan_finished(false);
    progress(false);
  }
  if (last_reported_ != n_done_) progress(true);
  write_tables();
  return n_failed_ > 0 ? kExitFailedCases : 0;
}

}  // namespace

int run_study(const StudyOptions& options, std::ostream& log) {
  const std::string text = scene::read_scene_file(options.scene_path);
  const StudyPlan plan = plan_study(text, options.scene_path);  // every case validated before anything runs
  const InterruptGuard guard;
  StudyRun study(options, plan, log);
  return study.run();
}

}  // namespace crackle::study
