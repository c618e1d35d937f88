#include "core/interrupt.hpp"

#include <atomic>

namespace crackle {

namespace {
// The one process-wide hook: a signal is process-wide too.
std::atomic<InterruptCheck> installed_check{nullptr};
}  // namespace

InterruptCheck set_interrupt_check(InterruptCheck check) { return installed_check.exchange(check); }

void poll_interrupt() {
  const InterruptCheck check = installed_check.load(std::memory_order_relaxed);
  if (check && check()) throw Interrupted("interrupted");
}

}  // namespace crackle
