#include <gtest/gtest.h>

#include <atomic>
#include <chrono>
#include <memory>
#include <stdexcept>
#include <thread>

#include "core/interrupt.hpp"

using namespace crackle;
using Clock = std::chrono::steady_clock;

namespace {
std::atomic<bool> stop_requested{false};
bool stop_check() { return stop_requested.load(); }

/// Installs stop_check for its lifetime, with no stop requested.
class CheckScope {
 public:
  CheckScope() : previous_(set_interrupt_check(&stop_check)) { stop_requested = false; }
  ~CheckScope() {
    set_interrupt_check(previous_);
    stop_requested = false;
  }

 private:
  InterruptCheck previous_;
};

double seconds_since(Clock::time_point start) {
  return std::chrono::duration<double>(Clock::now() - start).count();
}
}  // namespace

TEST(Interrupt, WithoutACheckTheWorkRunsOnTheCallersThread) {
  ASSERT_FALSE(interrupt_check_installed());
  std::thread::id ran_on;
  run_interruptible([&ran_on] { ran_on = std::this_thread::get_id(); });
  EXPECT_EQ(ran_on, std::this_thread::get_id());
  EXPECT_THROW(run_interruptible([] { throw std::runtime_error("failed"); }), std::runtime_error);
}

TEST(Interrupt, AWorkersResultAndErrorsReachTheCaller) {
  const CheckScope scope;
  ASSERT_TRUE(interrupt_check_installed());
  std::thread::id ran_on = std::this_thread::get_id();
  auto value = std::make_shared<int>(0);
  run_interruptible([value, &ran_on] {
    std::this_thread::sleep_for(std::chrono::milliseconds(60));  // past a few polls
    ran_on = std::this_thread::get_id();
    *value = 42;
  });
  EXPECT_EQ(*value, 42);
  EXPECT_NE(ran_on, std::this_thread::get_id());
  EXPECT_THROW(run_interruptible([] { throw std::runtime_error("failed"); }), std::runtime_error);
}

TEST(Interrupt, AStopReturnsAtOnceAndTheWorkerFinishesAlone) {
  const CheckScope scope;
  auto finished = std::make_shared<std::atomic<bool>>(false);
  const auto work_seconds = std::chrono::milliseconds(1500);
  std::thread stopper([] {
    std::this_thread::sleep_for(std::chrono::milliseconds(100));
    stop_requested = true;
  });
  const Clock::time_point start = Clock::now();
  EXPECT_THROW(run_interruptible([finished, work_seconds] {
                 std::this_thread::sleep_for(work_seconds);
                 *finished = true;
               }),
               Interrupted);
  const double returned_after = seconds_since(start);
  stopper.join();
  EXPECT_LT(returned_after, 0.6) << "the caller waited for the work";
  EXPECT_FALSE(*finished) << "the work cannot have finished before the caller returned";
  EXPECT_EQ(background_work(), 1);
  wait_for_abandoned_work();
  EXPECT_EQ(background_work(), 0);
  EXPECT_TRUE(*finished) << "wait_for_abandoned_work returned before the worker ended";
  EXPECT_GE(seconds_since(start), 1.4);
}
