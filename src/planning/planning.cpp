#include "planning/planning.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <fstream>
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

namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
constexpr double kInf = std::numeric_limits<double>::infinity();
/// Finite-difference step of the Jacobian, as a fraction of each prior width (identify's, chosen
/// against the forward model's noise: docs/benchmarks.md 13.4).
constexpr double kStep = 1e-4;
/// Half-width of the narrow sweep about a period-one drive, relative (identify's).
constexpr double kNarrowHalfWidth = 1e-4;
/// Half-width of the sweep with stability about a sub-harmonic drive, relative: the period-two
/// branch is born at a period doubling somewhere around 2 f_b; the sweep must find it and follow it.
constexpr double kSubharmonicHalfWidth = 0.15;
constexpr int kSubharmonicPoints = 40;
/// Detection threshold (DETECTION.md sec. 3) and the 95 % normal quantile of the widths.
constexpr double kDetect = 3.0;
constexpr double kZ95 = 1.959963984540054;
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

/// The sweep.csv rows around the drive on the period-two branch, both stable.
bool period_two_exists(const SweepTable& table, double drive_hz) {
  const int period = table.column("branch period [excitation periods]");
  const int stable = table.column("stable [1 yes, 0 no, -1 not computed]");
  if (period < 0 || stable < 0) return false;
  for (std::size_t r = 0; r + 1 < table.rows.size(); ++r) {
    const std::vector<double>&a = table.rows[r], &b = table.rows[r + 1];
    if (std::lround(a[static_cast<std::size_t>(period)]) != 2 || std::lround(b[static_cast<std::size_t>(period)]) != 2)
      continue;
    if ((a[0] - drive_hz) * (b[0] - drive_hz) > 0.0 || a[0] == b[0]) continue;
    if (a[static_cast<std::size_t>(stable)] == 1.0 && b[static_cast<std::size_t>(stable)] == 1.0) return true;
  }
  return false;
}

/// The quantities a candidate measures at its sensor.
std::vector<std::string> ratio_quantities(const DriveFrequency& f) {
  return f.subharmonic() ? std::vector<std::string>{"A1/2/A1"} : std::vector<std::string>{"A2/A1", "A3/A1"};
}

std::string drive_label(const PlanSpec& spec, std::size_t p, std::size_t f) {
  std::ostringstream label;
  label << "drive " << p + 1 << " (" << format_number(spec.drive_points[p][0]) << ", " << format_number(spec.drive_points[p][1])
        << ", " << format_number(spec.drive_points[p][2]) << ") at " << format_number(spec.frequencies[f].ratio) << " f_b"
        << spec.frequencies[f].mode;
  return label.str();
}

/// plan_map.png: a figure of each drive point and frequency over the sensor face (a face grid
/// only), one panel each, drawn by gnuplot; plan_map.dat/.gp beside it. "" when drawn, else why not.
std::string plot_face_maps(const fs::path& dir, const PlanSpec& spec, const std::string& figure,
                           const std::vector<std::pair<std::string, std::vector<double>>>& panels) {
  if (spec.face.empty() || spec.grid[0] < 2 || spec.grid[1] < 2) return "";  // a list of points: the VTU only
  const int normal = spec.face[0] - 'x';
  const int u = std::min((normal + 1) % 3, (normal + 2) % 3), v = std::max((normal + 1) % 3, (normal + 2) % 3);
  std::ostringstream data, plots;
  int shown = 0;
  for (const auto& [title, values] : panels) {
    if (std::none_of(values.begin(), values.end(), [](double x) { return std::isfinite(x); })) continue;
    data << "# " << title << "\n# " << static_cast<char>('x' + u) << " [m]  " << static_cast<char>('x' + v) << " [m]  "
         << figure << "\n";
    for (int a = 0; a < spec.grid[0]; ++a) {
      for (int b = 0; b < spec.grid[1]; ++b) {
        const std::size_t i = static_cast<std::size_t>(a * spec.grid[1] + b);
        data << format_number(spec.sensors[i][u]) << " " << format_number(spec.sensors[i][v]) << " "
             << (std::isfinite(values[i]) ? format_number(values[i]) : std::string("NaN")) << "\n";
      }
      data << "\n";
    }
    data << "\n";
    plots << "set title " << plot::gnuplot_quote(title) << "\nsplot 'plan_map.dat' index " << shown
          << " using 1:2:3 with pm3d notitle\n";
    ++shown;
  }
  if (shown == 0) return "plan_map.png: no candidate responds: nothing to map";
  // a long face (a beam's) as one column of wide panels, else up to three square-scaled columns
  double extent[2] = {0.0, 0.0};
  for (const Vec3& x : spec.sensors)
    for (int c = 0; c < 2; ++c) extent[c] = std::max(extent[c], std::abs(x[c == 0 ? u : v] - spec.sensors[0][c == 0 ? u : v]));
  const bool long_face = extent[0] > 3.0 * extent[1] || extent[1] > 3.0 * extent[0];
  const int columns = long_face ? 1 : std::min(shown, 3), rows = (shown + columns - 1) / columns;
  plot::PlotOptions options;
  options.width = long_face ? 1000 : 440 * columns;
  options.height = (long_face ? 230 : 400) * rows + 40;
  std::ostringstream body;  // the panels carry their own titles; the figure's is the multiplot's
  body << "unset grid\nset view map\nset pm3d map\nset palette rgb 33,13,10\n"
       << "set xlabel '" << static_cast<char>('x' + u) << " [m]'\nset ylabel '" << static_cast<char>('x' + v)
       << " [m]'\n" << (long_face ? "" : "set size ratio -1\n") << "set multiplot layout " << rows << "," << columns
       << " title " << plot::gnuplot_quote(figure + " over the sensor face " + spec.face +
                                               " (colour), per drive point and frequency")
       << "\n" << plots.str() << "unset multiplot\n";
  const plot::PlotResult drawn = plot::plot_script(dir / "plan_map.png", data.str(), body.str(), options);
  return drawn.written ? "" : drawn.note;
}

json finite_or_null(double value) { return std::isfinite(value) ? json(value) : json(nullptr); }

/// One sample's figures for a candidate.
struct SampleFigures {
  bool responds = true;
  /// A forward value the figures need is not finite although the drive responds (a period-one drive, or
  /// a sub-harmonic one whose branch exists): its sweep did not reach the drive frequency. Counted as
  /// not responding, and reported (plan.json `notes`, `per_sample[].missing`), never silently.
  bool missing = false;
  MatrixX frequency_fisher;  ///< of the driven mode's bilinear frequency
  MatrixX sensor_fisher;     ///< of the sensor's ratios
  double z = 0.0;            ///< the largest detection statistic
  std::vector<double> values;  ///< the sensor's ratios at the sample
  std::vector<double> sigmas;  ///< their standard deviations: noise and model error
  std::vector<double> noise_sigmas;  ///< the noise's part (a synthetic measurement's sigma)
  double frequency_hz = kNaN, frequency_sigma = kNaN;  ///< the driven mode's bilinear frequency
};

struct Candidate {
  std::size_t sensor = 0, drive = 0, frequency = 0;
  std::vector<SampleFigures> samples;
  int responding = 0;
  double mean_log_det = -kInf;
  std::vector<double> worst_width, mean_width;
  std::vector<double> smallest_crack;  ///< per position
  std::vector<identify::RefinementError> model_error;  ///< of each ratio quantity, then of f_bilinear
};

std::string vtu_text(const PlanSpec& spec, const std::vector<std::pair<std::string, std::vector<double>>>& arrays) {
  const std::size_t n = spec.sensors.size();
  std::vector<std::array<std::size_t, 4>> quads;
  if (!spec.face.empty() && spec.grid[0] > 1 && spec.grid[1] > 1) {
    const auto at = [&](int a, int b) { return static_cast<std::size_t>(a * spec.grid[1] + b); };
    for (int a = 0; a + 1 < spec.grid[0]; ++a)
      for (int b = 0; b + 1 < spec.grid[1]; ++b) quads.push_back({at(a, b), at(a + 1, b), at(a + 1, b + 1), at(a, b + 1)});
  }
  std::ostringstream out;
  out.precision(12);
  const std::size_t cells = quads.empty() ? n : quads.size();
  out << "<?xml version=\"1.0\"?>\n<VTKFile type=\"UnstructuredGrid\" version=\"0.1\" byte_order=\"LittleEndian\">\n"
      << "<UnstructuredGrid>\n<Piece NumberOfPoints=\"" << n << "\" NumberOfCells=\"" << cells << "\">\n<PointData>\n";
  for (const auto& [name, values] : arrays) {
    out << "<DataArray type=\"Float64\" Name=\"" << name << "\" format=\"ascii\">\n";
    for (double v : values) out << (std::isfinite(v) ? v : std::nan("")) << " ";
    out << "\n</DataArray>\n";
  }
  out << "</PointData>\n<Points>\n<DataArray type=\"Float64\" NumberOfComponents=\"3\" format=\"ascii\">\n";
  for (const Vec3& x : spec.sensors) out << x[0] << " " << x[1] << " " << x[2] << "\n";
  out << "</DataArray>\n</Points>\n<Cells>\n<DataArray type=\"Int64\" Name=\"connectivity\" format=\"ascii\">\n";
  if (quads.empty())
    for (std::size_t i = 0; i < n; ++i) out << i << " ";
  for (const auto& q : quads) out << q[0] << " " << q[1] << " " << q[2] << " " << q[3] << " ";
  out << "\n</DataArray>\n<DataArray type=\"Int64\" Name=\"offsets\" format=\"ascii\">\n";
  for (std::size_t c = 1; c <= cells; ++c) out << c * (quads.empty() ? 1 : 4) << " ";
  out << "\n</DataArray>\n<DataArray type=\"UInt8\" Name=\"types\" format=\"ascii\">\n";
  for (std::size_t c = 0; c < cells; ++c) out << (quads.empty() ? 1 : 9) << " ";
  out << "\n</DataArray>\n</Cells>\n</Piece>\n</UnstructuredGrid>\n</VTKFile>\n";
  return out.str();
}

}  // namespace

double log_det(const MatrixX& fisher) {
  if (fisher.size() == 0) return -kInf;
  const Eigen::SelfAdjointEigenSolver<MatrixX> eigen(fisher, Eigen::EigenvaluesOnly);
  const VectorX& lambda = eigen.eigenvalues();
  if (!(lambda.maxCoeff() > 0.0) || lambda.minCoeff() <= 1e-12 * lambda.maxCoeff()) return -kInf;
  return lambda.array().log().sum();
}

std::vector<std::pair<int, double>> greedy_sensors(const std::vector<MatrixX>& base,
                                                   const std::vector<std::vector<MatrixX>>& per_sensor, int count) {
  std::vector<std::pair<int, double>> chosen;
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
    chosen.emplace_back(best, best_value);
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
  // sensors
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
    const int normal = spec.face[0] - 'x';
    const int a = (normal + 1) % 3, b = (normal + 2) % 3;
    const int first = std::min(a, b), second = std::max(a, b);
    const double at = origin[normal] + (spec.face[1] == '+' ? size[normal] : 0.0);
    spec.grid[0] = std::max(2, static_cast<int>(std::lround(size[first] / spacing)) + 1);
    spec.grid[1] = std::max(2, static_cast<int>(std::lround(size[second] / spacing)) + 1);
    if (spec.grid[0] * spec.grid[1] > 2000)
      fail(file, scene::mark_line(sensors["spacing"]), "plan.sensors.spacing", "at most 2000 sensor points on the face",
           std::to_string(spec.grid[0] * spec.grid[1]));
    for (int i = 0; i < spec.grid[0]; ++i)
      for (int j = 0; j < spec.grid[1]; ++j) {
        Vec3 x;
        x[normal] = at;
        x[first] = origin[first] + size[first] * i / (spec.grid[0] - 1);
        x[second] = origin[second] + size[second] * j / (spec.grid[1] - 1);
        spec.sensors.push_back(x);
      }
  } else {
    fail(file, scene::mark_line(sensors), "plan.sensors", "face (with spacing) or points", "neither");
  }
  // drives
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
  // noise
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
  return spec;
}

json run_plan(const PlanOptions& options, std::ostream& log) {
  const auto start = std::chrono::steady_clock::now();
  const std::string& file = options.scene_path;
  const std::string text = scene::read_scene_file(file);
  const scene::Scene scene = scene::parse_scene(text, file);
  const PlanSpec spec = parse_plan_section(text, file, scene.box.origin, scene.box.size);
  const std::size_t k = spec.prior.size();

  // ---- checks against the scene
  if (!scene.transient || !scene.transient->excitation || scene.transient->excitation->kind != "harmonic")
    throw InputError(file + ": plan: expected a scene with a harmonic transient.excitation (its direction, amplitude and "
                     "damping drive every candidate; plan.drives moves it), got " +
                     std::string(!scene.transient || !scene.transient->excitation ? "none" : "a pulse"));
  for (std::size_t i = 0; i < spec.frequencies.size(); ++i) {
    if (spec.frequencies[i].mode > scene.modal.modes)
      throw InputError(file + ": plan.drives.frequencies[" + std::to_string(i) + "].mode: expected a mode the scene solves "
                       "(modal.modes = " + std::to_string(scene.modal.modes) + "), got " + std::to_string(spec.frequencies[i].mode));
    if (spec.frequencies[i].subharmonic() && scene.contact.friction > 0.0)
      throw InputError(file + ": plan.drives.frequencies[" + std::to_string(i) + "].ratio: expected a ratio below 1.5 with "
                       "friction (a sub-harmonic needs the sweep's stability, which is frictionless), got " +
                       format_number(spec.frequencies[i].ratio));
  }
  const auto inside = [&](const Vec3& x) {
    for (int a = 0; a < 3; ++a)
      if (x[a] < scene.box.origin[a] - 1e-12 || x[a] > scene.box.origin[a] + scene.box.size[a] + 1e-12) return false;
    return true;
  };
  for (std::size_t i = 0; i < spec.drive_points.size(); ++i)
    if (!inside(spec.drive_points[i]))
      throw InputError(file + ": plan.drives.points[" + std::to_string(i) + "]: expected a point of the body's box, got (" +
                       format_number(spec.drive_points[i][0]) + ", " + format_number(spec.drive_points[i][1]) + ", " +
                       format_number(spec.drive_points[i][2]) + ")");
  for (std::size_t i = 0; i < spec.sensors.size(); ++i)
    if (!inside(spec.sensors[i]))
      throw InputError(file + ": plan.sensors.points[" + std::to_string(i) + "]: expected a point of the body's box, got (" +
                       format_number(spec.sensors[i][0]) + ", " + format_number(spec.sensors[i][1]) + ", " +
                       format_number(spec.sensors[i][2]) + ")");

  YAML::Node base = scene::parse_yaml(text, file);
  base.remove("plan");
  base.remove("study");
  base.remove("identify");
  identify::prepare_base(base, scene, spec.prior, file, "plan.prior");
  // The candidate sensors are the sweep's probes; the drive is a point load of the scene's excitation.
  YAML::Node probes(YAML::NodeType::Sequence);
  const auto sensor_name = [](std::size_t i) { return "s" + std::to_string(i + 1); };
  for (std::size_t i = 0; i < spec.sensors.size(); ++i) {
    YAML::Node probe(YAML::NodeType::Map);
    probe["name"] = sensor_name(i);
    probe["point"] = YAML::Load(list_text({spec.sensors[i][0], spec.sensors[i][1], spec.sensors[i][2]}));
    if (spec.component >= 0) probe["component"] = std::string(1, static_cast<char>('x' + spec.component));
    probes.push_back(probe);
  }
  base["transient"]["probes"] = probes;
  YAML::Node excitation = base["transient"]["excitation"];
  for (const char* key : {"face", "group", "point"})
    if (excitation[key]) excitation.remove(key);
  const Vec3& first_drive = spec.drive_points.front();
  excitation["point"] = YAML::Load(list_text({first_drive[0], first_drive[1], first_drive[2]}));

  // ---- the prior samples (centres of equal bins per key) and their Jacobian points
  std::vector<std::vector<double>> axes(k);
  std::size_t n_samples = 1;
  for (std::size_t j = 0; j < k; ++j) {
    for (int i = 0; i < spec.samples; ++i)
      axes[j].push_back(spec.prior[j].lower + (spec.prior[j].upper - spec.prior[j].lower) * (i + 0.5) / spec.samples);
    n_samples *= axes[j].size();
  }
  fit::Bounds bounds{VectorX(k), VectorX(k)};
  for (std::size_t j = 0; j < k; ++j) {
    bounds.lower[static_cast<Eigen::Index>(j)] = spec.prior[j].lower;
    bounds.upper[static_cast<Eigen::Index>(j)] = spec.prior[j].upper;
  }
  std::vector<VectorX> samples, points;  // points: per sample, the sample then its k Jacobian points
  std::vector<std::vector<std::size_t>> sample_index(n_samples, std::vector<std::size_t>(k));
  for (std::size_t flat = 0; flat < n_samples; ++flat) {
    VectorX theta(static_cast<Eigen::Index>(k));
    std::size_t rest = flat;
    for (std::size_t j = k; j-- > 0;) {
      sample_index[flat][j] = rest % axes[j].size();
      theta[static_cast<Eigen::Index>(j)] = axes[j][rest % axes[j].size()];
      rest /= axes[j].size();
    }
    samples.push_back(theta);
    points.push_back(theta);
    for (const VectorX& point : fit::jacobian_points(theta, bounds, VectorX::Constant(static_cast<Eigen::Index>(k), kStep)))
      points.push_back(point);
  }
  const std::size_t per_sample = k + 1;
  const std::size_t n_drives = spec.drive_points.size(), n_freq = spec.frequencies.size(), n_sensors = spec.sensors.size();
  const fs::path dir(options.output_dir);
  fs::create_directories(dir);
  const identify::ForwardRunner runner{options.executable, options.jobs};
  int forward_runs = 0;

  // ---- 1. the bilinear frequencies of the driven modes at every point (crackle modal)
  log << "plan: " << n_samples << " prior samples x " << n_drives << " drive points x " << n_freq << " drive frequencies, "
      << n_sensors << " candidate sensors; 1. modal frequencies at " << points.size() << " points\n";
  // The model error (identify's: the orders p, p+1, p+2 in the middle of the prior) comes first in
  // each batch, the highest order first (the longest runs start while the others fill the cores).
  const VectorX middle = 0.5 * (bounds.lower + bounds.upper);
  const int order_run = scene.box.order;
  const std::vector<int> levels = identify::refinement_orders(order_run);
  const std::size_t n_levels = levels.size();
  std::vector<ForwardCase> modal_cases;
  for (std::size_t l = n_levels; l-- > 0;) modal_cases.push_back({middle, levels[l], {}});
  for (const VectorX& point : points) modal_cases.push_back({point, order_run, {}});
  const std::vector<fs::path> modal_folders =
      identify::run_forward_cases(base, spec.prior, modal_cases, "modal", dir / "modal", runner, log, options.progress);
  forward_runs += static_cast<int>(modal_folders.size());
  std::vector<std::vector<double>> f_u(points.size()), f_b(points.size()), level_f_b(n_levels);
  for (std::size_t c = 0; c < modal_folders.size(); ++c) {
    std::ifstream stream(modal_folders[c] / "modal.json");
    const json modal = json::parse(stream);
    std::vector<double>& bilinear = c < n_levels ? level_f_b[n_levels - 1 - c] : f_b[c - n_levels];
    for (const json& pair : modal["pairs"]) {
      if (c >= n_levels) f_u[c - n_levels].push_back(pair["f_uncracked_hz"].get<double>());
      bilinear.push_back(pair.value("paired", true) ? pair["f_bilinear_hz"].get<double>() : kNaN);
    }
  }
  // the relative model error of each mode's bilinear frequency (the driven ones are used)
  const auto at = [](const std::vector<double>& values, std::size_t i) { return values.size() > i ? values[i] : kNaN; };
  std::vector<identify::RefinementError> frequency_error;
  const std::size_t run_level = static_cast<std::size_t>(order_run - levels.front());
  for (std::size_t m = 0; m < static_cast<std::size_t>(scene.modal.modes); ++m)
    frequency_error.push_back(identify::refinement_error(at(level_f_b[0], m), at(level_f_b[1], m), at(level_f_b[2], m),
                                                         static_cast<int>(run_level)));
  const auto sweep_settings = [&](const DriveFrequency& f, std::vector<std::pair<std::string, std::string>>& set) {
    set.emplace_back("sweep.points", std::to_string(f.subharmonic() ? kSubharmonicPoints : 2));
    set.emplace_back("sweep.stability", f.subharmonic() ? "true" : "false");
    set.emplace_back("sweep.subharmonic", f.subharmonic() ? "2" : "1");
  };

  // The drive frequencies highest first within each sample and drive point: the cases of one crack
  // share a modal cache folder, and a reduction made for the highest frequency (the most modes) serves
  // the lower ones from the cache (reduced::ReductionOptions::frequency_margin).
  std::vector<std::size_t> freq_order(n_freq), freq_rank(n_freq);
  for (std::size_t f = 0; f < n_freq; ++f) freq_order[f] = f;
  const auto nominal_hz = [&](std::size_t f) {
    const double hz = spec.frequencies[f].ratio * at(level_f_b[run_level], static_cast<std::size_t>(spec.frequencies[f].mode - 1));
    return std::isfinite(hz) ? hz : 0.0;
  };
  std::stable_sort(freq_order.begin(), freq_order.end(), [&](std::size_t a, std::size_t b) { return nominal_hz(a) > nominal_hz(b); });
  for (std::size_t i = 0; i < n_freq; ++i) freq_rank[freq_order[i]] = i;

  // ---- 2. a sweep about each drive frequency at every sample (crackle sweep: every sensor at once)
  YAML::Node base_a = YAML::Clone(base);
  base_a["sweep"]["frequency"] = YAML::Load("{from: {mode: 1, ratio: 1}, to: {mode: 1, ratio: 2}}");
  std::vector<ForwardCase> cases_a;
  // the model error's levels (the middle of the prior at each refinement order) first, then the samples
  for (std::size_t s = 0; s < n_levels + n_samples; ++s)
    for (std::size_t p = 0; p < n_drives; ++p)
      for (const std::size_t f : freq_order) {
        const DriveFrequency& drive = spec.frequencies[f];
        const double half = drive.subharmonic() ? kSubharmonicHalfWidth : kNarrowHalfWidth;
        ForwardCase run = s < n_levels ? ForwardCase{middle, levels[n_levels - 1 - s], {}}
                                       : ForwardCase{samples[s - n_levels], order_run, {}};
        const Vec3& x = spec.drive_points[p];
        run.set = {{"transient.excitation.point", list_text({x[0], x[1], x[2]})},
                   {"sweep.frequency.from.mode", std::to_string(drive.mode)},
                   {"sweep.frequency.from.ratio", format_number(drive.ratio * (1.0 - half))},
                   {"sweep.frequency.to.mode", std::to_string(drive.mode)},
                   {"sweep.frequency.to.ratio", format_number(drive.ratio * (1.0 + half))}};
        sweep_settings(drive, run.set);
        cases_a.push_back(run);
      }
  log << "plan: 2. sweeps at the samples: " << cases_a.size() << " runs (" << n_levels * n_drives * n_freq
      << " of them for the model error)\n";
  const std::vector<fs::path> folders_a =
      identify::run_forward_cases(base_a, spec.prior, cases_a, "sweep", dir / "samples", runner, log, options.progress);
  forward_runs += static_cast<int>(folders_a.size());
  const auto index_a = [&](std::size_t s, std::size_t p, std::size_t f) { return (s * n_drives + p) * n_freq + freq_rank[f]; };
  std::vector<SweepTable> tables_a;
  std::vector<std::array<double, 2>> range_a;
  for (const fs::path& folder : folders_a) {
    tables_a.push_back(identify::read_sweep_csv(folder / "sweep.csv"));
    std::ifstream stream(folder / "sweep.json");
    const json sweep = json::parse(stream);
    range_a.push_back({sweep["settings"]["from_hz"].get<double>(), sweep["settings"]["to_hz"].get<double>()});
  }
  // the model error's runs: level l (order levels[l]) of drive p and frequency f, at their own drive
  const std::size_t n_level_runs = n_levels * n_drives * n_freq;
  std::vector<SweepTable> level_tables(tables_a.begin(), tables_a.begin() + static_cast<std::ptrdiff_t>(n_level_runs));
  std::vector<std::array<double, 2>> level_ranges(range_a.begin(), range_a.begin() + static_cast<std::ptrdiff_t>(n_level_runs));
  tables_a.erase(tables_a.begin(), tables_a.begin() + static_cast<std::ptrdiff_t>(n_level_runs));
  range_a.erase(range_a.begin(), range_a.begin() + static_cast<std::ptrdiff_t>(n_level_runs));
  const auto level_run = [&](std::size_t l, std::size_t p, std::size_t f) {
    return ((n_levels - 1 - l) * n_drives + p) * n_freq + freq_rank[f];
  };
  // the relative model error of a quantity of a sensor under drive p, frequency f
  const auto ratio_error = [&](const std::string& quantity, const std::string& sensor, std::size_t p, std::size_t f) {
    const int branch = spec.frequencies[f].subharmonic() ? 2 : 1;
    std::vector<double> q(n_levels);
    for (std::size_t l = 0; l < n_levels; ++l) {
      const std::size_t r = level_run(l, p, f);
      q[l] = sweep_value(level_tables[r], quantity, sensor, 0.5 * (level_ranges[r][0] + level_ranges[r][1]), branch);
    }
    return identify::refinement_error(q[0], q[1], q[2], static_cast<int>(run_level));
  };

  // the largest first harmonic over the sensors of each sample run (the reference of noise.floor)
  std::vector<double> largest_a1(tables_a.size(), 0.0);
  for (std::size_t a = 0; a < tables_a.size(); ++a) {
    const std::size_t f = freq_order[a % n_freq];
    const double drive_hz = 0.5 * (range_a[a][0] + range_a[a][1]);
    for (std::size_t i = 0; i < n_sensors; ++i) {
      const double a1 = sweep_value(tables_a[a], "A1", sensor_name(i), drive_hz, spec.frequencies[f].subharmonic() ? 2 : 1);
      if (std::isfinite(a1)) largest_a1[a] = std::max(largest_a1[a], a1);
    }
  }

  // ---- 3. the same sweeps at the Jacobian points, the drive fixed in Hz
  YAML::Node base_b = YAML::Clone(base);
  base_b["sweep"]["frequency"] = YAML::Load("{from: 1.0, to: 2.0}");
  std::vector<ForwardCase> cases_b;
  std::map<std::array<std::size_t, 4>, std::size_t> where_b;  // (s, j, p, f) -> case
  for (std::size_t s = 0; s < n_samples; ++s)
    for (std::size_t j = 1; j <= k; ++j)
      for (std::size_t p = 0; p < n_drives; ++p)
        for (const std::size_t f : freq_order) {
          const std::size_t a = index_a(s, p, f);
          const std::array<double, 2>& range = range_a[a];
          // A sub-harmonic drive without a stable period-two branch at the sample has no response:
          // no Jacobian (its sweeps with stability are the costliest runs).
          if (spec.frequencies[f].subharmonic() && !period_two_exists(tables_a[a], 0.5 * (range[0] + range[1]))) continue;
          where_b[{s, j, p, f}] = cases_b.size();
          ForwardCase run{points[s * per_sample + j], 0, {}};
          const Vec3& x = spec.drive_points[p];
          run.set = {{"transient.excitation.point", list_text({x[0], x[1], x[2]})},
                     {"sweep.frequency.from", format_number(range[0])},
                     {"sweep.frequency.to", format_number(range[1])}};
          sweep_settings(spec.frequencies[f], run.set);
          cases_b.push_back(run);
        }
  log << "plan: 3. sweeps at the Jacobian points: " << cases_b.size() << " runs\n";
  const std::vector<fs::path> folders_b =
      identify::run_forward_cases(base_b, spec.prior, cases_b, "sweep", dir / "jacobian", runner, log, options.progress);
  forward_runs += static_cast<int>(folders_b.size());
  std::vector<SweepTable> tables_b;
  for (const fs::path& folder : folders_b) tables_b.push_back(identify::read_sweep_csv(folder / "sweep.csv"));
  const SweepTable no_table;
  const auto table_b = [&](std::size_t s, std::size_t j, std::size_t p, std::size_t f) -> const SweepTable& {
    const auto it = where_b.find({s, j, p, f});
    return it == where_b.end() ? no_table : tables_b[it->second];
  };

  // ---- 4. the figures of every candidate at every sample
  std::vector<Candidate> candidates;
  for (std::size_t p = 0; p < n_drives; ++p)
    for (std::size_t f = 0; f < n_freq; ++f)
      for (std::size_t i = 0; i < n_sensors; ++i) candidates.push_back({i, p, f, {}, 0, -kInf, {}, {}, {}, {}});
  for (Candidate& c : candidates) {
    const DriveFrequency& drive = spec.frequencies[c.frequency];
    const int branch = drive.subharmonic() ? 2 : 1;
    const std::size_t mode = static_cast<std::size_t>(drive.mode - 1);
    const std::string name = sensor_name(c.sensor);
    for (const std::string& q : ratio_quantities(drive)) c.model_error.push_back(ratio_error(q, name, c.drive, c.frequency));
    c.model_error.push_back(frequency_error[mode]);
    const double frequency_eps = frequency_error[mode].relative;
    for (std::size_t s = 0; s < n_samples; ++s) {
      SampleFigures figures;
      const std::size_t a = index_a(s, c.drive, c.frequency);
      const double drive_hz = 0.5 * (range_a[a][0] + range_a[a][1]);
      const std::size_t p0 = s * per_sample;
      figures.frequency_fisher = MatrixX::Zero(static_cast<Eigen::Index>(k), static_cast<Eigen::Index>(k));
      figures.sensor_fisher = figures.frequency_fisher;
      VectorX row(static_cast<Eigen::Index>(k));
      const double fb0 = f_b[p0].size() > mode ? f_b[p0][mode] : kNaN;
      const double fu0 = f_u[p0].size() > mode ? f_u[p0][mode] : kNaN;
      // sigma of the frequency: the measurement's and the model's error (as identify weighs it)
      const double frequency_sigma = std::hypot(spec.noise_frequency, frequency_eps) * fb0;
      for (std::size_t j = 1; j <= k; ++j) {
        const double h = points[p0 + j][static_cast<Eigen::Index>(j - 1)] - points[p0][static_cast<Eigen::Index>(j - 1)];
        row[static_cast<Eigen::Index>(j - 1)] = (f_b[p0 + j][mode] - fb0) / h / frequency_sigma;
      }
      if (row.allFinite()) figures.frequency_fisher = row * row.transpose();
      figures.frequency_hz = fb0;
      figures.frequency_sigma = frequency_sigma;
      const double frequency_z = std::isfinite(fb0) ? (fu0 - fb0) / (spec.noise_frequency * fu0) : 0.0;
      figures.z = frequency_z;
      if (drive.subharmonic()) figures.responds = period_two_exists(tables_a[a], drive_hz);
      // The acquisition's noise floor in m: noise.floor of the largest first harmonic over the sensors.
      const double a1 = sweep_value(tables_a[a], "A1", name, drive_hz, branch);
      const double floor_m = spec.noise_floor * largest_a1[a];
      const std::vector<std::string> quantities = ratio_quantities(drive);
      for (std::size_t qi = 0; qi < quantities.size(); ++qi) {
        const std::string& q = quantities[qi];
        const double v0 = sweep_value(tables_a[a], q, name, drive_hz, branch);
        figures.values.push_back(v0);
        if (!std::isfinite(v0)) {
          figures.sigmas.push_back(kNaN);
          figures.noise_sigmas.push_back(kNaN);
          if (figures.responds) figures.missing = true;
          figures.responds = false;
          continue;
        }
        const double sigma = std::sqrt(std::pow(spec.noise_ratio * v0, 2) + std::pow(floor_m / a1, 2) +
                                       std::pow(c.model_error[qi].relative * v0, 2));
        figures.sigmas.push_back(sigma);
        figures.noise_sigmas.push_back(std::hypot(spec.noise_ratio * v0, floor_m / a1));
        for (std::size_t j = 1; j <= k; ++j) {
          const double h = points[p0 + j][static_cast<Eigen::Index>(j - 1)] - points[p0][static_cast<Eigen::Index>(j - 1)];
          const double v = sweep_value(table_b(s, j, c.drive, c.frequency), q, name, drive_hz, branch);
          row[static_cast<Eigen::Index>(j - 1)] = (v - v0) / h / sigma;
        }
        if (!row.allFinite()) {
          if (figures.responds) figures.missing = true;
          figures.responds = false;
          continue;
        }
        figures.sensor_fisher += row * row.transpose();
        figures.z = std::max(figures.z, v0 * a1 / floor_m);
      }
      if (!figures.responds) {
        figures.z = frequency_z;
        figures.sensor_fisher.setZero();
      }
      c.samples.push_back(figures);
    }
    // averages over the samples where the candidate responds
    double sum = 0.0;
    c.worst_width.assign(k, 0.0);
    c.mean_width.assign(k, 0.0);
    for (const SampleFigures& figures : c.samples) {
      if (!figures.responds) continue;
      ++c.responding;
      const MatrixX fisher = figures.frequency_fisher + figures.sensor_fisher;
      const double value = log_det(fisher);
      sum += value;
      const MatrixX covariance = std::isfinite(value) ? MatrixX(fisher.inverse()) : MatrixX::Constant(static_cast<Eigen::Index>(k), static_cast<Eigen::Index>(k), kInf);
      for (std::size_t j = 0; j < k; ++j) {
        const double width = 2.0 * kZ95 * std::sqrt(covariance(static_cast<Eigen::Index>(j), static_cast<Eigen::Index>(j)));
        c.worst_width[j] = std::max(c.worst_width[j], width);
        c.mean_width[j] += width;
      }
    }
    if (c.responding > 0) {
      c.mean_log_det = sum / c.responding;
      for (double& width : c.mean_width) width /= c.responding;
    }
  }

  // ---- detectability: the smallest crack per position, along the size key
  const std::size_t size = static_cast<std::size_t>(spec.size_key);
  // The small end of the size key: where the first driven mode's frequency drops least.
  double drop_first = 0.0, drop_last = 0.0;
  for (std::size_t s = 0; s < n_samples; ++s) {
    const std::size_t mode = static_cast<std::size_t>(spec.frequencies.front().mode - 1);
    const double drop = f_u[s * per_sample][mode] - f_b[s * per_sample][mode];
    if (sample_index[s][size] == 0) drop_first += drop;
    if (sample_index[s][size] + 1 == axes[size].size()) drop_last += drop;
  }
  const bool small_first = drop_first <= drop_last;
  std::vector<std::size_t> position_samples;  // a sample at the smallest crack of each position
  for (std::size_t s = 0; s < n_samples; ++s)
    if (sample_index[s][size] == (small_first ? 0 : axes[size].size() - 1)) position_samples.push_back(s);
  const std::size_t size_stride = [&] {
    std::size_t stride = 1;
    for (std::size_t j = k; j-- > size + 1;) stride *= axes[j].size();
    return stride;
  }();
  std::vector<std::vector<bool>> at_or_below(candidates.size());
  for (std::size_t ci = 0; ci < candidates.size(); ++ci) {
    Candidate& c = candidates[ci];
    for (std::size_t s0 : position_samples) {
      double smallest = kNaN;
      bool below = false;
      double previous_z = 0.0, previous_value = 0.0;
      for (std::size_t step = 0; step < axes[size].size(); ++step) {
        const std::size_t along = small_first ? step : axes[size].size() - 1 - step;
        const std::size_t s = small_first ? s0 + step * size_stride : s0 - step * size_stride;
        const double z = c.samples[s].z, value = axes[size][along];
        if (z >= kDetect) {
          if (step == 0) {
            smallest = value;
            below = true;
          } else {
            smallest = previous_value + (kDetect - previous_z) / (z - previous_z) * (value - previous_value);
          }
          break;
        }
        previous_z = z;
        previous_value = value;
      }
      c.smallest_crack.push_back(smallest);
      at_or_below[ci].push_back(below);
    }
  }

  // ---- ranking: responding at every sample first, then by the mean log det
  std::vector<std::size_t> order(candidates.size());
  for (std::size_t i = 0; i < order.size(); ++i) order[i] = i;
  const auto all = static_cast<int>(n_samples);
  std::stable_sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) {
    const Candidate &x = candidates[a], &y = candidates[b];
    if ((x.responding == all) != (y.responding == all)) return x.responding == all;
    if (x.responding != y.responding) return x.responding > y.responding;
    return x.mean_log_det > y.mean_log_det;
  });

  // ---- plan.json
  const auto keyed = [&](const std::vector<double>& v) {
    json object = json::object();
    for (std::size_t j = 0; j < k; ++j) object[spec.prior[j].key] = finite_or_null(v[j]);
    return object;
  };
  const auto theta_json = [&](const VectorX& theta) {
    return keyed(std::vector<double>(theta.data(), theta.data() + theta.size()));
  };
  const auto point_json = [](const Vec3& x) { return json::array({x[0], x[1], x[2]}); };
  json document;
  document["scene"] = file;
  json prior = json::object();
  for (const auto& u : spec.prior) prior[u.key] = {u.lower, u.upper};
  document["prior"] = prior;
  document["size_key"] = spec.prior[size].key;
  document["smaller_crack_towards"] = small_first ? "lower" : "upper";
  document["noise"] = {{"frequency", spec.noise_frequency}, {"ratio", spec.noise_ratio}, {"floor", spec.noise_floor}};
  json frequency_errors = json::array();
  for (std::size_t m = 0; m < frequency_error.size(); ++m)
    frequency_errors.push_back({{"mode", m + 1}, {"relative", frequency_error[m].relative}, {"verified", frequency_error[m].verified}});
  document["model_error"] = {{"orders", levels}, {"order_run", order_run}, {"at", theta_json(middle)},
                             {"f_bilinear", frequency_errors},
                             {"note", "the p-refinement estimate of identify, in the middle of the prior; added in quadrature "
                                      "to the noise in the Fisher information (not in detection: a detection compares with "
                                      "the same part's baseline)"}};
  document["averaging"] = "log_det: mean over the prior samples where the candidate responds; widths_95: mean and worst "
                          "over them; candidates that respond at every sample rank first";
  json sample_list = json::array();
  for (std::size_t s = 0; s < n_samples; ++s) {
    json entry = {{"theta", theta_json(samples[s])}};
    json modes = json::array();
    for (std::size_t m = 0; m < f_u[s * per_sample].size(); ++m)
      modes.push_back({{"mode", m + 1}, {"f_uncracked_hz", f_u[s * per_sample][m]}, {"f_bilinear_hz", finite_or_null(f_b[s * per_sample][m])}});
    entry["modes"] = modes;
    sample_list.push_back(entry);
  }
  document["samples"] = sample_list;
  json ranked = json::array();
  int missing_figures = 0;  // candidate samples with a missing forward value (SampleFigures::missing)
  for (std::size_t r = 0; r < order.size(); ++r) {
    const Candidate& c = candidates[order[r]];
    const DriveFrequency& drive = spec.frequencies[c.frequency];
    json entry = {{"rank", r + 1},
                  {"sensor", {{"name", sensor_name(c.sensor)}, {"point", point_json(spec.sensors[c.sensor])}}},
                  {"drive", {{"point", point_json(spec.drive_points[c.drive])}, {"mode", drive.mode}, {"ratio", drive.ratio},
                             {"subharmonic", drive.subharmonic()}}},
                  {"quantities", ratio_quantities(drive)},
                  {"responds", c.responding == all},
                  {"responding_samples", c.responding},
                  {"log_det", finite_or_null(c.mean_log_det)},
                  {"widths_95", {{"mean", keyed(c.mean_width)}, {"worst", keyed(c.worst_width)}}}};
    json errors = json::object();
    const std::vector<std::string> names_of = ratio_quantities(drive);
    for (std::size_t q = 0; q < c.model_error.size(); ++q)
      errors[q < names_of.size() ? names_of[q] : "f_bilinear"] = {{"relative", c.model_error[q].relative},
                                                                  {"verified", c.model_error[q].verified}};
    entry["model_error"] = errors;
    json detect = json::array();
    for (std::size_t q = 0; q < position_samples.size(); ++q) {
      json position = json::object();
      for (std::size_t j = 0; j < k; ++j)
        if (j != size) position[spec.prior[j].key] = samples[position_samples[q]][static_cast<Eigen::Index>(j)];
      detect.push_back({{"position", position}, {"smallest", finite_or_null(c.smallest_crack[q])},
                        {"at_or_below_prior", at_or_below[order[r]][q]}});
    }
    entry["detectability"] = detect;
    json per = json::array();
    for (std::size_t s = 0; s < n_samples; ++s) {
      const SampleFigures& figures = c.samples[s];
      const std::size_t a = index_a(s, c.drive, c.frequency);
      json values = json::object();
      const auto names = ratio_quantities(drive);
      json sigmas = json::object(), noise_sigmas = json::object();
      for (std::size_t q = 0; q < names.size(); ++q) {
        values[names[q]] = finite_or_null(figures.values[q]);
        sigmas[names[q]] = finite_or_null(figures.sigmas[q]);
        noise_sigmas[names[q]] = finite_or_null(figures.noise_sigmas[q]);
      }
      values["f_bilinear"] = finite_or_null(figures.frequency_hz);
      sigmas["f_bilinear"] = finite_or_null(figures.frequency_sigma);
      noise_sigmas["f_bilinear"] = finite_or_null(spec.noise_frequency * figures.frequency_hz);
      if (figures.missing) ++missing_figures;
      per.push_back({{"drive_hz", 0.5 * (range_a[a][0] + range_a[a][1])}, {"responds", figures.responds},
                     {"missing", figures.missing},
                     {"log_det", finite_or_null(figures.responds ? log_det(figures.frequency_fisher + figures.sensor_fisher) : kNaN)},
                     {"z", figures.z}, {"values", values}, {"sigmas", sigmas},
                     {"noise_sigmas", noise_sigmas}});
    }
    entry["per_sample"] = per;
    ranked.push_back(entry);
  }
  document["candidates"] = ranked;
  json notes = json::array();
  if (missing_figures > 0) {
    notes.push_back(std::to_string(missing_figures) +
                    " candidate samples lack a forward value although their drive responds (a sweep did not reach "
                    "its drive frequency; see the warnings in the case folders' sweep.json): counted as not "
                    "responding (per_sample[].missing)");
    log << "plan: warning: " << notes.back().get<std::string>() << "\n";
  }
  document["notes"] = notes;
  // the best set of 1..combine sensors for the best candidate's drive
  const Candidate& best = candidates[order.front()];
  std::vector<MatrixX> base_fisher;
  std::vector<std::vector<MatrixX>> per_sensor(n_sensors);
  std::vector<std::size_t> same_drive(n_sensors);
  for (std::size_t ci = 0; ci < candidates.size(); ++ci)
    if (candidates[ci].drive == best.drive && candidates[ci].frequency == best.frequency) same_drive[candidates[ci].sensor] = ci;
  for (std::size_t s = 0; s < n_samples; ++s) {
    if (!best.samples[s].responds) continue;
    base_fisher.push_back(best.samples[s].frequency_fisher);
    for (std::size_t i = 0; i < n_sensors; ++i) per_sensor[i].push_back(candidates[same_drive[i]].samples[s].sensor_fisher);
  }
  json sets = json::array();
  std::vector<std::string> chosen;
  for (const auto& [sensor, value] : greedy_sensors(base_fisher, per_sensor, spec.combine)) {
    chosen.push_back(sensor_name(static_cast<std::size_t>(sensor)));
    json points_of_set = json::array();
    for (const std::string& name : chosen) points_of_set.push_back(point_json(spec.sensors[std::stoul(name.substr(1)) - 1]));
    sets.push_back({{"k", chosen.size()}, {"sensors", chosen}, {"points", points_of_set}, {"log_det", finite_or_null(value)}});
  }
  document["best_sensors"] = {{"drive", {{"point", point_json(spec.drive_points[best.drive])},
                                         {"mode", spec.frequencies[best.frequency].mode},
                                         {"ratio", spec.frequencies[best.frequency].ratio}}},
                              {"sets", sets}};

  // ---- plan_sensors.vtu and the plots
  std::vector<std::pair<std::string, std::vector<double>>> arrays, map_panels;
  study::LinePlot plot{"log det F along the sensors (best over the sensors across)", "", "mean log det F", {}};
  const int along = spec.face.empty() ? -1 : std::min(((spec.face[0] - 'x') + 1) % 3, ((spec.face[0] - 'x') + 2) % 3);
  plot.x_label = along < 0 ? "sensor" : std::string(1, static_cast<char>('x' + along)) + " [m]";
  for (std::size_t p = 0; p < n_drives; ++p)
    for (std::size_t f = 0; f < n_freq; ++f) {
      const std::string tag = "d" + std::to_string(p + 1) + "f" + std::to_string(f + 1);
      std::vector<double> det(n_sensors), smallest(n_sensors), responds(n_sensors);
      std::vector<std::vector<double>> widths(k, std::vector<double>(n_sensors));
      for (const Candidate& c : candidates) {
        if (c.drive != p || c.frequency != f) continue;
        det[c.sensor] = std::isfinite(c.mean_log_det) ? c.mean_log_det : kNaN;
        responds[c.sensor] = static_cast<double>(c.responding) / static_cast<double>(n_samples);
        double worst = -kInf;
        for (double value : c.smallest_crack) worst = std::isfinite(value) ? std::max(worst, value) : kInf;
        smallest[c.sensor] = std::isfinite(worst) ? worst : kNaN;
        for (std::size_t j = 0; j < k; ++j) widths[j][c.sensor] = std::isfinite(c.mean_width[j]) ? c.mean_width[j] : kNaN;
      }
      arrays.emplace_back(tag + " log_det", det);
      map_panels.emplace_back(drive_label(spec, p, f), det);
      arrays.emplace_back(tag + " responding fraction", responds);
      arrays.emplace_back(tag + " smallest " + spec.prior[size].key + " (worst position)", smallest);
      for (std::size_t j = 0; j < k; ++j) arrays.emplace_back(tag + " width95 " + spec.prior[j].key, widths[j]);
      study::Series series{drive_label(spec, p, f), {}, {}};
      if (along < 0) {
        for (std::size_t i = 0; i < n_sensors; ++i) {
          series.x.push_back(static_cast<double>(i + 1));
          series.y.push_back(det[i]);
        }
      } else {
        for (int a = 0; a < spec.grid[0]; ++a) {
          double value = kNaN;
          for (int b = 0; b < spec.grid[1]; ++b) {
            const double v = det[static_cast<std::size_t>(a * spec.grid[1] + b)];
            if (std::isfinite(v) && !(v <= value)) value = v;
          }
          series.x.push_back(spec.sensors[static_cast<std::size_t>(a * spec.grid[1])][along]);
          series.y.push_back(value);
        }
      }
      plot.series.push_back(series);
    }
  io::write_file_atomic(dir / "plan_sensors.vtu", vtu_text(spec, arrays));
  json files = json::array({"plan.json", "plan_sensors.vtu"});
  const std::string note = study::plot_lines(dir / "plan_log_det.png", plot, "gnuplot");
  if (note.empty()) files.push_back("plan_log_det.png");
  json plot_notes = json::array();
  if (!note.empty()) plot_notes.push_back(note);
  if (!spec.face.empty()) {
    const std::string map_note = plot_face_maps(dir, spec, "mean log det F", map_panels);
    if (map_note.empty()) files.push_back("plan_map.png");
    else plot_notes.push_back(map_note);
  }
  document["files"] = files;
  if (!plot_notes.empty()) document["plot_notes"] = plot_notes;
  document["forward_runs"] = forward_runs;
  document["elapsed_s"] = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  io::write_file_atomic(dir / "plan.json", document.dump(2) + "\n");
  const json& top = ranked.front();
  log << "plan: best " << top["sensor"]["name"].get<std::string>() << " at (" << top["sensor"]["point"][0] << ", "
      << top["sensor"]["point"][1] << ", " << top["sensor"]["point"][2] << ") driven at "
      << top["drive"]["ratio"].get<double>() << " f_b" << top["drive"]["mode"].get<int>() << " from ("
      << top["drive"]["point"][0] << ", " << top["drive"]["point"][1] << ", " << top["drive"]["point"][2]
      << "): mean log det " << top["log_det"] << "; best " << chosen.size() << " sensors: " << join(chosen) << "\n"
      << "plan: " << forward_runs << " forward runs in " << format_number(std::round(document["elapsed_s"].get<double>() * 10) / 10)
      << " s; " << dir.string() << "/plan.json\n";
  return document;
}

}  // namespace crackle::planning
