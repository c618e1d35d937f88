#include "planning/planning.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <limits>
#include <map>
#include <ostream>
#include <sstream>

#include <Eigen/Eigenvalues>
#include <nlohmann/json.hpp>
#include <yaml-cpp/yaml.h>

#include "core/errors.hpp"
#include "fit/fit.hpp"
#include "io/files.hpp"
#include "planning/plan_stages.hpp"
#include "scene/scene.hpp"
#include "scene/schema.hpp"
#include "scene/yaml_text.hpp"
#include "plot/gnuplot.hpp"
#include "study/plot.hpp"

namespace crackle::planning {
namespace fs = std::filesystem;
using nlohmann::json;
using identify::ForwardCase;
using identify::SweepTable;

using detail::kInf;

namespace {

const std::vector<std::string> kFaces = {"x-", "x+", "y-", "y+", "z-", "z+"};

using identify::number_of;
using identify::only_keys;

/// The keys of a section of the parameter table (scene::plan_parameters(), which documents them).
std::vector<std::string> keys_of(const scene::Param& table) {
  std::vector<std::string> keys;
  for (const scene::Param& child : table.children) keys.push_back(child.name);
  return keys;
}

[[noreturn]] void fail(const std::string& file, int line, const std::string& path, const std::string& expected,
                       const std::string& got) {
  scene::fail(file, line, path, expected, got);
}

std::vector<Vec3> points_of(const YAML::Node& node, const std::string& file, const std::string& path) {
  if (!node.IsSequence() || node.size() == 0)
    fail(file, scene::mark_line(node), path, "a list of points [[x, y, z], ...]", scene::describe_node(node));
  std::vector<Vec3> points;
  for (std::size_t i = 0; i < node.size(); ++i) {
    const std::string where = path + "[" + std::to_string(i) + "]";
    if (!node[i].IsSequence() || node[i].size() != 3)
      fail(file, scene::mark_line(node[i]), where, "a point [x, y, z] in m", scene::describe_node(node[i]));
    points.emplace_back(number_of(node[i][0], file, where + "[0]"), number_of(node[i][1], file, where + "[1]"),
                        number_of(node[i][2], file, where + "[2]"));
  }
  return points;
}

/// The sensor points on the face `spec.face` every `spacing` (both ends included, at least 2 per axis).
void face_grid(PlanSpec& spec, const YAML::Node& spacing_node, double spacing, const std::string& file, const Vec3& origin,
               const Vec3& size) {
  const int normal = spec.face[0] - 'x';
  const int a = (normal + 1) % 3, b = (normal + 2) % 3;
  const int first = std::min(a, b), second = std::max(a, b);
  const double at = origin[normal] + (spec.face[1] == '+' ? size[normal] : 0.0);
  spec.grid[0] = std::max(2, static_cast<int>(std::lround(size[first] / spacing)) + 1);
  spec.grid[1] = std::max(2, static_cast<int>(std::lround(size[second] / spacing)) + 1);
  if (spec.grid[0] * spec.grid[1] > 2000)
    fail(file, scene::mark_line(spacing_node), "plan.sensors.spacing", "at most 2000 sensor points on the face",
         std::to_string(spec.grid[0] * spec.grid[1]));
  for (int i = 0; i < spec.grid[0]; ++i)
    for (int j = 0; j < spec.grid[1]; ++j) {
      Vec3 x;
      x[normal] = at;
      x[first] = origin[first] + size[first] * i / (spec.grid[0] - 1);
      x[second] = origin[second] + size[second] * j / (spec.grid[1] - 1);
      spec.sensors.push_back(x);
    }
}

/// plan.sensors: a face sampled on a grid, or a list of points; the analysed component.
void parse_sensors(const YAML::Node& section, const scene::Param& table, const std::string& file, const Vec3& origin,
                   const Vec3& size, PlanSpec& spec) {
  const YAML::Node sensors = section["sensors"];
  if (!sensors || !sensors.IsMap())
    fail(file, sensors ? scene::mark_line(sensors) : spec.line, "plan.sensors",
         "a map {face: z+, spacing: 0.01} or {points: [[x, y, z], ...]}", sensors ? scene::describe_node(sensors) : "nothing");
  only_keys(sensors, keys_of(*table.child("sensors")), file, "plan.sensors");
  if (const YAML::Node component = sensors["component"]) {
    const std::string axis = component.Scalar();
    if (axis != "x" && axis != "y" && axis != "z")
      fail(file, scene::mark_line(component), "plan.sensors.component", "one of x, y, z", "'" + axis + "'");
    spec.component = axis[0] - 'x';
  }
  if (sensors["face"] && sensors["points"])
    fail(file, scene::mark_line(sensors), "plan.sensors", "either face (with spacing) or points", "both");
  if (sensors["points"]) {
    spec.sensors = points_of(sensors["points"], file, "plan.sensors.points");
    if (sensors["spacing"]) fail(file, scene::mark_line(sensors["spacing"]), "plan.sensors.spacing", "spacing with face only", "points");
  } else if (sensors["face"]) {
    spec.face = sensors["face"].Scalar();
    if (std::find(kFaces.begin(), kFaces.end(), spec.face) == kFaces.end())
      fail(file, scene::mark_line(sensors["face"]), "plan.sensors.face", "one of " + join(kFaces),
           "'" + spec.face + "'" + scene::suggestion(spec.face, kFaces));
    if (!sensors["spacing"]) fail(file, scene::mark_line(sensors), "plan.sensors.spacing", "the spacing of the sensor grid [m]", "nothing");
    const double spacing = number_of(sensors["spacing"], file, "plan.sensors.spacing");
    if (!(spacing > 0.0)) fail(file, scene::mark_line(sensors["spacing"]), "plan.sensors.spacing", "a spacing > 0 [m]", format_number(spacing));
    face_grid(spec, sensors["spacing"], spacing, file, origin, size);
  } else {
    fail(file, scene::mark_line(sensors), "plan.sensors", "face (with spacing) or points", "neither");
  }
}

/// plan.drives: the drive points and frequencies (multiples of a mode's bilinear frequency).
void parse_drives(const YAML::Node& section, const scene::Param& table, const std::string& file, PlanSpec& spec) {
  const YAML::Node drives = section["drives"];
  if (!drives || !drives.IsMap())
    fail(file, drives ? scene::mark_line(drives) : spec.line, "plan.drives", "a map {points: [[x, y, z], ...], frequencies: [{mode, ratio}, ...]}",
         drives ? scene::describe_node(drives) : "nothing");
  only_keys(drives, keys_of(*table.child("drives")), file, "plan.drives");
  if (!drives["points"]) fail(file, scene::mark_line(drives), "plan.drives.points", "a list of drive points [[x, y, z], ...]", "nothing");
  spec.drive_points = points_of(drives["points"], file, "plan.drives.points");
  const YAML::Node frequencies = drives["frequencies"];
  if (!frequencies || !frequencies.IsSequence() || frequencies.size() == 0)
    fail(file, frequencies ? scene::mark_line(frequencies) : scene::mark_line(drives), "plan.drives.frequencies",
         "a list [{mode: 1, ratio: 0.5}, ...]", frequencies ? scene::describe_node(frequencies) : "nothing");
  for (std::size_t i = 0; i < frequencies.size(); ++i) {
    const std::string where = "plan.drives.frequencies[" + std::to_string(i) + "]";
    const YAML::Node f = frequencies[i];
    if (!f.IsMap()) fail(file, scene::mark_line(f), where, "a map {mode, ratio}", scene::describe_node(f));
    only_keys(f, keys_of(*table.child("drives")->child("frequencies")), file, where);
    DriveFrequency drive;
    if (!f["mode"]) fail(file, scene::mark_line(f), where + ".mode", "an uncracked mode number >= 1", "nothing");
    drive.mode = static_cast<int>(number_of(f["mode"], file, where + ".mode", true));
    if (drive.mode < 1) fail(file, scene::mark_line(f["mode"]), where + ".mode", "an uncracked mode number >= 1", std::to_string(drive.mode));
    if (!f["ratio"]) fail(file, scene::mark_line(f), where + ".ratio", "a multiple of the mode's bilinear frequency", "nothing");
    drive.ratio = number_of(f["ratio"], file, where + ".ratio");
    if (!(drive.ratio > 0.0) || drive.ratio > 10.0)
      fail(file, scene::mark_line(f["ratio"]), where + ".ratio", "a ratio in (0, 10]", format_number(drive.ratio));
    spec.frequencies.push_back(drive);
  }
}

/// plan.noise: relative sigmas of a measured frequency and ratio, and the noise floor.
void parse_noise(const YAML::Node& section, const scene::Param& table, const std::string& file, PlanSpec& spec) {
  if (const YAML::Node noise = section["noise"]) {
    if (!noise.IsMap()) fail(file, scene::mark_line(noise), "plan.noise", "a map {frequency, ratio, floor}", scene::describe_node(noise));
    only_keys(noise, keys_of(*table.child("noise")), file, "plan.noise");
    const auto positive = [&](const char* key, double& target) {
      if (!noise[key]) return;
      target = number_of(noise[key], file, std::string("plan.noise.") + key);
      if (!(target > 0.0)) fail(file, scene::mark_line(noise[key]), std::string("plan.noise.") + key, "a relative sigma > 0", format_number(target));
    };
    positive("frequency", spec.noise_frequency);
    positive("ratio", spec.noise_ratio);
    positive("floor", spec.noise_floor);
  }
}

}  // namespace

double log_det(const MatrixX& fisher) {
  if (fisher.size() == 0) return -kInf;
  const Eigen::SelfAdjointEigenSolver<MatrixX> eigen(fisher, Eigen::EigenvaluesOnly);
  const VectorX& lambda = eigen.eigenvalues();
  if (!(lambda.maxCoeff() > 0.0) || lambda.minCoeff() <= 1e-12 * lambda.maxCoeff()) return -kInf;
  return lambda.array().log().sum();
}

std::vector<GreedyStep> greedy_sensors(const std::vector<MatrixX>& base, const std::vector<std::vector<MatrixX>>& per_sensor,
                                       int count) {
  std::vector<GreedyStep> chosen;
  std::vector<MatrixX> sum = base;
  std::vector<bool> used(per_sensor.size(), false);
  for (int step = 0; step < count && step < static_cast<int>(per_sensor.size()); ++step) {
    int best = -1;
    double best_value = -kInf, best_trace = -kInf;
    for (std::size_t c = 0; c < per_sensor.size(); ++c) {
      if (used[c]) continue;
      double total = 0.0, trace = 0.0;
      for (std::size_t s = 0; s < sum.size(); ++s) {
        const MatrixX f = sum[s] + per_sensor[c][s];
        total += log_det(f);
        trace += f.trace();
      }
      const double value = total / static_cast<double>(std::max<std::size_t>(1, sum.size()));
      // Ties (every sum still singular) fall to the trace: the most information in any direction.
      if (best < 0 || value > best_value || (value == best_value && trace > best_trace)) {
        best = static_cast<int>(c);
        best_value = value;
        best_trace = trace;
      }
    }
    used[static_cast<std::size_t>(best)] = true;
    for (std::size_t s = 0; s < sum.size(); ++s) sum[s] += per_sensor[static_cast<std::size_t>(best)][s];
    chosen.push_back({best, best_value, sum});
  }
  return chosen;
}

PlanSpec parse_plan_section(const std::string& text, const std::string& file, const Vec3& origin, const Vec3& size) {
  PlanSpec spec;
  const YAML::Node document = scene::parse_yaml(text, file);
  if (!document.IsMap() || !document["plan"])
    fail(file, -1, "plan", "a section plan: {prior, sensors, drives, noise}", "nothing");
  YAML::Node section;
  for (const auto& entry : document)
    if (entry.first.Scalar() == "plan") {
      section = entry.second;
      spec.line = scene::mark_line(entry.first);
    }
  const scene::Param& table = *scene::plan_parameters().child("plan");
  const std::vector<std::string> keys = keys_of(table);
  if (!section.IsMap()) fail(file, spec.line, "plan", "a map with keys " + join(keys), scene::describe_node(section));
  only_keys(section, keys, file, "plan");
  spec.prior = identify::parse_unknowns(section["prior"], file, "plan.prior", spec.line);
  spec.size_key = static_cast<int>(spec.prior.size()) - 1;
  if (const YAML::Node size_key = section["size"]) {
    std::vector<std::string> names;
    for (const auto& u : spec.prior) names.push_back(u.key);
    const auto it = std::find(names.begin(), names.end(), size_key.Scalar());
    if (it == names.end())
      fail(file, scene::mark_line(size_key), "plan.size", "one of the prior keys " + join(names),
           "'" + size_key.Scalar() + "'" + scene::suggestion(size_key.Scalar(), names));
    spec.size_key = static_cast<int>(it - names.begin());
  }
  if (const YAML::Node samples = section["samples"]) {
    const double value = number_of(samples, file, "plan.samples", true);
    if (value < 2 || value > 9) fail(file, scene::mark_line(samples), "plan.samples", "an integer in 2..9", format_number(value));
    spec.samples = static_cast<int>(value);
  }
  if (const YAML::Node combine = section["combine"]) {
    const double value = number_of(combine, file, "plan.combine", true);
    if (value < 1 || value > 5) fail(file, scene::mark_line(combine), "plan.combine", "an integer in 1..5", format_number(value));
    spec.combine = static_cast<int>(value);
  }
  parse_sensors(section, table, file, origin, size, spec);
  parse_drives(section, table, file, spec);
  parse_noise(section, table, file, spec);
  return spec;
}

json run_plan(const PlanOptions& options, std::ostream& log) {
  const auto start = std::chrono::steady_clock::now();
  const std::string& file = options.scene_path;
  const std::string text = scene::read_scene_file(file);
  const scene::Scene scene = scene::parse_scene(text, file);
  const PlanSpec spec = parse_plan_section(text, file, scene.box.origin, scene.box.size);
  detail::PlanRun run{spec, scene, file, detail::forward_base(text, spec, scene, file), fs::path(options.output_dir),
                      identify::ForwardRunner{options.executable, options.jobs, (fs::path(options.output_dir) / "modal-cache").string()},
                      log, options.progress, 0};
  fs::create_directories(run.dir);

  // the forward runs: 1. modal frequencies, 2. sweeps at the samples, 3. at their Jacobian points
  const detail::PriorGrid grid = detail::prior_grid(spec);
  const detail::ModalFigures modal = detail::modal_figures(run, grid);
  const detail::SampleSweeps sweeps = detail::sample_sweeps(run, grid, modal);
  const detail::JacobianSweeps jacobian = detail::jacobian_sweeps(run, grid, sweeps);
  // 4. the figures of every candidate at every sample, detectability and ranking
  std::vector<detail::Candidate> candidates = detail::candidate_figures(spec, grid, modal, sweeps, jacobian);
  const detail::Detectability detect = detail::detectability(spec, grid, modal, candidates);
  const std::vector<std::size_t> order = detail::ranking(candidates, grid.n_samples);

  const detail::PlanFigures figures{grid, modal, sweeps, candidates, detect, order};
  json document = detail::plan_document(run, figures);
  json files, plot_notes;
  detail::write_sensor_figures(run, figures, files, plot_notes);
  document["files"] = files;
  if (!plot_notes.empty()) document["plot_notes"] = plot_notes;
  document["forward_runs"] = run.forward_runs;
  document["elapsed_s"] = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  io::write_file_atomic(run.dir / "plan.json", document.dump(2) + "\n");
  const json& top = document["candidates"].front();
  const json& sets = document["best_sensors"]["sets"];
  const std::vector<std::string> chosen =
      sets.empty() ? std::vector<std::string>() : sets.back()["sensors"].get<std::vector<std::string>>();
  // The mean 95 % widths against the prior's ranges: a width over its range is not determined.
  const auto widths_text = [&](const json& widths) {
    const auto three_digits = [](double value) {  // what a width is good to
      std::ostringstream out;
      out << std::setprecision(3) << value;
      return out.str();
    };
    std::string text;
    for (const identify::Unknown& key : spec.prior) {
      const json& width = widths["mean"][key.key];
      const double range = key.upper - key.lower;
      text += (text.empty() ? "" : ", ") + key.key + " " + (width.is_number() ? three_digits(width.get<double>()) : "inf") +
              " of " + three_digits(range) + (width.is_number() && width.get<double>() <= range ? "" : " (not determined)");
    }
    return text;
  };
  log << "plan: best " << top["sensor"]["name"].get<std::string>() << " at (" << top["sensor"]["point"][0] << ", "
      << top["sensor"]["point"][1] << ", " << top["sensor"]["point"][2] << ") driven at "
      << top["drive"]["ratio"].get<double>() << " f_b" << top["drive"]["mode"].get<int>() << " from ("
      << top["drive"]["point"][0] << ", " << top["drive"]["point"][1] << ", " << top["drive"]["point"][2]
      << "): mean log det " << top["log_det"] << "; best " << chosen.size() << " sensors: " << join(chosen) << "\n";
  for (const json& set : sets)
    log << "plan: mean 95 % widths against the prior's ranges with " << join(set["sensors"].get<std::vector<std::string>>())
        << ": " << widths_text(set["widths_95"]) << "\n";
  log << "plan: " << run.forward_runs << " forward runs in "
      << format_number(std::round(document["elapsed_s"].get<double>() * 10) / 10) << " s; " << run.dir.string()
      << "/plan.json\n";
  return document;
}

}  // namespace crackle::planning
