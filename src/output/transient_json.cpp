#include "output/transient_json.hpp"

#include <nlohmann/json.hpp>

#include "io/files.hpp"
#include "output/energy_csv.hpp"
#include "output/probes_csv.hpp"

namespace crackle::output {

nlohmann::json transient_json(const transient::TransientSummary& summary) {
  nlohmann::json json;
  json["status"] = summary.status;
  json["message"] = summary.message;
  json["steps"] = summary.steps;
  json["time"] = summary.time;
  json["dt"] = summary.dt;
  json["dt_critical"] = summary.dt_critical;
  json["omega_max"] = summary.omega_max;
  json["time_step_forced"] = summary.time_step_forced;
  json["penalty"] = nullptr;  // a contact term plugged in replaces it with its own fields
  json["damping"] = {{"alpha", summary.damping.alpha}, {"beta", summary.damping.beta}};
  json["energy_error"] = summary.energy_error;
  json["contact_fraction"] = summary.contact_fraction;
  const auto contact_seconds = summary.term_seconds.find("contact");
  json["contact_time_fraction"] = summary.wall_s > 0.0 && contact_seconds != summary.term_seconds.end()
                                      ? contact_seconds->second / summary.wall_s
                                      : 0.0;
  json["wall_s"] = summary.wall_s;
  json["setup_s"] = summary.setup_s;
  json["ns_per_dof_step"] = summary.ns_per_dof_step;
  json["dofs"] = summary.n_dofs;
  json["elements"] = summary.n_elements;
  json["threads"] = summary.n_threads;
  json["ranks"] = summary.ranks;
  json["elements_per_rank"] = {{"min", summary.elements_min}, {"max", summary.elements_max}};
  json["halo_overlapped"] = summary.halo_overlapped;
  json["kernel"] = summary.kernel;
  json["warnings"] = summary.warnings;
  return json;
}

void write_transient_outputs(const std::filesystem::path& directory, const transient::TransientSolver& solver,
                             const nlohmann::json& extra) {
  io::ensure_directory(directory);
  write_probe_csv(directory / "probes.csv", solver.probes());
  write_energy_csv(directory / "energy.csv", solver.energy());
  nlohmann::json json = transient_json(solver.summary());
  json.update(extra);
  io::write_json(directory / "transient.json", json);
}

void write_transient_outputs(const std::filesystem::path& directory, const transient::TransientSolver& solver) {
  write_transient_outputs(directory, solver, nlohmann::json::object());
}

nlohmann::json contact_json(const contact::PenaltyContact& contact) {
  const contact::PenaltyChoice& penalty = contact.penalty();
  nlohmann::json json;
  json["penalty"] = penalty.normal_penalty;
  json["penalty_tangential"] = penalty.tangential_penalty;
  json["penalty_auto"] = penalty.automatic;
  if (penalty.automatic) {
    json["penalty_factor"] = penalty.factor;
    json["penalty_modulus"] = penalty.modulus;
    json["penalty_element_size"] = penalty.element_size;
  }
  json["friction"] = contact.options().friction_coefficient;
  json["contact_integration"] = text_of(kContactIntegrationWords, contact.options().integration);
  return json;
}

}  // namespace crackle::output
