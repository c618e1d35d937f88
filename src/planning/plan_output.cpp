/// \file The files of `crackle plan` (plan_stages.hpp): plan.json's content (the ranked candidates
/// with their figures, the model error, the samples, the best sets of sensors), plan_sensors.vtu,
/// plan_log_det.png and plan_map.png.
#include <algorithm>
#include <cmath>
#include <ostream>
#include <sstream>

#include "core/errors.hpp"
#include "io/files.hpp"
#include "planning/plan_stages.hpp"
#include "plot/gnuplot.hpp"
#include "study/plot.hpp"

namespace crackle::planning::detail {
namespace fs = std::filesystem;
using nlohmann::json;

namespace {

json finite_or_null(double value) { return std::isfinite(value) ? json(value) : json(nullptr); }

json point_json(const Vec3& x) { return json::array({x[0], x[1], x[2]}); }

/// {key: value} over the prior's keys.
json keyed(const PlanSpec& spec, const std::vector<double>& values) {
  json object = json::object();
  for (std::size_t j = 0; j < spec.prior.size(); ++j) object[spec.prior[j].key] = finite_or_null(values[j]);
  return object;
}

json theta_json(const PlanSpec& spec, const VectorX& theta) {
  return keyed(spec, std::vector<double>(theta.data(), theta.data() + theta.size()));
}

std::string drive_label(const PlanSpec& spec, std::size_t p, std::size_t f) {
  std::ostringstream label;
  label << "drive " << p + 1 << " (" << format_number(spec.drive_points[p][0]) << ", " << format_number(spec.drive_points[p][1])
        << ", " << format_number(spec.drive_points[p][2]) << ") at " << format_number(spec.frequencies[f].ratio) << " f_b"
        << spec.frequencies[f].mode;
  return label.str();
}

json model_error_json(const PlanSpec& spec, const PriorGrid& grid, const ModalFigures& modal) {
  json frequency_errors = json::array();
  for (std::size_t m = 0; m < modal.frequency_error.size(); ++m)
    frequency_errors.push_back(
        {{"mode", m + 1}, {"relative", modal.frequency_error[m].relative}, {"verified", modal.frequency_error[m].verified}});
  return {{"orders", modal.levels}, {"order_run", modal.order_run}, {"at", theta_json(spec, grid.middle())},
          {"f_bilinear", frequency_errors},
          {"note", "the p-refinement estimate of identify, in the middle of the prior; added in quadrature "
                   "to the noise in the Fisher information (not in detection: a detection compares with "
                   "the same part's baseline)"}};
}

json samples_json(const PlanSpec& spec, const PriorGrid& grid, const ModalFigures& modal) {
  json list = json::array();
  for (std::size_t s = 0; s < grid.n_samples; ++s) {
    const std::size_t p0 = s * grid.per_sample;
    json modes = json::array();
    for (std::size_t m = 0; m < modal.f_u[p0].size(); ++m)
      modes.push_back({{"mode", m + 1}, {"f_uncracked_hz", modal.f_u[p0][m]}, {"f_bilinear_hz", finite_or_null(modal.f_b[p0][m])}});
    list.push_back({{"theta", theta_json(spec, grid.samples[s])}, {"modes", modes}});
  }
  return list;
}

/// A candidate's figures at each sample (plan.json `per_sample`).
json per_sample_json(const PlanSpec& spec, const SampleSweeps& sweeps, const Candidate& c) {
  const std::vector<std::string> names = ratio_quantities(spec.frequencies[c.frequency]);
  json per = json::array();
  for (std::size_t s = 0; s < c.samples.size(); ++s) {
    const SampleFigures& figures = c.samples[s];
    json values = json::object(), sigmas = json::object(), noise_sigmas = json::object();
    for (std::size_t q = 0; q < names.size(); ++q) {
      values[names[q]] = finite_or_null(figures.values[q]);
      sigmas[names[q]] = finite_or_null(figures.sigmas[q]);
      noise_sigmas[names[q]] = finite_or_null(figures.noise_sigmas[q]);
    }
    values["f_bilinear"] = finite_or_null(figures.frequency_hz);
    sigmas["f_bilinear"] = finite_or_null(figures.frequency_sigma);
    noise_sigmas["f_bilinear"] = finite_or_null(spec.noise_frequency * figures.frequency_hz);
    per.push_back({{"drive_hz", sweeps.drive_hz(sweeps.index(s, c.drive, c.frequency))}, {"responds", figures.responds},
                   {"missing", figures.missing},
                   {"log_det", finite_or_null(figures.responds ? log_det(figures.frequency_fisher + figures.sensor_fisher) : kNaN)},
                   {"z", figures.z}, {"values", values}, {"sigmas", sigmas}, {"noise_sigmas", noise_sigmas}});
  }
  return per;
}

/// The ranked candidate `ci` (plan.json `candidates[rank - 1]`).
json candidate_json(const PlanSpec& spec, const PlanFigures& figures, std::size_t rank, std::size_t ci) {
  const Candidate& c = figures.candidates[ci];
  const DriveFrequency& drive = spec.frequencies[c.frequency];
  const std::vector<std::string> names = ratio_quantities(drive);
  json entry = {{"rank", rank},
                {"sensor", {{"name", sensor_name(c.sensor)}, {"point", point_json(spec.sensors[c.sensor])}}},
                {"drive", {{"point", point_json(spec.drive_points[c.drive])}, {"mode", drive.mode}, {"ratio", drive.ratio},
                           {"subharmonic", drive.subharmonic()}}},
                {"quantities", names},
                {"responds", c.responding == static_cast<int>(figures.grid.n_samples)},
                {"responding_samples", c.responding},
                {"log_det", finite_or_null(c.mean_log_det)},
                {"widths_95", {{"mean", keyed(spec, c.mean_width)}, {"worst", keyed(spec, c.worst_width)}}}};
  json errors = json::object();
  for (std::size_t q = 0; q < c.model_error.size(); ++q)
    errors[q < names.size() ? names[q] : "f_bilinear"] = {{"relative", c.model_error[q].relative},
                                                          {"verified", c.model_error[q].verified}};
  entry["model_error"] = errors;
  const std::size_t size = static_cast<std::size_t>(spec.size_key);
  json detect = json::array();
  for (std::size_t q = 0; q < figures.detect.position_samples.size(); ++q) {
    json position = json::object();
    for (std::size_t j = 0; j < spec.prior.size(); ++j)
      if (j != size) position[spec.prior[j].key] = figures.grid.samples[figures.detect.position_samples[q]][static_cast<Eigen::Index>(j)];
    detect.push_back({{"position", position}, {"smallest", finite_or_null(c.smallest_crack[q])},
                      {"at_or_below_prior", figures.detect.at_or_below[ci][q]}});
  }
  entry["detectability"] = detect;
  entry["per_sample"] = per_sample_json(spec, figures.sweeps, c);
  return entry;
}

/// The best set of 1..combine sensors for the best candidate's drive, chosen greedily on log det.
json best_sensors_json(const PlanSpec& spec, const PlanFigures& figures) {
  const std::vector<Candidate>& candidates = figures.candidates;
  const Candidate& best = candidates[figures.order.front()];
  const std::size_t n_sensors = spec.sensors.size();
  std::vector<MatrixX> base_fisher;
  std::vector<std::vector<MatrixX>> per_sensor(n_sensors);
  std::vector<std::size_t> same_drive(n_sensors);
  for (std::size_t ci = 0; ci < candidates.size(); ++ci)
    if (candidates[ci].drive == best.drive && candidates[ci].frequency == best.frequency) same_drive[candidates[ci].sensor] = ci;
  for (std::size_t s = 0; s < figures.grid.n_samples; ++s) {
    if (!best.samples[s].responds) continue;
    base_fisher.push_back(best.samples[s].frequency_fisher);
    for (std::size_t i = 0; i < n_sensors; ++i) per_sensor[i].push_back(candidates[same_drive[i]].samples[s].sensor_fisher);
  }
  json sets = json::array();
  std::vector<std::string> chosen;
  json points_of_set = json::array();
  for (const GreedyStep& step : greedy_sensors(base_fisher, per_sensor, spec.combine)) {
    const auto s = static_cast<std::size_t>(step.sensor);
    chosen.push_back(sensor_name(s));
    points_of_set.push_back(point_json(spec.sensors[s]));
    const IntervalWidths widths = interval_widths(step.fisher, spec.prior.size());
    sets.push_back({{"k", chosen.size()},
                    {"sensors", chosen},
                    {"points", points_of_set},
                    {"log_det", finite_or_null(step.log_det)},
                    {"widths_95", {{"mean", keyed(spec, widths.mean)}, {"worst", keyed(spec, widths.worst)}}}});
  }
  return {{"drive", {{"point", point_json(spec.drive_points[best.drive])},
                     {"mode", spec.frequencies[best.frequency].mode},
                     {"ratio", spec.frequencies[best.frequency].ratio}}},
          {"sets", sets}};
}

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

/// The figures of each sensor under drive p, frequency f: the VTU's arrays and a series of the
/// log det plot (the best over the sensors across the face, along its first axis).
study::Series sensor_arrays(const PlanSpec& spec, const PlanFigures& figures, std::size_t p, std::size_t f, int along,
                            std::vector<std::pair<std::string, std::vector<double>>>& arrays,
                            std::vector<std::pair<std::string, std::vector<double>>>& map_panels) {
  const std::size_t n_sensors = spec.sensors.size(), k = spec.prior.size();
  const std::string tag = "d" + std::to_string(p + 1) + "f" + std::to_string(f + 1);
  std::vector<double> det(n_sensors), smallest(n_sensors), responds(n_sensors);
  std::vector<std::vector<double>> widths(k, std::vector<double>(n_sensors));
  for (const Candidate& c : figures.candidates) {
    if (c.drive != p || c.frequency != f) continue;
    det[c.sensor] = std::isfinite(c.mean_log_det) ? c.mean_log_det : kNaN;
    responds[c.sensor] = static_cast<double>(c.responding) / static_cast<double>(figures.grid.n_samples);
    double worst = -kInf;
    for (double value : c.smallest_crack) worst = std::isfinite(value) ? std::max(worst, value) : kInf;
    smallest[c.sensor] = std::isfinite(worst) ? worst : kNaN;
    for (std::size_t j = 0; j < k; ++j) widths[j][c.sensor] = std::isfinite(c.mean_width[j]) ? c.mean_width[j] : kNaN;
  }
  arrays.emplace_back(tag + " log_det", det);
  map_panels.emplace_back(drive_label(spec, p, f), det);
  arrays.emplace_back(tag + " responding fraction", responds);
  arrays.emplace_back(tag + " smallest " + spec.prior[static_cast<std::size_t>(spec.size_key)].key + " (worst position)", smallest);
  for (std::size_t j = 0; j < k; ++j) arrays.emplace_back(tag + " width95 " + spec.prior[j].key, widths[j]);
  study::Series series{drive_label(spec, p, f), {}, {}};
  if (along < 0) {
    for (std::size_t i = 0; i < n_sensors; ++i) {
      series.x.push_back(static_cast<double>(i + 1));
      series.y.push_back(det[i]);
    }
    return series;
  }
  for (int a = 0; a < spec.grid[0]; ++a) {
    double value = kNaN;
    for (int b = 0; b < spec.grid[1]; ++b) {
      const double v = det[static_cast<std::size_t>(a * spec.grid[1] + b)];
      if (std::isfinite(v) && !(v <= value)) value = v;
    }
    series.x.push_back(spec.sensors[static_cast<std::size_t>(a * spec.grid[1])][along]);
    series.y.push_back(value);
  }
  return series;
}

}  // namespace

json plan_document(const PlanRun& run, const PlanFigures& figures) {
  const PlanSpec& spec = run.spec;
  json document;
  document["scene"] = run.file;
  json prior = json::object();
  for (const auto& u : spec.prior) prior[u.key] = {u.lower, u.upper};
  document["prior"] = prior;
  document["size_key"] = spec.prior[static_cast<std::size_t>(spec.size_key)].key;
  document["smaller_crack_towards"] = figures.detect.small_first ? "lower" : "upper";
  document["noise"] = {{"frequency", spec.noise_frequency}, {"ratio", spec.noise_ratio}, {"floor", spec.noise_floor}};
  document["model_error"] = model_error_json(spec, figures.grid, figures.modal);
  document["averaging"] = "log_det: mean over the prior samples where the candidate responds; widths_95: mean and worst "
                          "over them; candidates that respond at every sample rank first";
  document["samples"] = samples_json(spec, figures.grid, figures.modal);
  json ranked = json::array();
  int missing_figures = 0;  // candidate samples with a missing forward value (SampleFigures::missing)
  for (std::size_t r = 0; r < figures.order.size(); ++r) {
    ranked.push_back(candidate_json(spec, figures, r + 1, figures.order[r]));
    for (const SampleFigures& sample : figures.candidates[figures.order[r]].samples) missing_figures += sample.missing;
  }
  document["candidates"] = ranked;
  json notes = json::array();
  if (missing_figures > 0) {
    notes.push_back(std::to_string(missing_figures) +
                    " candidate samples lack a forward value although their drive responds (a sweep did not reach "
                    "its drive frequency; see the warnings in the case folders' sweep.json): counted as not "
                    "responding (per_sample[].missing)");
    run.log << "plan: warning: " << notes.back().get<std::string>() << "\n";
  }
  document["notes"] = notes;
  document["best_sensors"] = best_sensors_json(spec, figures);
  return document;
}

void write_sensor_figures(const PlanRun& run, const PlanFigures& figures, json& files, json& notes) {
  const PlanSpec& spec = run.spec;
  std::vector<std::pair<std::string, std::vector<double>>> arrays, map_panels;
  study::LinePlot plot{"log det F along the sensors (best over the sensors across)", "", "mean log det F", {}};
  const int along = spec.face.empty() ? -1 : std::min(((spec.face[0] - 'x') + 1) % 3, ((spec.face[0] - 'x') + 2) % 3);
  plot.x_label = along < 0 ? "sensor" : std::string(1, static_cast<char>('x' + along)) + " [m]";
  for (std::size_t p = 0; p < spec.drive_points.size(); ++p)
    for (std::size_t f = 0; f < spec.frequencies.size(); ++f)
      plot.series.push_back(sensor_arrays(spec, figures, p, f, along, arrays, map_panels));
  io::write_file_atomic(run.dir / "plan_sensors.vtu", vtu_text(spec, arrays));
  files = json::array({"plan.json", "plan_sensors.vtu"});
  const std::string note = study::plot_lines(run.dir / "plan_log_det.png", plot, "gnuplot");
  if (note.empty()) files.push_back("plan_log_det.png");
  notes = json::array();
  if (!note.empty()) notes.push_back(note);
  if (!spec.face.empty()) {
    const std::string map_note = plot_face_maps(run.dir, spec, "mean log det F", map_panels);
    if (map_note.empty()) files.push_back("plan_map.png");
    else notes.push_back(map_note);
  }
}

}  // namespace crackle::planning::detail
