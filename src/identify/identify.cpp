#include "identify/identify.hpp"
#include "identify/identify_stages.hpp"

#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <limits>
#include <map>
#include <ostream>
#include <set>
#include <sstream>
#include <tuple>

#include <Eigen/Cholesky>
#include <Eigen/QR>
#include <nlohmann/json.hpp>

#include "core/errors.hpp"
#include "fit/fit.hpp"
#include "io/files.hpp"
#include "scene/scene.hpp"
#include "scene/schema.hpp"
#include "scene/yaml_text.hpp"
#include "plot/gnuplot.hpp"
#include "transient/damping.hpp"
#include "study/plan.hpp"
#include "study/study.hpp"

namespace crackle::identify {
namespace fs = std::filesystem;
using nlohmann::json;

namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
/// Map minima kept for a local fit: chi^2 within this of the best (3 sigma of one unknown).
constexpr double kMinimaSpread = 9.0;
constexpr std::size_t kMaxStarts = 4;
/// Two fitted minima "fit equally well" when their chi^2 differ by less than this.
constexpr double kEqualFit = 1.0;
/// Finite-difference step of the forward model, as a fraction of each bound width: the map shows the
/// model smooth to ~1e-9 relative (morphed mesh, eigen-solve tolerance 1e-10), sqrt of which is the
/// classic choice; 1e-4 of a width keeps the truncation error below the noise of a 0.05 % frequency.
constexpr double kForwardStep = 1e-4;
/// A local fit has converged when the forward model's Gauss-Newton step is at most this many of the
/// estimate's standard deviations (Mahalanobis): a further step would move it by less than 1/20 of
/// its 95 % interval.
constexpr double kAccept = 0.1;
/// Gauss-Newton iterations on the forward model before Levenberg-Marquardt takes over.
constexpr int kGaussNewtonIterations = 4;
constexpr int kHalvings = 4;  ///< trials of a Gauss-Newton step: 1, 1/2, 1/4, 1/8 of it

[[noreturn]] void fail(const std::string& file, int line, const std::string& path, const std::string& expected,
                       const std::string& got) {
  scene::fail(file, line, path, expected, got);
}

bool is_frequency(const std::string& quantity) {
  const auto& f = frequency_quantities();
  return std::find(f.begin(), f.end(), quantity) != f.end() || quantity == "damping_ratio";
}

/// Checks one measurement's own fields (the scene-dependent checks come later).
void check_measurement(const Measurement& m, const std::string& file, int line, const std::string& path) {
  const auto& all = all_quantities();
  if (std::find(all.begin(), all.end(), m.quantity) == all.end()) {
    fail(file, line, path + ".quantity", "one of " + join(all),
         "'" + m.quantity + "'" + scene::suggestion(m.quantity, all));
  }
  if (is_frequency(m.quantity) && m.mode < 1) fail(file, line, path + ".mode", "a mode number >= 1", "none");
  if (!is_frequency(m.quantity)) {
    if (m.probe.empty()) fail(file, line, path + ".probe", "the name of a probe of the scene", "none");
    if (!(m.drive_hz > 0.0) || !std::isfinite(m.drive_hz))
      fail(file, line, path + ".drive_hz", "a drive frequency > 0 [Hz]", format_number(m.drive_hz));
  }
  if (!std::isfinite(m.value)) fail(file, line, path + ".value", "a finite number", format_number(m.value));
  if (!(m.sigma > 0.0) || !std::isfinite(m.sigma))
    fail(file, line, path + ".sigma", "a standard deviation > 0", m.sigma == 0.0 ? "none or 0" : format_number(m.sigma));
}

Measurement measurement_from(const YAML::Node& node, const std::string& file, const std::string& path) {
  const int line = scene::mark_line(node);
  if (!node.IsMap()) fail(file, line, path, "a map {quantity, mode or probe and drive_hz, value, sigma}", scene::describe_node(node));
  Measurement m;
  m.where = file + ":" + std::to_string(line);
  const std::vector<std::string> keys = {"quantity", "mode", "probe", "drive_hz", "value", "sigma"};
  only_keys(node, keys, file, path);
  if (!node["quantity"]) fail(file, line, path + ".quantity", "one of " + join(all_quantities()), "nothing");
  m.quantity = node["quantity"].Scalar();
  if (node["mode"]) m.mode = static_cast<int>(number_of(node["mode"], file, path + ".mode", true));
  if (node["probe"]) m.probe = node["probe"].Scalar();
  if (node["drive_hz"]) m.drive_hz = number_of(node["drive_hz"], file, path + ".drive_hz");
  if (!node["value"]) fail(file, line, path + ".value", "the measured value", "nothing");
  m.value = number_of(node["value"], file, path + ".value");
  if (node["sigma"]) m.sigma = number_of(node["sigma"], file, path + ".sigma");
  check_measurement(m, file, line, path);
  return m;
}

/// Half-width of the sweep about a drive frequency, relative.
constexpr double kSweepHalfWidth = 1e-4;

/// The forward model: batches of parameter vectors run as studies of `crackle sweep` cases (one per
/// drive frequency: a narrow harmonic-balance sweep about it) when harmonic quantities are measured,
/// whose modal stages also give the frequencies; else of `crackle modal` cases. Both grade the mesh
/// towards the crack front (run_forward_cases).
class Forward {
 public:
  Forward(const IdentifySpec& spec, YAML::Node base, const scene::DampingSection& damping,
          const IdentifyOptions& options, std::ostream& log)
      : spec_(spec), base_(std::move(base)), scene_damping_(damping), options_(options), log_(log) {
    std::set<Drive> drives;
    for (const Measurement& m : spec_.measured) {
      if (!is_frequency(m.quantity)) drives.insert(drive_of(m));
      if (is_frequency(m.quantity)) frequencies_ = true;
    }
    drives_.assign(drives.begin(), drives.end());
  }

  /// Model values of every measurement at each theta; `folder` holds the batch's studies (a rerun
  /// with the same parameters reuses their cases). `orders`: a mesh.box.order per theta (empty: the
  /// scene's).
  std::vector<VectorX> models(const std::vector<VectorX>& thetas, const fs::path& folder, bool progress,
                              const std::vector<int>& orders = {}) {
    std::vector<json> modal;
    std::vector<std::vector<SweepTable>> sweeps(thetas.size());
    if (!drives_.empty()) {
      const std::vector<fs::path> cases =
          run_cases(thetas, drives_, orders, frequencies_ ? folder / "sweep" : folder, progress);
      for (std::size_t c = 0; c < cases.size(); ++c) sweeps[c / drives_.size()].push_back(read_sweep_csv(cases[c] / "sweep.csv"));
      // A sweep case's modal stage solves the modal batch's problem (the same graded mesh, order and
      // modal: section; docs/benchmarks.md 13.10): its modal.json gives the frequencies, and the
      // batch of `crackle modal` cases is not run (it was half of the forward runs).
      if (frequencies_) modal = sweep_modal(cases);
    }
    if (frequencies_ && modal.empty()) {
      const std::vector<fs::path> cases = run_cases(thetas, {}, orders, folder, progress && drives_.empty());
      for (const fs::path& case_dir : cases) {
        std::ifstream stream(case_dir / "modal.json");
        modal.push_back(json::parse(stream));
      }
    }
    std::vector<VectorX> result;
    for (std::size_t t = 0; t < thetas.size(); ++t) {
      VectorX m(static_cast<Eigen::Index>(spec_.measured.size()));
      for (std::size_t i = 0; i < spec_.measured.size(); ++i) {
        const Measurement& measurement = spec_.measured[i];
        double value = kNaN;
        if (!is_frequency(measurement.quantity)) {
          const Drive drive = drive_of(measurement);
          const SweepTable& table = sweeps[t][static_cast<std::size_t>(
              std::lower_bound(drives_.begin(), drives_.end(), drive) - drives_.begin())];
          value = harmonic_value(table, measurement.quantity, measurement.probe, drive.hz);
        } else {
          const json& pairs = modal[t]["pairs"];
          if (static_cast<std::size_t>(measurement.mode) <= pairs.size()) {
            const json& pair = pairs[static_cast<std::size_t>(measurement.mode - 1)];
            const bool paired = pair.value("paired", true);
            if (measurement.quantity == "f_uncracked") value = pair["f_uncracked_hz"].get<double>();
            if (measurement.quantity == "f_open" && paired) value = pair["f_open_hz"].get<double>();
            if (measurement.quantity == "f_bilinear" && paired) value = pair["f_bilinear_hz"].get<double>();
            if (measurement.quantity == "damping_ratio") value = damping_ratio(thetas[t], pairs, pair);
          }
        }
        m[static_cast<Eigen::Index>(i)] = value;
      }
      result.push_back(m);
    }
    return result;
  }

  int runs() const { return runs_; }

 private:
  /// A drive frequency of the harmonic measurements and its sweep: narrow about it (the period-one
  /// branch: A1, A2/A1, A3/A1), or wide with stability and the period-two branch (A1/2/A1).
  struct Drive {
    double hz = 0.0;
    bool subharmonic = false;
    bool operator<(const Drive& other) const { return std::tie(hz, subharmonic) < std::tie(other.hz, other.subharmonic); }
  };
  static Drive drive_of(const Measurement& m) { return {m.drive_hz, m.quantity == "A1/2/A1"}; }

  /// The modal damping ratio of the scene's Rayleigh damping (MODEL.md eq. 26) at a mode's frequency:
  /// xi = alpha / (2 omega) + beta omega / 2 at the bilinear frequency (the ring-down's) of a paired
  /// mode, else the uncracked one; the damping keys among the unknowns take theta's values; a ratio
  /// at a mode is at that mode's uncracked frequency, as crackle run sets it.
  double damping_ratio(const VectorX& theta, const json& pairs, const json& pair) const {
    scene::DampingSection damping = scene_damping_;
    for (std::size_t j = 0; j < spec_.unknowns.size(); ++j) {
      const std::string& key = spec_.unknowns[j].key;
      const double value = theta[static_cast<Eigen::Index>(j)];
      if (key == "transient.damping.ratio") damping.ratio = value;
      if (key == "transient.damping.alpha") damping.alpha = value;
      if (key == "transient.damping.beta") damping.beta = value;
      if (key == "transient.damping.at" || key == "transient.damping.at.hz") damping.at_hz = value;
    }
    const double f_hz = pair.value("paired", true) ? pair["f_bilinear_hz"].get<double>() : pair["f_uncracked_hz"].get<double>();
    double at_hz = damping.at_hz.value_or(kNaN);
    if (damping.ratio && !damping.at_hz) {
      if (damping.at_mode < 1 || static_cast<std::size_t>(damping.at_mode) > pairs.size()) return kNaN;
      at_hz = pairs[static_cast<std::size_t>(damping.at_mode - 1)]["f_uncracked_hz"].get<double>();
    }
    const transient::RayleighDamping rayleigh = transient::stated_damping(
        damping.ratio, damping.type == scene::DampingType::stiffness, at_hz, damping.alpha, damping.beta);
    return transient::damping_ratio(rayleigh, 2.0 * M_PI * f_hz);
  }

  /// The modal.json of each theta's first sweep case (theta-major `cases`), or none if a case has
  /// none or fewer pairs than the highest measured mode (its sweep needed no modal stage).
  std::vector<json> sweep_modal(const std::vector<fs::path>& cases) const {
    std::size_t highest = 0;
    for (const Measurement& m : spec_.measured)
      if (is_frequency(m.quantity)) highest = std::max(highest, static_cast<std::size_t>(std::max(m.mode, 1)));
    std::vector<json> modal;
    for (std::size_t c = 0; c < cases.size(); c += drives_.size()) {
      std::ifstream stream(cases[c] / "modal.json");
      if (!stream) return {};
      json document = json::parse(stream, nullptr, false);
      if (document.is_discarded() || !document.contains("pairs") || !document["pairs"].is_array() ||
          document["pairs"].size() < highest) {
        return {};
      }
      modal.push_back(std::move(document));
    }
    return modal;
  }

  /// One study over the thetas (times the drive frequencies, when given: `crackle sweep` cases);
  /// the case folders in order (theta-major). SolverError names a case that failed.
  std::vector<fs::path> run_cases(const std::vector<VectorX>& thetas, const std::vector<Drive>& drives,
                                  const std::vector<int>& orders, const fs::path& folder, bool progress) {
    YAML::Node document = YAML::Clone(base_);
    if (!drives.empty()) {
      // The sweep of each case: its range is set per case; no stability (amplitudes only).
      YAML::Node sweep = document["sweep"] ? document["sweep"] : YAML::Node(YAML::NodeType::Map);
      sweep["frequency"] = YAML::Node(YAML::NodeType::Map);
      sweep["frequency"]["from"] = 1.0;
      sweep["frequency"]["to"] = 2.0;
      sweep["points"] = 2;
      sweep["stability"] = false;
      if (sweep["subharmonic"]) sweep.remove("subharmonic");
      document["sweep"] = sweep;
    }
    std::vector<ForwardCase> cases;
    for (std::size_t t = 0; t < thetas.size(); ++t) {
      ForwardCase run{thetas[t], orders.empty() ? 0 : orders[t], {}};
      if (drives.empty()) cases.push_back(run);
      for (const Drive& drive : drives) {
        // Each branch is solved at the drive itself (sweep.solve_at): the value read there does not
        // move with the continuation's points, which finite differences would see as noise.
        const double half = drive.subharmonic ? kSubharmonicHalfWidth : kSweepHalfWidth;
        run.set = {{"sweep.frequency.from", format_number(drive.hz * (1.0 - half))},
                   {"sweep.frequency.to", format_number(drive.hz * (1.0 + half))},
                   {"sweep.points", std::to_string(drive.subharmonic ? kSubharmonicPoints : 2)},
                   {"sweep.stability", drive.subharmonic ? "true" : "false"},
                   {"sweep.subharmonic", drive.subharmonic ? "2" : "1"},
                   {"sweep.solve_at", "[" + format_number(drive.hz) + "]"}};
        cases.push_back(run);
      }
    }
    const std::vector<fs::path> folders = run_forward_cases(document, spec_.unknowns, cases, drives.empty() ? "modal" : "sweep",
                                                            folder, {options_.executable, options_.jobs, ""}, log_,
                                                            progress && options_.progress);
    runs_ += static_cast<int>(std::set<fs::path>(folders.begin(), folders.end()).size());  // distinct runs
    return folders;
  }

  const IdentifySpec& spec_;
  YAML::Node base_;
  scene::DampingSection scene_damping_;  ///< transient.damping as the scene writes it (damping_ratio)
  const IdentifyOptions& options_;
  std::ostream& log_;
  bool frequencies_ = false;    ///< a frequency is measured
  std::vector<Drive> drives_;  ///< distinct drives of the harmonic measurements, sorted
  int runs_ = 0;
};


}  // namespace

const std::vector<std::string>& frequency_quantities() {
  static const std::vector<std::string> names = {"f_uncracked", "f_open", "f_bilinear"};
  return names;
}

const std::vector<std::string>& all_quantities() {
  static const std::vector<std::string> names = {"f_uncracked", "f_open", "f_bilinear", "damping_ratio",
                                                 "A1",          "A2/A1",  "A3/A1",      "A1/2/A1"};
  return names;
}

std::vector<Measurement> read_measurements_csv(const std::string& path) {
  std::ifstream file(path);
  if (!file) throw InputError(path + ": expected a readable measurements file (CSV), got " + std::strerror(errno));
  const std::vector<std::string> header = {"quantity", "mode", "probe", "drive_hz", "value", "sigma"};
  std::string line;
  int number = 0;
  std::vector<Measurement> measured;
  bool have_header = false;
  while (std::getline(file, line)) {
    ++number;
    if (line.find_first_not_of(" \t\r") == std::string::npos || line[0] == '#') continue;
    const std::vector<std::string> cells = split_csv_line(line);
    if (!have_header) {
      if (cells != header) {
        throw InputError(path + ":" + std::to_string(number) + ": expected the header " + join(header, ",") +
                         ", got '" + line + "'");
      }
      have_header = true;
      continue;
    }
    const std::string where = path + ":" + std::to_string(number);
    if (cells.size() != header.size()) {
      throw InputError(where + ": expected " + std::to_string(header.size()) + " columns (" + join(header, ",") +
                       "), got " + std::to_string(cells.size()));
    }
    auto number_cell = [&](std::size_t c, bool integer) {
      double value = kNaN;
      if (!scene::parse_number(cells[c], value) || !std::isfinite(value) || (integer && value != std::floor(value))) {
        throw InputError(where + ": column " + header[c] + ": expected " + (integer ? "an integer" : "a finite number") +
                         ", got '" + cells[c] + "'");
      }
      return value;
    };
    Measurement m;
    m.where = where;
    m.quantity = cells[0];
    if (!cells[1].empty()) m.mode = static_cast<int>(number_cell(1, true));
    m.probe = cells[2];
    if (!cells[3].empty()) m.drive_hz = number_cell(3, false);
    if (cells[4].empty()) throw InputError(where + ": column value: expected the measured value, got an empty cell");
    m.value = number_cell(4, false);
    if (cells[5].empty()) throw InputError(where + ": column sigma: expected a standard deviation > 0, got an empty cell");
    m.sigma = number_cell(5, false);
    check_measurement(m, path, number, "row");
    measured.push_back(m);
  }
  if (!have_header) throw InputError(path + ": expected the header " + join(header, ",") + ", got an empty file");
  if (measured.empty()) throw InputError(path + ": expected at least one measurement row, got none");
  return measured;
}

IdentifySpec parse_identify_section(const std::string& text, const std::string& file) {
  IdentifySpec spec;
  const YAML::Node document = scene::parse_yaml(text, file);
  if (!document.IsMap() || !document["identify"]) {
    fail(file, -1, "identify", "a section identify: {unknowns: {key.path: [low, high]}, measured: [...]}", "nothing");
  }
  YAML::Node section;
  for (const auto& entry : document)
    if (entry.first.Scalar() == "identify") {
      section = entry.second;
      spec.line = scene::mark_line(entry.first);
    }
  if (!section.IsMap()) fail(file, spec.line, "identify", "a map with keys unknowns, measured, map, sigma, truth", scene::describe_node(section));
  const std::vector<std::string> keys = {"unknowns", "measured", "map", "sigma", "truth"};
  only_keys(section, keys, file, "identify");
  spec.unknowns = parse_unknowns(section["unknowns"], file, "identify.unknowns", spec.line);
  // measured
  const YAML::Node measured = section["measured"];
  if (!measured) fail(file, spec.line, "identify.measured", "a list of measurements or the path of a CSV file", "nothing");
  if (measured.IsScalar()) {
    fs::path csv(measured.Scalar());
    if (csv.is_relative()) csv = fs::path(file).parent_path() / csv;
    spec.measured = read_measurements_csv(csv.string());
  } else if (measured.IsSequence() && measured.size() > 0) {
    for (std::size_t i = 0; i < measured.size(); ++i)
      spec.measured.push_back(measurement_from(measured[i], file, "identify.measured[" + std::to_string(i) + "]"));
  } else {
    fail(file, scene::mark_line(measured), "identify.measured", "a list of measurements or the path of a CSV file",
         scene::describe_node(measured));
  }
  // map, sigma
  if (const YAML::Node map = section["map"]) {
    if (!map.IsMap()) fail(file, scene::mark_line(map), "identify.map", "a map {points}", scene::describe_node(map));
    for (const auto& entry : map)
      if (entry.first.Scalar() != "points")
        fail(file, scene::mark_line(entry.first), "identify.map." + entry.first.Scalar(), "one of points",
             "unknown key '" + entry.first.Scalar() + "'");
    if (map["points"]) {
      const double points = number_of(map["points"], file, "identify.map.points", true);
      if (points < 3 || points > 41) fail(file, scene::mark_line(map["points"]), "identify.map.points", "an integer in 3..41", format_number(points));
      spec.map_points = static_cast<int>(points);
    }
  }
  if (const YAML::Node sigma = section["sigma"]) {
    const std::string word = sigma.Scalar();
    const std::optional<bool> scaled = value_of(scene::kScaledSigmaWords, word);
    if (!scaled)
      fail(file, scene::mark_line(sigma), "identify.sigma", "one of " + join(texts_of(scene::kScaledSigmaWords)), "'" + word + "'");
    spec.scale_by_fit = *scaled;
  }
  if (const YAML::Node truth = section["truth"]) {
    const int line = scene::mark_line(truth);
    if (!truth.IsMap()) fail(file, line, "identify.truth", "a map {unknown: value} over the unknowns", scene::describe_node(truth));
    std::vector<std::string> names;
    for (const Unknown& u : spec.unknowns) names.push_back(u.key);
    for (const auto& entry : truth) {
      const std::string key = entry.first.Scalar();
      if (std::find(names.begin(), names.end(), key) == names.end())
        fail(file, scene::mark_line(entry.first), "identify.truth." + key, "one of the unknowns " + join(names),
             "'" + key + "'" + scene::suggestion(key, names));
    }
    for (const Unknown& u : spec.unknowns) {
      if (!truth[u.key]) fail(file, line, "identify.truth." + u.key, "the true value of every unknown", "nothing");
      spec.truth.push_back(number_of(truth[u.key], file, "identify.truth." + u.key));
    }
  }
  return spec;
}

namespace {

/// Refuses measurements the scene cannot compute (a probe it lacks, a harmonic ratio without a
/// harmonic excitation, a mode it does not solve) and unknowns no measured quantity depends on.
void check_against_scene(const IdentifySpec& spec, const scene::Scene& scene, const std::string& file) {
  for (const Measurement& m : spec.measured) {
    if (!is_frequency(m.quantity)) {
      bool found = false;
      if (scene.transient)
        for (const auto& probe : scene.transient->probes) found = found || probe.name == m.probe;
      if (!found) throw InputError(m.where + ": probe: expected a probe of the scene's transient.probes, got '" + m.probe + "'");
      if (!scene.transient->excitation || scene.transient->excitation->kind != scene::ExcitationKind::harmonic)
        throw InputError(m.where + ": quantity " + m.quantity + ": expected a scene with a harmonic transient.excitation "
                         "(its load is driven at drive_hz), got " + (scene.transient->excitation ? "a pulse" : "none"));
    }
    if (m.quantity == "A1/2/A1" && scene.contact.friction > 0.0)
      throw InputError(m.where + ": quantity A1/2/A1: expected a scene without friction (the period-two branch is "
                       "found by the sweep's stability, which is frictionless), got crack.contact.friction = " +
                       format_number(scene.contact.friction));
    if (is_frequency(m.quantity) && m.mode > scene.modal.modes)
      throw InputError(m.where + ": mode: expected a mode the scene solves (modal.modes = " +
                       std::to_string(scene.modal.modes) + "), got " + std::to_string(m.mode));
  }
  // An unknown that no measured quantity depends on cannot be identified: refused, not fitted flat.
  bool harmonic = false, frequency = false, damping = false;
  for (const Measurement& m : spec.measured) {
    harmonic = harmonic || !is_frequency(m.quantity);
    frequency = frequency || is_frequency(m.quantity);
    damping = damping || m.quantity == "damping_ratio";
  }
  for (const Unknown& u : spec.unknowns) {
    if ((frequency && study::output_reads("modal", u.path)) || (harmonic && study::output_reads("sweep", u.path)) ||
        (damping && u.path.rfind("transient.damping.", 0) == 0))
      continue;
    fail(file, u.line, "identify.unknowns." + u.key, "an unknown that a measured quantity depends on",
         "'" + u.key + "', which " +
             (harmonic ? std::string("no measured quantity depends on")
                       : "the measured frequencies (crackle modal) do not depend on; measure a damping_ratio or a "
                         "harmonic ratio (A2/A1, A3/A1 at a drive_hz: crackle sweep) to identify it, or drop it"));
  }
}

/// The map's axes (map_points values per unknown, the bounds included) and its points, row-major.
void map_grid(const IdentifySpec& spec, std::vector<std::vector<double>>& axes, std::vector<VectorX>& grid) {
  const std::size_t k = spec.unknowns.size();
  axes.assign(k, {});
  std::size_t total = 1;
  for (std::size_t j = 0; j < k; ++j) {
    for (int i = 0; i < spec.map_points; ++i)
      axes[j].push_back(spec.unknowns[j].lower + (spec.unknowns[j].upper - spec.unknowns[j].lower) * i / (spec.map_points - 1));
    total *= axes[j].size();
  }
  for (std::size_t flat = 0; flat < total; ++flat) {
    VectorX theta(static_cast<Eigen::Index>(k));
    std::size_t rest = flat;
    for (std::size_t j = k; j-- > 0;) {
      theta[static_cast<Eigen::Index>(j)] = axes[j][rest % axes[j].size()];
      rest /= axes[j].size();
    }
    grid.push_back(theta);
  }
}

/// chi^2 of a model against the measured values with `weights`; infinite where a value is missing.
double chi2_of(const VectorX& model, const VectorX& values, const VectorX& weights) {
  const VectorX r = (model - values).cwiseQuotient(weights);
  return r.allFinite() ? r.squaredNorm() : std::numeric_limits<double>::infinity();
}

/// The weighted residuals of the forward model by parameter vector, each computed once (fit_bounded
/// asks for its start, its end and their Jacobians again, which an earlier batch already has); each
/// batch of new vectors runs in DIR/fit/NNNN.
class ForwardResiduals {
 public:
  ForwardResiduals(Forward& forward, const VectorX& values, const VectorX& weights, fs::path folder)
      : forward_(forward), values_(values), weights_(weights), folder_(std::move(folder)) {}

  std::vector<VectorX> operator()(const std::vector<VectorX>& thetas) {
    std::vector<VectorX> missing;
    for (const VectorX& theta : thetas)
      if (!computed_.count(key(theta))) missing.push_back(theta);
    if (!missing.empty()) {
      char name[16];
      std::snprintf(name, sizeof name, "%04d", batch_++);
      const std::vector<VectorX> models = forward_.models(missing, folder_ / name, false);
      for (std::size_t i = 0; i < missing.size(); ++i) computed_[key(missing[i])] = (models[i] - values_).cwiseQuotient(weights_);
    }
    std::vector<VectorX> out;
    for (const VectorX& theta : thetas) out.push_back(computed_.at(key(theta)));
    return out;
  }

 private:
  static std::vector<double> key(const VectorX& theta) { return std::vector<double>(theta.data(), theta.data() + theta.size()); }
  Forward& forward_;
  const VectorX& values_;
  const VectorX& weights_;
  fs::path folder_;
  std::map<std::vector<double>, VectorX> computed_;
  int batch_ = 0;
};

/// A local fit on the forward model from the interpolant's estimate `start`: bounded Gauss-Newton
/// (fit::bounded_linear_step) until its step is below kAccept of the estimate's standard deviation
/// (each iteration one batch: the point and its Jacobian), the step halved until it lowers chi^2;
/// Levenberg-Marquardt takes over from the lowest point when no halving does.
detail::Fitted fit_minimum(const fit::BatchResiduals& on_model, const VectorX& start, const fit::Bounds& bounds,
                           const VectorX& steps, bool scale_by_fit, const std::string& which, std::ostream& log,
                           int& gauss_newton, int& levenberg_marquardt) {
  VectorX theta = start;  // every move lowers chi^2: theta is the lowest point so far
  fit::FitResult result;
  bool accepted = false;
  for (int iteration = 0; iteration < kGaussNewtonIterations && !accepted; ++iteration) {
    std::vector<VectorX> points = {theta};
    for (const VectorX& point : fit::jacobian_points(theta, bounds, steps)) points.push_back(point);
    on_model(points);
    const VectorX r0 = on_model({theta}).front();
    if (!r0.allFinite()) break;
    ++gauss_newton;
    const MatrixX j0 = fit::jacobian(on_model, theta, r0, bounds, steps);
    const fit::Uncertainty u0 = fit::uncertainty(j0, theta, r0.squaredNorm(), scale_by_fit);
    if (!j0.allFinite() || u0.rank_deficient) break;
    // The Gauss-Newton step of the bounded fit (the linearised misfit's minimum over the bounds, not
    // the free step clipped to them, which can predict a rise where the misfit still falls along a
    // bound) and its predicted decrease in units of the covariance (Mahalanobis).
    const VectorX moved = fit::bounded_linear_step(j0, r0, bounds.lower - theta, bounds.upper - theta);
    const double change = (r0.squaredNorm() - (r0 + j0 * moved).squaredNorm()) / u0.s2;
    const double step_in_sd = std::sqrt(std::max(change, 0.0));
    log << "identify: minimum " << which << ", Gauss-Newton iteration " << iteration + 1 << ": chi2 "
        << format_number(r0.squaredNorm()) << ", step " << format_number(step_in_sd) << " sd\n";
    if (step_in_sd <= kAccept) {
      accepted = true;
      result.theta = theta;
      result.residuals = r0;
      result.jacobian = j0;
      result.chi2 = r0.squaredNorm();
      result.converged = true;
      result.at_bound = fit::at_bounds(theta, bounds);
      break;
    }
    // Backtracking along the step (each trial one forward run; the box is convex, so every trial is
    // inside it): the first that lowers chi^2 is taken, else Levenberg-Marquardt goes on from theta.
    bool lowered = false;
    for (int halving = 0; halving < kHalvings && !lowered; ++halving) {
      const VectorX trial = theta + std::ldexp(1.0, -halving) * moved;
      const VectorX r = on_model({trial}).front();
      lowered = r.allFinite() && r.squaredNorm() < r0.squaredNorm();
      if (lowered) theta = trial;
      if (lowered && halving > 0) log << "identify: minimum " << which << ": step halved " << halving << " time(s)\n";
    }
    if (!lowered) break;
  }
  if (!accepted) {
    fit::FitOptions exact;
    exact.steps = steps;
    exact.max_iterations = 8;
    exact.function_tolerance = 1e-8;
    exact.parameter_tolerance = 1e-7;
    log << "identify: minimum " << which << ": Levenberg-Marquardt on the forward model\n";
    result = fit::fit_bounded(on_model, theta, bounds, exact);
    ++levenberg_marquardt;
  }
  detail::Fitted f;
  f.theta = result.theta;
  f.chi2 = result.chi2;
  f.residuals = result.residuals;
  f.at_bound = result.at_bound;
  f.converged = result.converged;
  f.uncertainty = fit::uncertainty(result.jacobian, result.theta, result.chi2, scale_by_fit);
  return f;
}

/// Two parameter vectors within 1e-3 of the bounds' widths of each other in every unknown: one point.
bool same_point(const VectorX& a, const VectorX& b, const fit::Bounds& bounds) {
  return (a - b).cwiseQuotient(bounds.upper - bounds.lower).cwiseAbs().maxCoeff() < 1e-3;
}

/// The fitted minima, the best first; starts that converged to the same point are one minimum.
std::vector<detail::Fitted> distinct_minima(std::vector<detail::Fitted> fitted, const fit::Bounds& bounds) {
  std::sort(fitted.begin(), fitted.end(), [](const detail::Fitted& a, const detail::Fitted& b) { return a.chi2 < b.chi2; });
  std::vector<detail::Fitted> distinct;
  for (const detail::Fitted& f : fitted) {
    bool same = false;
    for (const detail::Fitted& d : distinct)
      same = same || same_point(f.theta, d.theta, bounds);
    if (!same) distinct.push_back(f);
  }
  return distinct;
}

/// Why the best minimum does not identify the unknowns (empty: it does).
std::vector<std::string> identifiability(const IdentifySpec& spec, const std::vector<detail::Fitted>& minima) {
  const std::size_t k = spec.unknowns.size(), n = spec.measured.size();
  const detail::Fitted& best = minima.front();
  std::vector<std::string> reasons;
  if (n < k) reasons.push_back(std::to_string(n) + " measurements for " + std::to_string(k) + " unknowns");
  if (best.uncertainty.rank_deficient)
    reasons.push_back("the Jacobian has rank " + std::to_string(best.uncertainty.rank) + " < " + std::to_string(k) +
                      ": some combination of the unknowns does not change the measured quantities");
  for (std::size_t j = 0; j < k; ++j)
    if (best.at_bound[j]) reasons.push_back(spec.unknowns[j].key + " is at a bound: its interval is not reliable");
  // A linearised interval wider than the bounds: the measurements do not narrow the unknown beyond
  // what was assumed before them (the profiles show the misfit inside the bounds).
  for (std::size_t j = 0; j < k && !best.uncertainty.rank_deficient; ++j) {
    const Unknown& unknown = spec.unknowns[j];
    const double width = best.uncertainty.interval_95[j][1] - best.uncertainty.interval_95[j][0];
    const double range = unknown.upper - unknown.lower;
    if (width > range)
      reasons.push_back(unknown.key + ": its 95 % interval (" + format_number(width) + ") is wider than its bounds (" +
                        format_number(range) + "): the measurements do not determine it within them (see profiles)");
  }
  for (std::size_t d = 1; d < minima.size(); ++d)
    if (minima[d].chi2 - best.chi2 < kEqualFit)
      reasons.push_back("several minima fit equally well (chi2 " + format_number(best.chi2) + " and " +
                        format_number(minima[d].chi2) + "): see minima");
  return reasons;
}

/// A synthetic test's `truth`: the error against the truth, and the Cramer-Rao bound there (the
/// Gauss-Newton covariance with the sigmas trusted, DETECTION.md sec. 2) from one batch of runs.
json truth_json(Forward& forward, const detail::IdentifyFigures& f, const fit::Bounds& bounds) {
  const IdentifySpec& spec = f.spec;
  const std::size_t k = spec.unknowns.size(), n = spec.measured.size();
  const detail::Fitted& best = f.best();
  const VectorX truth = Eigen::Map<const VectorX>(spec.truth.data(), static_cast<Eigen::Index>(k));
  const VectorX steps = VectorX::Constant(static_cast<Eigen::Index>(k), kForwardStep);
  std::vector<VectorX> points = {truth};
  for (const VectorX& point : fit::jacobian_points(truth, bounds, steps)) points.push_back(point);
  const std::vector<VectorX> models = forward.models(points, f.map_dir / "truth", false);
  MatrixX jacobian(static_cast<Eigen::Index>(n), static_cast<Eigen::Index>(k));
  for (Eigen::Index j = 0; j < static_cast<Eigen::Index>(k); ++j)
    jacobian.col(j) = (models[static_cast<std::size_t>(j) + 1] - models[0]).cwiseQuotient(f.weights) /
                      (points[static_cast<std::size_t>(j) + 1][j] - truth[j]);
  const fit::Uncertainty bound = fit::uncertainty(jacobian, truth, 0.0, false);
  // The same with the measurement noise alone (no model error in the weights): the scatter that
  // noise alone would give an unbiased estimator.
  const MatrixX noise_jacobian = f.weights.cwiseQuotient(f.sigma).asDiagonal() * jacobian;
  const fit::Uncertainty noise_bound = fit::uncertainty(noise_jacobian, truth, 0.0, false);
  json inside = json::object(), error = json::object(), in_bound = json::object();
  for (std::size_t j = 0; j < k; ++j) {
    const Eigen::Index jj = static_cast<Eigen::Index>(j);
    const auto& interval = best.uncertainty.interval_95[j];
    inside[spec.unknowns[j].key] = interval[0] <= truth[jj] && truth[jj] <= interval[1];
    error[spec.unknowns[j].key] = best.theta[jj] - truth[jj];
    in_bound[spec.unknowns[j].key] = (best.theta[jj] - truth[jj]) / bound.sd[jj];
  }
  return {{"value", detail::keyed(spec, truth)}, {"error", error}, {"inside_95", inside},
          {"cramer_rao_sd", detail::keyed(spec, bound.sd)}, {"error_in_cramer_rao_sd", in_bound},
          {"cramer_rao_noise_sd", detail::keyed(spec, noise_bound.sd)},
          {"chi2_at_truth", ((models[0] - f.values).cwiseQuotient(f.weights)).squaredNorm()}};
}

/// Stages 1 and 2: the map, and the model error in the middle of the bounds (the reference crack;
/// independent of the measurements, so a cached map keeps it too) from the orders p, p+1, p+2
/// (Richardson): one batch, the highest order first (the longest run starts while the map fills
/// the other cores). Sets the figures' map, measurements, model error and weights; returns the
/// map's models, and the map minima to start local fits from in `starts`.
std::vector<VectorX> map_and_model_error(Forward& forward, int p, const fit::Bounds& bounds, std::ostream& log,
                                         detail::IdentifyFigures& figures, std::vector<std::size_t>& starts) {
  const IdentifySpec& spec = figures.spec;
  const std::size_t n = spec.measured.size();
  const VectorX middle = 0.5 * (bounds.lower + bounds.upper);
  const std::vector<int> levels = refinement_orders(p);
  log << "identify: map of " << figures.grid.size() << " forward runs (" << spec.map_points << " per unknown) and the model error "
      << "from the orders " << levels[0] << ", " << levels[1] << ", " << levels[2] << " in the middle of the bounds\n";
  std::vector<VectorX> map_batch = {middle, middle, middle};
  std::vector<int> orders = {levels[2], levels[1], levels[0]};
  for (const VectorX& theta : figures.grid) {
    map_batch.push_back(theta);
    orders.push_back(p);
  }
  const std::vector<VectorX> batch_models = forward.models(map_batch, figures.map_dir, true, orders);
  const std::vector<VectorX> level_models = {batch_models[2], batch_models[1], batch_models[0]};
  std::vector<VectorX> map_models(batch_models.begin() + 3, batch_models.end());
  figures.values.resize(static_cast<Eigen::Index>(n));
  figures.sigma.resize(static_cast<Eigen::Index>(n));
  for (std::size_t i = 0; i < n; ++i) {
    figures.values[static_cast<Eigen::Index>(i)] = spec.measured[i].value;
    figures.sigma[static_cast<Eigen::Index>(i)] = spec.measured[i].sigma;
  }
  const VectorX& values = figures.values;
  for (const VectorX& m : map_models) figures.map_chi2.push_back(chi2_of(m, values, figures.sigma));
  if (fit::grid_minima(figures.axes, figures.map_chi2).empty())
    throw SolverError("identify: no finite misfit on the map (no mode paired anywhere)");

  figures.model_error.resize(static_cast<Eigen::Index>(n));
  figures.error_verified.assign(n, true);
  for (std::size_t i = 0; i < n; ++i) {
    const Eigen::Index ii = static_cast<Eigen::Index>(i);
    const RefinementError error =
        refinement_error(level_models[0][ii], level_models[1][ii], level_models[2][ii], p - levels.front());
    // Relative to the value, carried to every parameter vector.
    figures.model_error[ii] = error.relative;
    figures.error_verified[i] = error.verified;
  }
  // Weights from the measured values (fixed during the fit: the estimate's relative error times them).
  figures.weights.resize(static_cast<Eigen::Index>(n));
  for (Eigen::Index i = 0; i < static_cast<Eigen::Index>(n); ++i) {
    const double eps = figures.model_error[i] * std::abs(values[i]);
    figures.weights[i] = std::sqrt(figures.sigma[i] * figures.sigma[i] + eps * eps);
  }
  const VectorX& weights = figures.weights;
  figures.map_chi2.clear();
  for (const VectorX& m : map_models) figures.map_chi2.push_back(chi2_of(m, values, weights));
  const std::vector<std::size_t> minima = fit::grid_minima(figures.axes, figures.map_chi2);
  figures.best_map = figures.map_chi2[minima.front()];
  for (std::size_t index : minima)
    if (figures.map_chi2[index] <= figures.best_map + kMinimaSpread && starts.size() < kMaxStarts) starts.push_back(index);
  figures.starts = starts.size();
  return map_models;
}

/// Stage 3: a local fit from each start, on the map's interpolant (`on_spline`) and then on the
/// forward model (one batch checks every interpolant estimate and its Jacobian first); sets the
/// figures' distinct minima and the fits' counts.
void local_fits(Forward& forward, const fit::BatchResiduals& on_spline, const std::vector<std::size_t>& starts,
                const fit::Bounds& bounds, const fs::path& dir, std::ostream& log, detail::IdentifyFigures& figures) {
  const std::size_t k = figures.spec.unknowns.size();
  const VectorX& values = figures.values;
  const VectorX& weights = figures.weights;
  ForwardResiduals residuals(forward, values, weights, dir / "fit");
  const fit::BatchResiduals on_model = [&](const std::vector<VectorX>& thetas) { return residuals(thetas); };
  const VectorX steps = VectorX::Constant(static_cast<Eigen::Index>(k), kForwardStep);
  fit::FitOptions smooth;
  smooth.steps = VectorX::Constant(static_cast<Eigen::Index>(k), 1e-6);
  std::vector<VectorX> smooth_estimates, check_points;
  // Map minima whose interpolant estimates coincide (same_point, distinct_minima's rule) start one
  // fit: the second would run the same forward cases a few 1e-7 apart.
  std::vector<std::size_t> first_with(starts.size());
  for (std::size_t s = 0; s < starts.size(); ++s) {
    smooth_estimates.push_back(fit::fit_bounded(on_spline, figures.grid[starts[s]], bounds, smooth).theta);
    first_with[s] = s;
    for (std::size_t t = 0; t < s && first_with[s] == s; ++t)
      if (same_point(smooth_estimates[s], smooth_estimates[t], bounds)) first_with[s] = t;
    if (first_with[s] != s) continue;
    check_points.push_back(smooth_estimates.back());
    for (const VectorX& point : fit::jacobian_points(smooth_estimates.back(), bounds, steps)) check_points.push_back(point);
  }
  log << "identify: the forward model at the interpolant's " << starts.size() << " estimate(s) and their Jacobians ("
      << check_points.size() << " runs)\n";
  on_model(check_points);
  std::vector<detail::Fitted> fitted;
  for (std::size_t s = 0; s < starts.size(); ++s) {
    const std::string which = std::to_string(s + 1) + "/" + std::to_string(starts.size());
    if (first_with[s] != s) {
      log << "identify: minimum " << which << ": the interpolant's estimate is minimum " << first_with[s] + 1
          << "'s: fitted once\n";
      continue;
    }
    detail::Fitted f = fit_minimum(on_model, smooth_estimates[s], bounds, steps, figures.spec.scale_by_fit, which, log,
                                   figures.gauss_newton, figures.levenberg_marquardt);
    // A coarse map's interpolant can start the fit in another valley, where Gauss-Newton stops at a
    // stationary point of its linearisation: a fit that ends above its own map point (the same
    // forward model and weights) is redone from that point, so that no estimate is worse than a map
    // point (a 3-point map once ended at chi2 138 beside a map point's 1.41).
    const double at_map_point = figures.map_chi2[starts[s]];
    if (!(f.chi2 <= at_map_point + kAccept * kAccept)) {  // more than (0.1 sd)^2 above it
      log << "identify: minimum " << which << " ended at chi2 " << format_number(f.chi2) << ", above its map point's "
          << format_number(at_map_point) << ": fitted again from the map point\n";
      ++figures.from_map_point;
      detail::Fitted again = fit_minimum(on_model, figures.grid[starts[s]], bounds, steps, figures.spec.scale_by_fit,
                                         which, log, figures.gauss_newton, figures.levenberg_marquardt);
      if (again.chi2 < f.chi2) f = std::move(again);
    }
    fitted.push_back(std::move(f));
    fitted.back().model = fitted.back().residuals.cwiseProduct(weights) + values;
  }
  figures.minima = distinct_minima(std::move(fitted), bounds);
}

}  // namespace

json run_identify(const IdentifyOptions& options, std::ostream& log) {
  const auto start = std::chrono::steady_clock::now();
  const std::string& file = options.scene_path;
  const std::string text = scene::read_scene_file(file);
  IdentifySpec spec = parse_identify_section(text, file);
  const scene::Scene scene = scene::parse_scene(text, file);
  const std::size_t k = spec.unknowns.size(), n = spec.measured.size();
  check_against_scene(spec, scene, file);
  YAML::Node base = scene::parse_yaml(text, file);
  base.remove("identify");
  base.remove("study");
  // the reference crack: the middle of the bounds (its plane on the nearest uniform grid plane)
  prepare_base(base, scene, spec.unknowns, file, "identify.unknowns");

  // A rerun into the same folder resumes: the forward runs are study cases, cached by their scenes.
  const fs::path dir(options.output_dir);
  fs::create_directories(dir);
  Forward forward(spec, base, scene.transient ? scene.transient->damping : scene::DampingSection{}, options, log);
  fit::Bounds bounds{VectorX(k), VectorX(k)};
  for (std::size_t j = 0; j < k; ++j) {
    bounds.lower[static_cast<Eigen::Index>(j)] = spec.unknowns[j].lower;
    bounds.upper[static_cast<Eigen::Index>(j)] = spec.unknowns[j].upper;
  }
  detail::IdentifyFigures figures(spec);
  figures.reference_at = std::stod(base["crack"]["reference"]["at"].Scalar());
  map_grid(spec, figures.axes, figures.grid);
  // ---- 1 and 2: the map and the model error
  figures.map_dir = options.map_cache.empty() ? dir / "map" : fs::path(options.map_cache);
  std::vector<std::size_t> starts;
  const std::vector<VectorX> map_models = map_and_model_error(forward, scene.box.order, bounds, log, figures, starts);

  // ---- 3. local fits: on the map's interpolant; the forward model checks each (one batch for all)
  const fit::TensorSpline spline(figures.axes, map_models);
  const fit::BatchResiduals on_spline = [&](const std::vector<VectorX>& thetas) {
    std::vector<VectorX> out;
    for (const VectorX& theta : thetas) out.push_back((spline(theta) - figures.values).cwiseQuotient(figures.weights));
    return out;
  };
  local_fits(forward, on_spline, starts, bounds, dir, log, figures);

  // ---- 4. the 2D profile of the misfit for each pair of unknowns: the least over the others on the
  // map's interpolant, from each slice's least map point (with two unknowns, the map itself)
  if (k >= 2) {
    fit::FitOptions smooth;
    smooth.steps = VectorX::Constant(static_cast<Eigen::Index>(k), 1e-6);
    const auto profiles_start = std::chrono::steady_clock::now();
    for (std::size_t i = 0; i < k; ++i)
      for (std::size_t j = i + 1; j < k; ++j)
        figures.profiles.push_back(fit::profile(on_spline, figures.axes, figures.map_chi2, bounds, i, j, smooth));
    if (k > 2)
      log << "identify: the misfit's profiles over " << figures.profiles.size() << " pairs of unknowns on the interpolant in "
          << format_number(std::chrono::duration<double>(std::chrono::steady_clock::now() - profiles_start).count())
          << " s\n";
  }

  // ---- flags and outputs
  figures.reasons = identifiability(spec, figures.minima);
  std::vector<std::string> notes;
  for (std::size_t i = 0; i < n; ++i)
    if (!figures.error_verified[i])
      notes.push_back("the model error of " + detail::measurement_label(spec.measured[i]) +
                      " is not verified (the orders do not converge monotonically, or a level has no value): 3x a change of two levels is used (0 if only the run's level has a value)");
  json document = detail::identify_json(figures);
  if (!spec.truth.empty()) document["truth"] = truth_json(forward, figures, bounds);
  document["forward_runs"] = forward.runs();
  document["wall_s"] = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  detail::write_identify_tables(dir, figures);
  detail::draw_identify_plots(dir, figures, notes);
  document["notes"] = notes;
  io::write_json(dir / "identify.json", document);
  detail::print_identify_summary(log, figures, forward.runs(), notes);
  return document;
}

}  // namespace crackle::identify
