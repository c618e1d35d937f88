#pragma once
/// \file A command owns its output folder. `crackle run` and `crackle modal` record what they
/// wrote in `crackle-run.json` (one entry per command: status, scene, files); a rerun into the same
/// folder removes the leftovers of interrupted writes (`name.tmp.PID`) and the files of the earlier
/// run of the same command (saying so), so old snapshots or spectra never mix with new ones. A
/// folder that holds other files (not written by crackle, or written by another command) is
/// refused unless `--overwrite` is given; with it they are kept.
#include <filesystem>
#include <iosfwd>
#include <set>
#include <string>

namespace crackle::pipeline {

/// The marker file of a folder written by `crackle run` or `crackle modal`.
inline constexpr const char* kFolderMarker = "crackle-run.json";

class OutputFolder {
 public:
  /// Checks that `directory` can be written (creating it), cleans it for `command` ("run" or
  /// "modal") as described above, notes what it removed on `log`, and records the command as
  /// running. `scene_path` is the scene file (kept when it lies in the folder). InputError for a
  /// folder with files of others (without `overwrite`), IoError for an unwritable one.
  OutputFolder(const std::filesystem::path& directory, const std::string& command, const std::string& scene_path,
               bool overwrite, std::ostream& log);

  /// Records the files this command wrote (those new or rewritten since it started) with a status
  /// ("done", "failed").
  void finish(const std::string& status);

 private:
  void write_marker(const std::string& status, const std::set<std::string>& files) const;

  std::filesystem::path directory_;
  std::string command_;
  std::string scene_path_;
  std::filesystem::file_time_type started_;
  bool created_ = false;  ///< the folder did not exist before
  std::set<std::string> kept_;  ///< files present at the start that this command does not own
};

}  // namespace crackle::pipeline
