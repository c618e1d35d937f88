#include "pipeline/output_folder.hpp"

#include <algorithm>
#include <ostream>
#include <vector>

#include <nlohmann/json.hpp>

#include "core/errors.hpp"
#include "io/files.hpp"

namespace crackle::pipeline {
namespace {

namespace fs = std::filesystem;

bool starts_with(const std::string& text, const std::string& prefix) { return text.rfind(prefix, 0) == 0; }
bool ends_with(const std::string& text, const std::string& suffix) {
  return text.size() >= suffix.size() && text.compare(text.size() - suffix.size(), suffix.size(), suffix) == 0;
}

/// Output names of `crackle modal` (and of the modal stage of `crackle run`).
bool is_modal_output(const std::string& name) {
  return name == "modal.json" || name == "modes.csv" || name == "modes_uncracked.vtu" || name == "modes_open.vtu";
}

/// Output names of `crackle run` besides the modal ones (the plots come with their gnuplot data and
/// script).
bool is_run_output(const std::string& name) {
  return name == "run.json" || name == "transient.json" || name == "probes.csv" || name == "energy.csv" ||
         name == "spectrum.json" || name == "snapshots.pvd" ||
         (starts_with(name, "snapshot_") && ends_with(name, ".vtu")) ||
         ((starts_with(name, "spectrum_") || starts_with(name, "history_") || starts_with(name, "ringdown_") ||
           starts_with(name, "frf_")) &&
          (ends_with(name, ".csv") || ends_with(name, ".png") || ends_with(name, ".dat") || ends_with(name, ".gp")));
}

/// Names of a study's own folder (`crackle study -o DIR`).
bool is_study_output(const std::string& name) {
  return name == "study.csv" || name == "study.json" || name == "cases" || name == "plots" ||
         starts_with(name, ".study");
}

std::string name_list(const std::vector<std::string>& names) {
  std::string text;
  for (std::size_t i = 0; i < names.size() && i < 4; ++i) text += (i ? ", " : "") + names[i];
  if (names.size() > 4) text += ", ... (" + std::to_string(names.size()) + " in all)";
  return text;
}

}  // namespace

namespace {

/// What earlier commands recorded in the folder's marker: the files of this command and of others,
/// and whether this command has an entry (maybe of a killed run).
struct Recorded {
  std::set<std::string> own, other;
  bool earlier_same = false;
};

Recorded read_marker(const fs::path& directory, const std::string& command) {
  Recorded recorded;
  std::error_code error;
  if (!fs::is_regular_file(directory / kFolderMarker, error)) return recorded;
  nlohmann::json marker;
  try {
    marker = nlohmann::json::parse(io::read_file(directory / kFolderMarker));
  } catch (const std::exception&) {
    return recorded;  // a damaged marker: judge the files by their names
  }
  if (!marker.is_object() || !marker.contains("commands") || !marker["commands"].is_object()) return recorded;
  recorded.earlier_same = marker["commands"].contains(command);
  for (const auto& [name, entry] : marker["commands"].items()) {
    if (!entry.is_object() || !entry.contains("files") || !entry["files"].is_array()) continue;
    for (const auto& file : entry["files"]) {
      if (file.is_string()) (name == command ? recorded.own : recorded.other).insert(file.get<std::string>());
    }
  }
  return recorded;
}

/// The folder's entries sorted by what the command may do with them.
struct Listing {
  std::vector<std::string> temporary;  ///< leftovers of interrupted writes: removed
  std::vector<std::string> own;        ///< the command's earlier outputs: removed
  std::vector<std::string> others;     ///< kept; each named with its likely owner for the message
  std::set<std::string> kept;          ///< names of the entries kept (others and the scene file)
};

Listing list_folder(const fs::path& directory, const std::string& command, const std::string& scene_path) {
  const Recorded recorded = read_marker(directory, command);
  std::error_code error;
  fs::path scene_file;
  if (!scene_path.empty()) scene_file = fs::weakly_canonical(fs::absolute(scene_path), error);
  Listing listing;
  for (const fs::directory_entry& entry : fs::directory_iterator(directory, error)) {
    const std::string name = entry.path().filename().string();
    if (name == kFolderMarker || starts_with(name, ".crackle-write-test.")) continue;
    if (io::is_temporary_name(name)) {
      listing.temporary.push_back(name);
      continue;
    }
    std::error_code ignored;
    if (!scene_file.empty() && fs::weakly_canonical(entry.path(), ignored) == scene_file) {
      listing.kept.insert(name);
      continue;
    }
    // A run writes the modal outputs too when it has a modal stage: they are its own when its
    // earlier entry (perhaps of a run killed before it listed them) is there and no other claims them.
    const bool mine = recorded.own.count(name) ||
                      (!recorded.other.count(name) &&
                       (command == "run" ? is_run_output(name) || (recorded.earlier_same && is_modal_output(name))
                                         : is_modal_output(name)));
    if (mine && entry.is_regular_file(ignored)) {
      listing.own.push_back(name);
    } else {
      listing.kept.insert(name);
      const std::string owner = recorded.other.count(name) ? "" : is_modal_output(name) ? " (crackle modal)"
                                                           : is_run_output(name)        ? " (crackle run)"
                                                           : is_study_output(name)      ? " (crackle study)"
                                                                                        : "";
      listing.others.push_back(name + owner);
    }
  }
  if (error) throw IoError(directory.string() + ": cannot list the output directory (" + error.message() + ")");
  for (std::vector<std::string>* names : {&listing.temporary, &listing.own, &listing.others})
    std::sort(names->begin(), names->end());
  return listing;
}

/// Removes the temporary and own entries of `listing`, noting on `log` what went.
void remove_earlier(const fs::path& directory, const std::string& command, const Listing& listing, std::ostream& log) {
  std::error_code error;
  for (const std::vector<std::string>* names : {&listing.temporary, &listing.own}) {
    for (const std::string& name : *names) {
      fs::remove_all(directory / name, error);  // a temporary may be a folder (accuracy.tmp.PID)
      if (error) throw IoError((directory / name).string() + ": cannot remove (" + error.message() + ")");
    }
  }
  const std::vector<std::string>& own = listing.own;
  const std::vector<std::string>& temporary = listing.temporary;
  if (own.empty() && temporary.empty()) return;
  log << "crackle: note: " << directory.string() << ": removed";
  if (!own.empty()) log << " " << own.size() << " file(s) of an earlier crackle " << command << " (" << name_list(own) << ")";
  if (!own.empty() && !temporary.empty()) log << " and";
  if (!temporary.empty()) log << " " << temporary.size() << " leftover(s) of an interrupted write (" << name_list(temporary) << ")";
  log << "\n";
}

}  // namespace

OutputFolder::OutputFolder(const fs::path& directory, const std::string& command, const std::string& scene_path,
                           bool overwrite, std::ostream& log)
    : directory_(directory), command_(command), scene_path_(scene_path) {
  std::error_code exists_error;
  created_ = !fs::exists(directory, exists_error);
  io::check_writable_directory(directory);
  Listing listing = list_folder(directory, command, scene_path);
  if (!listing.others.empty() && !overwrite) {
    throw InputError(directory.string() + ": expected an empty output folder or one of an earlier crackle " + command +
                     ", got files crackle " + command + " does not own: " + name_list(listing.others) +
                     "; choose another folder (-o), or pass --overwrite to write into it anyway (they are kept)");
  }
  remove_earlier(directory, command, listing, log);
  kept_ = std::move(listing.kept);
  started_ = fs::file_time_type::clock::now();
  write_marker("running", {});
}

void OutputFolder::finish(const std::string& status) {
  std::set<std::string> files;
  std::error_code error;
  for (const fs::directory_entry& entry : fs::directory_iterator(directory_, error)) {
    const std::string name = entry.path().filename().string();
    if (name == kFolderMarker || io::is_temporary_name(name) || !entry.is_regular_file(error)) continue;
    if (!kept_.count(name) || entry.last_write_time(error) >= started_) files.insert(name);
  }
  if (status != "failed" || !files.empty()) {
    write_marker(status, files);
    return;
  }
  // A command that failed before writing anything (bad input found late) leaves the folder as it was.
  nlohmann::json marker;
  try {
    marker = nlohmann::json::parse(io::read_file(directory_ / kFolderMarker));
  } catch (const std::exception&) {
    return;
  }
  if (marker.contains("commands") && marker["commands"].is_object()) marker["commands"].erase(command_);
  if (!marker.contains("commands") || !marker["commands"].is_object() || marker["commands"].empty()) {
    fs::remove(directory_ / kFolderMarker, error);
    if (created_ && fs::is_empty(directory_, error)) fs::remove(directory_, error);
  } else {
    io::write_json(directory_ / kFolderMarker, marker);
  }
}

void OutputFolder::write_marker(const std::string& status, const std::set<std::string>& files) const {
  nlohmann::json marker = nlohmann::json::object();
  std::error_code error;
  if (fs::is_regular_file(directory_ / kFolderMarker, error)) {
    try {
      marker = nlohmann::json::parse(io::read_file(directory_ / kFolderMarker));
    } catch (const std::exception&) {
    }
  }
  if (!marker.is_object()) marker = nlohmann::json::object();
  marker["about"] = "the files each crackle command wrote into this folder; a rerun of a command removes its own";
  if (!marker.contains("commands") || !marker["commands"].is_object()) marker["commands"] = nlohmann::json::object();
  marker["commands"][command_] = {{"status", status}, {"scene", scene_path_}, {"files", files}};
  io::write_json(directory_ / kFolderMarker, marker);
}

}  // namespace crackle::pipeline
