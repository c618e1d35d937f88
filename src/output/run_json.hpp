#pragma once
/// \file run.json, and the stage lines run.json and sweep.json share (the output layer).
#include <filesystem>
#include <string>
#include <vector>

#include <nlohmann/json_fwd.hpp>

namespace crackle::output {

/// One line of run.json / sweep.json: a stage, whether it ran, why, and its time.
struct Stage {
  std::string name;
  bool ran = false;
  std::string reason;
  double seconds = 0.0;
};

/// `[{"name", "ran", "reason", "seconds"}, ...]`.
nlohmann::json stages_json(const std::vector<Stage>& stages);

/// run.json: `scene`, `output`, `stages`, `excitation_hz`, `route` and `accuracy` (each where not
/// null), `wall_s`.
void write_run_json(const std::filesystem::path& directory, const std::string& scene_file,
                    const std::vector<Stage>& stages, double excitation_hz, const nlohmann::json& route,
                    const nlohmann::json& accuracy, double wall_s);

}  // namespace crackle::output
