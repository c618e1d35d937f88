#include "core/mpi_session.hpp"

#include <cstdlib>
#include <string>
#include <system_error>

namespace crackle {

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
