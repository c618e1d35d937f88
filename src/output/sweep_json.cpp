/// \file sweep.json and sweep.csv (output/sweep_json.hpp).
#include "output/sweep_json.hpp"

#include <algorithm>
#include <cmath>
#include <functional>

#include <nlohmann/json.hpp>

namespace crackle::output {
namespace {

/// "1", "2", "1/2", "3/2": an order k / nu of the excitation frequency (sweep.csv's column names).
std::string order_label(int k, int nu) {
  if (k % nu == 0) return std::to_string(k / nu);
  return std::to_string(k) + "/" + std::to_string(nu);
}

/// The frequency and value of the largest `value(point)`, refined by a parabola through the three
/// points around it (on a monotonic stretch of the branch). A largest value at the first or last
/// point of a branch that stepped past the end of the range is taken at that end (linear between the
/// two points around it; `at_end`), so that it does not depend on how far the last step overshot.
/// A sweep over windows of the range looks within the window of the largest value only, and says
/// `window_edge` when that value is a window's end inside the range (the peak may lie outside it).
nlohmann::json peak(const sweep::SweepResult& result, const SweepFileSettings& settings,
                    const std::function<double(const sweep::SweepPoint&)>& value) {
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

double amplitude_of(const sweep::SweepPoint& point, const sweep::SweepProbe& probe, int k, int nu) {
  return point.solution.amplitude(probe.row, double(k) / nu);
}

io::CsvTable sweep_table(const sweep::SweepResult& result, const SweepFileSettings& settings) {
  const int harmonics = settings.harmonics, nu = settings.subharmonic;
  const auto column = [&](const std::function<double(const sweep::SweepPoint&)>& value) {
    std::vector<double> values;
    for (const sweep::SweepPoint& point : result.points) values.push_back(value(point));
    return values;
  };
  io::CsvTable table;
  table.add("excitation frequency [Hz]", column([](const sweep::SweepPoint& p) { return p.frequency_hz(); }));
  for (const sweep::SweepProbe& probe : settings.probes) {
    const std::string prefix = probe.name + " u_" + axis_name(probe.component) + " ";
    for (int k = 0; k <= harmonics; ++k) {
      const std::string order = order_label(k, nu);
      table.add(prefix + "A" + order + " [m]", column([&](const sweep::SweepPoint& p) { return amplitude_of(p, probe, k, nu); }));
      table.add(prefix + "phase" + order + " [rad]",
                column([&](const sweep::SweepPoint& p) { return p.solution.phase(probe.row, double(k) / nu); }));
    }
    table.add(prefix + "A2/A1 [-]", column([&](const sweep::SweepPoint& p) { return p.solution.ratios(probe.row).second; }));
    table.add(prefix + "A3/A1 [-]", column([&](const sweep::SweepPoint& p) { return p.solution.ratios(probe.row).third; }));
    table.add(prefix + "A1/2/A1 [-]", column([&](const sweep::SweepPoint& p) { return p.solution.ratios(probe.row).half; }));
  }
  table.add("stable [1 yes, 0 no, -1 not computed]",
            column([](const sweep::SweepPoint& p) { return p.stability_known ? double(p.stable) : -1.0; }));
  table.add("newton iterations [-]", column([](const sweep::SweepPoint& p) { return double(p.solution.iterations); }));
  table.add("residual [-]", column([](const sweep::SweepPoint& p) { return p.solution.residual; }));
  table.add("top harmonic share [-]", column([](const sweep::SweepPoint& p) { return p.solution.top_harmonic_share; }));
  table.add("direction [1 up, -1 down]", column([](const sweep::SweepPoint& p) { return double(p.direction); }));
  table.add("periods [-]", column([](const sweep::SweepPoint& p) { return double(p.periods); }));
  table.add("branch period [excitation periods]", column([](const sweep::SweepPoint& p) { return double(p.solution.subharmonic); }));
  return table;
}

nlohmann::json sweep_json(const sweep::SweepResult& result, const SweepFileSettings& settings) {
  nlohmann::json document = {
      {"settings", {{"from_hz", settings.from_hz}, {"to_hz", settings.to_hz}, {"harmonics", settings.harmonics},
                    {"subharmonic", settings.subharmonic}, {"method", settings.method}, {"stability", settings.stability},
                    {"stability_method", "Floquet multipliers from the monodromy matrix at every point; Hill's method "
                                         "at the two points around each stability change (hill_agrees)"},
                    {"points", settings.points}, {"tolerance", settings.tolerance}, {"max_periods", settings.max_periods}}},
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
  for (const sweep::SweepEvent& event : result.events) {
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
  for (const sweep::SweepProbe& probe : settings.probes) {
    const auto ratio = [&](double order) {
      return [&probe, order](const sweep::SweepPoint& p) {
        const double a1 = p.solution.amplitude(probe.row, 1.0);
        return a1 > 0.0 ? p.solution.amplitude(probe.row, order) / a1 : 0.0;
      };
    };
    probes[probe.name] = {{"component", axis_name(probe.component)}, {"unit", "m"},
                          {"peak_a1", peak(result, settings, [&](const sweep::SweepPoint& p) { return p.solution.amplitude(probe.row, 1.0); })},
                          {"peak_a2_over_a1", peak(result, settings, ratio(2.0))},
                          {"peak_a3_over_a1", peak(result, settings, ratio(3.0))}};
    if (settings.subharmonic == 2) probes[probe.name]["peak_a_half_over_a1"] = peak(result, settings, ratio(0.5));
  }
  document["probes"] = probes;
  return document;
}

}  // namespace crackle::output
