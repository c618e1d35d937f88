#pragma once
/// \file The runs of one `crackle run` with its estimate (DETECTION.md sec. 1): the scene's own into
/// the output folder with its progress, and one refinement run per setting, silent, in temporary
/// folders sharing the modal and reduction caches (and, between runs of one element order, the model).
#include <iosfwd>
#include <map>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "pipeline/commands.hpp"
#include "pipeline/refinement.hpp"
#include "pipeline/run_scene.hpp"
#include "scene/scene.hpp"

namespace crackle::pipeline {

/// The runs of one `crackle run` with its estimate: each setting run once, the first (the scene's
/// own) into the output folder with its progress, the others silent in temporary folders.
class RefinementRuns {
 public:
  RefinementRuns(const scene::Scene& scene, const std::vector<scene::Override>& overrides,
                 const RunCommandOptions& options, std::ostream& out);

  /// The outcome of a setting (run now unless it ran before); `first` runs into the output folder.
  const RunOutcome& get(const Setting& setting, bool first = false);
  /// Moves the files of a setting's run into the output folder.
  void adopt(const Setting& setting) const { folders_.adopt(setting); }

  std::string describe(const Setting& setting) const { return describe_setting(setting, box_mesh()); }
  const nlohmann::json& runs_json() const { return runs_; }
  double refinement_s() const { return refinement_s_; }
  bool box_mesh() const { return scene_.gmsh_file.empty(); }
  /// Whether the run has contact pairs whose penalty can be refined.
  bool has_contact() const { return outcomes_.at(first_key_).normal_penalty > 0.0; }
  const scene::Scene& scene() const { return scene_; }

 private:
  int steps_per_period(const Setting& setting) const {
    return scene_.transient->reduced.steps_per_period << setting.steps;
  }
  std::vector<scene::Override> level_overrides(const Setting& setting) const;

  const scene::Scene& scene_;
  std::vector<scene::Override> overrides_;
  RunCommandOptions options_;
  std::ostream& out_;
  RefinementFolders folders_;
  std::map<std::string, RunOutcome> outcomes_;
  std::string first_key_;
  RunReuse reuse_;
  nlohmann::json runs_ = nlohmann::json::array();
  double refinement_s_ = 0.0;
};

}  // namespace crackle::pipeline
