#include "io/cache_file.hpp"

#include <cstdio>
#include <cstring>

#include "io/files.hpp"

namespace crackle::io {

std::filesystem::path cache_file(const std::filesystem::path& directory, const std::string& prefix, std::uint64_t key) {
  char hex[20];
  std::snprintf(hex, sizeof hex, "%016llx", static_cast<unsigned long long>(key));
  return directory / (prefix + "-" + hex + ".bin");
}

CacheWriter::CacheWriter(const char (&magic)[8], std::uint64_t key) : key_(key), bytes_(magic, sizeof magic) {
  put(key);
}

void CacheWriter::put_matrix(const MatrixX& matrix) {
  const std::int64_t size[2] = {matrix.rows(), matrix.cols()};
  bytes_.append(reinterpret_cast<const char*>(size), sizeof size);
  bytes_.append(reinterpret_cast<const char*>(matrix.data()), sizeof(double) * static_cast<std::size_t>(matrix.size()));
}

void CacheWriter::put_text(const std::string& text) {
  put(static_cast<std::int64_t>(text.size()));
  bytes_ += text;
}

void CacheWriter::store(const std::filesystem::path& directory, const std::string& prefix) const {
  ensure_directory(directory);
  write_file_atomic(cache_file(directory, prefix, key_), bytes_);
}

CacheReader::CacheReader(const std::filesystem::path& directory, const std::string& prefix, const char (&magic)[8],
                         std::uint64_t key)
    : path_(cache_file(directory, prefix, key)), in_(path_, std::ios::binary) {
  if (!in_) return;
  std::error_code error;
  left_ = std::filesystem::file_size(path_, error);
  if (error) return;
  char stored_magic[8];
  std::uint64_t stored_key = 0;
  ok_ = true;
  ok_ = read(stored_magic, sizeof stored_magic) && std::memcmp(stored_magic, magic, sizeof stored_magic) == 0 &&
        get(stored_key) && stored_key == key;
}

bool CacheReader::get_text(std::string& text) {
  std::int64_t size = 0;
  if (!get(size) || size < 0 || !fits(static_cast<double>(size))) return ok_ = false;
  text.assign(static_cast<std::size_t>(size), '\0');
  return read(text.data(), text.size());
}

bool CacheReader::read(void* data, std::size_t bytes) {
  if (!ok_ || bytes > left_) return ok_ = false;
  if (!in_.read(static_cast<char*>(data), static_cast<std::streamsize>(bytes))) return ok_ = false;
  left_ -= bytes;
  return true;
}

}  // namespace crackle::io
