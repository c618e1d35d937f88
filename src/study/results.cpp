#include "study/results.hpp"

#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <functional>
#include <map>
#include <set>
#include <nlohmann/json.hpp>

#include "core/errors.hpp"
#include "io/csv.hpp"
#include "io/files.hpp"

namespace crackle::study {
namespace fs = std::filesystem;
using nlohmann::json;

namespace {

/// The first of `names` that `object` holds as a number, else null.
json number_field(const json& object, const std::vector<std::string>& names) {
  if (!object.is_object()) return nullptr;
  for (const std::string& name : names) {
    const auto found = object.find(name);
    if (found != object.end() && found->is_number()) return *found;
  }
  return nullptr;
}

json number_list(const json& list) {
  json numbers = json::array();
  if (!list.is_array()) return numbers;
  for (const json& item : list) numbers.push_back(item.is_number() ? item : json(nullptr));
  return numbers;
}

bool read_json(const fs::path& path, json& document, std::string& problem) {
  std::error_code error;
  if (!fs::is_regular_file(path, error)) {
    problem = path.filename().string() + ": missing after the command succeeded";
    return false;
  }
  try {
    document = json::parse(io::read_file(path));
    return true;
  } catch (const std::exception& failure) {
    problem = path.filename().string() + ": unreadable (" + failure.what() + ")";
    return false;
  }
}

/// "1/2" for 0.5, "2" for 2, "2.25" otherwise.
std::string order_label(double order) {
  const double twice = 2.0 * order;
  if (std::abs(twice - std::round(twice)) < 1e-9) {
    const long halves = std::lround(twice);
    return halves % 2 == 0 ? std::to_string(halves / 2) : std::to_string(halves) + "/2";
  }
  return number_text(order);
}

Cell number_cell(const json& value) {
  Cell cell;
  if (value.is_number()) {
    cell.number = value.get<double>();
    cell.text = number_text(cell.number);
  }
  return cell;
}

Cell text_cell(const std::string& text) {
  Cell cell;
  cell.text = text;
  char* end = nullptr;
  const double value = std::strtod(text.c_str(), &end);
  if (!text.empty() && end == text.c_str() + text.size() && std::isfinite(value)) cell.number = value;
  return cell;
}

json node_to_json(const YAML::Node& node) {
  switch (node.Type()) {
    case YAML::NodeType::Scalar: {
      const std::string& text = node.Scalar();
      if (node.Tag() != "!") {
        char* end = nullptr;
        const double value = std::strtod(text.c_str(), &end);
        if (!text.empty() && end == text.c_str() + text.size() && std::isfinite(value)) return value;
        if (text == "true" || text == "True" || text == "TRUE") return true;
        if (text == "false" || text == "False" || text == "FALSE") return false;
      }
      return text;
    }
    case YAML::NodeType::Sequence: {
      json list = json::array();
      for (const auto& item : node) list.push_back(node_to_json(item));
      return list;
    }
    case YAML::NodeType::Map: {
      json object = json::object();
      for (const auto& entry : node) object[entry.first.Scalar()] = node_to_json(entry.second);
      return object;
    }
    default:
      return nullptr;
  }
}

/// Known damage indices first, in this order; others after them, alphabetically.
const std::vector<std::string> kIndexOrder = {"A2/A1", "A3/A1", "A1/2/A1", "beta"};

}  // namespace

std::string number_text(double value) { return std::isfinite(value) ? shortest_text(value) : std::string(); }

json yaml_text_to_json(const std::string& yaml) {
  try {
    return node_to_json(YAML::Load(yaml));
  } catch (const std::exception&) {
    return yaml;
  }
}

json summarize_modal(const json& modal) {
  json summary = json::object();
  const json variants = modal.is_object() ? modal.value("variants", json::object()) : json::object();
  for (const char* name : {"uncracked", "open"}) {
    if (variants.is_object() && variants.contains(name) && variants[name].is_object())
      summary[std::string(name) + "_hz"] = number_list(variants[name].value("frequencies_hz", json::array()));
  }
  json pairs = json::array();
  if (modal.is_object() && modal.contains("pairs") && modal["pairs"].is_array()) {
    for (const json& pair : modal["pairs"]) {
      // An unpaired mode (MAC below modal::kPairingMac) has no open partner: its ratio and
      // bilinear frequency would be those of a mismatched pair, so the table leaves them empty.
      const bool paired = !(pair.is_object() && pair.contains("paired") && pair["paired"] == false);
      pairs.push_back({{"uncracked_mode", number_field(pair, {"uncracked_mode", "mode"})},
                       {"open_mode", number_field(pair, {"open_mode"})},
                       {"f_uncracked_hz", number_field(pair, {"f_uncracked_hz", "uncracked_hz"})},
                       {"f_open_hz", number_field(pair, {"f_open_hz", "open_hz"})},
                       {"ratio", paired ? number_field(pair, {"ratio"}) : json(nullptr)},
                       {"mac", number_field(pair, {"mac", "MAC"})},
                       {"bilinear_hz", paired ? number_field(pair, {"f_bilinear_hz", "bilinear_hz", "f_b_hz"})
                                              : json(nullptr)},
                       {"paired", paired}});
    }
  }
  summary["pairs"] = pairs;
  // The estimated relative errors of the frequencies (modal.json accuracy), where the solve had one.
  const json accuracy = modal.is_object() ? modal.value("accuracy", json::object()) : json::object();
  if (accuracy.is_object() && accuracy.value("estimated", false)) {
    const auto errors = [](const json& estimates) {
      json list = json::array();
      if (!estimates.is_array()) return list;
      for (const json& estimate : estimates) list.push_back(number_field(estimate, {"error"}));
      return list;
    };
    const json estimated = accuracy.value("variants", json::object());
    for (const char* name : {"uncracked", "open"}) {
      if (estimated.is_object() && estimated.contains(name) && estimated[name].is_object())
        summary[std::string(name) + "_error"] = errors(estimated[name].value("frequencies_hz", json::array()));
    }
    json bilinear = json::array();
    const json estimated_pairs = accuracy.value("pairs", json::array());
    for (const json& pair : estimated_pairs)
      bilinear.push_back(pair.is_object() ? pair.value("f_bilinear_hz", json()) : json());
    summary["bilinear_error"] = errors(bilinear);
  }
  return summary;
}

json summarize_spectrum(const json& spectrum) {
  json summary = json::object();
  summary["excitation_hz"] = number_field(spectrum, {"excitation_hz"});
  json probes = json::object();
  if (spectrum.is_object() && spectrum.contains("probes") && spectrum["probes"].is_object()) {
    for (const auto& [name, probe] : spectrum["probes"].items()) {
      if (!probe.is_object()) continue;
      json kept = json::object();
      if (probe.contains("component") && probe["component"].is_string())
        kept["component"] = probe["component"];
      if (probe.contains("unit") && probe["unit"].is_string()) kept["unit"] = probe["unit"];
      json amplitudes = json::array();
      if (probe.contains("harmonics") && probe["harmonics"].is_array()) {
        for (const json& harmonic : probe["harmonics"]) {
          const json order = number_field(harmonic, {"order"});
          if (order.is_null()) continue;
          amplitudes.push_back({{"order", order}, {"amplitude", number_field(harmonic, {"amplitude"})}});
        }
      }
      kept["amplitudes"] = amplitudes;
      json indices = json::object();
      if (probe.contains("indices") && probe["indices"].is_object()) {
        for (const auto& [index, value] : probe["indices"].items())
          indices[index] = value.is_number() ? value : json(nullptr);
      }
      kept["indices"] = indices;
      // The run's error estimate of each signature (spectrum.json accuracy, issue 23): its relative sum.
      json errors = json::object();
      const json accuracy = spectrum.value("accuracy", json::object());
      if (accuracy.is_object() && accuracy.contains("probes") && accuracy["probes"].is_object() &&
          accuracy["probes"].contains(name) && accuracy["probes"][name].is_object()) {
        for (const auto& [quantity, estimate] : accuracy["probes"][name].items())
          errors[quantity] = number_field(estimate, {"error"});
      }
      kept["errors"] = errors;
      probes[name] = kept;
    }
  }
  summary["probes"] = probes;
  return summary;
}

json summarize_sweep(const json& sweep) {
  json summary = {{"points", number_field(sweep, {"points"})}};
  summary["completed"] = sweep.is_object() && sweep.value("completed", false);
  const json events = sweep.is_object() ? sweep.value("events", json::array()) : json::array();
  summary["events"] = events.is_array() ? events.size() : 0;
  summary["first_event_hz"] = events.is_array() && !events.empty() ? number_field(events[0], {"frequency_hz"}) : json();
  json probes = json::object();
  if (sweep.is_object() && sweep.contains("probes") && sweep["probes"].is_object()) {
    for (const auto& [name, probe] : sweep["probes"].items()) {
      json kept = json::object();
      for (const char* peak : {"peak_a1", "peak_a2_over_a1", "peak_a3_over_a1"}) {
        const json entry = probe.is_object() ? probe.value(peak, json()) : json();
        kept[peak] = {{"frequency_hz", number_field(entry, {"frequency_hz"})}, {"value", number_field(entry, {"value"})}};
      }
      probes[name] = kept;
    }
  }
  summary["probes"] = probes;
  return summary;
}

json read_case_outputs(const fs::path& case_directory, const std::vector<std::string>& outputs,
                       std::string& problem) {
  json kept = json::object();
  problem.clear();
  const bool want_modal = std::count(outputs.begin(), outputs.end(), "modal") > 0;
  const bool want_spectrum = std::count(outputs.begin(), outputs.end(), "spectrum") > 0;
  json document;
  std::string missing;
  if (read_json(case_directory / "modal.json", document, missing)) {
    kept["modal"] = summarize_modal(document);
  } else if (want_modal) {
    problem = missing;
  }
  if (want_spectrum) {
    if (read_json(case_directory / "spectrum.json", document, missing))
      kept["spectrum"] = summarize_spectrum(document);
    else if (problem.empty())
      problem = missing;
  }
  if (std::count(outputs.begin(), outputs.end(), "sweep") > 0) {
    if (read_json(case_directory / "sweep.json", document, missing))
      kept["sweep"] = summarize_sweep(document);
    else if (problem.empty())
      problem = missing;
  }
  return kept;
}

json read_finished_case(const fs::path& case_directory, const std::string& hash) {
  std::error_code error;
  const fs::path path = case_directory / "case.json";
  if (!fs::is_regular_file(path, error)) return nullptr;
  try {
    json document = json::parse(io::read_file(path));
    if (document.is_object() && document.value("scene_hash", std::string()) == hash &&
        document.contains("status"))
      return document;
  } catch (const std::exception&) {
  }
  return nullptr;
}

int StudyTable::column(const std::string& header) const {
  const auto found = std::find(headers.begin(), headers.end(), header);
  return found == headers.end() ? -1 : static_cast<int>(found - headers.begin());
}

/// Columns of sweep.json's summary: points, events, the first event, per probe the peaks.
template <class Add>
void add_sweep_columns(const std::vector<json>& cases, std::string& kind, const Add& add) {
  std::set<std::string> names;
  bool any = false;
  for (const json& c : cases) {
    if (!c.is_object() || !c.contains("sweep")) continue;
    any = true;
    for (const auto& [name, probe] : c["sweep"].value("probes", json::object()).items()) names.insert(name);
  }
  if (!any) return;
  const auto field = [](const char* key) {
    return [key](const json& c) { return c.contains("sweep") ? number_cell(c["sweep"].value(key, json())) : Cell{}; };
  };
  kind = "sweep";
  add("sweep.points [-]", field("points"));
  add("sweep.events [-]", field("events"));
  add("sweep.first_event [Hz]", field("first_event_hz"));
  for (const std::string& name : names) {
    for (const auto& [peak, label] : std::vector<std::pair<std::string, std::string>>{
             {"peak_a1", "peak_A1"}, {"peak_a2_over_a1", "peak_A2/A1"}, {"peak_a3_over_a1", "peak_A3/A1"}}) {
      const auto entry = [name, peak = peak](const json& c, const char* what) -> Cell {
        if (!c.contains("sweep")) return Cell{};
        const json probe = c["sweep"].value("probes", json::object()).value(name, json::object());
        return number_cell(probe.value(peak, json::object()).value(what, json()));
      };
      add(name + ".sweep." + label + " [" + (peak == "peak_a1" ? "m" : "-") + "]",
          [entry](const json& c) { return entry(c, "value"); });
      add(name + ".sweep." + label + " at [Hz]", [entry](const json& c) { return entry(c, "frequency_hz"); });
    }
  }
}

StudyTable build_table(const StudyPlan& plan, const std::vector<json>& cases) {
  // The result columns are the union over the cases, so that every row has the same columns.
  std::size_t n_uncracked = 0, n_open = 0, n_pairs = 0;
  bool has_excitation = false;
  struct ProbeColumns {
    std::set<double> orders;
    std::set<std::string> indices;
    std::set<std::string> errors;  ///< signatures with an error estimate in some case
    std::string unit;
  };
  std::map<std::string, ProbeColumns> probes;
  for (const json& c : cases) {
    if (c.contains("modal")) {
      const json& modal = c["modal"];
      n_uncracked = std::max(n_uncracked, modal.value("uncracked_hz", json::array()).size());
      n_open = std::max(n_open, modal.value("open_hz", json::array()).size());
      n_pairs = std::max(n_pairs, modal.value("pairs", json::array()).size());
    }
    if (c.contains("spectrum")) {
      const json& spectrum = c["spectrum"];
      has_excitation = has_excitation || spectrum.value("excitation_hz", json()).is_number();
      const json all = spectrum.value("probes", json::object());
      for (const auto& [name, probe] : all.items()) {
        ProbeColumns& columns = probes[name];
        for (const json& a : probe.value("amplitudes", json::array()))
          columns.orders.insert(a["order"].get<double>());
        const json indices = probe.value("indices", json::object());
        for (const auto& [index, value] : indices.items()) columns.indices.insert(index);
        const json errors = probe.value("errors", json::object());
        for (const auto& [quantity, value] : errors.items()) columns.errors.insert(quantity);
        if (probe.contains("unit") && columns.unit.empty()) columns.unit = probe["unit"].get<std::string>();
      }
    }
  }

  StudyTable table;
  const auto add_fixed = [&](const std::string& header, const std::string& kind) {
    table.headers.push_back(header);
    table.kinds.push_back(kind);
  };
  add_fixed("case", "case");
  for (const VariedKey& key : plan.spec.vary) add_fixed(key_header(key.path), "parameter");
  add_fixed("status", "status");
  add_fixed("error", "error");
  using Extract = std::function<Cell(const json&)>;
  std::vector<Extract> extractors;
  std::string kind;  // of the columns added next
  const auto add = [&](const std::string& header, Extract extract) {
    add_fixed(header, kind);
    extractors.push_back(std::move(extract));
  };
  const auto modal_entry = [](const json& c, const char* list, std::size_t k, const char* field) -> json {
    if (!c.contains("modal")) return nullptr;
    const json items = c["modal"].value(list, json::array());
    if (k >= items.size()) return nullptr;
    return field ? items[k].value(field, json()) : items[k];
  };
  // Error columns of the frequencies where any case's modal.json estimated them.
  std::map<std::string, bool> modal_errors;
  for (const json& c : cases) {
    if (!c.is_object() || !c.contains("modal")) continue;
    for (const char* list : {"uncracked_error", "open_error", "bilinear_error"})
      modal_errors[list] = modal_errors[list] || c["modal"].contains(list);
  }
  const auto add_error = [&](const std::string& header, const char* list, std::size_t k) {
    if (!modal_errors[list]) return;
    kind = "error";
    add(header + " error [-]", [=](const json& c) { return number_cell(modal_entry(c, list, k, nullptr)); });
    kind = "frequency";
  };
  for (std::size_t k = 0; k < std::max({n_uncracked, n_open, n_pairs}); ++k) {
    const std::string mode = std::to_string(k + 1);
    kind = "frequency";
    if (k < n_uncracked) {
      add("f_uncracked_" + mode + " [Hz]",
          [=](const json& c) { return number_cell(modal_entry(c, "uncracked_hz", k, nullptr)); });
      add_error("f_uncracked_" + mode, "uncracked_error", k);
    }
    if (k < n_open) {
      add("f_open_" + mode + " [Hz]",
          [=](const json& c) { return number_cell(modal_entry(c, "open_hz", k, nullptr)); });
      add_error("f_open_" + mode, "open_error", k);
    }
    if (k < n_pairs) {
      add("f_bilinear_" + mode + " [Hz]",
          [=](const json& c) { return number_cell(modal_entry(c, "pairs", k, "bilinear_hz")); });
      add_error("f_bilinear_" + mode, "bilinear_error", k);
      kind = "mac";
      add("mac_" + mode + " [-]",
          [=](const json& c) { return number_cell(modal_entry(c, "pairs", k, "mac")); });
    }
  }
  if (has_excitation) {
    kind = "excitation";
    add("excitation [Hz]", [](const json& c) {
      return c.contains("spectrum") ? number_cell(c["spectrum"].value("excitation_hz", json())) : Cell{};
    });
  }
  for (const auto& [name, columns] : probes) {
    const auto probe_of = [name = name](const json& c) -> json {
      if (!c.contains("spectrum")) return nullptr;
      const json all = c["spectrum"].value("probes", json::object());
      return all.contains(name) ? all[name] : json();
    };
    // The probe's own unit when spectrum.json gives one, else that of what a probe's spectrum
    // analyses, as the scene table declares it (transient.probes[].component: a displacement).
    const std::string amplitude_unit =
        columns.unit.empty() ? key_unit("transient.probes[0].component") : columns.unit;
    const std::string unit = amplitude_unit.empty() ? "" : " [" + amplitude_unit + "]";
    kind = "amplitude";
    for (double order : columns.orders) {
      add(name + ".A" + order_label(order) + unit, [=](const json& c) {
        const json probe = probe_of(c);
        if (probe.is_null()) return Cell{};
        for (const json& a : probe.value("amplitudes", json::array()))
          if (a["order"].get<double>() == order) return number_cell(a.value("amplitude", json()));
        return Cell{};
      });
    }
    std::vector<std::string> indices;
    for (const std::string& known : kIndexOrder)
      if (columns.indices.count(known)) indices.push_back(known);
    for (const std::string& other : columns.indices)
      if (std::find(kIndexOrder.begin(), kIndexOrder.end(), other) == kIndexOrder.end())
        indices.push_back(other);
    kind = "index";
    for (const std::string& index : indices) {
      const std::string index_unit = index == "beta"
                                         ? (amplitude_unit.empty() ? "" : " [1/" + amplitude_unit + "]")
                                     : index.find('/') != std::string::npos ? " [-]"
                                                                            : "";
      add(name + "." + index + index_unit, [=](const json& c) {
        const json probe = probe_of(c);
        if (probe.is_null() || !probe.contains("indices")) return Cell{};
        return number_cell(probe["indices"].value(index, json()));
      });
    }
    // The estimated relative error of A1 and of each index (the sum of its components), where the
    // runs estimated it.
    kind = "error";
    std::vector<std::string> estimated = {"A1"};
    estimated.insert(estimated.end(), indices.begin(), indices.end());
    for (const std::string& quantity : estimated) {
      if (!columns.errors.count(quantity)) continue;
      add(name + "." + quantity + " error [-]", [=](const json& c) {
        const json probe = probe_of(c);
        if (probe.is_null() || !probe.contains("errors")) return Cell{};
        return number_cell(probe["errors"].value(quantity, json()));
      });
    }
  }

  add_sweep_columns(cases, kind, add);

  for (std::size_t i = 0; i < plan.cases.size(); ++i) {
    const StudyCase& study_case = plan.cases[i];
    const json& c = i < cases.size() ? cases[i] : json();
    std::vector<Cell> row;
    row.push_back(text_cell(std::to_string(study_case.index)));
    for (std::size_t k = 0; k < plan.spec.vary.size(); ++k)
      row.push_back(text_cell(study_case.overrides[k].value));
    Cell status, error;
    status.text = c.is_object() ? c.value("status", std::string("missing")) : "missing";
    error.text = c.is_object() ? c.value("error", std::string()) : "";
    row.push_back(status);
    row.push_back(error);
    for (const Extract& extract : extractors) row.push_back(c.is_object() ? extract(c) : Cell{});
    table.rows.push_back(std::move(row));
  }
  return table;
}

std::string table_csv(const StudyTable& table) {
  std::string text;
  for (std::size_t c = 0; c < table.headers.size(); ++c) text += (c ? "," : "") + io::csv_field(table.headers[c]);
  text += '\n';
  for (const auto& row : table.rows) {
    for (std::size_t c = 0; c < row.size(); ++c) text += (c ? "," : "") + io::csv_field(row[c].text);
    text += '\n';
  }
  return text;
}

json study_json(const StudyPlan& plan, const StudyTable& table, const std::vector<json>& cases) {
  json document = json::object();
  document["scene"] = plan.file;
  document["mode"] = text_of(scene::kStudyModeWords, plan.spec.mode);
  document["outputs"] = plan.spec.outputs;
  json varied = json::array();
  for (const VariedKey& key : plan.spec.vary) {
    json values = json::array();
    for (const std::string& value : key.values) values.push_back(yaml_text_to_json(value));
    varied.push_back({{"path", key.path}, {"values", values}});
  }
  document["varied"] = varied;
  document["shares_grid_lines"] = plan.shares_grid_lines;
  document["columns"] = table.headers;
  int n_ok = 0, n_failed = 0;
  double wall_s = 0.0;
  json rows = json::array();
  for (std::size_t i = 0; i < plan.cases.size(); ++i) {
    const StudyCase& study_case = plan.cases[i];
    json row = i < cases.size() && cases[i].is_object() ? cases[i] : json::object();
    json parameters = json::object();
    for (std::size_t k = 0; k < plan.spec.vary.size(); ++k)
      parameters[study_case.overrides[k].path] = yaml_text_to_json(study_case.overrides[k].value);
    row["case"] = study_case.index;
    row["folder"] = case_folder(study_case.index);
    row["parameters"] = parameters;
    const std::string status = row.value("status", std::string("missing"));
    row["status"] = status;
    n_ok += status == "ok";
    n_failed += status == "failed";
    if (row.contains("wall_s") && row["wall_s"].is_number()) wall_s += row["wall_s"].get<double>();
    rows.push_back(row);
  }
  document["n_cases"] = plan.cases.size();
  document["n_ok"] = n_ok;
  document["n_failed"] = n_failed;
  document["cases_wall_s"] = wall_s;
  document["cases"] = rows;
  return document;
}

}  // namespace crackle::study
