#include "core/errors.hpp"

#include "core/interrupt.hpp"

#include <charconv>
#include <cstdio>
#include <cstdlib>
#include <new>
#include <string>

namespace crackle {

int exit_code_for(const std::exception& error) {
  if (dynamic_cast<const Interrupted*>(&error)) return 130;
  if (dynamic_cast<const InputError*>(&error)) return 2;
  if (dynamic_cast<const SolverError*>(&error)) return 3;
  if (dynamic_cast<const IoError*>(&error)) return 4;
  if (dynamic_cast<const std::bad_alloc*>(&error)) return 3;  // out of memory: the computation could not finish
  return 1;
}

std::string shortest_text(double value) {
  char buffer[64];
  const auto result = std::to_chars(buffer, buffer + sizeof buffer, value);
  return std::string(buffer, result.ptr);
}

std::string join(const std::vector<std::string>& words, const std::string& separator) {
  std::string text;
  for (std::size_t i = 0; i < words.size(); ++i) text += (i ? separator : "") + words[i];
  return text;
}

std::string list_text(const std::vector<double>& values) {
  std::vector<std::string> entries;
  for (double value : values) entries.push_back(format_number(value));
  return "[" + join(entries) + "]";
}

std::string format_number(double value) {
  // Round to 15 significant digits (hides binary noise of computed values), then print the
  // shortest text that reads back as that number.
  char buffer[40];
  std::snprintf(buffer, sizeof buffer, "%.15g", value);
  const double rounded = std::strtod(buffer, nullptr);
  auto result = std::to_chars(buffer, buffer + sizeof buffer, rounded);
  *result.ptr = '\0';
  std::string text(buffer);
  // "2e+11" -> "2e11", "1e-05" -> "1e-5": the way people write it in YAML.
  auto e = text.find('e');
  if (e != std::string::npos) {
    std::string mantissa = text.substr(0, e);
    std::string exponent = text.substr(e + 1);
    bool negative = exponent[0] == '-';
    if (exponent[0] == '+' || exponent[0] == '-') exponent.erase(0, 1);
    while (exponent.size() > 1 && exponent[0] == '0') exponent.erase(0, 1);
    text = mantissa + "e" + (negative ? "-" : "") + exponent;
  }
  return text;
}

}  // namespace crackle
