#include "core/resources.hpp"

#include <fstream>
#include <string>

namespace crackle {
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
