#pragma once
/// \file Wall-clock timer and memory figures for reports, benchmarks and the memory checks.
#include <chrono>
#include <string>

namespace crackle {

/// Wall-clock stopwatch started at construction.
class Stopwatch {
 public:
  Stopwatch() : start_(std::chrono::steady_clock::now()) {}
  /// Seconds since construction or the last restart().
  double seconds() const {
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count();
  }
  void restart() { start_ = std::chrono::steady_clock::now(); }

 private:
  std::chrono::steady_clock::time_point start_;
};

/// A duration for progress lines: "12.3 s" below 2 min, "4.5 min" below 2 h, else "3.1 h".
std::string duration_text(double seconds);

/// Peak resident set size of this process so far, in bytes (0 where unknown).
long long peak_rss_bytes();

/// Current resident set size of this process, in bytes (0 where unknown).
long long current_rss_bytes();

/// Memory this process may still take [bytes]: MemAvailable of /proc/meminfo (sysconf where that
/// is missing), lowered to the address-space limit (RLIMIT_AS) and the cgroup's memory.max when set.
/// `source` says which figure it is, for messages.
double available_memory_bytes(std::string* source = nullptr);

/// "1.5 GiB", "300 MiB", "2.4e7 TiB".
std::string bytes_text(double bytes);

}  // namespace crackle
