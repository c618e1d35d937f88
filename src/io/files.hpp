#pragma once
/// \file Whole-or-nothing output files: content goes to a temporary file beside the target, which
/// is renamed over it only when complete (a failing run never leaves a half-written file).
#include <filesystem>
#include <string>

#include <nlohmann/json.hpp>

namespace crackle::io {

/// Creates the directory (and parents) if needed; IoError if that fails.
void ensure_directory(const std::filesystem::path& directory);

/// Writes `content` to `path` atomically (temporary file + rename). IoError on failure.
void write_file_atomic(const std::filesystem::path& path, const std::string& content);

/// Writes pretty-printed JSON atomically.
void write_json(const std::filesystem::path& path, const nlohmann::json& value);

/// Reads a whole file; IoError naming the file if it cannot.
std::string read_file(const std::filesystem::path& path);

}  // namespace crackle::io
