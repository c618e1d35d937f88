/// \file The sweep's solvers (harmonic balance continuation, stepped sine) and its files.
#include "pipeline/sweep.hpp"

#include <algorithm>
#include <cmath>
#include <complex>
#include <functional>
#include <limits>
#include <optional>

#include <Eigen/Core>

#include "core/errors.hpp"
#include "core/interrupt.hpp"
#include "core/resources.hpp"
#include "reduced/integrator.hpp"
#include "spectral/harmonics.hpp"
#include "sweep/branch_switching.hpp"

namespace crackle::pipeline {
namespace {

constexpr double kGapScaleFactor = 30.0;  ///< gap scale of the continuation / the automatic one

/// "1", "2", "1/2", "3/2": an order k / nu of the excitation frequency.
std::string order_label(int k, int nu) {
  if (k % nu == 0) return std::to_string(k / nu);
  return std::to_string(k) + "/" + std::to_string(nu);
}

/// Frequency where a quantity that is `a` at `fa` and `b` at `fb` crosses zero (the midpoint if it does not).
double zero_crossing(double fa, double a, double fb, double b) {
  if (a == b || (a > 0.0) == (b > 0.0)) return 0.5 * (fa + fb);
  return fa + (fb - fa) * a / (a - b);
}

/// The events between the previous point and `point` of a harmonic-balance branch.
void add_events(const sweep::BranchPoint& previous, const sweep::BranchPoint& point, std::size_t index,
                std::vector<SweepEvent>& events) {
  const double fa = previous.solution.omega / kTwoPi, fb = point.solution.omega / kTwoPi;
  if (point.fold) {
    events.push_back({"fold", zero_crossing(fa, previous.tangent_omega, fb, point.tangent_omega), index, point.hill_check});
  }
  const double at = zero_crossing(fa, previous.stability.max_real_part, fb, point.stability.max_real_part);
  if (point.period_doubling) events.push_back({"period_doubling", at, index, point.hill_check});
  if (previous.stability.unstable_complex != point.stability.unstable_complex) {
    events.push_back({"neimark_sacker", at, index, point.hill_check});
  }
  if (point.stability_change && !point.fold && !point.period_doubling &&
      previous.stability.unstable_complex == point.stability.unstable_complex) {
    events.push_back({"stability_change", at, index, point.hill_check});
  }
}

/// The H-convergence warning of a finished harmonic-balance sweep (first among the warnings).
void add_harmonics_warning(const SweepSettings& settings, double threshold, int flagged, double first_flagged_hz,
                           SweepResult& result) {
  if (flagged == 0) return;
  result.warnings.insert(
      result.warnings.begin(),
      "H = " + std::to_string(settings.section.harmonics) + ": the top harmonics hold up to " +
          format_number(result.max_top_share) + " of the gap response (> " + format_number(threshold) + ") at " +
          std::to_string(flagged) + " of " + std::to_string(result.points.size()) + " points, first at " +
          format_number(first_flagged_hz) + " Hz: raise sweep.harmonics");
}

/// Whether the (first) branch reached the end of the range, with a warning when not: its reason is the
/// point limit (`max_points`) when the branch has that many points, else the corrector.
void add_completion(const SweepSettings& settings, int max_points, SweepResult& result) {
  const double last_hz = result.points.empty() ? settings.from_hz : result.points.back().frequency_hz();
  const bool upward = settings.to_hz > settings.from_hz;
  result.completed = upward ? last_hz >= settings.to_hz : last_hz <= settings.to_hz;
  if (!result.completed) {
    const bool at_limit = static_cast<int>(result.points.size()) >= max_points;
    result.warnings.push_back("the continuation stopped at " + format_number(last_hz) + " Hz, before " +
                              format_number(settings.to_hz) + " Hz (" +
                              (at_limit ? "after the most points it may take, " + std::to_string(max_points) +
                                              " = 50 x sweep.points"
                                        : std::string("the corrector failed down to the smallest step")) +
                              ")");
  }
}

/// Eigen's products on one thread while it lives. The sweep's dense products are small (hundreds of
/// rows); Eigen's OpenMP threads spin-wait between them, which on a shared machine (load 9 on 2 cores)
/// made the beam sweep 14x slower (43 s against 3 s for 52 points, docs/benchmarks.md section 7).
class SingleThreadedEigen {
 public:
  SingleThreadedEigen() : threads_(Eigen::nbThreads()) { Eigen::setNbThreads(1); }
  ~SingleThreadedEigen() { Eigen::setNbThreads(threads_); }
  SingleThreadedEigen(const SingleThreadedEigen&) = delete;
  SingleThreadedEigen& operator=(const SingleThreadedEigen&) = delete;

 private:
  int threads_;
};

/// One stepped-sine frequency: from the state (q, v), periods of the base period until the table
/// settles; leaves the final state in (q, v).
SweepPoint stepped_sine_point(const reduced::ReducedSystem& system, const SweepSettings& settings, double frequency_hz,
                              VectorX& q, VectorX& v) {
  const scene::SweepSection& section = settings.section;
  const int nu = section.subharmonic;
  const double omega = kTwoPi * frequency_hz, base_period = nu / frequency_hz;
  // Four times the default resolution: near a resonance the scheme's frequency error, (omega h)^2 / 12,
  // is amplified by 1 / (2 zeta) in the amplitude.
  const double recommended =
      reduced::reduced_time_step(system, section.harmonics * frequency_hz / nu, 4 * reduced::kDefaultStepsPerPeriod);
  const Index n = std::max<Index>(4 * section.harmonics + 4, Index(std::ceil(base_period / recommended)));
  reduced::ReducedIntegrator integrator(system, base_period / double(n), [omega](double t) { return std::cos(omega * t); });
  integrator.set_initial_state(q, v, 0.0);
  SweepPoint point;
  point.solution.omega = omega;
  point.solution.subharmonic = nu;
  point.solution.residual = std::numeric_limits<double>::infinity();
  MatrixX samples(system.n_outputs(), n);
  std::vector<Index> probe_rows;
  for (const SweepProbe& probe : settings.probes) probe_rows.push_back(probe.row);
  sweep::ComplexMatrixX before;
  for (point.periods = 1; point.periods <= section.max_periods; ++point.periods) {
    poll_interrupt();
    for (Index j = 0; j < n; ++j) {
      samples.col(j) = integrator.outputs();
      integrator.step();
    }
    // The table of one base period (its harmonic k is order k / nu of the drive), and the probes'
    // change from the period before (spectral's steady-state measure).
    sweep::ComplexMatrixX table = spectral::period_harmonics(samples, section.harmonics);
    if (point.periods > 1) point.solution.residual = spectral::period_table_change(table, before, probe_rows, nu);
    before = std::move(table);
    if (point.solution.residual <= section.tolerance) break;
  }
  point.periods = std::min(point.periods, section.max_periods);
  point.solution.outputs = before;
  point.solution.converged = point.solution.residual <= section.tolerance;
  q = integrator.modal_displacement();
  v = integrator.modal_velocity();
  return point;
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
nlohmann::json peak(const SweepResult& result, const SweepSettings& settings,
                    const std::function<double(const SweepPoint&)>& value) {
  const auto& points = result.points;
  if (points.empty()) return nullptr;
  std::size_t best = 0;
  for (std::size_t i = 1; i < points.size(); ++i)
    if (value(points[i]) > value(points[best])) best = i;
  double f = points[best].frequency_hz(), y = value(points[best]);
  if (points.size() >= 2 && (best == 0 || best + 1 == points.size())) {
    const std::size_t inner = best == 0 ? 1 : best - 1;
    const double end = best == 0 ? settings.from_hz : settings.to_hz;
    const double fi = points[inner].frequency_hz();
    if ((f - end) * (fi - end) < 0.0) {  // the end lies between the last two points
      y = value(points[inner]) + (y - value(points[inner])) * (end - fi) / (f - fi);
      return {{"frequency_hz", end}, {"value", y}, {"point", best}, {"at_end", true}};
    }
  }
  if (best > 0 && best + 1 < points.size()) {
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
  return {{"frequency_hz", f}, {"value", y}, {"point", best}};
}

}  // namespace

double SweepPoint::frequency_hz() const { return solution.omega / kTwoPi; }

std::vector<SweepProbe> sweep_probes(const scene::Scene& scene) {
  std::vector<SweepProbe> probes;
  const scene::TransientSection& section = *scene.transient;
  for (std::size_t p = 0; p < section.probes.size(); ++p) {
    SweepProbe probe;
    probe.name = section.probes[p].name;
    probe.component = section.probes[p].component >= 0 ? section.probes[p].component : section.excitation->direction;
    probe.row = static_cast<Index>(3 * p) + probe.component;
    probes.push_back(probe);
  }
  return probes;
}

namespace {

/// Records continued points into a SweepResult: events against the previous point of the same
/// segment, the H-convergence flags, progress.
class BranchRecorder {
 public:
  BranchRecorder(const SweepSettings& settings, SweepResult& result, const SweepProgress& progress)
      : settings_(settings), result_(result), progress_(progress) {}

  /// Starts a new segment (no event against the last point of the previous one).
  void start_segment() {
    previous_.reset();
    ++segment_;
  }
  /// Stop a segment when this returns false for a point (recorded first).
  std::function<bool(const sweep::Solution&)> keep_going;

  bool operator()(const sweep::BranchPoint& branch_point) {
    SweepPoint point;
    point.solution = branch_point.solution;
    point.stability_known = settings_.section.stability;
    point.stable = !settings_.section.stability || branch_point.stability.stable;
    point.fold = branch_point.fold;
    point.period_doubling = branch_point.period_doubling;
    point.segment = segment_;
    if (previous_) add_events(*previous_, branch_point, result_.points.size(), result_.events);
    result_.max_top_share = std::max(result_.max_top_share, point.solution.top_harmonic_share);
    if (point.solution.harmonics_flagged && flagged_++ == 0) first_flagged_hz_ = point.frequency_hz();
    result_.points.push_back(std::move(point));
    previous_ = branch_point;
    previous_->solution = sweep::Solution();  // only omega, the tangent and the stability counts are needed
    previous_->solution.omega = branch_point.solution.omega;
    if (progress_) {
      progress_(result_, (result_.points.back().frequency_hz() - settings_.from_hz) / (settings_.to_hz - settings_.from_hz));
    }
    return keep_going ? keep_going(branch_point.solution) : true;
  }

  int flagged() const { return flagged_; }
  double first_flagged_hz() const { return first_flagged_hz_; }

 private:
  const SweepSettings& settings_;
  SweepResult& result_;
  const SweepProgress& progress_;
  std::optional<sweep::BranchPoint> previous_;
  int segment_ = 0;
  int flagged_ = 0;
  double first_flagged_hz_ = 0.0;
};


/// The solver options of a sweep with `harmonics` of the base frequency Omega / nu, driven from
/// `drive_omega` [rad/s] (the automatic gap scale's dynamic floor).
sweep::HarmonicBalanceOptions balance_options(const reduced::ReducedSystem& system, int harmonics, int nu,
                                              const std::string& solver, double drive_omega) {
  sweep::HarmonicBalanceOptions options;
  options.harmonics = harmonics;
  options.subharmonic = nu;
  options.solver = sweep::linear_solver_named(solver);
  // The arclength runs in (G / s, Omega / Omega_from): with s the static gap response the many gap
  // harmonics dominate it near a super-harmonic resonance and the frequency creeps (thousands of
  // points). A larger s makes the step mostly frequency (the Newton tolerance is on r / s).
  options.scale_frequency = drive_omega;
  options.gap_scale = kGapScaleFactor * sweep::HarmonicBalance(system, options).gap_scale();
  return options;
}

sweep::ContinuationOptions continuation_options(const SweepSettings& settings) {
  const scene::SweepSection& section = settings.section;
  sweep::ContinuationOptions continuation;
  continuation.stability = section.stability;
  continuation.max_step = std::abs(settings.to_hz - settings.from_hz) / settings.from_hz / section.points;
  continuation.initial_step = continuation.max_step;
  continuation.min_step = std::min(continuation.min_step, 1e-3 * continuation.max_step);
  continuation.max_points = 50 * section.points;
  return continuation;
}

}  // namespace

SweepResult harmonic_balance_sweep(const reduced::ReducedSystem& system, const SweepSettings& settings,
                                   const SweepProgress& progress) {
  const SingleThreadedEigen one_thread;
  Stopwatch clock;
  const scene::SweepSection& section = settings.section;
  const double from = kTwoPi * settings.from_hz, to = kTwoPi * settings.to_hz;
  const sweep::ContinuationOptions continuation = continuation_options(settings);
  const bool switch_branch = section.subharmonic == 2 && section.stability;
  // subharmonic 2: the period-one branch first (H/2 harmonics of Omega, the same orders), then the
  // period-two branch from its first period doubling, both ways until it rejoins the period-one branch
  const sweep::HarmonicBalance hb(
      system, balance_options(system, switch_branch ? std::max(1, section.harmonics / 2) : section.harmonics,
                              switch_branch ? 1 : section.subharmonic, section.solver, from));
  SweepResult result;
  BranchRecorder recorder(settings, result, progress);
  std::vector<sweep::BranchPoint> period_one;
  const auto record = [&](const sweep::BranchPoint& point) {
    if (switch_branch) period_one.push_back(point);
    return recorder(point);
  };
  sweep::continue_branch(hb, from, to, continuation, record);
  add_completion(settings, continuation.max_points, result);
  if (section.subharmonic == 2 && !section.stability) {
    result.warnings.push_back("subharmonic 2 without stability: no period doubling can be found, so the branch is the "
                              "period-one response (A1/2 = 0); set sweep.stability: true (frictionless contact)");
  }
  if (switch_branch) {
    const sweep::HarmonicBalance two(system, balance_options(system, section.harmonics, 2, section.solver, from));
    const std::optional<sweep::Solution> start = sweep::period_two_start(system, hb, two, period_one, continuation);
    period_one.clear();
    if (!start) {
      result.warnings.push_back("subharmonic 2: no period doubling of the period-one branch in the range (or no "
                                "period-two solution found from it): no period-two branch");
    } else {
      // Each segment ends where the branch rejoins the period-one one, or where its odd part reverses
      // from one point to the next: it went through the doubling onto its own image shifted by one
      // excitation period (the same orbit).
      const std::vector<Index> odd = sweep::odd_unknowns(system.n_rows(), section.harmonics);
      VectorX previous_odd;
      recorder.keep_going = [&](const sweep::Solution& solution) {
        VectorX part = sweep::odd_part(solution, odd);
        const bool reversed = part.dot(previous_odd) < 0.0;
        previous_odd = std::move(part);
        return !reversed && sweep::period_two_share(solution, system.n_rows()) > sweep::kJoinedShare;
      };
      // down, then up from the start, each within the whole range (a branch may turn back past its start)
      for (const auto& [begin, end] : {std::pair(to, from), std::pair(from, to)}) {
        previous_odd = sweep::odd_part(*start, odd);
        recorder.start_segment();
        sweep::continue_branch(two, begin, end, continuation, std::ref(recorder), &*start);
      }
    }
  }
  add_harmonics_warning(settings, hb.options().top_threshold, recorder.flagged(), recorder.first_flagged_hz(), result);
  result.linear_solver = hb.matrix_free() ? "krylov" : "dense";
  result.krylov = hb.krylov_statistics();
  result.solve_s = clock.seconds();
  return result;
}

SweepResult stepped_sine_sweep(const reduced::ReducedSystem& system, const SweepSettings& settings,
                               const SweepProgress& progress) {
  const SingleThreadedEigen one_thread;
  Stopwatch clock;
  const int count = settings.section.points;
  VectorX q = VectorX::Zero(system.n_modes()), v = VectorX::Zero(system.n_modes());
  SweepResult result;
  std::vector<double> unsettled;
  for (int step = 0; step < 2 * count; ++step) {
    const int i = step < count ? step : 2 * count - 1 - step;
    const double f = settings.from_hz + (settings.to_hz - settings.from_hz) * i / double(count - 1);
    SweepPoint point = stepped_sine_point(system, settings, f, q, v);
    point.direction = step < count ? 1 : -1;
    if (!point.solution.converged) unsettled.push_back(f);
    result.points.push_back(std::move(point));
    if (progress) progress(result, (step + 1.0) / (2.0 * count));
  }
  if (!unsettled.empty()) {
    result.warnings.push_back(std::to_string(unsettled.size()) + " of " + std::to_string(2 * count) +
                              " frequencies did not settle to sweep.tolerance within sweep.max_periods = " +
                              std::to_string(settings.section.max_periods) + " periods, first at " +
                              format_number(unsettled.front()) + " Hz");
  }
  result.solve_s = clock.seconds();
  return result;
}

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

spectral::PlotResult plot_sweep(const std::filesystem::path& png, const SweepResult& result,
                                const SweepSettings& settings, std::size_t probe_index,
                                const spectral::PlotOptions& options) {
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
                     spectral::gnuplot_quote(options.quantity + " amplitude " + unit) + "\nset key outside right\n";
  const double low = std::min(settings.from_hz, settings.to_hz), high = std::max(settings.from_hz, settings.to_hz);
  body += "set xrange [" + shortest_text(low) + ":" + shortest_text(high) + "]\n";
  if (settings.bilinear_hz > 0.0) {
    for (const auto& [divisor, label] : std::vector<std::pair<double, std::string>>{{2, "f_b/2"}, {3, "f_b/3"}, {1, "f_b"}, {0.5, "2 f_b"}}) {
      const double x = settings.bilinear_hz / divisor;
      if (x < low || x > high) continue;
      body += "set arrow from " + shortest_text(x) + ", graph 0 to " + shortest_text(x) +
              ", graph 1 nohead dashtype 3 linecolor rgb 'gray50'\n";
      body += "set label " + spectral::gnuplot_quote(label) + " at " + shortest_text(x) + ", graph 0.97 center front\n";
    }
  }
  const std::string file = spectral::gnuplot_quote(std::filesystem::path(png).replace_extension(".dat").filename().string());
  const char* names[] = {"A1", "A2", "A3", "A1/2"};
  const char* colours[] = {"#1f77b4", "#d62728", "#2ca02c", "#9467bd"};
  std::string plots;
  for (std::size_t c = 0; c < orders.size(); ++c) {
    const std::string style = " using 1:" + std::to_string(c + 2) + " with lines linewidth 2 linecolor rgb '" + colours[c] + "'";
    plots += std::string(plots.empty() ? "plot " : ", \\\n     ") + file + " index 0" + style + " title '" + names[c] + "'";
    if (!blocks[1].empty()) plots += ", \\\n     " + file + " index 1" + style + " dashtype 2 title '" + names[c] + " unstable'";
  }
  return spectral::plot_script(png, data, body + plots + "\n", options);
}

}  // namespace crackle::pipeline
