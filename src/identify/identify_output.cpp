/// \file The files of `crackle identify` (identify_stages.hpp): identify.json, identify_map.csv,
/// identify_profiles.csv, identify_map.png, identify_profiles.png and identify_fit.png.
#include <algorithm>
#include <cmath>
#include <ostream>
#include <sstream>

#include <Eigen/Cholesky>

#include "core/errors.hpp"
#include "identify/identify_stages.hpp"
#include "io/files.hpp"
#include "plot/gnuplot.hpp"
#include "study/plan.hpp"

namespace crackle::identify::detail {
namespace fs = std::filesystem;
using nlohmann::json;

json keyed(const IdentifySpec& spec, const VectorX& v) {
  json out = json::object();
  for (std::size_t j = 0; j < spec.unknowns.size(); ++j) out[spec.unknowns[j].key] = v[static_cast<Eigen::Index>(j)];
  return out;
}

std::string measurement_label(const Measurement& m) {
  return m.quantity + (m.mode > 0 ? " mode " + std::to_string(m.mode) : "") +
         (m.probe.empty() ? "" : " " + m.probe + " @ " + format_number(m.drive_hz) + " Hz");
}

namespace {

json vector_json(const VectorX& v) {
  json out = json::array();
  for (Eigen::Index i = 0; i < v.size(); ++i) out.push_back(std::isfinite(v[i]) ? json(v[i]) : json(nullptr));
  return out;
}

json matrix_json(const MatrixX& m) {
  json out = json::array();
  for (Eigen::Index r = 0; r < m.rows(); ++r) out.push_back(vector_json(m.row(r).transpose()));
  return out;
}


json intervals_json(const IdentifySpec& spec, const fit::Uncertainty& u) {
  json out = json::object();
  for (std::size_t j = 0; j < spec.unknowns.size(); ++j) {
    const auto& interval = u.interval_95[j];
    out[spec.unknowns[j].key] = {std::isfinite(interval[0]) ? json(interval[0]) : json(nullptr),
                                 std::isfinite(interval[1]) ? json(interval[1]) : json(nullptr)};
  }
  return out;
}


/// The Gauss-Newton 95 % joint region of unknowns i and j (the ellipse of their marginal
/// covariance), as gnuplot data; empty where the covariance has no finite positive block.
std::string region_data(const Fitted& best, std::size_t i, std::size_t j) {
  std::ostringstream region;
  if (!best.uncertainty.covariance.allFinite()) return "";
  const Eigen::Index a = static_cast<Eigen::Index>(i), b = static_cast<Eigen::Index>(j);
  Eigen::Matrix2d block;
  block << best.uncertainty.covariance(a, a), best.uncertainty.covariance(a, b), best.uncertainty.covariance(b, a),
      best.uncertainty.covariance(b, b);
  const Eigen::LLT<Eigen::Matrix2d> llt(block);
  if (llt.info() != Eigen::Success) return "";
  const Eigen::Matrix2d l = llt.matrixL();
  const Eigen::Vector2d centre(best.theta[a], best.theta[b]);
  for (int t = 0; t <= 100; ++t) {
    const double angle = 2.0 * M_PI * t / 100.0;
    const Eigen::Vector2d p = centre + std::sqrt(kChi2Two95) * l * Eigen::Vector2d(std::cos(angle), std::sin(angle));
    region << p[0] << " " << p[1] << "\n";
  }
  return region.str();
}

/// gnuplot data of a misfit over two axes (row-major over the first): x y log10(chi^2), a blank line
/// after each row.
std::string surface_data(const std::vector<double>& x, const std::vector<double>& y, const std::vector<double>& chi2) {
  std::ostringstream data;
  for (std::size_t a = 0; a < x.size(); ++a) {
    for (std::size_t b = 0; b < y.size(); ++b)
      data << x[a] << " " << y[b] << " " << std::log10(chi2[a * y.size() + b] + 1e-300) << "\n";
    data << "\n";
  }
  return data.str();
}

/// identify_map.png: chi^2 over the first two unknowns (or one; with more, its profile: the least
/// over the others), the minima, the estimate and its 95 % joint region (the Gauss-Newton ellipse).
/// Never throws: returns a note on failure.
std::string plot_map(const fs::path& dir, const IdentifySpec& spec, const std::vector<std::vector<double>>& axes,
                     const std::vector<double>& chi2, const std::vector<Fitted>& minima, const Fitted& best) {
  plot::PlotOptions probe;
  if (!plot::gnuplot_available(probe)) return "gnuplot not found: no plots";
  std::ostringstream data, marks, script;
  const std::size_t k = spec.unknowns.size();
  if (k > 1) {
    data << surface_data(axes[0], axes[1], chi2);
  } else {
    for (std::size_t flat = 0; flat < chi2.size(); ++flat) data << axes[0][flat] << " 0 " << std::log10(chi2[flat] + 1e-300) << "\n";
  }
  for (const Fitted& m : minima) marks << m.theta[0] << " " << (k > 1 ? m.theta[1] : m.chi2) << "\n";
  io::write_file_atomic(dir / "identify_map.dat", "# " + spec.unknowns[0].key + (k > 1 ? " " + spec.unknowns[1].key : "") +
                                                      " log10(chi2)\n" + data.str());
  io::write_file_atomic(dir / "identify_minima.dat", marks.str());
  io::write_file_atomic(dir / "identify_region.dat", k > 1 ? region_data(best, 0, 1) : "");
  script << "# gnuplot script written by crackle identify; run: gnuplot identify_map.gp\n"
         << "set terminal pngcairo size 900,700 noenhanced\nset output 'identify_map.png'\n";
  script << "set xlabel " << plot::gnuplot_quote(spec.unknowns[0].key) << "\n"
         << "set xrange [" << spec.unknowns[0].lower << ":" << spec.unknowns[0].upper << "]\n";
  if (k > 1) script << "set yrange [" << spec.unknowns[1].lower << ":" << spec.unknowns[1].upper << "]\n";
  if (k > 1) {
    script << "set ylabel " << plot::gnuplot_quote(spec.unknowns[1].key) << "\n"
           << "set title '" << (k > 2 ? "misfit profile log10(chi^2) (least over the other unknowns)" : "misfit log10(chi^2)")
           << ", the minima (circles) and the 95 % region of the estimate'\n"
           << "set view map\nset pm3d map interpolate 4,4\nset palette rgb 33,13,10\n"
           << "splot 'identify_map.dat' using 1:2:3 with pm3d notitle, "
           << "'identify_minima.dat' using 1:2:(0) with points pt 7 ps 1.5 lc rgb 'white' title 'minima', "
           << "'identify_region.dat' using 1:2:(0) with lines lw 2 lc rgb 'white' title '95 %'\n";
  } else {
    script << "set ylabel 'log10(chi^2)'\nplot 'identify_map.dat' using 1:3 with linespoints title 'map', "
           << "'identify_minima.dat' using 1:(log10($2)) with points pt 7 ps 1.5 title 'minima'\n";
  }
  io::write_file_atomic(dir / "identify_map.gp", script.str());
  const plot::PlotResult drawn = plot::run_gnuplot(dir / "identify_map.png", dir / "identify_map.gp", probe);
  return drawn.written ? "" : drawn.note;
}

/// identify_profiles.png (three unknowns or more): one panel per pair of unknowns, its profile
/// log10(chi^2), the estimate and the Gauss-Newton 95 % region of the pair. Never throws.
std::string plot_profiles(const fs::path& dir, const IdentifySpec& spec, const std::vector<std::vector<double>>& axes,
                          const std::vector<fit::Profile>& profiles, const Fitted& best) {
  plot::PlotOptions probe;
  if (!plot::gnuplot_available(probe)) return "gnuplot not found: no plots";
  const std::size_t panels = profiles.size();
  const std::size_t columns = std::min<std::size_t>(panels, 3), rows = (panels + columns - 1) / columns;
  std::ostringstream script;
  script << "# gnuplot script written by crackle identify; run: gnuplot identify_profiles.gp\n"
         << "set terminal pngcairo size " << 500 * columns << "," << 450 * rows << " noenhanced\n"
         << "set output 'identify_profiles.png'\nset view map\nset pm3d map interpolate 4,4\n"
         << "set palette rgb 33,13,10\nunset key\nset lmargin 12\nset xtics rotate by -30\nset multiplot layout " << rows << "," << columns
         << " title 'misfit profiles log10(chi^2): the least over the other unknowns; the estimate and its 95 % region'\n";
  for (std::size_t q = 0; q < panels; ++q) {
    const fit::Profile& p = profiles[q];
    const std::string name = "identify_profile_" + std::to_string(p.first + 1) + "_" + std::to_string(p.second + 1);
    io::write_file_atomic(dir / (name + ".dat"), "# " + spec.unknowns[p.first].key + " " + spec.unknowns[p.second].key +
                                                     " log10(chi2)\n" + surface_data(axes[p.first], axes[p.second], p.chi2));
    io::write_file_atomic(dir / (name + "_region.dat"), region_data(best, p.first, p.second));
    std::ostringstream estimate;
    estimate << best.theta[static_cast<Eigen::Index>(p.first)] << " " << best.theta[static_cast<Eigen::Index>(p.second)] << "\n";
    io::write_file_atomic(dir / (name + "_estimate.dat"), estimate.str());
    const Unknown& x = spec.unknowns[p.first];
    const Unknown& y = spec.unknowns[p.second];
    script << "set xlabel " << plot::gnuplot_quote(x.key) << "\nset ylabel " << plot::gnuplot_quote(y.key) << "\n"
           << "set xrange [" << x.lower << ":" << x.upper << "]\nset yrange [" << y.lower << ":" << y.upper << "]\n"
           << "splot '" << name << ".dat' using 1:2:3 with pm3d, '" << name
           << "_region.dat' using 1:2:(0) with lines lw 2 lc rgb 'white', '" << name
           << "_estimate.dat' using 1:2:(0) with points pt 7 ps 1.2 lc rgb 'white'\n";
  }
  script << "unset multiplot\n";
  io::write_file_atomic(dir / "identify_profiles.gp", script.str());
  const plot::PlotResult drawn = plot::run_gnuplot(dir / "identify_profiles.png", dir / "identify_profiles.gp", probe);
  return drawn.written ? "" : drawn.note;
}

std::string plot_fit(const fs::path& dir, const IdentifySpec& spec, const Fitted& best, const VectorX& weights) {
  plot::PlotOptions probe;
  if (!plot::gnuplot_available(probe)) return "gnuplot not found: no plots";
  std::ostringstream data;
  data << "# index measured sigma model weight(sqrt(sigma^2+eps^2)) label\n";
  for (std::size_t i = 0; i < spec.measured.size(); ++i) {
    const Measurement& m = spec.measured[i];
    data << i + 1 << " " << m.value << " " << m.sigma << " " << best.model[static_cast<Eigen::Index>(i)] << " "
         << weights[static_cast<Eigen::Index>(i)] << " \"" << measurement_label(m) << "\"\n";
  }
  plot::PlotOptions options;
  options.title = "measured (sigma bars) against fitted (model-error bars), normalised by the measured value";
  options.width = 900;
  const std::string body =
      "set ylabel 'value / measured [-]'\nset xtics rotate by -30\nset offsets 0.5,0.5,0,0\n"
      "plot 'identify_fit.dat' using 1:(1):($3/$2):xtic(6) with yerrorbars pt 7 title 'measured', "
      "'' using ($1+0.1):($4/$2):($5/$2) with yerrorbars pt 5 title 'fitted'\n";
  const plot::PlotResult drawn = plot::plot_script(dir / "identify_fit.png", data.str(), body, options);
  return drawn.written ? "" : drawn.note;
}

/// identify.json's profiles: each pair's unknowns, axes and chi^2 (rows over the first).
json profiles_json(const IdentifyFigures& f) {
  const IdentifySpec& spec = f.spec;
  json list = json::array();
  for (const fit::Profile& p : f.profiles) {
    json rows = json::array();
    for (std::size_t a = 0; a < f.axes[p.first].size(); ++a) {
      json row = json::array();
      for (std::size_t b = 0; b < f.axes[p.second].size(); ++b) {
        const double value = p.chi2[a * f.axes[p.second].size() + b];
        row.push_back(std::isfinite(value) ? json(value) : json(nullptr));
      }
      rows.push_back(row);
    }
    list.push_back({{"unknowns", {spec.unknowns[p.first].key, spec.unknowns[p.second].key}},
                    {"axes", {f.axes[p.first], f.axes[p.second]}},
                    {"chi2", rows},
                    {"method", spec.unknowns.size() == 2 ? "the map" : "least over the other unknowns on the map's interpolant"}});
  }
  return list;
}

/// identify.json's residuals: per measurement, the model value, the normalised residual, the model error.
json residuals_json(const IdentifyFigures& f) {
  json list = json::array();
  const Fitted& best = f.best();
  for (std::size_t i = 0; i < f.spec.measured.size(); ++i) {
    const Measurement& m = f.spec.measured[i];
    const Eigen::Index ii = static_cast<Eigen::Index>(i);
    json row = {{"quantity", m.quantity}, {"value", m.value}, {"sigma", m.sigma},
                {"model", std::isfinite(best.model[ii]) ? json(best.model[ii]) : json(nullptr)},
                {"model_error", f.model_error[ii] * std::abs(f.values[ii])},
                {"model_error_verified", static_cast<bool>(f.error_verified[i])},
                {"normalised", best.residuals[ii]}};
    if (m.mode > 0) row["mode"] = m.mode;
    if (!m.probe.empty()) row["probe"] = m.probe;
    if (m.drive_hz > 0) row["drive_hz"] = m.drive_hz;
    list.push_back(row);
  }
  return list;
}

}  // namespace

json identify_json(const IdentifyFigures& f) {
  const IdentifySpec& spec = f.spec;
  const std::size_t k = spec.unknowns.size(), n = spec.measured.size();
  const Fitted& best = f.best();
  json document;
  document["estimate"] = keyed(spec, best.theta);
  document["interval_95"] = intervals_json(spec, best.uncertainty);
  document["sd"] = keyed(spec, best.uncertainty.sd);
  document["covariance"] = matrix_json(best.uncertainty.covariance);
  document["correlation"] = matrix_json(best.uncertainty.correlation);
  document["unknowns"] = json::array();
  for (const Unknown& u : spec.unknowns) document["unknowns"].push_back({{"key", u.key}, {"bounds", {u.lower, u.upper}}});
  document["minima"] = json::array();
  for (const Fitted& m : f.minima) {
    json at_bound = json::object();
    for (std::size_t j = 0; j < k; ++j) at_bound[spec.unknowns[j].key] = static_cast<bool>(m.at_bound[j]);
    document["minima"].push_back({{"estimate", keyed(spec, m.theta)}, {"misfit", m.chi2},
                                  {"interval_95", intervals_json(spec, m.uncertainty)}, {"at_bound", at_bound},
                                  {"converged", m.converged}});
  }
  document["identifiable"] = f.reasons.empty();
  document["reasons"] = f.reasons;
  document["residuals"] = residuals_json(f);
  document["chi2"] = best.chi2;
  document["dof"] = static_cast<int>(n) - static_cast<int>(k);
  document["sigma"] = spec.scale_by_fit ? "scaled" : "trusted";
  document["t_quantile"] = best.uncertainty.t;
  document["reference_crack"] = {{"at", f.reference_at}};
  document["map"] = {{"points_per_unknown", spec.map_points}, {"runs", static_cast<int>(f.grid.size())},
                     {"folder", f.map_dir.string()}, {"best_chi2", f.best_map}, {"minima_kept", f.starts}};
  document["profiles"] = profiles_json(f);
  document["local_fits"] = {{"gauss_newton_iterations", f.gauss_newton},
                             {"levenberg_marquardt", f.levenberg_marquardt},
                             {"from_map_point", f.from_map_point}};
  return document;
}

void write_identify_tables(const fs::path& dir, const IdentifyFigures& f) {
  const IdentifySpec& spec = f.spec;
  const std::size_t k = spec.unknowns.size();
  std::ostringstream csv;
  for (std::size_t j = 0; j < k; ++j)
    csv << study::key_header(spec.unknowns[j].path) +
               (spec.unknowns[j].index >= 0 ? "[" + std::to_string(spec.unknowns[j].index) + "]" : "")
        << ",";
  csv << "chi2 [-]\n";
  for (std::size_t flat = 0; flat < f.grid.size(); ++flat) {
    for (std::size_t j = 0; j < k; ++j) csv << format_number(f.grid[flat][static_cast<Eigen::Index>(j)]) << ",";
    csv << (std::isfinite(f.map_chi2[flat]) ? format_number(f.map_chi2[flat]) : "") << "\n";
  }
  io::write_file_atomic(dir / "identify_map.csv", csv.str());
  if (f.profiles.empty()) return;
  std::ostringstream table;
  table << "unknown_x,unknown_y,x,y,chi2 [-]\n";
  for (const fit::Profile& p : f.profiles)
    for (std::size_t a = 0; a < f.axes[p.first].size(); ++a)
      for (std::size_t b = 0; b < f.axes[p.second].size(); ++b) {
        const double value = p.chi2[a * f.axes[p.second].size() + b];
        table << spec.unknowns[p.first].key << "," << spec.unknowns[p.second].key << "," << format_number(f.axes[p.first][a])
              << "," << format_number(f.axes[p.second][b]) << "," << (std::isfinite(value) ? format_number(value) : "") << "\n";
      }
  io::write_file_atomic(dir / "identify_profiles.csv", table.str());
}

void draw_identify_plots(const fs::path& dir, const IdentifyFigures& f, std::vector<std::string>& notes) {
  const std::size_t k = f.spec.unknowns.size();
  const std::vector<double>& shown = k > 2 ? f.profiles.front().chi2 : f.map_chi2;
  if (std::string note = plot_map(dir, f.spec, f.axes, shown, f.minima, f.best()); !note.empty()) notes.push_back(note);
  if (k > 2)
    if (std::string note = plot_profiles(dir, f.spec, f.axes, f.profiles, f.best()); !note.empty()) notes.push_back(note);
  if (std::string note = plot_fit(dir, f.spec, f.best(), f.weights); !note.empty()) notes.push_back(note);
}

void print_identify_summary(std::ostream& log, const IdentifyFigures& f, int forward_runs,
                            const std::vector<std::string>& notes) {
  const std::size_t k = f.spec.unknowns.size(), n = f.spec.measured.size();
  const Fitted& best = f.best();
  for (std::size_t j = 0; j < k; ++j) {
    const auto& interval = best.uncertainty.interval_95[j];
    log << "  " << f.spec.unknowns[j].key << " = " << format_number(best.theta[static_cast<Eigen::Index>(j)])
        << "  95 %: [" << format_number(interval[0]) << ", " << format_number(interval[1]) << "]\n";
  }
  log << "  chi2 = " << format_number(best.chi2) << " (" << n << " measurements, " << k << " unknowns), "
      << forward_runs << " forward runs, " << (f.reasons.empty() ? "identifiable" : "NOT identifiable") << "\n";
  for (const std::string& reason : f.reasons) log << "  not identifiable: " << reason << "\n";
  for (const std::string& note : notes) log << "  note: " << note << "\n";
}

}  // namespace crackle::identify::detail
