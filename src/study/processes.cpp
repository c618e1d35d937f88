#include "study/processes.hpp"

#include <fcntl.h>
#include <sys/prctl.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cerrno>
#include <csignal>
#include <cstring>

#include "core/errors.hpp"

extern char** environ;

namespace crackle::study {

std::string ExitStatus::describe() const {
  if (signal != 0) {
    const char* name = ::strsignal(signal);
    return "killed by signal " + std::to_string(signal) + (name ? std::string(" (") + name + ")" : "");
  }
  return "exit status " + std::to_string(code);
}

namespace {

int open_output(const std::filesystem::path& path) {
  const int fd = ::open(path.c_str(), O_WRONLY | O_CREAT | O_APPEND | O_CLOEXEC, 0644);
  if (fd < 0) throw IoError(path.string() + ": cannot open for writing (" + std::strerror(errno) + ")");
  return fd;
}

ExitStatus status_of(int raw) {
  ExitStatus status;
  if (WIFSIGNALED(raw))
    status.signal = WTERMSIG(raw);
  else if (WIFEXITED(raw))
    status.code = WEXITSTATUS(raw);
  return status;
}

}  // namespace

ChildProcess start_process(const std::vector<std::string>& argv, const std::vector<std::string>& environment,
                           const std::filesystem::path& stdout_path,
                           const std::filesystem::path& stderr_path) {
  // Everything the child needs is prepared before fork(): after it, only async-signal-safe calls.
  std::vector<char*> arguments, variables;
  for (const std::string& a : argv) arguments.push_back(const_cast<char*>(a.c_str()));
  arguments.push_back(nullptr);
  for (const std::string& v : environment) variables.push_back(const_cast<char*>(v.c_str()));
  variables.push_back(nullptr);
  const std::string failure = "crackle study: cannot execute " + argv.at(0) + "\n";

  const int out = open_output(stdout_path);
  const int err = open_output(stderr_path);
  const int in = ::open("/dev/null", O_RDONLY | O_CLOEXEC);
  const pid_t parent = ::getpid();
  const pid_t pid = ::fork();
  if (pid == 0) {
    ::prctl(PR_SET_PDEATHSIG, SIGKILL);
    if (::getppid() != parent) ::_exit(127);  // the study died before prctl took effect
    if (in >= 0) ::dup2(in, STDIN_FILENO);
    ::dup2(out, STDOUT_FILENO);
    ::dup2(err, STDERR_FILENO);
    ::execve(arguments[0], arguments.data(), variables.data());
    const ssize_t ignored = ::write(STDERR_FILENO, failure.data(), failure.size());
    (void)ignored;
    ::_exit(127);
  }
  const int fork_error = errno;
  ::close(out);
  ::close(err);
  if (in >= 0) ::close(in);
  if (pid < 0)
    throw IoError(std::string("cannot start a case process (fork: ") + std::strerror(fork_error) + ")");
  return {pid};
}

std::optional<ExitStatus> poll_process(const ChildProcess& child) {
  int raw = 0;
  pid_t done = 0;
  do {
    done = ::waitpid(child.pid, &raw, WNOHANG);
  } while (done < 0 && errno == EINTR);
  if (done == 0) return std::nullopt;
  if (done < 0) return ExitStatus{127, 0};  // not our child any more: treat as failed
  return status_of(raw);
}

void signal_process(const ChildProcess& child, int signal) {
  if (child.pid > 0) ::kill(child.pid, signal);
}

ExitStatus wait_process(const ChildProcess& child) {
  int raw = 0;
  pid_t done = 0;
  do {
    done = ::waitpid(child.pid, &raw, 0);
  } while (done < 0 && errno == EINTR);
  if (done < 0) return ExitStatus{127, 0};
  return status_of(raw);
}

std::vector<std::string> child_environment(int threads) {
  std::vector<std::string> environment;
  bool has_threads = false, has_blas_threads = false;
  for (char** entry = environ; entry && *entry; ++entry) {
    const std::string variable = *entry;
    const auto starts = [&](const char* prefix) { return variable.rfind(prefix, 0) == 0; };
    if (starts("OMPI_") || starts("PMIX_") || starts("PMI_")) continue;
    if (starts("OMP_NUM_THREADS=")) has_threads = true;
    if (starts("OPENBLAS_NUM_THREADS=")) has_blas_threads = true;
    environment.push_back(variable);
  }
  if (!has_threads && threads > 0) environment.push_back("OMP_NUM_THREADS=" + std::to_string(threads));
  // OpenBLAS (the pthreads build) starts a thread per core of its own, whatever OpenMP's count: cases
  // run side by side would oversubscribe the cores, and its threads wait by spinning.
  if (!has_blas_threads && threads > 0) environment.push_back("OPENBLAS_NUM_THREADS=" + std::to_string(threads));
  return environment;
}

}  // namespace crackle::study
