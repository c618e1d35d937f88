/// \file The harmonic-balance sweep (continuation over the range or its windows, the period-two
/// branch); the stepped sine is stepped_sine.cpp's, the files sweep_output.cpp's.
#include "pipeline/sweep.hpp"

#include <algorithm>
#include <cmath>
#include <functional>
#include <optional>

#include "core/errors.hpp"
#include "core/resources.hpp"
#include "linalg/threads.hpp"
#include "sweep/branch_switching.hpp"

namespace crackle::pipeline {
namespace {

constexpr double kGapScaleFactor = 30.0;  ///< gap scale of the continuation / the automatic one

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

}  // namespace

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
                                              LinearSolver solver, double drive_omega) {
  sweep::HarmonicBalanceOptions options;
  options.harmonics = harmonics;
  options.subharmonic = nu;
  options.solver = solver;
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
  for (const double hz : section.solve_at_hz) continuation.solve_at.push_back(kTwoPi * hz);
  return continuation;
}

/// The solution at `omega` by Newton from `gaps` (of `harmonics` H), mapped onto `hb`'s harmonics (the
/// common ones kept, the others zero); none where the pair rows differ or Newton fails from it.
std::optional<sweep::Solution> window_start(const sweep::HarmonicBalance& hb, int harmonics, const VectorX& gaps,
                                            double omega) {
  const int own = hb.options().harmonics;
  const Index rows = hb.n_unknowns() / (2 * own + 1);
  if (gaps.size() == 0 || gaps.size() != rows * (2 * harmonics + 1)) return std::nullopt;
  VectorX guess = VectorX::Zero(hb.n_unknowns());
  const Index common = rows * (2 * std::min(own, harmonics) + 1);
  guess.head(common) = gaps.head(common);
  try {
    return hb.solve(omega, guess);
  } catch (const SolverError&) {
    return std::nullopt;  // continue_branch starts from the linear solution
  }
}

/// The branch over each of settings.windows (one segment each, started from settings.window_starts or
/// the linear solution at its lower end), with `completed` false and a warning for a window not reached to its end.
void continue_windows(const sweep::HarmonicBalance& hb, const SweepSettings& settings,
                      const sweep::ContinuationOptions& continuation, BranchRecorder& recorder, SweepResult& result) {
  const double from = kTwoPi * settings.from_hz, span = kTwoPi * (settings.to_hz - settings.from_hz);
  for (std::size_t w = 0; w < settings.windows.size(); ++w) {
    if (w > 0) recorder.start_segment();
    const double begin = from + settings.windows[w].first * span, end = from + settings.windows[w].second * span;
    // The steps are relative to the start frequency: the same largest step in Hz as the whole range's.
    sweep::ContinuationOptions options = continuation;
    const double scale = from / begin;
    options.max_step *= scale;
    options.initial_step *= scale;
    options.min_step *= scale;
    const std::size_t before = result.points.size();
    std::optional<sweep::Solution> start;
    if (w < settings.window_starts.gaps.size()) start = window_start(hb, settings.window_starts.harmonics,
                                                                    settings.window_starts.gaps[w], begin);
    sweep::continue_branch(hb, begin, end, options, std::ref(recorder), start ? &*start : nullptr);
    const double last = result.points.size() > before ? result.points.back().solution.omega : begin;
    if (span > 0.0 ? last < end : last > end) {
      result.completed = false;
      result.warnings.push_back("the continuation stopped at " + format_number(last / kTwoPi) + " Hz, before the end " +
                                "of its window at " + format_number(end / kTwoPi) + " Hz");
    }
  }
}

}  // namespace

SweepResult harmonic_balance_sweep(const reduced::ReducedSystem& system, const SweepSettings& settings,
                                   const SweepProgress& progress) {
  const linalg::SingleThreadedEigen one_thread;
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
  if (settings.windows.empty() || switch_branch) {
    sweep::continue_branch(hb, from, to, continuation, record);
    add_completion(settings, continuation.max_points, result);
  } else {
    continue_windows(hb, settings, continuation, recorder, result);
  }
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
  for (const double hz : section.solve_at_hz)
    if ((hz - settings.from_hz) * (hz - settings.to_hz) > 0.0)
      result.warnings.push_back("sweep.solve_at: " + format_number(hz) + " Hz lies outside the range " +
                                format_number(settings.from_hz) + " - " + format_number(settings.to_hz) +
                                " Hz: no point solved there");
  result.linear_solver = hb.matrix_free() ? "krylov" : "dense";
  result.krylov = hb.krylov_statistics();
  result.solve_s = clock.seconds();
  return result;
}

WindowStarts window_starts(const SweepResult& result, double from_hz, double to_hz, int harmonics,
                           const std::vector<std::pair<double, double>>& windows) {
  WindowStarts starts;
  starts.harmonics = harmonics;
  const auto& points = result.points;
  for (const auto& [begin, end] : windows) {
    const double f = from_hz + begin * (to_hz - from_hz);
    VectorX gaps;
    for (std::size_t i = 0; i + 1 < points.size() && points[i + 1].segment == points.front().segment; ++i) {
      const double fa = points[i].frequency_hz(), fb = points[i + 1].frequency_hz();
      if ((f - fa) * (f - fb) > 0.0) continue;
      const double t = fb == fa ? 0.0 : (f - fa) / (fb - fa);
      gaps = (1.0 - t) * points[i].solution.gaps + t * points[i + 1].solution.gaps;
      break;
    }
    starts.gaps.push_back(std::move(gaps));
  }
  return starts;
}

}  // namespace crackle::pipeline
