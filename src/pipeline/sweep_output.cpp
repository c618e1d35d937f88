/// \file The sweep's plots (pipeline/sweep.hpp): the response curve of a probe; sweep.json and
/// sweep.csv are output/sweep_json.hpp's.
#include "pipeline/sweep.hpp"

#include <algorithm>
#include <cmath>
#include <string>
#include <utility>
#include <vector>

#include "core/errors.hpp"
#include "output/sweep_json.hpp"

namespace crackle::pipeline {

output::SweepFileSettings file_settings(const SweepSettings& settings) {
  output::SweepFileSettings file;
  file.from_hz = settings.from_hz;
  file.to_hz = settings.to_hz;
  file.bilinear_hz = settings.bilinear_hz;
  file.harmonics = settings.section.harmonics;
  file.subharmonic = settings.section.subharmonic;
  file.method = scene::method_name(settings.section.method);
  file.stability = settings.section.stability;
  file.points = settings.section.points;
  file.tolerance = settings.section.tolerance;
  file.max_periods = settings.section.max_periods;
  file.probes = settings.probes;
  file.windows = settings.windows;
  return file;
}

plot::PlotResult plot_sweep(const std::filesystem::path& png, const SweepResult& result,
                                const SweepSettings& settings, std::size_t probe_index,
                                const plot::PlotOptions& options) {
  const SweepProbe& probe = settings.probes.at(probe_index);
  const int nu = settings.section.subharmonic;
  std::vector<int> orders = {nu, 2 * nu, 3 * nu};  // A1, A2, A3 as k of the base frequency
  if (nu == 2) orders.push_back(1);
  double largest = 0.0;
  for (const SweepPoint& point : result.points) largest = std::max(largest, output::amplitude_of(point, probe, nu, nu));
  const double floor = largest > 0.0 ? 1e-12 * largest : 1e-300;
  // Stable runs in data block 0, unstable runs in block 1, each run carried on to the next one's first point.
  // An order below the floor (round-off, or A1/2 of a period-one point) is not drawn (nan): on the log
  // scale it would pull the axis down to the round-off.
  std::string blocks[2];
  const auto row = [&](const SweepPoint& point) {
    std::string line = shortest_text(point.frequency_hz());
    for (int k : orders) {
      const double amplitude = output::amplitude_of(point, probe, k, nu);
      line += " " + (amplitude > floor ? shortest_text(amplitude) : std::string("nan"));
    }
    return line + "\n";
  };
  int current = 0;
  for (std::size_t i = 0; i < result.points.size(); ++i) {
    const SweepPoint& point = result.points[i];
    const int kind = point.stable ? 0 : 1;
    const bool turned = i > 0 && (point.direction != result.points[i - 1].direction ||
                                  point.segment != result.points[i - 1].segment);
    if (i > 0 && (kind != current || turned)) {
      if (!turned) blocks[current] += row(point);  // the run goes on to where the next one starts
      blocks[current] += "\n";
    }
    blocks[kind] += row(point);
    current = kind;
  }
  while (!blocks[0].empty() && blocks[0].back() == '\n') blocks[0].pop_back();  // exactly two blank lines follow
  if (!blocks[0].empty()) blocks[0] += "\n";
  const std::string unit = "[" + options.unit + "]";
  const std::string empty_row = "nan nan nan nan nan\n";
  std::string data = "# excitation frequency [Hz], then A1, A2, A3" + std::string(nu == 2 ? ", A1/2 " : " ") + unit +
                     "; block 0 stable, block 1 unstable\n" + (blocks[0].empty() ? empty_row : blocks[0]) + "\n\n" +
                     (blocks[1].empty() ? empty_row : blocks[1]);
  std::string body = "set logscale y\nset xlabel 'excitation frequency [Hz]'\nset ylabel " +
                     plot::gnuplot_quote(options.quantity + " amplitude " + unit) + "\nset key outside right\n";
  const double low = std::min(settings.from_hz, settings.to_hz), high = std::max(settings.from_hz, settings.to_hz);
  body += "set xrange [" + shortest_text(low) + ":" + shortest_text(high) + "]\n";
  if (settings.bilinear_hz > 0.0) {
    for (const auto& [divisor, label] : std::vector<std::pair<double, std::string>>{{2, "f_b/2"}, {3, "f_b/3"}, {1, "f_b"}, {0.5, "2 f_b"}}) {
      const double x = settings.bilinear_hz / divisor;
      if (x < low || x > high) continue;
      body += "set arrow from " + shortest_text(x) + ", graph 0 to " + shortest_text(x) +
              ", graph 1 nohead dashtype 3 linecolor rgb 'gray50'\n";
      body += "set label " + plot::gnuplot_quote(label) + " at " + shortest_text(x) + ", graph 0.97 center front\n";
    }
  }
  const std::string file = plot::gnuplot_quote(std::filesystem::path(png).replace_extension(".dat").filename().string());
  const char* names[] = {"A1", "A2", "A3", "A1/2"};
  const char* colours[] = {"#1f77b4", "#d62728", "#2ca02c", "#9467bd"};
  std::string plots;
  for (std::size_t c = 0; c < orders.size(); ++c) {
    const std::string style = " using 1:" + std::to_string(c + 2) + " with lines linewidth 2 linecolor rgb '" + colours[c] + "'";
    plots += std::string(plots.empty() ? "plot " : ", \\\n     ") + file + " index 0" + style + " title '" + names[c] + "'";
    if (!blocks[1].empty()) plots += ", \\\n     " + file + " index 1" + style + " dashtype 2 title '" + names[c] + " unstable'";
  }
  return plot::plot_script(png, data, body + plots + "\n", options);
}


}  // namespace crackle::pipeline
