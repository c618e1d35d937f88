#pragma once
/// \file One binary file cache for every solver that keeps results between runs (the modes of
/// modal/cache.hpp, the reduced models of reduction/reduction.hpp): a record `<prefix>-<key>.bin` in a
/// folder, the key a 64-bit fingerprint (core/fingerprint.hpp) in 16 hex digits, opening with an
/// 8-byte magic (the format and its version) and the key, then what the owner puts: raw values,
/// dense matrices (int64 rows, cols, then the doubles column by column) and texts (int64 length, then
/// the bytes). Stored whole (io/files.hpp write_file_atomic: several processes may store the same
/// key at once); a missing, damaged or foreign record reads as absent, so it is simply recomputed.
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <string>
#include <type_traits>

#include "core/types.hpp"

namespace crackle::io {

/// The path of a record: `<directory>/<prefix>-<key as 16 hex digits>.bin`.
std::filesystem::path cache_file(const std::filesystem::path& directory, const std::string& prefix, std::uint64_t key);

/// A record being written; `store` writes it whole.
class CacheWriter {
 public:
  CacheWriter(const char (&magic)[8], std::uint64_t key);
  template <typename T>
  void put(const T& value) {
    static_assert(std::is_trivially_copyable_v<T>);
    bytes_.append(reinterpret_cast<const char*>(&value), sizeof value);
  }
  void put_matrix(const MatrixX& matrix);
  void put_text(const std::string& text);
  /// Writes the record into `directory` (made if missing).
  void store(const std::filesystem::path& directory, const std::string& prefix) const;

 private:
  std::uint64_t key_;
  std::string bytes_;
};

/// A record being read: `ok()` is false when the file is missing, of another magic or key, or once
/// a read ran past its end or met a size beyond it; every read after that returns false.
class CacheReader {
 public:
  CacheReader(const std::filesystem::path& directory, const std::string& prefix, const char (&magic)[8],
              std::uint64_t key);
  bool ok() const { return ok_; }
  template <typename T>
  bool get(T& value) {
    static_assert(std::is_trivially_copyable_v<T>);
    return read(&value, sizeof value);
  }
  /// A dense matrix or vector (a vector's record must have one column).
  template <typename Dense>
  bool get_matrix(Dense& matrix) {
    std::int64_t size[2] = {0, 0};
    if (!read(size, sizeof size) || size[0] < 0 || size[1] < 0 || (Dense::ColsAtCompileTime == 1 && size[1] != 1) ||
        !fits(static_cast<double>(size[0]) * static_cast<double>(size[1]) * sizeof(double))) {
      return ok_ = false;
    }
    matrix.resize(size[0], size[1]);
    return read(matrix.data(), sizeof(double) * static_cast<std::size_t>(matrix.size()));
  }
  bool get_text(std::string& text);

 private:
  bool read(void* data, std::size_t bytes);
  /// Whether `bytes` more lie in the file (a damaged size must not allocate before it fails).
  bool fits(double bytes) const { return bytes <= static_cast<double>(left_); }
  std::filesystem::path path_;
  std::ifstream in_;
  std::uintmax_t left_ = 0;  ///< bytes not read yet
  bool ok_ = false;
};

}  // namespace crackle::io
