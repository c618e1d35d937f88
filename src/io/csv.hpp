#pragma once
/// \file CSV tables with units in the header ("time [s]"), written atomically.
#include <filesystem>
#include <string>
#include <vector>

namespace crackle::io {

/// A column-oriented table; every column has a name with its unit, e.g. "frequency [Hz]".
struct CsvTable {
  std::vector<std::string> headers;
  std::vector<std::vector<double>> columns;  ///< columns[c][row]
  /// Adds a column; all columns must have the same length when written.
  void add(std::string header, std::vector<double> values) {
    headers.push_back(std::move(header));
    columns.push_back(std::move(values));
  }
};

/// One CSV field per RFC 4180: as it is, or in double quotes (quotes doubled) when it holds a
/// comma, a double quote or a line break.
std::string csv_field(const std::string& text);

/// Text of the table (headers quoted per RFC 4180 where needed, numbers in full double precision,
/// comma-separated, '\n' line ends).
std::string to_csv(const CsvTable& table);

/// Writes the table atomically; IoError on failure or on columns of unequal length.
void write_csv(const std::filesystem::path& path, const CsvTable& table);

}  // namespace crackle::io
