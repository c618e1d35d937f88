#include "output/run_json.hpp"

#include <nlohmann/json.hpp>

#include "io/files.hpp"

namespace crackle::output {

nlohmann::json stages_json(const std::vector<Stage>& stages) {
  nlohmann::json list = nlohmann::json::array();
  for (const Stage& stage : stages) {
    list.push_back({{"name", stage.name}, {"ran", stage.ran}, {"reason", stage.reason}, {"seconds", stage.seconds}});
  }
  return list;
}

void write_run_json(const std::filesystem::path& directory, const std::string& scene_file,
                    const std::vector<Stage>& stages, double excitation_hz, const nlohmann::json& route,
                    const nlohmann::json& accuracy, double wall_s) {
  nlohmann::json run_json = {{"scene", scene_file}, {"output", directory.string()}};
  run_json["stages"] = stages_json(stages);
  run_json["excitation_hz"] = excitation_hz;
  if (!route.is_null()) run_json["route"] = route;
  if (!accuracy.is_null()) run_json["accuracy"] = accuracy;
  run_json["wall_s"] = wall_s;
  io::write_json(directory / "run.json", run_json);
}

}  // namespace crackle::output
