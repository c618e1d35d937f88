#include "core/resources.hpp"

#include <sys/resource.h>
#include <unistd.h>

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <string>

namespace crackle {

std::string duration_text(double seconds) {
  char buffer[32];
  if (seconds < 120.0) {
    std::snprintf(buffer, sizeof buffer, "%.1f s", seconds);
  } else if (seconds < 7200.0) {
    std::snprintf(buffer, sizeof buffer, "%.1f min", seconds / 60.0);
  } else {
    std::snprintf(buffer, sizeof buffer, "%.1f h", seconds / 3600.0);
  }
  return buffer;
}
namespace {

long long status_field_kb(const char* field) {
  std::ifstream status("/proc/self/status");
  std::string line;
  const std::string key = std::string(field) + ":";
  while (std::getline(status, line)) {
    if (line.compare(0, key.size(), key) == 0) return std::stoll(line.substr(key.size()));
  }
  return 0;
}

}  // namespace

long long peak_rss_bytes() { return status_field_kb("VmHWM") * 1024; }
long long current_rss_bytes() { return status_field_kb("VmRSS") * 1024; }

namespace {

/// The first number of a line starting with `key` in a /proc-style file [kB for meminfo], or -1.
double field_of(const char* file, const std::string& key) {
  std::ifstream in(file);
  std::string line;
  while (std::getline(in, line)) {
    if (line.compare(0, key.size(), key) == 0) return std::strtod(line.c_str() + key.size(), nullptr);
  }
  return -1.0;
}

/// A cgroup v2 limit less what the group uses, or -1 without a limit.
double cgroup_room() {
  std::ifstream max_file("/sys/fs/cgroup/memory.max");
  std::string max_text;
  if (!(max_file >> max_text) || max_text == "max") return -1.0;
  const double limit = std::strtod(max_text.c_str(), nullptr);
  std::ifstream current_file("/sys/fs/cgroup/memory.current");
  double current = 0.0;
  current_file >> current;
  return std::max(0.0, limit - current);
}

}  // namespace

std::string bytes_text(double bytes) {
  const char* units[] = {"B", "KiB", "MiB", "GiB", "TiB"};
  int unit = 0;
  while (unit < 4 && bytes >= 1024.0) {
    bytes /= 1024.0;
    ++unit;
  }
  char buffer[48];
  std::snprintf(buffer, sizeof buffer, bytes < 1e4 ? "%.3g %s" : "%.2g %s", bytes, units[unit]);
  return buffer;
}

double available_memory_bytes(std::string* source) {
  double bytes = field_of("/proc/meminfo", "MemAvailable:") * 1024.0;
  std::string from = "MemAvailable in /proc/meminfo";
  if (bytes < 0.0) {
    bytes = static_cast<double>(::sysconf(_SC_AVPHYS_PAGES)) * static_cast<double>(::sysconf(_SC_PAGESIZE));
    from = "available physical pages (sysconf)";
  }
  struct rlimit limit {};
  if (::getrlimit(RLIMIT_AS, &limit) == 0 && limit.rlim_cur != RLIM_INFINITY &&
      static_cast<double>(limit.rlim_cur) < bytes) {
    bytes = static_cast<double>(limit.rlim_cur);
    from = "the address-space limit (ulimit -v)";
  }
  const double cgroup = cgroup_room();
  if (cgroup >= 0.0 && cgroup < bytes) {
    bytes = cgroup;
    from = "the cgroup's memory.max";
  }
  if (source) *source = from;
  return bytes;
}

}  // namespace crackle
