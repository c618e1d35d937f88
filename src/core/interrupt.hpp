#pragma once
/// \file Cooperative stop of long loops for a host that embeds crackle (the Python module turns a
/// KeyboardInterrupt into a stop). The host installs a check; the time loops and the sweeps call
/// poll_interrupt() between steps and points. Without a check installed (the command line, the
/// tests) a poll costs one load and nothing else changes.
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

}  // namespace crackle
