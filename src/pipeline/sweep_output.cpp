/// \file The sweep's files (pipeline/sweep.hpp): sweep.csv's table, sweep.json's settings, events
/// and peaks, and the response-curve plots.
#include "pipeline/sweep.hpp"

#include <algorithm>
#include <cmath>
#include <functional>
#include <limits>

#include "core/errors.hpp"

namespace crackle::pipeline {
namespace {

/// "1", "2", "1/2", "3/2": an order k / nu of the excitation frequency.
std::string order_label(int k, int nu) {
  if (k % nu == 0) return std::to_string(k / nu);
  return std::to_string(k) + "/" + std::to_string(nu);
}

/// Amplitude of order k / nu of a probe at a point (nu the sweep's: a period-one point of a
/// `subharmonic: 2` sweep has no odd k).
double amplitude_of(const SweepPoint& point, const SweepProbe& probe, int k, int nu) {
  return point.solution.amplitude(probe.row, double(k) / nu);
}

/// The frequency and value of the largest `value(point)`, refined by a parabola through the three
/// points around it (on a monotonic stretch of the branch). A largest value at the first or last
/// point of a branch that stepped past the end of the range is taken at that end (linear between the
/// two points around it; `at_end`), so that it does not depend on how far the last step overshot.
/// A sweep over windows of the range looks within the window of the largest value only, and says
/// `window_edge` when that value is a window's end inside the range (the peak may lie outside it).
nlohmann::json peak(const SweepResult& result, const SweepSettings& settings,
                    const std::function<double(const SweepPoint&)>& value) {
  const auto& points = result.points;
  if (points.empty()) return nullptr;
  std::size_t best = 0;
  for (std::size_t i = 1; i < points.size(); ++i)
    if (value(points[i]) > value(points[best])) best = i;
  std::size_t first = 0, last = points.size() - 1;  // the stretch of points around `best`
  const bool windowed = !settings.windows.empty();
  if (windowed) {
    while (first < best && points[first].segment != points[best].segment) ++first;
    while (last > best && points[last].segment != points[best].segment) --last;
  }
  double f = points[best].frequency_hz(), y = value(points[best]);
  if (last > first && (best == first || best == last)) {
    const std::size_t inner = best == first ? first + 1 : best - 1;
    const double end = best == first ? settings.from_hz : settings.to_hz;
    const double fi = points[inner].frequency_hz();
    if ((f - end) * (fi - end) < 0.0) {  // the end lies between the last two points
      y = value(points[inner]) + (y - value(points[inner])) * (end - fi) / (f - fi);
      return {{"frequency_hz", end}, {"value", y}, {"point", best}, {"at_end", true}};
    }
  }
  if (best > first && best < last) {
    const double x0 = points[best - 1].frequency_hz(), x1 = f, x2 = points[best + 1].frequency_hz();
    const double y0 = value(points[best - 1]), y1 = y, y2 = value(points[best + 1]);
    const bool monotonic = (x0 < x1 && x1 < x2) || (x0 > x1 && x1 > x2);
    const double d01 = (y1 - y0) / (x1 - x0), d12 = (y2 - y1) / (x2 - x1), curvature = (d12 - d01) / (x2 - x0);
    if (monotonic && curvature < 0.0) {
      const double vertex = 0.5 * (x0 + x1) - d01 / (2.0 * curvature);
      if (vertex > std::min(x0, x2) && vertex < std::max(x0, x2)) {
        f = vertex;
        y = y1 + d01 * (vertex - x1) + curvature * (vertex - x0) * (vertex - x1);
      }
    }
  }
  nlohmann::json found = {{"frequency_hz", f}, {"value", y}, {"point", best}};
  if (windowed) {
    const auto& window = settings.windows.at(static_cast<std::size_t>(points[best].segment));
    found["window_edge"] = (best == first && window.first > 0.0) || (best == last && window.second < 1.0);
  }
  return found;
}

}  // namespace

io::CsvTable sweep_table(const SweepResult& result, const SweepSettings& settings) {
  const int harmonics = settings.section.harmonics, nu = settings.section.subharmonic;
  const auto column = [&](const std::function<double(const SweepPoint&)>& value) {
    std::vector<double> values;
    for (const SweepPoint& point : result.points) values.push_back(value(point));
    return values;
  };
  io::CsvTable table;
  table.add("excitation frequency [Hz]", column([](const SweepPoint& p) { return p.frequency_hz(); }));
  for (const SweepProbe& probe : settings.probes) {
    const std::string prefix = probe.name + " u_" + axis_name(probe.component) + " ";
    for (int k = 0; k <= harmonics; ++k) {
      const std::string order = order_label(k, nu);
      table.add(prefix + "A" + order + " [m]", column([&](const SweepPoint& p) { return amplitude_of(p, probe, k, nu); }));
      table.add(prefix + "phase" + order + " [rad]",
                column([&](const SweepPoint& p) { return p.solution.phase(probe.row, double(k) / nu); }));
    }
    table.add(prefix + "A2/A1 [-]", column([&](const SweepPoint& p) { return p.solution.ratios(probe.row).second; }));
    table.add(prefix + "A3/A1 [-]", column([&](const SweepPoint& p) { return p.solution.ratios(probe.row).third; }));
    table.add(prefix + "A1/2/A1 [-]", column([&](const SweepPoint& p) { return p.solution.ratios(probe.row).half; }));
  }
  table.add("stable [1 yes, 0 no, -1 not computed]",
            column([](const SweepPoint& p) { return p.stability_known ? double(p.stable) : -1.0; }));
  table.add("newton iterations [-]", column([](const SweepPoint& p) { return double(p.solution.iterations); }));
  table.add("residual [-]", column([](const SweepPoint& p) { return p.solution.residual; }));
  table.add("top harmonic share [-]", column([](const SweepPoint& p) { return p.solution.top_harmonic_share; }));
  table.add("direction [1 up, -1 down]", column([](const SweepPoint& p) { return double(p.direction); }));
  table.add("periods [-]", column([](const SweepPoint& p) { return double(p.periods); }));
  table.add("branch period [excitation periods]", column([](const SweepPoint& p) { return double(p.solution.subharmonic); }));
  return table;
}

nlohmann::json sweep_json(const SweepResult& result, const SweepSettings& settings) {
  const scene::SweepSection& section = settings.section;
  nlohmann::json document = {
      {"settings", {{"from_hz", settings.from_hz}, {"to_hz", settings.to_hz}, {"harmonics", section.harmonics},
                    {"subharmonic", section.subharmonic}, {"method", section.method}, {"stability", section.stability},
                    {"stability_method", "Floquet multipliers from the monodromy matrix at every point; Hill's method "
                                         "at the two points around each stability change (hill_agrees)"},
                    {"points", section.points}, {"tolerance", section.tolerance}, {"max_periods", section.max_periods}}},
      {"bilinear_hz", settings.bilinear_hz > 0.0 ? nlohmann::json(settings.bilinear_hz) : nlohmann::json(nullptr)},
      {"points", result.points.size()}, {"completed", result.completed}, {"max_top_share", result.max_top_share},
      {"warnings", result.warnings}, {"solve_s", result.solve_s},
      {"amplitude_convention", "peak amplitude A_k of u(t) = sum A_k cos(2 pi k f t + phi_k), f the excitation "
                               "frequency, phases relative to the load cos(2 pi f t)"}};
  if (!settings.windows.empty()) {  // fractions of the range, each swept as a segment of its own
    nlohmann::json windows = nlohmann::json::array();
    for (const auto& [begin, end] : settings.windows) windows.push_back({begin, end});
    document["settings"]["windows"] = windows;
  }
  nlohmann::json events = nlohmann::json::array();
  for (const SweepEvent& event : result.events) {
    nlohmann::json entry = {{"kind", event.kind}, {"frequency_hz", event.frequency_hz}, {"point", event.point}};
    if (settings.bilinear_hz > 0.0) entry["ratio_to_bilinear"] = event.frequency_hz / settings.bilinear_hz;
    if (event.hill_check >= 0) entry["hill_agrees"] = event.hill_check == 1;
    events.push_back(entry);
  }
  document["events"] = events;
  if (!result.linear_solver.empty()) {
    nlohmann::json linear = {{"kind", result.linear_solver}};
    if (result.linear_solver == "krylov")
      linear.update({{"gmres_solves", result.krylov.solves}, {"gmres_iterations", result.krylov.iterations},
                     {"gmres_max_iterations", result.krylov.max_iterations},
                     {"preconditioner", sweep::KrylovOptions{}.preconditioner ==
                                                sweep::KrylovPreconditioner::pair_blocks
                                            ? "mean_stiffness+pair_blocks"
                                            : "mean_stiffness"},
                     {"preconditioner_factors", result.krylov.factorisations},
                     {"gmres_unconverged", result.krylov.unconverged}});
    document["linear_solver"] = linear;
  }
  nlohmann::json probes = nlohmann::json::object();
  for (const SweepProbe& probe : settings.probes) {
    const auto ratio = [&](double order) {
      return [&probe, order](const SweepPoint& p) {
        const double a1 = p.solution.amplitude(probe.row, 1.0);
        return a1 > 0.0 ? p.solution.amplitude(probe.row, order) / a1 : 0.0;
      };
    };
    probes[probe.name] = {{"component", axis_name(probe.component)}, {"unit", "m"},
                          {"peak_a1", peak(result, settings, [&](const SweepPoint& p) { return p.solution.amplitude(probe.row, 1.0); })},
                          {"peak_a2_over_a1", peak(result, settings, ratio(2.0))},
                          {"peak_a3_over_a1", peak(result, settings, ratio(3.0))}};
    if (section.subharmonic == 2) probes[probe.name]["peak_a_half_over_a1"] = peak(result, settings, ratio(0.5));
  }
  document["probes"] = probes;
  return document;
}

plot::PlotResult plot_sweep(const std::filesystem::path& png, const SweepResult& result,
                                const SweepSettings& settings, std::size_t probe_index,
                                const plot::PlotOptions& options) {
  const SweepProbe& probe = settings.probes.at(probe_index);
  const int nu = settings.section.subharmonic;
  std::vector<int> orders = {nu, 2 * nu, 3 * nu};  // A1, A2, A3 as k of the base frequency
  if (nu == 2) orders.push_back(1);
  double largest = 0.0;
  for (const SweepPoint& point : result.points) largest = std::max(largest, amplitude_of(point, probe, nu, nu));
  const double floor = largest > 0.0 ? 1e-12 * largest : 1e-300;
  // Stable runs in data block 0, unstable runs in block 1, each run carried on to the next one's first point.
  // An order below the floor (round-off, or A1/2 of a period-one point) is not drawn (nan): on the log
  // scale it would pull the axis down to the round-off.
  std::string blocks[2];
  const auto row = [&](const SweepPoint& point) {
    std::string line = shortest_text(point.frequency_hz());
    for (int k : orders) {
      const double amplitude = amplitude_of(point, probe, k, nu);
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
