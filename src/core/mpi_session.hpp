#pragma once
/// \file A private folder for the MPI session files of a process that starts MPI on its own (a
/// singleton, not launched by mpirun).
///
/// Open MPI singletons that start at the same instant race to create the shared session folder
/// /tmp/ompi.HOST.UID, which the last one to exit removes again: one of them fails in MPI_Init
/// ("A call to mkdir was unable to create the desired directory ... File exists"). That happens
/// whenever a study starts two cases at once, or a test runner two tests. A singleton whose
/// OMPI_MCA_orte_tmpdir_base is its own folder has no one to race.
#include <filesystem>
#include <initializer_list>
#include <optional>

namespace crackle {

/// The first of the environment variables `names` that holds a whole number, else `fallback`.
int environment_integer(std::initializer_list<const char*> names, int fallback);

/// The MPI launcher's view of this process, from its environment (readable before MPI or PETSc
/// starts; Open MPI's and PMI's names): the ranks it started (1 without a launcher), this
/// process's rank (0) and the ranks on this node (1).
int launcher_world_size();
int launcher_world_rank();
int launcher_local_size();

class MpiSessionFolder {
 public:
  /// Before MPI_Init: when this process was not launched by an MPI launcher and no session folder
  /// base is set, creates TMPDIR/crackle-mpi-XXXXXX and sets OMPI_MCA_orte_tmpdir_base to it (for
  /// this process and the daemon it starts). Otherwise does nothing. Never throws: without a folder
  /// MPI uses its default.
  MpiSessionFolder();
  /// Removes the folder (after MPI_Finalize).
  ~MpiSessionFolder();
  MpiSessionFolder(const MpiSessionFolder&) = delete;
  MpiSessionFolder& operator=(const MpiSessionFolder&) = delete;

  /// The folder made, if any.
  const std::optional<std::filesystem::path>& path() const { return path_; }

 private:
  std::optional<std::filesystem::path> path_;
};

}  // namespace crackle
