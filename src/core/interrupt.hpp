#pragma once
/// \file Cooperative stop of long loops for a host that embeds crackle (the Python module turns a
/// KeyboardInterrupt into a stop). The host installs a check; the time loops and the sweeps call
/// poll_interrupt() between steps and points. Without a check installed (the command line, the
/// tests) a poll costs one load and nothing else changes.
#include <functional>

#include "core/errors.hpp"

namespace crackle {

/// Thrown by poll_interrupt() when the host's check asks to stop. It leaves the loop like any
/// other error (the pipeline records the command as failed); its exit code is 130.
class Interrupted : public Error {
 public:
  using Error::Error;
};

/// Returns true to stop. Called from the thread that runs the loop; keep it cheap or rate-limited.
using InterruptCheck = bool (*)();

/// Installs the host's check (nullptr: none). Returns the previous one.
InterruptCheck set_interrupt_check(InterruptCheck check);

/// Throws Interrupted when the installed check returns true.
void poll_interrupt();

/// The installed check's answer, without the throw: for the calling thread inside an OpenMP
/// parallel region (the master), which may not throw; the caller throws Interrupted after it.
bool interrupt_requested();

/// True while a host's check is installed.
bool interrupt_check_installed();

/// Runs one long library call that has no place to poll (a sparse factorisation) so that a stop
/// is not kept waiting for it. Without a check installed, `work()` runs here. With one, `work()`
/// runs on a worker thread (unless the check asks to stop already) while this thread polls the
/// check every 20 ms: it returns when `work` returns (an exception of `work` is thrown here), or
/// throws Interrupted as soon as the check asks to stop, leaving the worker to finish on its own.
/// `work` must therefore own everything it touches (capture copies or shared pointers, never
/// references to this thread's objects).
void run_interruptible(std::function<void()> work);

/// How many workers of run_interruptible are running now (those an interruption left behind, and
/// one whose caller is still waiting for it).
int background_work();

/// Blocks until every worker that run_interruptible left behind has finished (a host calls it
/// before it unloads the library). Returns at once when none is running.
void wait_for_abandoned_work();

}  // namespace crackle
