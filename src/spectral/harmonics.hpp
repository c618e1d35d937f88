#pragma once
/// \file Harmonic tables of sampled responses: batch extraction, an incremental single-bin DFT
/// accumulator for time-stepping runs, and steady-state detection (MODEL.md §5, "spectral
/// signatures": a breathing crack turns a tone at f into 2f, 3f, ... and f/2).
///
/// **Conventions** (shared by every function here and by the JSON of signature.hpp):
/// - Peak amplitudes and cosine phases at absolute time:
///   \f[ x(t) = A_0 + \sum_{k} A_k \cos(2\pi k f t + \varphi_k), \qquad A_k \ge 0 \ (k > 0), \f]
///   where t is the absolute time of the samples, \f$t_i = t_0 + i\,\Delta t\f$ (Sampling), not
///   the time since the analysed window began. So a phase does not depend on which periods were
///   analysed, and phases of different probes of one run compare directly.
/// - Order 0 is the mean: \f$A_0\f$ is signed and its phase is 0.
/// - Orders k = 1..H; with sub-harmonics also k = 1/2, 3/2, ..., H - 1/2. Frequency k f [Hz].
/// - "Periods" always count excitation periods 1/f. With sub-harmonics the analysed periods
///   are even in number (whole periods of f/2), so every order is an exact DFT bin.
#include <cmath>
#include <complex>
#include <cstdint>
#include <limits>
#include <vector>

#include "core/types.hpp"
#include "spectral/window.hpp"

namespace crackle::spectral {

/// Uniform sampling of a record: sample i is at t_i = start_time + i * time_step.
struct Sampling {
  double time_step = 0.0;   ///< [s], > 0
  double start_time = 0.0;  ///< [s], time of sample 0
};

/// What to extract.
struct HarmonicOptions {
  double excitation_frequency_hz = 0.0;  ///< f > 0
  int max_order = 3;                     ///< H >= 1: orders 1..H
  bool subharmonics = false;             ///< also orders 1/2, 3/2, ..., H - 1/2
  /// Excitation periods analysed, taken from the END of the record (the most settled part);
  /// 0 = as many whole periods as fit (an even number with sub-harmonics).
  int periods = 0;
  /// auto: rectangular over whole periods, on the samples themselves when 1/(f dt) is an
  /// integer (exact bins), else on a resampled grid (exact bins again, up to interpolation
  /// error, ~1e-8 of A_1 at 17 samples per period of order H); Hann on the raw samples when the
  /// sampling is too coarse to resample accurately (fewer than 8 samples per period of order
  /// H). hann / flattop: single-bin DFTs at the exact frequencies over the last `periods`
  /// periods of raw samples (the nearest whole sample count), amplitude-corrected by sum(w);
  /// leakage between orders falls with the number of periods (~1e-6 of A_1 over 40).
  Window window = Window::automatic;
};

/// How a table was computed.
enum class Method {
  exact_bins,  ///< rectangular DFT on the samples: 1/(f dt) is an integer
  resampled,   ///< rectangular DFT on an 8-point Lagrange-interpolated grid of whole periods
  windowed,    ///< Hann or flat-top single-bin DFTs on the raw samples
};

/// Name of a method: "exact_bins", "resampled", "windowed".
const char* method_name(Method method);

/// One sinusoid of the table (see the conventions above).
struct Harmonic {
  double order = 0.0;         ///< k: 0, 0.5, 1, 1.5, ...
  double frequency_hz = 0.0;  ///< k f
  double amplitude = 0.0;     ///< A_k, peak [unit of the signal]; signed for k = 0
  double phase_rad = 0.0;     ///< phi_k in (-pi, pi], at absolute time
  /// The complex amplitude A_k e^{i phi_k} (A_0 for the mean).
  std::complex<double> complex_amplitude() const {
    return {amplitude * std::cos(phase_rad), amplitude * std::sin(phase_rad)};
  }
};

/// Harmonic table of one signal over one analysed window.
struct HarmonicTable {
  double excitation_frequency_hz = 0.0;
  std::vector<Harmonic> harmonics;  ///< ascending order, the mean (order 0) first
  double start_time = 0.0;          ///< analysed window [start_time, end_time) [s]
  double end_time = 0.0;
  int periods = 0;  ///< excitation periods in the window
  Method method = Method::exact_bins;
  Window window = Window::rectangular;

  /// Whether the table has order k.
  bool has(double order) const;
  /// The harmonic of order k; InputError if the table does not have it.
  const Harmonic& at(double order) const;
  /// A_k; InputError if absent.
  double amplitude(double order) const { return at(order).amplitude; }
};

/// The orders that options ask for, ascending, 0 first. InputError on max_order < 1.
std::vector<double> harmonic_orders(const HarmonicOptions& options);

/// Harmonic table of the last options.periods excitation periods of a record (see
/// HarmonicOptions::window for the method). InputError on bad options, a record shorter than
/// one period (two with sub-harmonics), fewer whole periods than asked, or orders at or above
/// the Nyquist frequency.
HarmonicTable extract_harmonics(const std::vector<double>& values, const Sampling& sampling,
                                const HarmonicOptions& options);

/// Relative change between two tables of the same orders:
/// \f[ \Delta = \max_k |C_k^{now} - C_k^{prev}| \,/\, A_1^{now}, \qquad C_k = A_k e^{i\varphi_k}, \f]
/// over every order including the mean. It bounds the amplitude change
/// \f$\max_k |A_k^{now} - A_k^{prev}|/A_1^{now}\f$ and also catches phase drift. 0 when both
/// tables are identical, +inf when A_1^now = 0 and they differ. InputError on different orders.
double table_change(const HarmonicTable& now, const HarmonicTable& previous);

/// Harmonic tables of exactly one period T of several signals at once (the rows of `samples`, n
/// samples at t_j = t_0 + j T / n): columns k = 0..H, Y_0 the mean and
/// \f$Y_k = (2/n) \sum_j y_j e^{-2\pi i k j / n}\f$, so that
/// \f$y(t) = \mathrm{Re} \sum_k Y_k e^{2\pi i k (t - t_0) / T}\f$: the conventions above with
/// f = 1/T and phases at t_0. A rectangular window over one whole period, so every order is an
/// exact bin. The stepped sine's table of one period of its base frequency.
Eigen::MatrixXcd period_harmonics(const Eigen::MatrixXd& samples, int harmonics);

/// table_change() between two period tables, over the given rows, each relative to its column
/// `reference` (A_1): the largest \f$\max_k |Y_k^{now} - Y_k^{prev}| / |Y_{ref}^{now}|\f$; a row
/// with A_1 = 0 counts 1 when it changed, 0 when not.
double period_table_change(const Eigen::MatrixXcd& now, const Eigen::MatrixXcd& previous,
                           const std::vector<Index>& rows, int reference);

/// When a run counts as settled: the table over the last window_periods excitation periods
/// differs from the table over the window_periods before them by table_change() < tolerance.
struct SteadyStateCriterion {
  int window_periods = 4;   ///< >= 1; even with sub-harmonics
  double tolerance = 1e-3;  ///< > 0
  int max_periods = 0;      ///< stop anyway after this many periods (>= window); 0 = no limit
};

/// Verdict of a steady-state check.
struct SteadyState {
  bool settled = false;        ///< change < tolerance
  bool limit_reached = false;  ///< max_periods completed (whether settled or not)
  int periods_used = 0;        ///< excitation periods completed when the verdict was made
  double change = std::numeric_limits<double>::infinity();  ///< table_change(); inf before 2 windows
  /// Whether a time-stepping run should stop now.
  bool stop() const { return settled || limit_reached; }
};

/// Single-bin DFT accumulator for a time-stepping run: add(t, x) at every step; it keeps only
/// 8 samples and one complex sum per order and excitation period, never the history.
///
/// Period p covers [start_time + p/f, start_time + (p+1)/f). Each period is sampled on a grid
/// of P points, t_j = start_time + j h: the step times themselves when 1/(f dt) is an integer P
/// (h = dt, exact DFT bins), else P = ceil(1/(f dt)), h = 1/(f P), and x(t_j) is interpolated
/// from the 8 nearest samples (Lagrange, error ~ 1e-3 (2 pi k f dt)^8 relative). Times may be
/// non-uniform; a grid point is taken as soon as 4 samples follow it (at once if it
/// coincides with a sample), so a period completes up to 4 steps after its end.
/// A table equals extract_harmonics() whenever the two windows coincide.
/// Not thread-safe; use one accumulator per signal.
class HarmonicAccumulator {
 public:
  /// options.periods and options.window are ignored. time_step: the nominal dt that sets the
  /// grid; start_time: the beginning of period 0 (the run's start). InputError on bad options.
  HarmonicAccumulator(const HarmonicOptions& options, double time_step, double start_time = 0.0);

  /// Adds the sample x(time); times strictly increase; the first must be <= start_time (earlier
  /// samples only feed the interpolation). Returns the number of periods this sample completed.
  int add(double time, double value);
  /// Processes the grid points up to the last sample with one-sided stencils (end of record).
  /// Returns the number of periods completed.
  int finish();

  /// Completed excitation periods.
  int n_periods() const { return static_cast<int>(period_sums_.size()); }
  /// Grid points per excitation period.
  int points_per_period() const { return points_per_period_; }
  /// Whether the grid is the step times themselves (exact bins).
  bool exact_grid() const { return exact_grid_; }
  /// Table over the completed periods [first, first + count); InputError if not all complete or
  /// count is odd with sub-harmonics.
  HarmonicTable table(int first, int count) const;
  /// Table over the last `count` completed periods.
  HarmonicTable last_table(int count) const { return table(n_periods() - count, count); }
  /// Steady-state verdict now (call it when add() reports a completed period).
  SteadyState steady_state(const SteadyStateCriterion& criterion) const;

 private:
  void take(double value);
  void process_pending(bool flush);

  double frequency_ = 0.0;
  double start_time_ = 0.0;
  double grid_step_ = 0.0;
  int points_per_period_ = 0;
  bool exact_grid_ = false;
  std::vector<double> orders_;
  std::vector<int> twice_orders_;
  std::vector<std::complex<double>> base_phasor_;  ///< e^{-i 2 pi k f start_time}
  std::vector<std::complex<double>> step_phasor_;  ///< e^{-i 2 pi k / P}
  std::vector<std::complex<double>> phasor_;       ///< e^{-i 2 pi k f t_j} for the next point
  std::vector<std::complex<double>> current_;      ///< sums of the period in progress
  std::vector<std::vector<std::complex<double>>> period_sums_;
  std::int64_t next_point_ = 0;
  static constexpr int kStencil = 8;
  double buffer_time_[kStencil] = {};
  double buffer_value_[kStencil] = {};
  int buffer_count_ = 0;  ///< samples held, the newest at (buffer_head_ - 1) mod 8
  int buffer_head_ = 0;
  bool any_interpolated_ = false;
};

/// Steady-state detection over a stored record (the same test a run makes on the fly).
struct SteadyStateRun {
  SteadyState state;
  HarmonicTable table;  ///< over the last window_periods periods at the verdict
};

/// Feeds the record from its first sample (= start of period 0) into a HarmonicAccumulator,
/// checks after every completed period and stops at the first settled or limit verdict.
/// InputError when fewer than window_periods whole periods fit.
SteadyStateRun detect_steady_state(const std::vector<double>& values, const Sampling& sampling,
                                   const HarmonicOptions& options,
                                   const SteadyStateCriterion& criterion);

}  // namespace crackle::spectral
