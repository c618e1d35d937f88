#include "study/plan.hpp"

#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <array>
#include <set>

#include "core/errors.hpp"
#include "scene/schema.hpp"
#include "scene/yaml_text.hpp"

namespace crackle::study {
namespace {

using scene::Kind;
using scene::Param;

constexpr std::size_t kMaxCases = 100000;
/// Most YAML nodes of all case scenes together (cases x nodes of the scene file).
constexpr std::size_t kMaxPlanNodes = 100000000;

using scene::describe_node;
using scene::is_quoted;
using scene::parse_number;
using scene::suggestion;

using scene::mark_line;

/// The command a study output runs.
std::string command_of(const std::string& output) {
  return output == "modal" ? "modal" : output == "spectrum" ? "run" : "sweep";
}

[[noreturn]] void fail(const std::string& file, int line, const std::string& path,
                       const std::string& expected, const std::string& got) {
  scene::fail(file, line, path, expected, got);
}

// ---- emitting YAML that reads back as the same document (quoted scalars stay quoted)

bool all_scalars(const YAML::Node& node) {
  for (const auto& item : node) {
    const YAML::Node value = node.IsMap() ? item.second : item;
    if (!value.IsScalar() && !(value.IsSequence() && all_scalars(value))) return false;
  }
  return true;
}

void emit_node(YAML::Emitter& out, const YAML::Node& node, bool flow) {
  switch (node.Type()) {
    case YAML::NodeType::Scalar:
      if (is_quoted(node))
        out << YAML::DoubleQuoted << node.Scalar();
      else
        out << node.Scalar();
      break;
    case YAML::NodeType::Sequence:
      if (flow || all_scalars(node)) out << YAML::Flow;
      out << YAML::BeginSeq;
      for (const auto& item : node) emit_node(out, item, flow || all_scalars(node));
      out << YAML::EndSeq;
      break;
    case YAML::NodeType::Map:
      if (flow) out << YAML::Flow;
      out << YAML::BeginMap;
      for (const auto& entry : node) {
        out << YAML::Key;
        emit_node(out, entry.first, true);
        out << YAML::Value;
        emit_node(out, entry.second, flow);
      }
      out << YAML::EndMap;
      break;
    default:
      out << YAML::Null;
  }
}

std::string emit(const YAML::Node& node, bool flow) {
  YAML::Emitter out;
  emit_node(out, node, flow);
  return out.c_str();
}

/// A deep copy (yaml-cpp nodes are references).
YAML::Node copy_of(const YAML::Node& node) { return YAML::Clone(node); }

// ---- key paths

using scene::PathStep;
using scene::split_path;

std::vector<std::string> child_names(const Param& param) {
  std::vector<std::string> names;
  for (const Param& c : param.children) names.push_back(c.name);
  return names;
}

void collect_leaves(const Param& param, const std::string& path, std::vector<std::string>& paths) {
  for (const Param& c : param.children) {
    const std::string child = path.empty() ? c.name : path + "." + c.name;
    if (c.kind == Kind::map)
      collect_leaves(c, child, paths);
    else if (c.kind == Kind::list)
      collect_leaves(c, child + "[0]", paths);
    else
      paths.push_back(child);
  }
}

// ---- the study section

/// The value of `key` in a map node, with the line of the key; undefined node when absent.
struct Entry {
  YAML::Node value;
  int line = -1;
};

std::vector<std::pair<std::string, Entry>> entries_of(const YAML::Node& map, const std::string& file,
                                                      const std::string& path,
                                                      const std::vector<std::string>& known) {
  std::vector<std::pair<std::string, Entry>> entries;
  std::set<std::string> seen;
  for (const auto& entry : map) {
    const int line = mark_line(entry.first);
    const std::string key_path = path + "." + entry.first.Scalar();
    if (!entry.first.IsScalar()) fail(file, line, path, "keys that are words", describe_node(entry.first));
    const std::string& key = entry.first.Scalar();
    if (!known.empty() && std::find(known.begin(), known.end(), key) == known.end())
      fail(file, line, key_path, "one of " + join(known),
           "unknown key '" + key + "'" + suggestion(key, known));
    if (!seen.insert(key).second) fail(file, line, key_path, "each key once", "'" + key + "' again");
    entries.push_back({key, {entry.second, line}});
  }
  return entries;
}

/// A number or a list of numbers (a range end); `numbers` receives them.
void read_range_end(const YAML::Node& node, const std::string& file, int line, const std::string& path,
                    std::vector<double>& numbers, bool& is_list) {
  const std::string expected = "a number or a list of numbers";
  is_list = node.IsSequence();
  if (node.IsScalar()) {
    double value = 0;
    if (is_quoted(node) || !parse_number(node.Scalar(), value))
      fail(file, line, path, expected, describe_node(node));
    numbers.push_back(value);
    return;
  }
  if (!node.IsSequence() || node.size() == 0) fail(file, line, path, expected, describe_node(node));
  for (std::size_t i = 0; i < node.size(); ++i) {
    double value = 0;
    if (!node[i].IsScalar() || is_quoted(node[i]) || !parse_number(node[i].Scalar(), value))
      fail(file, line, path + "[" + std::to_string(i) + "]", "a number", describe_node(node[i]));
    numbers.push_back(value);
  }
}

/// The values of a range {from, to, steps}: linear, both ends included.
std::vector<std::string> range_values(const YAML::Node& node, const std::string& file, int line,
                                      const std::string& path) {
  Entry from, to, steps;
  for (const auto& [key, entry] : entries_of(node, file, path, {"from", "to", "steps"}))
    (key == "from" ? from : key == "to" ? to : steps) = entry;
  if (from.line < 0) fail(file, line, path + ".from", "a number or a list of numbers", "nothing");
  if (to.line < 0) fail(file, line, path + ".to", "a number or a list of numbers", "nothing");
  if (steps.line < 0) fail(file, line, path + ".steps", "an integer >= 2", "nothing");
  const int from_line = from.line, to_line = to.line, steps_line = steps.line;
  std::vector<double> low, high;
  bool low_list = false, high_list = false;
  read_range_end(from.value, file, from_line, path + ".from", low, low_list);
  read_range_end(to.value, file, to_line, path + ".to", high, high_list);
  if (low_list != high_list || low.size() != high.size()) {
    fail(file, to_line, path + ".to",
         low_list ? "a list of " + std::to_string(low.size()) + " numbers, like from" : "a number, like from",
         describe_node(to.value));
  }
  const YAML::Node& count_node = steps.value;
  long long count = 0;
  const bool whole = count_node.IsScalar() && !is_quoted(count_node) &&
                     scene::parse_integer(count_node.Scalar(), count);
  if (!whole || count < 2 || count > static_cast<long long>(kMaxCases)) {
    double number = 0;
    // An integer or a number is shown as written (10000000, not 1e7).
    const bool numeric = count_node.IsScalar() && !is_quoted(count_node) &&
                         (whole || parse_number(count_node.Scalar(), number));
    fail(file, steps_line, path + ".steps",
         "an integer in 2.." + std::to_string(kMaxCases) + " (a study has at most " + std::to_string(kMaxCases) +
             " cases)",
         numeric ? count_node.Scalar() : describe_node(count_node));
  }
  std::vector<std::string> values;
  for (long long k = 0; k < count; ++k) {
    std::vector<std::string> parts;
    for (std::size_t i = 0; i < low.size(); ++i) {
      const double t = static_cast<double>(k) / static_cast<double>(count - 1);
      const double value = k == count - 1 ? high[i] : low[i] + (high[i] - low[i]) * t;
      parts.push_back(format_number(value));
    }
    values.push_back(low_list ? "[" + join(parts) + "]" : parts[0]);
  }
  return values;
}

/// Removes the prefix "file: " or "file:line: " from a loader message.
std::string without_file(const std::string& message, const std::string& file) {
  if (message.compare(0, file.size() + 1, file + ":") != 0) return message;
  std::size_t i = file.size() + 1;
  while (i < message.size() && std::isdigit(static_cast<unsigned char>(message[i]))) ++i;
  if (i < message.size() && message[i] == ':') ++i;
  while (i < message.size() && message[i] == ' ') ++i;
  return message.substr(i);
}

std::string describe_case(const StudyCase& study_case, std::size_t n_varied) {
  std::vector<std::string> parts;
  for (std::size_t k = 0; k < n_varied && k < study_case.overrides.size(); ++k)
    parts.push_back(study_case.overrides[k].path + " = " + study_case.overrides[k].value);
  return "case " + std::to_string(study_case.index) + " (" + join(parts) + ")";
}

/// Whether the scene format declares mesh.box.lines as a map with keys x, y, z.
bool format_has_grid_lines() {
  const Param* mesh = scene::scene_parameters().child("mesh");
  const Param* box = mesh ? mesh->child("box") : nullptr;
  const Param* lines = box ? box->child("lines") : nullptr;
  return lines && lines->kind == Kind::map && lines->child("x") && lines->child("y") && lines->child("z");
}

const char* const kAxes[3] = {"x", "y", "z"};

/// StudyCase::accuracy_key of a case document.
std::string accuracy_key(const YAML::Node& document) {
  YAML::Node key_document = copy_of(document);
  if (key_document["transient"].IsMap()) {
    key_document["transient"].remove("excitation");
    key_document["transient"].remove("damping");
  }
  key_document.remove("spectrum");
  key_document.remove("sweep");
  return hash_text(emit(key_document, false));
}

}  // namespace

std::string hash_text(const std::string& text) {
  std::uint64_t hash = 14695981039346656037ULL;
  for (unsigned char c : text) {
    hash ^= c;
    hash *= 1099511628211ULL;
  }
  char buffer[17];
  std::snprintf(buffer, sizeof buffer, "%016llx", static_cast<unsigned long long>(hash));
  return buffer;
}

std::string case_folder(int index) {
  char buffer[32];
  std::snprintf(buffer, sizeof buffer, "cases/%04d", index);
  return buffer;
}

std::string check_key_path(const std::string& path) {
  std::vector<PathStep> steps;
  if (!split_path(path, steps) || steps.front().key.empty())
    return "expected a key path like crack.region.z or boundary[0].face, got '" + path + "'";
  if (steps.front().key == "study") return "expected a scene key, got 'study' (a study cannot vary itself)";
  const Param* param = &scene::scene_parameters();
  std::string where;
  for (std::size_t s = 0; s < steps.size(); ++s) {
    const PathStep& step = steps[s];
    if (step.key.empty()) {
      if (param->kind != Kind::list && !param->is_list_of_scalars())
        return "expected a scene key, got an index after " + where + ", which is not a list";
      where += "[" + std::to_string(step.index) + "]";
      if (param->is_list_of_scalars() && s + 1 < steps.size())
        return "expected a scene key, got '" + path + "' (" + where + " is a single value)";
      continue;
    }
    if (param->kind == Kind::list && (s == 0 || !steps[s - 1].key.empty()))
      return "expected an index after " + where + ", as in " + where + "[0]." + step.key + ", got '" + path +
             "'";
    if (param->kind != Kind::map && param->kind != Kind::list)
      return "expected a scene key, got '" + path + "' (" + where + " has no keys below it)";
    const Param* child = param->child(step.key);
    if (!child) {
      const std::string prefix = where.empty() ? "" : where + ".";
      return "expected a scene key (" + (where.empty() ? std::string("sections") : "keys of " + where) +
             ": " + join(child_names(*param)) + "), got '" + path + "'" +
             suggestion(step.key, child_names(*param), prefix);
    }
    where += (where.empty() ? "" : ".") + step.key;
    param = child;
  }
  return "";
}

std::string key_unit(const std::string& path) {
  std::vector<PathStep> steps;
  if (!split_path(path, steps)) return "";
  const Param* param = &scene::scene_parameters();
  for (const PathStep& step : steps) {
    if (step.key.empty()) continue;  // an index: the entry of a list has the list's keys
    param = param->child(step.key);
    if (!param) return "";
  }
  if (!param->unit.empty()) return param->unit;
  return param->kind == Kind::number || param->kind == Kind::integer ? "-" : "";
}

std::string key_header(const std::string& path) {
  const std::string unit = key_unit(path);
  return unit.empty() ? path : path + " [" + unit + "]";
}

std::vector<std::string> leaf_key_paths() {
  std::vector<std::string> paths;
  collect_leaves(scene::scene_parameters(), "", paths);
  return paths;
}

std::string strip_study_section(const std::string& text, const std::string& file) {
  const YAML::Node document = scene::parse_yaml(text, file);
  if (!document.IsMap() || !document["study"].IsDefined()) return text;
  int start = -1, end = -1;
  bool block = true;
  for (const auto& entry : document) {
    const YAML::Mark mark = entry.first.Mark();
    if (mark.column != 0 || mark.line < 0) block = false;
    if (entry.first.Scalar() == "study") start = mark.line;
  }
  for (const auto& entry : document) {
    const int line = entry.first.Mark().line;
    if (line > start && (end < 0 || line < end)) end = line;
  }
  if (block && start >= 0) {
    std::string stripped;
    int line = 0;
    std::size_t position = 0;
    while (position < text.size()) {
      std::size_t next = text.find('\n', position);
      const bool last = next == std::string::npos;
      if (last) next = text.size();
      if (line < start || (end >= 0 && line >= end)) stripped.append(text, position, next - position);
      if (!last) stripped += '\n';
      position = next + 1;
      ++line;
    }
    const YAML::Node check = scene::parse_yaml(stripped, file);
    if (check.IsMap() && !check["study"].IsDefined() && check.size() + 1 == document.size()) return stripped;
  }
  YAML::Node copy = copy_of(document);  // not block style: lines cannot be kept
  copy.remove("study");
  return emit(copy, false) + "\n";
}

StudySpec parse_study_section(const std::string& text, const std::string& file) {
  StudySpec spec;
  const YAML::Node document = scene::parse_yaml(text, file);
  if (!document.IsMap()) return spec;
  YAML::Node study;
  for (const auto& entry : document) {
    if (entry.first.Scalar() == "study") {
      study = entry.second;
      spec.line = mark_line(entry.first);
    }
  }
  if (spec.line < 0) return spec;
  // Keys and choices as declared in scene::study_parameters() (which documents them).
  const scene::Param& table = *scene::study_parameters().child("study");
  const std::vector<std::string>& modes = table.child("mode")->choices;
  const std::vector<std::string>& known = table.child("outputs")->choices;
  std::vector<std::string> keys;
  for (const scene::Param& child : table.children) keys.push_back(child.name);
  if (!study.IsMap()) fail(file, spec.line, "study", "a map with keys " + join(keys, ", "), describe_node(study));

  Entry vary_entry, mode_entry, outputs_entry;  // line -1: absent
  for (const auto& [key, entry] : entries_of(study, file, "study", keys))
    (key == "vary" ? vary_entry : key == "mode" ? mode_entry : outputs_entry) = entry;
  const YAML::Node &vary = vary_entry.value, &mode = mode_entry.value, &outputs = outputs_entry.value;
  const int vary_line = vary_entry.line, mode_line = mode_entry.line, outputs_line = outputs_entry.line;

  if (mode_line >= 0) {
    if (!mode.IsScalar() || std::find(modes.begin(), modes.end(), mode.Scalar()) == modes.end())
      fail(file, mode_line, "study.mode", "one of " + join(modes, ", "),
           describe_node(mode) + (mode.IsScalar() ? suggestion(mode.Scalar(), modes) : ""));
    spec.mode = *value_of(scene::kStudyModeWords, mode.Scalar());
  }

  if (outputs_line >= 0) {
    std::vector<YAML::Node> items;
    if (outputs.IsScalar()) items.push_back(outputs);
    if (outputs.IsSequence())
      for (const auto& item : outputs) items.push_back(item);
    if (items.empty())
      fail(file, outputs_line, "study.outputs", "a list of entries from " + join(known, ", "),
           describe_node(outputs));
    std::set<std::string> chosen;
    for (std::size_t i = 0; i < items.size(); ++i) {
      const std::string item_path =
          "study.outputs" + (outputs.IsSequence() ? "[" + std::to_string(i) + "]" : "");
      if (!items[i].IsScalar() || std::find(known.begin(), known.end(), items[i].Scalar()) == known.end())
        fail(file, outputs_line, item_path, "one of " + join(known, ", "),
             describe_node(items[i]) + (items[i].IsScalar() ? suggestion(items[i].Scalar(), known) : ""));
      if (!chosen.insert(items[i].Scalar()).second)
        fail(file, outputs_line, item_path, "each entry at most once", describe_node(items[i]) + " again");
    }
    spec.outputs.clear();
    for (const std::string& name : known)
      if (chosen.count(name)) spec.outputs.push_back(name);
  }

  const std::string vary_expected =
      "a map from scene key paths (e.g. crack.region.z) to lists of values or ranges";
  if (vary_line < 0) fail(file, spec.line, "study.vary", vary_expected, "nothing");
  if (!vary.IsMap() || vary.size() == 0)
    fail(file, vary_line, "study.vary", vary_expected, describe_node(vary));
  for (const auto& [path, entry] : entries_of(vary, file, "study.vary", {})) {
    const std::string vary_path = "study.vary." + path;
    const std::string problem = check_key_path(path);
    if (!problem.empty()) {
      throw InputError(file + (entry.line > 0 ? ":" + std::to_string(entry.line) : "") + ": " + vary_path +
                       ": " + problem);
    }
    for (const VariedKey& earlier : spec.vary) {
      const auto inside = [](const std::string& inner, const std::string& outer) {
        return inner.size() > outer.size() && inner.compare(0, outer.size(), outer) == 0 &&
               (inner[outer.size()] == '.' || inner[outer.size()] == '[');
      };
      if (inside(path, earlier.path) || inside(earlier.path, path))
        fail(file, entry.line, vary_path, "keys that do not overlap",
             "'" + path + "' and '" + earlier.path + "'");
    }
    VariedKey key;
    key.path = path;
    key.line = entry.line;
    if (entry.value.IsSequence() && entry.value.size() > 0) {
      for (const auto& item : entry.value) key.values.push_back(emit(item, true));
    } else if (entry.value.IsMap()) {
      key.values = range_values(entry.value, file, entry.line, vary_path);
    } else {
      fail(file, entry.line, vary_path, "a list of values [a, b, ...] or a range {from, to, steps}",
           describe_node(entry.value));
    }
    spec.vary.push_back(key);
  }

  for (const VariedKey& key : spec.vary) {
    if (std::any_of(spec.outputs.begin(), spec.outputs.end(),
                    [&](const std::string& output) { return output_reads(output, key.path); }))
      continue;
    fail(file, key.line, "study.vary." + key.path,
         "a key that an output of study.outputs (" + join(spec.outputs) + ") reads",
         "'" + key.path + "', which " + (spec.outputs.size() == 1 ? "crackle " + command_of(spec.outputs.front()) + " never"
                                                                  : std::string("none of their commands")) +
             " reads (every case would be the same run); add the output that uses it to study.outputs "
             "(spectrum: crackle run, sweep: crackle sweep) or vary another key");
  }

  if (spec.mode == StudyMode::zip) {
    for (const VariedKey& key : spec.vary) {
      if (key.values.size() != spec.vary.front().values.size()) {
        fail(file, key.line, "study.vary." + key.path,
             "as many values as " + spec.vary.front().path + " (" +
                 std::to_string(spec.vary.front().values.size()) + ") in mode zip",
             std::to_string(key.values.size()));
      }
    }
  }
  return spec;
}

bool output_reads(const std::string& output, const std::string& path) {
  const std::string section = path.substr(0, path.find_first_of(".["));
  if (section == "study" || section == "identify" || section == "plan") return false;
  if (output == "modal") return section != "transient" && section != "spectrum" && section != "sweep";
  if (output == "spectrum") return section != "sweep";
  return true;
}

std::vector<std::vector<double>> shared_crack_lines(const std::vector<scene::Scene>& scenes) {
  std::vector<std::vector<double>> lines(3);
  for (int axis = 0; axis < 3; ++axis) {
    std::set<std::pair<double, double>> extents;
    for (const scene::Scene& s : scenes)
      if (s.crack && s.crack->normal != axis)
        extents.insert({s.crack->region[axis][0], s.crack->region[axis][1]});
    if (extents.size() < 2) continue;
    std::set<double> edges;
    for (const auto& [low, high] : extents) {
      edges.insert(low);
      edges.insert(high);
    }
    lines[axis].assign(edges.begin(), edges.end());
  }
  return lines;
}

std::string shared_grading(const std::vector<scene::Scene>& scenes) {
  std::array<std::set<double>, 3> fronts;
  std::set<std::array<std::vector<double>, 3>> per_case;
  std::set<int> layers;
  const scene::Scene* graded = nullptr;
  for (const scene::Scene& s : scenes) {
    if (!s.gmsh_file.empty() || !s.crack || s.grading.mode == scene::GradingMode::none) continue;
    mesh::BoxSpec box = s.box;
    box.grading = s.grading.grading;
    std::array<std::vector<double>, 3> own = mesh::crack_fronts(box, *s.crack);
    for (int axis = 0; axis < 3; ++axis) {
      own[axis].insert(own[axis].end(), box.grading.fronts[axis].begin(), box.grading.fronts[axis].end());
      std::sort(own[axis].begin(), own[axis].end());
      fronts[axis].insert(own[axis].begin(), own[axis].end());
    }
    per_case.insert(own);
    layers.insert(mesh::resolve_grading(box, *s.crack).layers);
    graded = &s;
  }
  if (per_case.size() < 2) return "";
  // The same mode, ratio and layers in every case (auto layers may differ with the crack: the most).
  const mesh::Grading& grading = graded->grading.grading;
  std::string text = "{mode: " + scene::grading_mode_name(graded->grading.mode) + ", layers: " + std::to_string(*layers.rbegin()) +
                     ", ratio: " + format_number(grading.ratio) + ", fronts: {";
  std::vector<std::string> axes;
  for (int axis = 0; axis < 3; ++axis) {
    if (fronts[axis].empty()) continue;
    std::vector<std::string> parts;
    for (double value : fronts[axis]) parts.push_back(format_number(value));
    axes.push_back(std::string(kAxes[axis]) + ": [" + join(parts) + "]");
  }
  return text + join(axes) + "}}";
}

StudyPlan plan_study(const std::string& text, const std::string& file) {
  StudyPlan plan;
  plan.file = file;
  plan.spec = parse_study_section(text, file);
  plan.base_text = strip_study_section(text, file);
  if (plan.spec.line < 0)
    fail(file, -1, "study", "a section study: {vary: {key.path: [values]}, mode, outputs}", "nothing");
  const StudySpec& spec = plan.spec;

  // The cases' overrides: grid (first key slowest) or zip.
  std::size_t n_cases = spec.vary.front().values.size();
  if (spec.mode == StudyMode::grid) {
    n_cases = 1;
    for (const VariedKey& key : spec.vary) {
      n_cases *= key.values.size();
      if (n_cases > kMaxCases)
        fail(file, spec.line, "study.vary", "at most " + std::to_string(kMaxCases) + " cases", "more");
    }
  }
  if (n_cases > kMaxCases)
    fail(file, spec.line, "study.vary", "at most " + std::to_string(kMaxCases) + " cases",
         std::to_string(n_cases));
  // Every case is validated and written as a whole scene: bound the work (aliases expanded).
  const std::size_t document_nodes = scene::count_nodes(scene::parse_yaml(text, file), kMaxPlanNodes);
  if (n_cases * document_nodes > kMaxPlanNodes)
    fail(file, spec.line, "study.vary",
         "at most " + std::to_string(kMaxPlanNodes) + " YAML nodes over all cases (cases x nodes of the scene)",
         std::to_string(n_cases) + " cases of " + std::to_string(document_nodes) + " nodes");
  plan.cases.resize(n_cases);
  for (std::size_t c = 0; c < n_cases; ++c) {
    StudyCase& study_case = plan.cases[c];
    study_case.index = static_cast<int>(c);
    std::size_t rest = c;
    std::vector<std::size_t> picks(spec.vary.size(), c);
    if (spec.mode == StudyMode::grid) {
      for (std::size_t k = spec.vary.size(); k-- > 0;) {
        picks[k] = rest % spec.vary[k].values.size();
        rest /= spec.vary[k].values.size();
      }
    }
    for (std::size_t k = 0; k < spec.vary.size(); ++k)
      study_case.overrides.push_back({spec.vary[k].path, spec.vary[k].values[picks[k]]});
  }

  // Validate every case with the scene loader; messages name the case and the key path.
  std::vector<scene::Scene> scenes;
  for (const StudyCase& study_case : plan.cases) {
    try {
      scenes.push_back(scene::parse_scene(plan.base_text, file, study_case.overrides));
    } catch (const InputError& error) {
      // A message with a line is about the base scene (override nodes carry no line): as it is.
      const std::string message = error.what();
      if (message.size() > file.size() + 1 && message.compare(0, file.size() + 1, file + ":") == 0 &&
          std::isdigit(static_cast<unsigned char>(message[file.size() + 1])))
        throw;
      const std::string inner = without_file(message, file);
      const VariedKey* blamed = nullptr;
      for (const VariedKey& key : spec.vary)
        if (inner.compare(0, key.path.size(), key.path) == 0 &&
            (!blamed || key.path.size() > blamed->path.size()))
          blamed = &key;
      const int line = blamed ? blamed->line : spec.line;
      throw InputError(file + (line > 0 ? ":" + std::to_string(line) : "") + ": study.vary" +
                       (blamed ? "." + blamed->path : "") + ": " +
                       describe_case(study_case, spec.vary.size()) + ": " + inner);
    }
  }

  // One mesh for all cases: the union of their crack edges as extra grid lines, when the scene
  // format has mesh.box.lines (otherwise each case meshes its own crack edges).
  const YAML::Node base_document = scene::parse_yaml(plan.base_text, file);
  // Cases whose grid is made for one reference crack (crack.reference) share its topology already.
  const bool morphed = !scenes.empty() && std::all_of(scenes.begin(), scenes.end(), [](const scene::Scene& s) {
    return s.crack_reference.has_value();
  });
  // Cases whose run or sweep takes the automatic route's own mesh (graded towards their own crack
  // front) mesh themselves: a mesh with every case's crack edges and fronts would be many times
  // larger, and the route would lower its order for it (then the mesh error is not estimated).
  const bool own_meshes = !scenes.empty() && std::all_of(scenes.begin(), scenes.end(), [&](const scene::Scene& s) {
    return std::any_of(spec.outputs.begin(), spec.outputs.end(), [&](const std::string& output) {
      return output != "modal" && scene::takes_route_mesh(s, output == "spectrum" ? "run" : output);
    });
  });
  if (format_has_grid_lines() && !morphed && !own_meshes) {
    const auto lines = shared_crack_lines(scenes);
    for (int axis = 0; axis < 3; ++axis) {
      if (lines[axis].empty()) continue;
      std::set<double> merged(lines[axis].begin(), lines[axis].end());
      // Look the existing lines up through const nodes: indexing a missing key of a non-const
      // node makes a node that throws when indexed again.
      const YAML::Node& root = base_document;
      YAML::Node given;
      if (root["mesh"] && root["mesh"]["box"] && root["mesh"]["box"]["lines"]) {
        given = root["mesh"]["box"]["lines"][kAxes[axis]];
      }
      if (given && given.IsSequence()) {
        for (const auto& item : given) {
          double value = 0;
          if (parse_number(item.Scalar(), value)) merged.insert(value);
        }
      }
      std::vector<std::string> parts;
      for (double value : merged) parts.push_back(format_number(value));
      const std::string override_text = "[" + join(parts) + "]";
      for (StudyCase& study_case : plan.cases)
        study_case.overrides.push_back({std::string("mesh.box.lines.") + kAxes[axis], override_text});
      plan.shares_grid_lines = true;
    }
  }

  // Graded meshes: every case grades towards the fronts of all cases (from the same grid), so
  // that the cases still share one mesh.
  if (const std::string grading = morphed || own_meshes ? std::string() : shared_grading(scenes); !grading.empty()) {
    for (StudyCase& study_case : plan.cases) study_case.overrides.push_back({"mesh.box.grading", grading});
    plan.shares_grid_lines = true;
  }

  const std::string outputs = join(spec.outputs, ",");
  for (std::size_t c = 0; c < plan.cases.size(); ++c) {
    StudyCase& study_case = plan.cases[c];
    YAML::Node document = copy_of(base_document);
    for (const scene::Override& change : study_case.overrides)
      scene::apply_override(document, change.path, change.value, file);
    const std::string body = emit(document, false) + "\n";
    study_case.scene_text =
        "# " + describe_case(study_case, spec.vary.size()) + " of the study in " + file + "\n" + body;
    const std::string case_name = file + " " + case_folder(study_case.index) + "/scene.yaml";
    bool tolerance = false;  // whether the case's estimate may refine to a tolerance
    try {
      if (plan.shares_grid_lines) scene::parse_scene(plan.base_text, file, study_case.overrides);
      const scene::Scene case_scene = scene::parse_scene(study_case.scene_text, case_name);
      study_case.has_modal_section = case_scene.has_modal_section;
      const bool automatic = case_scene.transient && case_scene.transient->model == scene::TransientModel::automatic;
      tolerance = case_scene.accuracy.estimate != scene::EstimateChoice::off && (case_scene.accuracy.tolerance || automatic);
    } catch (const InputError& error) {
      throw InputError(file + ": study: " + describe_case(study_case, spec.vary.size()) +
                       ": the case scene does not read back: " + error.what());
    }
    study_case.hash = hash_text(body + "# outputs: " + outputs + "\n");

    // What the uncracked modes depend on: everything but the transient run, the modal variants,
    // and the crack (all of it when the cases share one mesh, else just its gap).
    YAML::Node key_document = copy_of(document);
    key_document.remove("transient");
    key_document.remove("spectrum");  // the primer drops them too: the uncracked modes do not read them
    key_document.remove("sweep");
    key_document.remove("accuracy");
    if (key_document["modal"].IsMap()) key_document["modal"].remove("variants");
    if (plan.shares_grid_lines)
      key_document.remove("crack");
    else if (key_document["crack"].IsMap())
      key_document["crack"].remove("gap");
    study_case.modal_key = hash_text(emit(key_document, false));

    if (tolerance) study_case.accuracy_key = accuracy_key(document);

    YAML::Node primer = copy_of(document);
    primer.remove("transient");  // and what needs it: a modal solve is all the primer does
    primer.remove("spectrum");
    primer.remove("sweep");
    primer.remove("accuracy");  // it needs the transient and spectrum sections
    const bool modal_output = std::find(spec.outputs.begin(), spec.outputs.end(), "modal") != spec.outputs.end();
    if (!modal_output && primer["mesh"].IsMap() && primer["mesh"]["box"].IsMap()) {
      // The cases' run and sweep mesh a box uniformly where mesh.box.grading is auto; crackle modal
      // grades it: the primer's modes would be of another mesh (never the cases' key).
      YAML::Node box = primer["mesh"]["box"];
      const YAML::Node grading = box["grading"];
      if (!grading || (grading.IsScalar() && grading.Scalar() == "auto")) {
        box["grading"] = "none";
      } else if (grading.IsMap() && (!grading["mode"] || grading["mode"].Scalar() == "auto")) {
        box["grading"]["mode"] = "none";
      }
    }
    if (!primer["modal"].IsMap()) primer["modal"] = YAML::Node(YAML::NodeType::Map);
    primer["modal"]["variants"] = YAML::Load("[uncracked]");
    study_case.primer_text = "# uncracked modes shared by the cases with modal cache key " +
                             study_case.modal_key + "\n" + emit(primer, false) + "\n";
    try {
      scene::parse_scene(study_case.primer_text, case_name);
    } catch (const InputError&) {
      study_case.primer_text.clear();
    }
    // The route's own meshes are not the scene's: modes primed on the scene's mesh would serve no case.
    if (own_meshes) study_case.primer_text.clear();
  }
  return plan;
}

}  // namespace crackle::study
