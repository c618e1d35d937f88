#pragma once
/// \file The sweeps of one `crackle sweep` with its estimate (DETECTION.md sec. 1): the scene's own
/// into the output folder with its progress, and one refinement sweep per setting, silent, in
/// temporary folders sharing the modal and reduction caches: over windows of the range around the
/// first sweep's peaks where they hold (sweep_windows.hpp), else the whole range at half the points.
#include <iosfwd>
#include <map>
#include <string>
#include <utility>
#include <vector>

#include <nlohmann/json.hpp>

#include "pipeline/refinement.hpp"
#include "pipeline/sweep.hpp"
#include "pipeline/sweep_accuracy.hpp"
#include "pipeline/sweep_windows.hpp"
#include "scene/scene.hpp"

namespace crackle::pipeline {

/// Harmonics added per level of the harmonics refinement (H against H + 2, HYBRID.md sec. 4).
constexpr int kHarmonicsStep = 2;

/// The peaks of sweep.json `probes` that are estimated, with the quantity each one's value is.
const std::vector<std::pair<std::string, std::string>>& sweep_peak_keys();

/// The sweeps of one `crackle sweep` with its estimate: each setting swept once, the first (the
/// scene's own) into the output folder with its progress, the others silent in temporary folders.
class RefinementSweeps {
 public:
  RefinementSweeps(const scene::Scene& scene, const std::vector<scene::Override>& overrides,
                   const SweepCommandOptions& options, std::ostream& out, std::ostream& progress);

  /// The sweep of a setting over the whole range (the scene's own when `first`).
  const SweepOutcome& get(const Setting& setting, bool first = false);
  /// A refinement of the setting estimated, for its estimate: over the windows around the first
  /// sweep's peaks where every peak stays inside its window (sweep_windows.hpp), else the whole range.
  const SweepOutcome& near(const Setting& setting);
  /// What a sweep of the whole range at a setting costs [s]: its own wall time, or a windowed one's
  /// with its solve scaled to the first sweep's points.
  double cost_s(const Setting& setting);
  /// Moves the files of a setting's sweep into the output folder.
  void adopt(const Setting& setting) const { folders_.adopt(setting); }

  std::string describe(const Setting& setting) const;
  /// The scene's sweep has contact pairs whose penalty can be refined.
  bool has_contact() const { return base_penalty() > 0.0; }
  int harmonics(const Setting& setting) const { return scene_.sweep->harmonics + kHarmonicsStep * setting.harmonics; }
  const nlohmann::json& runs_json() const { return runs_; }
  double refinement_s() const { return refinement_s_; }
  bool box_mesh() const { return scene_.gmsh_file.empty(); }
  const scene::Scene& scene() const { return scene_; }

 private:
  SweepOutcome sweep(const Setting& setting, bool first, const SweepWindows* windows);
  double base_penalty() const;
  std::vector<scene::Override> level_overrides(const Setting& setting, bool windowed) const;
  const nlohmann::json& base_events() const;

  const scene::Scene& scene_;
  std::vector<scene::Override> overrides_;
  SweepCommandOptions options_;
  std::ostream& out_;
  std::ostream& progress_;
  RefinementFolders folders_;
  std::map<std::string, SweepOutcome> outcomes_;  ///< whole-range sweeps
  std::map<std::string, SweepOutcome> windowed_;  ///< refinement sweeps over windows
  SweepWindows windows_;  ///< the refinements' windows, from the first sweep's peaks
  WindowStarts starts_;   ///< the first sweep's gaps at the start of each window
  std::string first_key_;
  nlohmann::json runs_ = nlohmann::json::array();
  double refinement_s_ = 0.0;
};

}  // namespace crackle::pipeline
