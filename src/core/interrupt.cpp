#include "core/interrupt.hpp"

#include <atomic>
#include <chrono>
#include <condition_variable>
#include <exception>
#include <memory>
#include <mutex>
#include <thread>

namespace crackle {

namespace {
// The one process-wide hook: a signal is process-wide too.
std::atomic<InterruptCheck> installed_check{nullptr};

/// Workers of run_interruptible still running, and the wait for them to end.
struct Workers {
  std::mutex mutex;
  std::condition_variable ended;
  int running = 0;
};

Workers& workers() {
  static Workers* instance = new Workers;  // never destroyed: a worker may outlive static destruction's start
  return *instance;
}

/// What a worker and its caller share; owned by both, so either may leave first.
struct Job {
  std::mutex mutex;
  std::condition_variable done_signal;
  bool done = false;
  std::exception_ptr error;
};
}  // namespace

InterruptCheck set_interrupt_check(InterruptCheck check) { return installed_check.exchange(check); }

bool interrupt_requested() {
  const InterruptCheck check = installed_check.load(std::memory_order_relaxed);
  return check && check();
}

void poll_interrupt() {
  if (interrupt_requested()) throw Interrupted("interrupted");
}

bool interrupt_check_installed() { return installed_check.load(std::memory_order_relaxed) != nullptr; }

void run_interruptible(std::function<void()> work) {
  if (!interrupt_check_installed()) {
    work();
    return;
  }
  poll_interrupt();  // a stop asked for already starts nothing
  auto job = std::make_shared<Job>();
  {
    const std::lock_guard lock(workers().mutex);
    ++workers().running;
  }
  std::thread([job, work = std::move(work)]() mutable {
    std::exception_ptr error;
    try {
      work();
    } catch (...) {
      error = std::current_exception();
    }
    work = nullptr;  // what the work owned goes before the worker counts as ended
    {
      const std::lock_guard lock(job->mutex);
      job->error = error;
      job->done = true;
    }
    job->done_signal.notify_all();
    Workers& all = workers();
    {
      const std::lock_guard lock(all.mutex);
      --all.running;
    }
    all.ended.notify_all();
  }).detach();
  std::unique_lock lock(job->mutex);
  while (!job->done_signal.wait_for(lock, std::chrono::milliseconds(20), [&] { return job->done; })) {
    lock.unlock();
    poll_interrupt();  // throws Interrupted: the worker goes on alone and frees what it owns
    lock.lock();
  }
  if (job->error) std::rethrow_exception(job->error);
}

int background_work() {
  Workers& all = workers();
  const std::lock_guard lock(all.mutex);
  return all.running;
}

void wait_for_abandoned_work() {
  Workers& all = workers();
  std::unique_lock lock(all.mutex);
  all.ended.wait(lock, [&] { return all.running == 0; });
}

}  // namespace crackle
