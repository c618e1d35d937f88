#pragma once
/// \file Command-line helpers shared by the benchmark drivers.
#include <sstream>
#include <string>
#include <vector>

namespace crackle::bench {

/// "1,2,4" -> {1, 2, 4}.
inline std::vector<double> parse_list(const std::string& text) {
  std::vector<double> values;
  std::stringstream stream(text);
  std::string item;
  while (std::getline(stream, item, ',')) values.push_back(std::stod(item));
  return values;
}

}  // namespace crackle::bench
