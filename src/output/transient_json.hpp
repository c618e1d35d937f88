#pragma once
/// \file transient.json, and the probes.csv, energy.csv and transient.json of a finished full
/// transient (the output layer: the integrator and the contact term return structs).
#include <filesystem>

#include <nlohmann/json_fwd.hpp>

#include "contact/contact.hpp"
#include "transient/solver.hpp"

namespace crackle::output {

/// The summary as transient.json's fields (public names: steps, dt, dt_critical, energy_error,
/// contact_fraction, wall_s, and more; the contact's own fields are added by whoever plugged it in).
nlohmann::json transient_json(const transient::TransientSummary& summary);
/// probes.csv, energy.csv and transient.json (the summary merged with `extra`) into a directory
/// (created if needed).
void write_transient_outputs(const std::filesystem::path& directory, const transient::TransientSolver& solver,
                             const nlohmann::json& extra);
/// The same without extra fields.
void write_transient_outputs(const std::filesystem::path& directory, const transient::TransientSolver& solver);

/// transient.json's contact fields (public names): penalty, penalty_tangential, penalty_auto,
/// penalty_factor / penalty_modulus / penalty_element_size (automatic only), friction,
/// contact_integration.
nlohmann::json contact_json(const contact::PenaltyContact& contact);

}  // namespace crackle::output
