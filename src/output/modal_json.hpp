#pragma once
/// \file modal.json, modes.csv and the mode-shape VTU files of a modal result (the output layer:
/// the modal solvers return ModalResult and write no file).
#include <filesystem>

#include <nlohmann/json_fwd.hpp>

#include "mesh/mesh.hpp"
#include "modal/modal.hpp"

namespace crackle::output {

/// The modal.json document: {"dofs", "variants": {name: {"frequencies_hz", ...}}, "pairs",
/// "solver", "timings_s", ...}.
nlohmann::json modal_json(const modal::ModalResult& result);

/// Writes DIR/modal.json, DIR/modes.csv and DIR/modes_<variant>.vtu (all modes as point data).
/// `accuracy` (given): modal.json's `accuracy` block, whose estimates at `pairs[i].<field>` or
/// `variants.<name>.frequencies_hz[i]` give modes.csv its "<column> error [-]" columns.
/// Collective-free: call it on one rank (see is_output_rank()).
void write_modal_outputs(const std::filesystem::path& directory, const mesh::Mesh& mesh,
                         const modal::ModalResult& result, const nlohmann::json* accuracy = nullptr);

/// modal.json and modes.csv alone, as write_modal_outputs writes them (the mode shapes unchanged).
void write_modal_tables(const std::filesystem::path& directory, const modal::ModalResult& result,
                        const nlohmann::json* accuracy = nullptr);

}  // namespace crackle::output
