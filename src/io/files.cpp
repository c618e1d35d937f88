#include "io/files.hpp"

#include <cerrno>
#include <cstring>
#include <fstream>
#include <sstream>

#include <unistd.h>
#include <nlohmann/json.hpp>

#include "core/errors.hpp"

namespace crackle::io {

namespace fs = std::filesystem;

void ensure_directory(const fs::path& directory) {
  std::error_code error;
  fs::create_directories(directory, error);
  if (error || !fs::is_directory(directory)) {
    throw IoError(directory.string() + ": cannot create the output directory (" +
                  (error ? error.message() : std::string("exists and is not a directory")) + ")");
  }
}

void check_writable_directory(const fs::path& directory) {
  ensure_directory(directory);
  const fs::path probe = directory / (".crackle-write-test." + std::to_string(::getpid()));
  std::string reason;
  {
    std::ofstream out(probe, std::ios::binary | std::ios::trunc);
    if (!out) {
      reason = std::strerror(errno);
    } else {
      out << "crackle\n";
      out.flush();
      if (!out) reason = "write failed, disk full?";
    }
  }
  std::error_code error;
  fs::remove(probe, error);
  if (reason.empty() && error) reason = "cannot remove a file there: " + error.message();
  if (reason.empty()) {
    const fs::space_info space = fs::space(directory, error);
    if (!error && space.available == 0) reason = "no space left on its file system";
  }
  if (!reason.empty()) {
    throw IoError(directory.string() + ": cannot write into the output directory (" + reason + ")");
  }
}

double available_disk_bytes(const fs::path& path) {
  std::error_code error;
  const fs::space_info space = fs::space(path, error);
  if (error || space.available == static_cast<std::uintmax_t>(-1)) return 1e300;
  return static_cast<double>(space.available);
}

bool is_temporary_name(const std::string& file_name) {
  const std::size_t at = file_name.rfind(".tmp.");
  if (at == std::string::npos || at == 0 || at + 5 == file_name.size()) return false;
  for (std::size_t i = at + 5; i < file_name.size(); ++i) {
    if (file_name[i] < '0' || file_name[i] > '9') return false;
  }
  return true;
}

void write_file_atomic(const fs::path& path, const std::string& content) {
  // A unique temporary name in the same directory, so that rename() is atomic.
  const fs::path temporary = path.string() + ".tmp." + std::to_string(::getpid());
  {
    std::ofstream out(temporary, std::ios::binary | std::ios::trunc);
    if (!out) {
      throw IoError(path.string() + ": cannot write (" + std::strerror(errno) + ")");
    }
    out.write(content.data(), static_cast<std::streamsize>(content.size()));
    out.flush();
    if (!out) {
      std::error_code ignored;
      fs::remove(temporary, ignored);
      throw IoError(path.string() + ": write failed (disk full?)");
    }
  }
  std::error_code error;
  fs::rename(temporary, path, error);
  if (error) {
    fs::remove(temporary, error);
    throw IoError(path.string() + ": cannot move the finished file into place (" + error.message() + ")");
  }
}

void write_json(const fs::path& path, const nlohmann::json& value) {
  write_file_atomic(path, value.dump(2) + "\n");
}

std::string read_file(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw IoError(path.string() + ": cannot open (" + std::strerror(errno) + ")");
  std::ostringstream text;
  text << in.rdbuf();
  return text.str();
}

}  // namespace crackle::io
