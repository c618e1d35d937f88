#include "core/mpi_session.hpp"

#include <algorithm>
#include <cstdlib>
#include <string>
#include <system_error>

namespace crackle {

int environment_integer(std::initializer_list<const char*> names, int fallback) {
  for (const char* name : names) {
    const char* value = std::getenv(name);
    if (value && *value) {
      char* end = nullptr;
      const long number = std::strtol(value, &end, 10);
      if (*end == '\0') return static_cast<int>(number);
    }
  }
  return fallback;
}

int launcher_world_size() { return std::max(1, environment_integer({"OMPI_COMM_WORLD_SIZE", "PMI_SIZE"}, 1)); }
int launcher_world_rank() { return environment_integer({"OMPI_COMM_WORLD_RANK", "PMI_RANK"}, 0); }
int launcher_local_size() {
  return std::max(1, environment_integer({"OMPI_COMM_WORLD_LOCAL_SIZE", "MPI_LOCALNRANKS"}, 1));
}

MpiSessionFolder::MpiSessionFolder() {
  for (const char* launched : {"OMPI_COMM_WORLD_SIZE", "PMIX_RANK", "PMI_RANK", "OMPI_MCA_orte_tmpdir_base"})
    if (std::getenv(launched)) return;
  std::error_code error;
  const std::filesystem::path base = std::filesystem::temp_directory_path(error);
  if (error) return;
  std::string pattern = (base / "crackle-mpi-XXXXXX").string();
  if (!::mkdtemp(pattern.data())) return;
  if (::setenv("OMPI_MCA_orte_tmpdir_base", pattern.c_str(), 0) != 0) {
    std::filesystem::remove_all(pattern, error);
    return;
  }
  path_ = pattern;
}

MpiSessionFolder::~MpiSessionFolder() {
  if (!path_) return;
  std::error_code error;
  std::filesystem::remove_all(*path_, error);
  ::unsetenv("OMPI_MCA_orte_tmpdir_base");
}

}  // namespace crackle
