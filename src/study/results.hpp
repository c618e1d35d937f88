#pragma once
/// \file What a study keeps of each case (case.json), read defensively from the case's own
/// outputs, and the study tables built from it (study.csv, study.json).
///
/// Fields read from the case outputs (anything else is ignored; a missing field is a blank cell):
/// - modal.json: `variants.<uncracked|open>.frequencies_hz[]`; per entry of `pairs[]`:
///   `uncracked_mode`, `open_mode`, `f_uncracked_hz`, `f_open_hz`, `ratio`, `mac` and
///   `f_bilinear_hz` (or `bilinear_hz`).
/// - spectrum.json: `excitation_hz`; per probe of `probes{}`: `component`, `unit` (optional),
///   `harmonics[].order` and `.amplitude`, `indices{}` (every index given, e.g. "A2/A1", "beta").
#include <filesystem>
#include <limits>
#include <nlohmann/json_fwd.hpp>
#include <string>
#include <vector>

#include "study/plan.hpp"

namespace crackle::study {

/// The case fields kept from the outputs of a case folder: `{"modal": {...}, "spectrum": {...}}`
/// for the outputs asked. `problem` is set when an output asked for is missing or unreadable.
nlohmann::json read_case_outputs(const std::filesystem::path& case_directory,
                                 const std::vector<std::string>& outputs, std::string& problem);

/// The summary of the modal.json document (see the file comment).
nlohmann::json summarize_modal(const nlohmann::json& modal);

/// The summary of the spectrum.json document (see the file comment).
nlohmann::json summarize_spectrum(const nlohmann::json& spectrum);

/// The summary of the sweep.json document: points, completed, folds and bifurcations (count and
/// the first one's frequency), per probe the peaks of A1 and A2/A1 and A3/A1 (frequency, value).
nlohmann::json summarize_sweep(const nlohmann::json& sweep);

/// case.json of a finished case if it exists, reads, and belongs to this scene (hash); else null.
nlohmann::json read_finished_case(const std::filesystem::path& case_directory, const std::string& hash);

/// One cell of a table: its text, and its value when it is a number (NaN otherwise).
struct Cell {
  std::string text;
  double number = std::numeric_limits<double>::quiet_NaN();
};

/// The study table: one row per case, in case order.
struct StudyTable {
  std::vector<std::string> headers;  ///< "case", the varied key paths, "status", "error", results with units
  /// Per column: case, parameter, status, error, frequency, mac, excitation, amplitude or index.
  std::vector<std::string> kinds;
  std::vector<std::vector<Cell>> rows;
  /// Index of a header, or -1.
  int column(const std::string& header) const;
};

/// Builds the table from the plan and each case's case.json (`cases[i]` of case i).
StudyTable build_table(const StudyPlan& plan, const std::vector<nlohmann::json>& cases);

/// CSV text of the table: RFC 4180 quoting, numbers in the shortest form that reads back exactly.
std::string table_csv(const StudyTable& table);

/// study.json: the study (scene, mode, outputs, varied keys), the columns of study.csv, and per
/// case its folder, parameters and case.json fields (wall times included: the only fields that
/// differ between two runs of the same study).
nlohmann::json study_json(const StudyPlan& plan, const StudyTable& table,
                          const std::vector<nlohmann::json>& cases);

/// A YAML value as JSON: numbers, booleans, strings, lists, maps.
nlohmann::json yaml_text_to_json(const std::string& yaml);

/// Shortest text that reads back as `value` (core shortest_text); empty for NaN and infinities (an empty cell).
std::string number_text(double value);

}  // namespace crackle::study
