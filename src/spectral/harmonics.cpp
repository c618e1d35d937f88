#include "spectral/harmonics.hpp"

#include <algorithm>
#include <cmath>
#include <string>

#include "core/errors.hpp"
#include "core/types.hpp"

namespace crackle::spectral {
namespace {

/// A grid point within this fraction of the grid step of a sample takes the sample itself.
constexpr double kCoincidence = 1e-6;
/// Relative tolerance for "1/(f dt) is an integer".
constexpr double kIntegerPeriod = 1e-9;
/// auto resamples only with at least this many samples per period of the highest order: below
/// it 8-point interpolation loses to a Hann window (measured: equal near 8.4 over 40 periods).
constexpr double kMinSamplesToResample = 8.0;


/// Fractional part in [0, 1).
double fraction(double x) { return x - std::floor(x); }

struct Grid {
  int points = 0;  ///< per excitation period
  bool exact = false;
  double step = 0.0;
};

/// Samples per excitation period, 1/(f dt).
double raw_points_per_period(double frequency, double time_step) {
  return 1.0 / (frequency * time_step);
}

Grid choose_grid(double frequency, double time_step) {
  const double p = raw_points_per_period(frequency, time_step);
  if (!(p < 1e9)) {
    throw InputError("harmonics: " + format_number(p) + " samples per excitation period is too many (f = " +
                     format_number(frequency) + " Hz, dt = " + format_number(time_step) + " s)");
  }
  const double rounded = std::round(p);
  if (rounded >= 1.0 && std::abs(p - rounded) <= kIntegerPeriod * p) {
    return {static_cast<int>(rounded), true, time_step};
  }
  const int points = static_cast<int>(std::ceil(p));
  return {points, false, 1.0 / (frequency * points)};
}

/// Checks options and the sampling; the Nyquist check needs the highest order below 1/(2 dt).
void check_options(const HarmonicOptions& options, double time_step) {
  const double f = options.excitation_frequency_hz;
  if (!(f > 0.0) || !std::isfinite(f)) {
    throw InputError("harmonics: excitation frequency must be > 0, got " + format_number(f));
  }
  if (!(time_step > 0.0) || !std::isfinite(time_step)) {
    throw InputError("harmonics: time step must be > 0, got " + format_number(time_step));
  }
  if (options.max_order < 1) {
    throw InputError("harmonics: max_order must be >= 1, got " + std::to_string(options.max_order));
  }
  if (options.periods < 0) {
    throw InputError("harmonics: periods must be >= 0, got " + std::to_string(options.periods));
  }
  if (options.subharmonics && options.periods % 2 != 0) {
    throw InputError("harmonics: with sub-harmonics the analysed periods must be even, got " +
                     std::to_string(options.periods));
  }
  const double p = raw_points_per_period(f, time_step);
  if (!(2.0 * options.max_order < p)) {
    throw InputError("harmonics: order " + std::to_string(options.max_order) + " at " +
                     format_number(options.max_order * f) + " Hz is not below the Nyquist frequency " +
                     format_number(0.5 / time_step) + " Hz (dt = " + format_number(time_step) + " s)");
  }
}

HarmonicTable make_table(double frequency, const std::vector<double>& orders,
                         const std::vector<std::complex<double>>& sums, double scale) {
  HarmonicTable table;
  table.excitation_frequency_hz = frequency;
  for (std::size_t k = 0; k < orders.size(); ++k) {
    Harmonic h;
    h.order = orders[k];
    h.frequency_hz = orders[k] * frequency;
    if (orders[k] == 0.0) {
      h.amplitude = sums[k].real() * scale;
      h.phase_rad = 0.0;
    } else {
      const std::complex<double> c = sums[k] * (2.0 * scale);
      h.amplitude = std::abs(c);
      h.phase_rad = std::arg(c);
    }
    table.harmonics.push_back(h);
  }
  return table;
}

}  // namespace

const char* method_name(Method method) {
  switch (method) {
    case Method::exact_bins: return "exact_bins";
    case Method::resampled: return "resampled";
    case Method::windowed: return "windowed";
  }
  return "?";
}

bool HarmonicTable::has(double order) const {
  return std::any_of(harmonics.begin(), harmonics.end(),
                     [&](const Harmonic& h) { return h.order == order; });
}

const Harmonic& HarmonicTable::at(double order) const {
  for (const Harmonic& h : harmonics) {
    if (h.order == order) return h;
  }
  throw InputError("harmonic table has no order " + format_number(order));
}

std::vector<double> harmonic_orders(const HarmonicOptions& options) {
  if (options.max_order < 1) {
    throw InputError("harmonics: max_order must be >= 1, got " + std::to_string(options.max_order));
  }
  std::vector<double> orders{0.0};
  for (int k = 1; k <= options.max_order; ++k) {
    if (options.subharmonics) orders.push_back(k - 0.5);
    orders.push_back(k);
  }
  return orders;
}

double table_change(const HarmonicTable& now, const HarmonicTable& previous) {
  if (now.harmonics.size() != previous.harmonics.size()) {
    throw InputError("table_change: tables of " + std::to_string(now.harmonics.size()) + " and " +
                     std::to_string(previous.harmonics.size()) + " orders");
  }
  double largest = 0.0;
  for (std::size_t k = 0; k < now.harmonics.size(); ++k) {
    if (now.harmonics[k].order != previous.harmonics[k].order) {
      throw InputError("table_change: order " + format_number(now.harmonics[k].order) + " against " +
                       format_number(previous.harmonics[k].order));
    }
    largest = std::max(largest, std::abs(now.harmonics[k].complex_amplitude() -
                                         previous.harmonics[k].complex_amplitude()));
  }
  if (largest == 0.0) return 0.0;
  const double a1 = now.amplitude(1.0);
  return a1 > 0.0 ? largest / a1 : std::numeric_limits<double>::infinity();
}

Eigen::MatrixXcd period_harmonics(const Eigen::MatrixXd& samples, int harmonics) {
  const Index n = static_cast<Index>(samples.cols());
  Eigen::MatrixXcd table = Eigen::MatrixXcd::Zero(samples.rows(), harmonics + 1);
  for (int k = 0; k <= harmonics; ++k) {
    Eigen::VectorXcd basis(n);
    for (Index j = 0; j < n; ++j) basis[j] = std::polar(1.0, -kTwoPi * double(k) * double(j) / double(n));
    table.col(k) = samples.cast<std::complex<double>>() * basis * ((k == 0 ? 1.0 : 2.0) / double(n));
  }
  return table;
}

double period_table_change(const Eigen::MatrixXcd& now, const Eigen::MatrixXcd& previous,
                           const std::vector<Index>& rows, int reference) {
  double change = 0.0;
  for (const Index row : rows) {
    const double a1 = std::abs(now(row, reference));
    const double difference = (now.row(row) - previous.row(row)).cwiseAbs().maxCoeff();
    change = std::max(change, a1 > 0.0 ? difference / a1 : (difference > 0.0 ? 1.0 : 0.0));
  }
  return change;
}

// ---- HarmonicAccumulator

HarmonicAccumulator::HarmonicAccumulator(const HarmonicOptions& options, double time_step,
                                         double start_time) {
  HarmonicOptions checked = options;
  checked.periods = 0;
  check_options(checked, time_step);
  if (!std::isfinite(start_time)) throw InputError("harmonics: start time must be finite");
  frequency_ = options.excitation_frequency_hz;
  start_time_ = start_time;
  const Grid grid = choose_grid(frequency_, time_step);
  points_per_period_ = grid.points;
  exact_grid_ = grid.exact;
  grid_step_ = grid.step;
  orders_ = harmonic_orders(options);
  for (double order : orders_) {
    const int twice = static_cast<int>(std::lround(2.0 * order));
    twice_orders_.push_back(twice);
    // e^{-i 2 pi k f t0}, with the whole cycles removed before the angle is formed.
    base_phasor_.push_back(std::polar(1.0, -kTwoPi * fraction(0.5 * twice * frequency_ * start_time)));
    step_phasor_.push_back(std::polar(1.0, -kTwoPi * (0.5 * twice) / points_per_period_));
  }
  phasor_ = base_phasor_;
  current_.assign(orders_.size(), 0.0);
}

int HarmonicAccumulator::add(double time, double value) {
  if (!std::isfinite(time) || !std::isfinite(value)) {
    throw InputError("harmonics: sample (" + format_number(time) + " s, " + format_number(value) + ") is not finite");
  }
  const double tolerance = kCoincidence * grid_step_;
  if (buffer_count_ == 0) {
    if (time > start_time_ + tolerance) {
      throw InputError("harmonics: first sample at t = " + format_number(time) +
                       " s comes after the start of period 0 at " + format_number(start_time_) + " s");
    }
  } else {
    const double newest = buffer_time_[(buffer_head_ + kStencil - 1) % kStencil];
    if (!(time > newest)) {
      throw InputError("harmonics: sample times must increase: " + format_number(time) + " s after " +
                       format_number(newest) + " s");
    }
  }
  buffer_time_[buffer_head_] = time;
  buffer_value_[buffer_head_] = value;
  buffer_head_ = (buffer_head_ + 1) % kStencil;
  buffer_count_ = std::min(buffer_count_ + 1, kStencil);
  const int before = n_periods();
  process_pending(false);
  return n_periods() - before;
}

int HarmonicAccumulator::finish() {
  const int before = n_periods();
  if (buffer_count_ > 0) process_pending(true);
  return n_periods() - before;
}

void HarmonicAccumulator::process_pending(bool flush) {
  const double tolerance = kCoincidence * grid_step_;
  const double newest = buffer_time_[(buffer_head_ + kStencil - 1) % kStencil];
  while (true) {
    const double point = start_time_ + static_cast<double>(next_point_) * grid_step_;
    if (point > newest + tolerance) break;
    int before = 0, after = 0, coincident = -1;
    for (int m = 0; m < buffer_count_; ++m) {
      const double d = buffer_time_[m] - point;
      if (std::abs(d) <= tolerance) {
        coincident = m;
      } else if (d > 0.0) {
        ++after;
      } else {
        ++before;
      }
    }
    if (coincident >= 0) {
      take(buffer_value_[coincident]);
      continue;
    }
    // Wait for 4 samples after the point and 8 in all, unless the record has ended.
    if (!flush && after < std::max(kStencil / 2, kStencil - before)) break;
    // Lagrange interpolation through the buffered samples, in units of the grid step.
    double s[kStencil];
    for (int m = 0; m < buffer_count_; ++m) s[m] = (buffer_time_[m] - point) / grid_step_;
    double value = 0.0;
    for (int j = 0; j < buffer_count_; ++j) {
      double weight = 1.0;
      for (int m = 0; m < buffer_count_; ++m) {
        if (m != j) weight *= -s[m] / (s[j] - s[m]);
      }
      value += weight * buffer_value_[j];
    }
    take(value);
    any_interpolated_ = true;
  }
}

void HarmonicAccumulator::take(double value) {
  for (std::size_t k = 0; k < orders_.size(); ++k) current_[k] += value * phasor_[k];
  ++next_point_;
  const std::int64_t cycle = 2 * static_cast<std::int64_t>(points_per_period_);
  if (next_point_ % 64 == 0) {
    // Resynchronise the phasors from exact integer phases: no drift over long runs.
    const std::int64_t j = next_point_ % cycle;
    for (std::size_t k = 0; k < orders_.size(); ++k) {
      const std::int64_t index = (twice_orders_[k] * j) % cycle;
      phasor_[k] = base_phasor_[k] *
                   std::polar(1.0, -kTwoPi * static_cast<double>(index) / static_cast<double>(cycle));
    }
  } else {
    for (std::size_t k = 0; k < orders_.size(); ++k) phasor_[k] *= step_phasor_[k];
  }
  if (next_point_ % points_per_period_ == 0) {
    period_sums_.push_back(current_);
    std::fill(current_.begin(), current_.end(), 0.0);
  }
}

HarmonicTable HarmonicAccumulator::table(int first, int count) const {
  if (first < 0 || count < 1 || first + count > n_periods()) {
    throw InputError("harmonics: periods [" + std::to_string(first) + ", " +
                     std::to_string(first + count) + ") asked, " + std::to_string(n_periods()) +
                     " complete");
  }
  const bool subharmonics = orders_.size() > 1 && orders_[1] == 0.5;
  if (subharmonics && count % 2 != 0) {
    throw InputError("harmonics: with sub-harmonics a table needs an even number of periods, got " +
                     std::to_string(count));
  }
  std::vector<std::complex<double>> sums(orders_.size(), 0.0);
  for (int p = first; p < first + count; ++p) {
    for (std::size_t k = 0; k < orders_.size(); ++k) sums[k] += period_sums_[p][k];
  }
  HarmonicTable table = make_table(frequency_, orders_, sums,
                                   1.0 / (static_cast<double>(count) * points_per_period_));
  const double period_length = points_per_period_ * grid_step_;
  table.start_time = start_time_ + first * period_length;
  table.end_time = start_time_ + (first + count) * period_length;
  table.periods = count;
  table.method = exact_grid_ && !any_interpolated_ ? Method::exact_bins : Method::resampled;
  table.window = Window::rectangular;
  return table;
}

SteadyState HarmonicAccumulator::steady_state(const SteadyStateCriterion& criterion) const {
  const bool subharmonics = orders_.size() > 1 && orders_[1] == 0.5;
  const int window = criterion.window_periods;
  if (window < 1 || (subharmonics && window % 2 != 0)) {
    throw InputError("steady state: window_periods must be >= 1 (even with sub-harmonics), got " +
                     std::to_string(window));
  }
  if (!(criterion.tolerance > 0.0)) {
    throw InputError("steady state: tolerance must be > 0, got " + format_number(criterion.tolerance));
  }
  if (criterion.max_periods != 0 && criterion.max_periods < window) {
    throw InputError("steady state: max_periods must be 0 (no limit) or >= window_periods " +
                     std::to_string(window) + ", got " + std::to_string(criterion.max_periods));
  }
  SteadyState state;
  const int n = n_periods();
  state.periods_used = n;
  state.limit_reached = criterion.max_periods > 0 && n >= criterion.max_periods;
  if (n >= 2 * window) {
    state.change = table_change(table(n - window, window), table(n - 2 * window, window));
    state.settled = state.change < criterion.tolerance;
  }
  return state;
}

// ---- batch analysis

HarmonicTable extract_harmonics(const std::vector<double>& values, const Sampling& sampling,
                                const HarmonicOptions& options) {
  check_options(options, sampling.time_step);
  const double f = options.excitation_frequency_hz;
  const double dt = sampling.time_step;
  const double t0 = sampling.start_time;
  const auto n = static_cast<std::int64_t>(values.size());
  for (double x : values) {
    if (!std::isfinite(x)) throw InputError("harmonics: the record holds a non-finite value");
  }
  const double p = raw_points_per_period(f, dt);
  const Grid grid = choose_grid(f, dt);

  Window window = options.window;
  if (window == Window::automatic) {
    window = (grid.exact || p / options.max_order >= kMinSamplesToResample) ? Window::rectangular
                                                                            : Window::hann;
  }
  const int step = options.subharmonics ? 2 : 1;
  std::int64_t available = 0;
  if (n >= 2) {
    available = window == Window::rectangular
                    ? static_cast<std::int64_t>(
                          std::floor(((n - 1) * dt / grid.step + 1.0 + 1e-7) / grid.points))
                    : static_cast<std::int64_t>(std::floor(n / p + 1e-9));
  }
  available -= available % step;
  const std::int64_t periods = options.periods > 0 ? options.periods : available;
  if (periods < step || periods > available) {
    throw InputError("harmonics: the record of " + std::to_string(n) + " samples (" +
                     format_number(n * dt) + " s) holds " + std::to_string(available) +
                     " whole excitation periods of " + format_number(1.0 / f) + " s; " +
                     (options.periods > 0 ? std::to_string(options.periods) : std::to_string(step)) +
                     " needed");
  }

  if (window == Window::rectangular) {
    // Grid ending at the last sample: t_j = t_last - (M P - 1 - j) h.
    const double t_last = t0 + static_cast<double>(n - 1) * dt;
    const double start = t_last - static_cast<double>(periods * grid.points - 1) * grid.step;
    HarmonicAccumulator accumulator(options, dt, start);
    const std::int64_t first =
        std::max<std::int64_t>(0, static_cast<std::int64_t>(std::floor((start - t0) / dt)) - 4);
    for (std::int64_t i = first; i < n; ++i) {
      accumulator.add(t0 + static_cast<double>(i) * dt, values[i]);
    }
    accumulator.finish();
    return accumulator.table(0, static_cast<int>(periods));
  }

  // Windowed single-bin DFTs at the exact frequencies over the last M periods of samples.
  const std::int64_t count =
      grid.exact ? periods * grid.points
                 : std::min<std::int64_t>(n, static_cast<std::int64_t>(std::floor(periods * p + 1e-9)));
  const std::int64_t offset = n - count;
  const std::vector<double> w = window_values(window, static_cast<int>(count));
  double weight_sum = 0.0;
  for (double wi : w) weight_sum += wi;
  const std::vector<double> orders = harmonic_orders(options);
  std::vector<std::complex<double>> sums(orders.size(), 0.0);
  const double t_first = t0 + static_cast<double>(offset) * dt;
  for (std::size_t k = 0; k < orders.size(); ++k) {
    const double cycles0 = fraction(orders[k] * f * t_first);
    const double cycles_per_sample = orders[k] * f * dt;
    std::complex<double> sum = 0.0;
    for (std::int64_t i = 0; i < count; ++i) {
      const double cycles = fraction(cycles0 + cycles_per_sample * static_cast<double>(i));
      sum += w[i] * values[offset + i] * std::polar(1.0, -kTwoPi * cycles);
    }
    sums[k] = sum;
  }
  HarmonicTable table = make_table(f, orders, sums, 1.0 / weight_sum);
  table.start_time = t_first;
  table.end_time = t_first + static_cast<double>(count) * dt;
  table.periods = static_cast<int>(periods);
  table.method = Method::windowed;
  table.window = window;
  return table;
}

SteadyStateRun detect_steady_state(const std::vector<double>& values, const Sampling& sampling,
                                   const HarmonicOptions& options,
                                   const SteadyStateCriterion& criterion) {
  HarmonicAccumulator accumulator(options, sampling.time_step, sampling.start_time);
  SteadyStateRun run;
  for (std::size_t i = 0; i < values.size(); ++i) {
    if (accumulator.add(sampling.start_time + static_cast<double>(i) * sampling.time_step,
                        values[i]) > 0) {
      run.state = accumulator.steady_state(criterion);
      if (run.state.stop() && accumulator.n_periods() >= criterion.window_periods) {
        run.table = accumulator.last_table(criterion.window_periods);
        return run;
      }
    }
  }
  accumulator.finish();
  run.state = accumulator.steady_state(criterion);
  if (accumulator.n_periods() < criterion.window_periods) {
    throw InputError("steady state: the record holds " + std::to_string(accumulator.n_periods()) +
                     " whole periods, fewer than the window of " +
                     std::to_string(criterion.window_periods));
  }
  run.table = accumulator.last_table(criterion.window_periods);
  return run;
}

}  // namespace crackle::spectral
