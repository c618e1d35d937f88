#include "io/csv.hpp"

#include <charconv>

#include "core/errors.hpp"
#include "io/files.hpp"

namespace crackle::io {

std::string csv_field(const std::string& text) {
  if (text.find_first_of(",\"\n\r") == std::string::npos) return text;
  std::string quoted = "\"";
  for (const char c : text) quoted += c == '"' ? std::string("\"\"") : std::string(1, c);
  return quoted + "\"";
}

std::string to_csv(const CsvTable& table) {
  std::string text;
  for (std::size_t c = 0; c < table.headers.size(); ++c) {
    if (c) text += ',';
    text += csv_field(table.headers[c]);
  }
  text += '\n';
  const std::size_t rows = table.columns.empty() ? 0 : table.columns.front().size();
  char buffer[32];
  for (std::size_t r = 0; r < rows; ++r) {
    for (std::size_t c = 0; c < table.columns.size(); ++c) {
      if (c) text += ',';
      auto result = std::to_chars(buffer, buffer + sizeof buffer, table.columns[c][r]);  // round-trip
      text.append(buffer, result.ptr);
    }
    text += '\n';
  }
  return text;
}

void write_csv(const std::filesystem::path& path, const CsvTable& table) {
  if (table.headers.size() != table.columns.size()) {
    throw IoError(path.string() + ": " + std::to_string(table.headers.size()) + " headers for " +
                  std::to_string(table.columns.size()) + " columns");
  }
  for (const auto& column : table.columns) {
    if (column.size() != table.columns.front().size()) {
      throw IoError(path.string() + ": columns of unequal length");
    }
  }
  write_file_atomic(path, to_csv(table));
}

}  // namespace crackle::io
