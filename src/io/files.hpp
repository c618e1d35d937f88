#pragma once
/// \file Whole-or-nothing output files: content goes to a temporary file beside the target, which
/// is renamed over it only when complete (a failing run never leaves a half-written file).
#include <filesystem>
#include <string>
#include <vector>

#include <nlohmann/json_fwd.hpp>

namespace crackle::io {

/// Creates the directory (and parents) if needed; IoError if that fails.
void ensure_directory(const std::filesystem::path& directory);

/// Creates the directory if needed and proves that files can be written there: creates, writes
/// and removes a small probe file (`.crackle-write-test.PID`). IoError naming the folder and the
/// reason (read-only, not a directory, no space left) otherwise. Commands call it before they
/// compute, so an unwritable folder fails in a second, not after the run.
void check_writable_directory(const std::filesystem::path& directory);

/// Bytes free for this user on the file system of `path` (a large number where unknown).
double available_disk_bytes(const std::filesystem::path& path);

/// True for the name of a temporary file of write_file_atomic: `name.tmp.PID`.
bool is_temporary_name(const std::string& file_name);

/// Writes `content` to `path` atomically (temporary file + rename). IoError on failure.
void write_file_atomic(const std::filesystem::path& path, const std::string& content);

/// Writes pretty-printed JSON atomically.
void write_json(const std::filesystem::path& path, const nlohmann::json& value);

/// Reads a whole file; IoError naming the file if it cannot.
std::string read_file(const std::filesystem::path& path);

}  // namespace crackle::io
