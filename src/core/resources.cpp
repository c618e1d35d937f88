#include "core/resources.hpp"

#include <cstdio>
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

}  // namespace crackle
