#pragma once
/// \file Child processes of a study: start a command with its output in files, poll it, stop it.
/// Children die with the study (Linux parent-death signal), so a killed study leaves no orphan
/// computing a case that the next run would compute again.
#include <sys/types.h>

#include <filesystem>
#include <optional>
#include <string>
#include <vector>

namespace crackle::study {

/// How a child ended.
struct ExitStatus {
  int code = 0;    ///< exit code when it exited
  int signal = 0;  ///< the signal that killed it, else 0
  bool ok() const { return code == 0 && signal == 0; }
  /// "exit status 3", "killed by signal 9 (Killed)".
  std::string describe() const;
};

/// A started child.
struct ChildProcess {
  pid_t pid = -1;
};

/// Runs `argv` (argv[0] a path) with the environment `environment` ("NAME=value" entries), stdin
/// from /dev/null, stdout appended to `stdout_path` and stderr appended to `stderr_path`. IoError
/// when the files cannot be opened or fork fails; a command that cannot be executed exits 127
/// with a message in its stderr file.
ChildProcess start_process(const std::vector<std::string>& argv, const std::vector<std::string>& environment,
                           const std::filesystem::path& stdout_path,
                           const std::filesystem::path& stderr_path);

/// The exit status if the child has ended (reaps it), else nothing. Never blocks.
std::optional<ExitStatus> poll_process(const ChildProcess& child);

/// Sends `signal` to the child (no effect if it has ended).
void signal_process(const ChildProcess& child, int signal);

/// Blocks until the child ends; its exit status.
ExitStatus wait_process(const ChildProcess& child);

/// The current environment without the variables of an MPI launcher (OMPI_*, PMIX_*, PMI_*), so
/// that a child started by one rank runs on its own; with OMP_NUM_THREADS and OPENBLAS_NUM_THREADS
/// each set to `threads` when it is not set already and threads > 0.
std::vector<std::string> child_environment(int threads);

}  // namespace crackle::study
