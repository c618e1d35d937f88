// io/cache_file.hpp: the one binary record format of the mode and reduced-model caches.
#include <gtest/gtest.h>
#include <unistd.h>

#include <cstdint>
#include <filesystem>
#include <fstream>
#include <string>

#include "io/cache_file.hpp"

namespace crackle::io {
namespace {

namespace fs = std::filesystem;
constexpr char kMagic[8] = {'T', 'E', 'S', 'T', 'R', 'E', 'C', '1'};
constexpr char kOtherMagic[8] = {'T', 'E', 'S', 'T', 'R', 'E', 'C', '2'};

fs::path folder() {
  const fs::path path = fs::temp_directory_path() / ("crackle-cache-file-" + std::to_string(::getpid()));
  fs::remove_all(path);
  return path;
}

TEST(CacheFile, ARecordReadsBackWhatWasPutAndIsNamedByItsKey) {
  const fs::path directory = folder();
  const std::uint64_t key = 0x0123456789abcdefull;
  MatrixX matrix(3, 2);
  matrix << 1.0, -2.0, 3.5, 4.25, 1e-300, 6.0;
  const VectorX vector = VectorX::LinSpaced(5, 0.0, 1.0);
  CacheWriter out(kMagic, key);
  out.put(static_cast<char>(1));
  const double times[2] = {0.5, 7.0};
  out.put(times);
  out.put_text("{\"solver\": \"arpack\"}");
  out.put_matrix(matrix);
  out.put_matrix(vector);
  out.store(directory, "modes");
  EXPECT_TRUE(fs::is_regular_file(directory / "modes-0123456789abcdef.bin"));
  EXPECT_EQ(cache_file(directory, "modes", key), directory / "modes-0123456789abcdef.bin");

  CacheReader in(directory, "modes", kMagic, key);
  ASSERT_TRUE(in.ok());
  char flag = 0;
  double read_times[2] = {0.0, 0.0};
  std::string text;
  MatrixX read_matrix;
  VectorX read_vector;
  ASSERT_TRUE(in.get(flag) && in.get(read_times) && in.get_text(text) && in.get_matrix(read_matrix) &&
              in.get_matrix(read_vector));
  EXPECT_EQ(flag, 1);
  EXPECT_EQ(read_times[1], 7.0);
  EXPECT_EQ(text, "{\"solver\": \"arpack\"}");
  EXPECT_EQ(read_matrix, matrix);  // bit for bit
  EXPECT_EQ(read_vector, vector);
  EXPECT_FALSE(in.get(flag));  // past the end
  EXPECT_FALSE(in.ok());
  fs::remove_all(directory);
}

TEST(CacheFile, AMissingForeignTruncatedOrDamagedRecordReadsAsAbsent) {
  const fs::path directory = folder();
  const std::uint64_t key = 42;
  EXPECT_FALSE(CacheReader(directory, "modes", kMagic, key).ok());  // no folder, no file
  CacheWriter out(kMagic, key);
  out.put_matrix(MatrixX::Ones(100, 10));
  out.store(directory, "modes");
  EXPECT_FALSE(CacheReader(directory, "modes", kOtherMagic, key).ok());  // another format
  {
    // a record of key 43 renamed to 42's name: the key inside decides
    CacheWriter other(kMagic, 43);
    other.store(directory, "modes");
    fs::rename(cache_file(directory, "modes", 43), cache_file(directory, "other", 42));
    EXPECT_FALSE(CacheReader(directory, "other", kMagic, key).ok());
  }
  MatrixX matrix;
  {
    CacheReader in(directory, "modes", kMagic, key);
    ASSERT_TRUE(in.ok());
    EXPECT_TRUE(in.get_matrix(matrix));
  }
  const fs::path path = cache_file(directory, "modes", key);
  fs::resize_file(path, fs::file_size(path) - 8);  // truncated: the last double is gone
  {
    CacheReader in(directory, "modes", kMagic, key);
    ASSERT_TRUE(in.ok());
    EXPECT_FALSE(in.get_matrix(matrix));
  }
  {
    // a damaged size: 1e15 x 1e3 doubles must fail before allocating them
    std::fstream file(path, std::ios::in | std::ios::out | std::ios::binary);
    file.seekp(16);
    const std::int64_t huge[2] = {1000000000000000, 1000};
    file.write(reinterpret_cast<const char*>(huge), sizeof huge);
  }
  CacheReader in(directory, "modes", kMagic, key);
  ASSERT_TRUE(in.ok());
  EXPECT_FALSE(in.get_matrix(matrix));
  std::string text;
  EXPECT_FALSE(in.get_text(text));  // and every read after it
  fs::remove_all(directory);
}

}  // namespace
}  // namespace crackle::io
