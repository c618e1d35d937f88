#include "identify/forward.hpp"

#include "accuracy/estimate.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <fstream>
#include <limits>
#include <map>
#include <ostream>
#include <sstream>

#include <nlohmann/json.hpp>

#include "core/errors.hpp"
#include "io/files.hpp"
#include "scene/scene.hpp"
#include "scene/schema.hpp"
#include "scene/yaml_text.hpp"
#include "study/plan.hpp"
#include "study/study.hpp"

namespace crackle::identify {
namespace fs = std::filesystem;
using nlohmann::json;

namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

int uniform_index(double at, double origin, double size, int cells) {
  return static_cast<int>(std::lround((at - origin) / size * cells));
}

}  // namespace

double number_of(const YAML::Node& node, const std::string& file, const std::string& path, bool integer) {
  double value = kNaN;
  if (!node.IsScalar() || !scene::parse_number(node.Scalar(), value) || !std::isfinite(value) ||
      (integer && value != std::floor(value)))
    scene::fail(file, scene::mark_line(node), path, integer ? "an integer" : "a finite number", scene::describe_node(node));
  return value;
}

void only_keys(const YAML::Node& map, const std::vector<std::string>& keys, const std::string& file,
               const std::string& path) {
  for (const auto& entry : map) {
    const std::string key = entry.first.Scalar();
    if (std::find(keys.begin(), keys.end(), key) == keys.end())
      scene::fail(file, scene::mark_line(entry.first), path + "." + key, "one of " + join(keys),
                  "unknown key '" + key + "'" + scene::suggestion(key, keys));
  }
}

std::vector<std::string> split_csv_line(const std::string& line) {
  // RFC 4180: a quoted cell may hold commas ("stable [1 yes, 0 no, -1 not computed]"), "" is a quote.
  std::vector<std::string> cells;
  std::string cell;
  bool quoted = false;
  for (std::size_t i = 0; i < line.size(); ++i) {
    const char c = line[i];
    if (quoted) {
      if (c == '"' && i + 1 < line.size() && line[i + 1] == '"') {
        cell += '"';
        ++i;
      } else if (c == '"') {
        quoted = false;
      } else {
        cell += c;
      }
    } else if (c == '"') {
      quoted = true;
    } else if (c == ',') {
      cells.push_back(cell);
      cell.clear();
    } else if (c != '\r') {
      cell += c;
    }
  }
  cells.push_back(cell);
  for (std::string& text : cells) {
    const auto first = text.find_first_not_of(" \t"), last = text.find_last_not_of(" \t");
    text = first == std::string::npos ? "" : text.substr(first, last - first + 1);
  }
  return cells;
}

std::vector<int> refinement_orders(int p) {
  const int first = std::min(p, 2);
  return {first, first + 1, first + 2};
}

RefinementError refinement_error(double q0, double q1, double q2, int run_level) {
  const std::array<double, 3> q = {q0, q1, q2};
  const double run = q[static_cast<std::size_t>(run_level)];
  if (!std::isfinite(run) || run == 0.0) return {0.0, false};  // no relative error of a zero (no sub-harmonic)
  if (std::isfinite(q0) && std::isfinite(q1) && std::isfinite(q2)) {
    const accuracy::Component component = accuracy::three_level_at(
        "mesh", q0, q1, q2, run_level + 1, accuracy::kOrderLevelRatio, accuracy::kOrderRateMin, accuracy::kOrderRateMax);
    if (std::isfinite(component.delta)) return {std::abs(component.delta), component.verified};
  }
  // A level without a value (a mode unpaired there, a sweep without the response): three times the
  // change from the run's level to the nearest other level that has one, the finer first (an order
  // cannot be observed from two), not verified.
  for (const int other : {run_level + 1, run_level - 1, run_level + 2, run_level - 2}) {
    if (other < 0 || other > 2 || !std::isfinite(q[static_cast<std::size_t>(other)])) continue;
    return {accuracy::kCautiousSafetyFactor * std::abs(q[static_cast<std::size_t>(other)] - run) / std::abs(run), false};
  }
  return {0.0, false};
}

std::vector<Unknown> parse_unknowns(const YAML::Node& map, const std::string& file, const std::string& where, int line) {
  if (!map || !map.IsMap() || map.size() == 0)
    scene::fail(file, map ? scene::mark_line(map) : line, where, "a map of scene key paths to [low, high] bounds",
                map ? scene::describe_node(map) : "nothing");
  std::vector<Unknown> unknowns;
  for (const auto& entry : map) {
    Unknown u;
    u.key = entry.first.Scalar();
    u.line = scene::mark_line(entry.first);
    const std::string where_path = where + "." + u.key;
    u.path = u.key;
    const auto bracket = u.key.find('[');
    if (bracket != std::string::npos && u.key.back() == ']') {
      u.path = u.key.substr(0, bracket);
      double index = kNaN;
      if (!scene::parse_number(u.key.substr(bracket + 1, u.key.size() - bracket - 2), index) || index < 0 ||
          index != std::floor(index))
        scene::fail(file, u.line, where_path, "a key path with a list index as [0]", "'" + u.key + "'");
      u.index = static_cast<int>(index);
    }
    if (const std::string problem = study::check_key_path(u.path); !problem.empty())
      throw InputError(file + ":" + std::to_string(u.line) + ": " + where_path + ": " + problem);
    if (study::key_unit(u.path).empty())
      scene::fail(file, u.line, where_path, "a numeric scene key", "'" + u.path + "' (not a number)");
    const YAML::Node bounds = entry.second;
    if (!bounds.IsSequence() || bounds.size() != 2)
      scene::fail(file, u.line, where_path, "bounds [low, high]", scene::describe_node(bounds));
    u.lower = number_of(bounds[0], file, where_path + "[0]");
    u.upper = number_of(bounds[1], file, where_path + "[1]");
    if (!(u.upper > u.lower))
      scene::fail(file, u.line, where_path, "bounds [low, high] with low < high",
                  format_number(u.lower) + ", " + format_number(u.upper));
    for (const Unknown& other : unknowns)
      if (other.key == u.key) scene::fail(file, u.line, where_path, "each unknown once", "'" + u.key + "' again");
    unknowns.push_back(u);
  }
  return unknowns;
}

YAML::Node node_at(const YAML::Node& document, const std::string& path) {
  // Walks with fresh handles (operator[] on a copied handle would rebind it, not copy the tree).
  std::vector<YAML::Node> chain = {document};
  std::stringstream stream(path);
  std::string key;
  while (std::getline(stream, key, '.')) {
    const YAML::Node& node = chain.back();
    if (!node.IsMap() || !node[key]) return YAML::Node(YAML::NodeType::Undefined);
    chain.push_back(node[key]);
  }
  return YAML::Clone(chain.back());
}

void prepare_base(YAML::Node& base, const scene::Scene& scene, const std::vector<Unknown>& unknowns,
                  const std::string& file, const std::string& where) {
  const std::string command = where.substr(0, where.find('.'));
  if (!scene.crack || !scene.gmsh_file.empty())
    throw InputError(file + ": " + command + ": expected a box mesh with a crack (crack.plane and crack.region), got " +
                     (scene.gmsh_file.empty() ? "no crack" : "a Gmsh mesh (its crack cannot be moved)"));
  for (const Unknown& u : unknowns) {
    const YAML::Node value = node_at(base, u.path);
    if (u.index >= 0 && (!value.IsSequence() || static_cast<int>(value.size()) <= u.index))
      throw InputError(file + ":" + std::to_string(u.line) + ": " + where + "." + u.key +
                       ": expected an entry of a list the scene gives at " + u.path + ", got " +
                       (value.IsDefined() ? scene::describe_node(value) : "nothing"));
    if (u.index < 0 && value.IsSequence())
      throw InputError(file + ":" + std::to_string(u.line) + ": " + where + "." + u.key + ": expected one entry (" +
                       u.path + "[0]), got the whole list");
  }
  mesh::CrackSpec reference = *scene.crack;
  for (const Unknown& u : unknowns) {
    const double middle = 0.5 * (u.lower + u.upper);
    if (u.path == "crack.plane.at") {
      const int axis = reference.normal;
      const int cells = scene.box.cells[axis];
      const int line = std::clamp(uniform_index(middle, scene.box.origin[axis], scene.box.size[axis], cells), 1, cells - 1);
      reference.at = scene.box.origin[axis] + scene.box.size[axis] * line / cells;
    }
    for (int axis = 0; axis < 3; ++axis)
      if (u.path == std::string("crack.region.") + "xyz"[axis] && u.index >= 0 && u.index < 2)
        reference.region[axis][static_cast<std::size_t>(u.index)] = middle;
  }
  YAML::Node ref(YAML::NodeType::Map);
  ref["at"] = format_number(reference.at);
  for (int axis = 0; axis < 3; ++axis) {
    if (axis == reference.normal) continue;
    YAML::Node range(YAML::NodeType::Sequence);
    range.push_back(format_number(reference.region[axis][0]));
    range.push_back(format_number(reference.region[axis][1]));
    range.SetStyle(YAML::EmitterStyle::Flow);
    ref["region"][std::string(1, "xyz"[axis])] = range;
  }
  base["crack"]["reference"] = ref;
}

std::vector<fs::path> run_forward_cases(const YAML::Node& base, const std::vector<Unknown>& unknowns,
                                        const std::vector<ForwardCase>& cases, const std::string& command,
                                        const fs::path& folder, const ForwardRunner& runner, std::ostream& log,
                                        bool progress) {
  if (cases.empty()) return {};
  YAML::Node document = YAML::Clone(base);
  // Only the tables are read: a sweep case draws no PNG per probe (a plan's dozens of sensors would
  // cost several times the sweep in gnuplot starts).
  if (command == "sweep" && document["sweep"]) document["sweep"]["plots"] = false;
  // A forward sweep runs on the scene's mesh as written (its error is identify's own p-refinement
  // estimate): transient.model: auto would give every case the route's finer mesh and its
  // refinement sweeps (crackle sweep's default).
  const YAML::Node& view = document;
  const YAML::Node transient = view["transient"];
  if (command == "sweep" && transient.IsMap() && (!transient["model"] || transient["model"].Scalar() == "auto")) {
    document["transient"]["model"] = "reduced";
  }
  // A forward sweep grades its box mesh towards the crack front, as the modal batch does (crackle
  // modal's default; `grading: auto` leaves crackle sweep's mesh uniform). The ratios converge far
  // slower on the uniform grid: A2/A1 of data/identify-beam.yaml's middle crack at p = 2, 3, 4 is
  // 0.0282, 0.0354, 0.0385 uniform against 0.0393, 0.0431, 0.0435 graded (docs/benchmarks.md 13.7).
  const YAML::Node box = view["mesh"] ? view["mesh"]["box"] : YAML::Node();
  if (command == "sweep" && box && box.IsMap()) {
    const YAML::Node grading = box["grading"];
    if (!grading || (grading.IsScalar() && grading.Scalar() == "auto")) {
      document["mesh"]["box"]["grading"] = "always";
    } else if (grading.IsMap() && (!grading["mode"] || grading["mode"].Scalar() == "auto")) {
      document["mesh"]["box"]["grading"]["mode"] = "always";
    }
  }
  // A forward modal case is not estimated by its own lower orders (crackle modal's default at order 3
  // or more): identify's error is its own p-refinement of the map.
  if (command == "modal" && (view["modal"] || view["spectrum"] || view["sweep"])) {
    YAML::Node accuracy(YAML::NodeType::Map);
    accuracy["estimate"] = "off";
    document["accuracy"] = accuracy;
  }
  std::vector<std::pair<std::string, std::vector<std::string>>> values;  // key path -> one text per case
  const auto add = [&](const std::string& path, const std::string& text, std::size_t c) {
    auto it = std::find_if(values.begin(), values.end(), [&](const auto& entry) { return entry.first == path; });
    if (it == values.end()) {
      if (c != 0) throw SolverError("forward runs: case " + std::to_string(c) + " sets " + path + ", the first does not");
      values.emplace_back(path, std::vector<std::string>{});
      it = values.end() - 1;
    }
    it->second.push_back(text);
  };
  std::map<std::string, YAML::Node> base_lists;
  for (std::size_t c = 0; c < cases.size(); ++c) {
    const ForwardCase& run = cases[c];
    std::map<std::string, YAML::Node> lists;
    for (std::size_t j = 0; j < unknowns.size(); ++j) {
      const Unknown& u = unknowns[j];
      // A key the batch's command never reads (transient.damping.ratio in a modal batch) is not set:
      // the study refuses to vary it, and the runs are the same without it.
      if (!study::output_reads(command == "modal" ? "modal" : command == "run" ? "spectrum" : "sweep", u.path)) continue;
      const double value = run.theta[static_cast<Eigen::Index>(j)];
      if (u.index < 0) {
        add(u.path, format_number(value), c);
        continue;
      }
      if (!base_lists.count(u.path)) base_lists[u.path] = node_at(base, u.path);
      if (!lists.count(u.path)) lists[u.path] = YAML::Clone(base_lists[u.path]);
      lists[u.path][static_cast<std::size_t>(u.index)] = format_number(value);
    }
    for (auto& [path, list] : lists) {
      std::vector<std::string> entries;
      for (const auto& item : list) entries.push_back(item.Scalar());
      add(path, "[" + join(entries) + "]", c);
    }
    for (const auto& [path, text] : run.set) add(path, text, c);
    if ((run.order > 0) != (cases.front().order > 0))
      throw SolverError("forward runs: mesh.box.order given for some cases of a batch only");
    if (run.order > 0) add("mesh.box.order", std::to_string(run.order), c);
  }
  for (const auto& [path, list] : values)
    if (list.size() != cases.size()) throw SolverError("forward runs: not every case sets " + path);
  // Cases that set the same values are one run (the points of a map that differ only in an unknown
  // this command never reads, such as the damping of a modal batch).
  std::vector<std::size_t> run_of(cases.size());
  std::vector<std::size_t> distinct;  // the first case of each run
  std::map<std::string, std::size_t> seen;
  for (std::size_t c = 0; c < cases.size(); ++c) {
    std::string signature;
    for (const auto& [path, list] : values) signature += path + "=" + list[c] + "\n";
    const auto [it, inserted] = seen.emplace(signature, distinct.size());
    if (inserted) distinct.push_back(c);
    run_of[c] = it->second;
  }
  if (values.empty()) {  // no case sets anything: one run of the scene as it is, at its own order
    const YAML::Node order = base["mesh"] && base["mesh"]["box"] ? base["mesh"]["box"]["order"] : YAML::Node();
    if (!order || !order.IsScalar()) throw SolverError("forward runs: no unknown is read by crackle " + command);
    values.emplace_back("mesh.box.order", std::vector<std::string>{order.Scalar()});
  }
  YAML::Node vary(YAML::NodeType::Map);
  for (const auto& [path, list] : values) {
    YAML::Node seq(YAML::NodeType::Sequence);
    for (std::size_t c : distinct) seq.push_back(YAML::Load(list[std::min(c, list.size() - 1)]));
    vary[path] = seq;
  }
  document["study"]["vary"] = vary;
  document["study"]["mode"] = "zip";
  document["study"]["outputs"] = std::vector<std::string>{command};
  fs::create_directories(folder);
  YAML::Emitter out;
  out << document;
  const fs::path scene_path = folder / "forward.yaml";
  io::write_file_atomic(scene_path, std::string(out.c_str()) + "\n");
  study::StudyOptions study;
  study.scene_path = scene_path.string();
  study.output_dir = (folder / "runs").string();
  study.executable = runner.executable;
  study.jobs = runner.jobs;
  // A forward run that failed fails the whole command (below), so a rerun retries it rather than
  // reading the old failure back: a run killed or interrupted by its machine is redone.
  study.retry_failed = true;
  // Modal batches: every case has its own (moved) mesh, so a cache would only add a primer per case.
  // Sweep batches: the cases of one crack (its drive points and frequencies) share one modal cache
  // folder, so the modal stage and the reduction of a drive point are computed once for them. With
  // the runner's one folder (crackle plan) every batch writes there: the sweeps at a crack and order
  // read the modes, and the MAC, that the modal batch solved for it (docs/benchmarks.md section 15, one modal cache).
  study.modal_cache = command == "sweep" || !runner.modal_cache.empty();
  study.modal_cache_directory = runner.modal_cache;
  study.gnuplot = "";
  std::ostringstream quiet;
  const int code = study::run_study(study, progress ? log : quiet);
  if (code == 130) throw SolverError("identify: interrupted");
  std::vector<fs::path> folders;
  const std::string wanted = command == "modal" ? "modal.json" : "sweep.csv";
  for (std::size_t c = 0; c < cases.size(); ++c) {
    const fs::path case_dir = folder / "runs" / study::case_folder(static_cast<int>(run_of[c]));
    if (!fs::exists(case_dir / wanted)) {
      std::string error = "no " + wanted;
      try {
        std::ifstream record(case_dir / "case.json");
        const json value = json::parse(record);
        if (value.contains("error")) error = value["error"].get<std::string>();
      } catch (const std::exception&) {
      }
      throw SolverError("forward run " + case_dir.string() + " failed: " + error);
    }
    folders.push_back(case_dir);
  }
  return folders;
}

int SweepTable::probe_column(const std::string& probe, const std::string& name) const {
  const std::string prefix = probe + " u_";
  for (std::size_t c = 0; c < header.size(); ++c) {
    const std::string& h = header[c];
    if (h.size() == prefix.size() + 2 + name.size() && h.rfind(prefix, 0) == 0 &&
        h.compare(h.size() - name.size(), name.size(), name) == 0)
      return static_cast<int>(c);
  }
  return -1;
}

int SweepTable::column(const std::string& name) const {
  const auto it = std::find(header.begin(), header.end(), name);
  return it == header.end() ? -1 : static_cast<int>(it - header.begin());
}

SweepTable read_sweep_csv(const fs::path& path) {
  std::ifstream file(path);
  if (!file) throw SolverError("forward run: no " + path.string());
  SweepTable table;
  std::string line;
  if (std::getline(file, line)) table.header = split_csv_line(line);
  while (std::getline(file, line)) {
    if (line.empty()) continue;
    std::vector<double> row;
    for (const std::string& cell : split_csv_line(line)) {
      double value = kNaN;
      scene::parse_number(cell, value);
      row.push_back(value);
    }
    table.rows.push_back(row);
  }
  return table;
}

double sweep_value(const SweepTable& table, const std::string& quantity, const std::string& probe, double drive_hz,
                   int branch_period) {
  const int index = table.probe_column(probe, quantity == "A1" ? "A1 [m]" : quantity + " [-]");
  if (index < 0) return kNaN;
  const int period = table.column("branch period [excitation periods]");
  const auto on_branch = [&](const std::vector<double>& row) {
    return period < 0 ? branch_period == 1 : std::lround(row[static_cast<std::size_t>(period)]) == branch_period;
  };
  for (std::size_t r = 0; r + 1 < table.rows.size(); ++r) {
    const std::vector<double>&a = table.rows[r], &b = table.rows[r + 1];
    if (!on_branch(a) || !on_branch(b)) continue;
    const double f0 = a[0], f1 = b[0];
    if ((f0 - drive_hz) * (f1 - drive_hz) > 0.0 || f0 == f1) continue;
    const double w = (drive_hz - f0) / (f1 - f0);
    return (1.0 - w) * a[static_cast<std::size_t>(index)] + w * b[static_cast<std::size_t>(index)];
  }
  return kNaN;
}

namespace {

/// The rows of `table` on the branch of `period` excitation periods around (or at) the drive, each
/// pair [a, b] of consecutive rows whose frequencies enclose it; a row at the drive itself gives
/// [r, r]. Consecutive rows further apart than the continuation's longest step over a sweep about a
/// sub-harmonic drive (kSubharmonicHalfWidth, kSubharmonicPoints) are the end of one segment of the
/// branch and the start of the next, not neighbours.
std::vector<std::pair<std::size_t, std::size_t>> rows_around(const SweepTable& table, double drive_hz, int period) {
  const double longest_step = (1.0 + 1e-9) * 2.0 * kSubharmonicHalfWidth * drive_hz / kSubharmonicPoints;
  const int column = table.column("branch period [excitation periods]");
  const auto on_branch = [&](std::size_t r) {
    return column < 0 ? period == 1 : std::lround(table.rows[r][static_cast<std::size_t>(column)]) == period;
  };
  const double at = 1e-12 * drive_hz;
  std::vector<std::pair<std::size_t, std::size_t>> around;
  for (std::size_t r = 0; r < table.rows.size(); ++r)
    if (on_branch(r) && std::abs(table.rows[r][0] - drive_hz) <= at) around.emplace_back(r, r);
  for (std::size_t r = 0; r + 1 < table.rows.size(); ++r) {
    const double f0 = table.rows[r][0], f1 = table.rows[r + 1][0];
    if (on_branch(r) && on_branch(r + 1) && (f0 - drive_hz) * (f1 - drive_hz) < 0.0 && std::abs(f1 - f0) <= longest_step)
      around.emplace_back(r, r + 1);
  }
  return around;
}

/// Whether both rows of `around` are stable.
bool stable_rows(const SweepTable& table, const std::pair<std::size_t, std::size_t>& around) {
  const int stable = table.column("stable [1 yes, 0 no, -1 not computed]");
  if (stable < 0) return false;
  const auto column = static_cast<std::size_t>(stable);
  return table.rows[around.first][column] == 1.0 && table.rows[around.second][column] == 1.0;
}

}  // namespace

bool period_two_exists(const SweepTable& table, double drive_hz) {
  for (const auto& around : rows_around(table, drive_hz, 2))
    if (stable_rows(table, around)) return true;
  return false;
}

double subharmonic_value(const SweepTable& table, const std::string& probe, double drive_hz) {
  const int index = table.probe_column(probe, "A1/2/A1 [-]");
  if (index < 0) return kNaN;
  const auto value = [&](const std::pair<std::size_t, std::size_t>& around) {
    const std::vector<double>&a = table.rows[around.first], &b = table.rows[around.second];
    const double w = around.first == around.second ? 0.0 : (drive_hz - a[0]) / (b[0] - a[0]);
    return (1.0 - w) * a[static_cast<std::size_t>(index)] + w * b[static_cast<std::size_t>(index)];
  };
  for (const auto& around : rows_around(table, drive_hz, 2))  // a row at the drive comes first
    if (stable_rows(table, around)) return value(around);
  for (const auto& around : rows_around(table, drive_hz, 1))
    if (stable_rows(table, around)) return 0.0;
  return kNaN;
}

double harmonic_value(const SweepTable& table, const std::string& quantity, const std::string& probe, double drive_hz,
                      int branch_period) {
  return quantity == "A1/2/A1" ? subharmonic_value(table, probe, drive_hz)
                               : sweep_value(table, quantity, probe, drive_hz, branch_period);
}

}  // namespace crackle::identify
