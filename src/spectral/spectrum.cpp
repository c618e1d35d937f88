#include "spectral/spectrum.hpp"

#include <fftw3.h>

#include <charconv>
#include <cmath>
#include <list>
#include <mutex>
#include <utility>

#include "core/errors.hpp"
#include "core/fftw_buffer.hpp"

namespace crackle::spectral {
namespace {

constexpr int kMaxPlans = 8;

/// The FFTW planner is process-global state; every plan creation and destruction goes through
/// this lock.
std::mutex& planner_mutex() {
  static std::mutex mutex;
  return mutex;
}

/// An r2c plan of one length; destroyed under the planner lock when its last user lets go.
struct Plan {
  int length = 0;
  fftw_plan plan = nullptr;
  ~Plan() {
    if (!plan) return;
    std::lock_guard<std::mutex> lock(planner_mutex());
    fftw_destroy_plan(plan);
  }
};

}  // namespace

struct SpectrumAnalyzer::Cache {
  mutable std::mutex mutex;
  std::list<std::shared_ptr<const Plan>> plans;  ///< most recently used first

  std::shared_ptr<const Plan> get(int length) {
    std::lock_guard<std::mutex> lock(mutex);
    for (auto it = plans.begin(); it != plans.end(); ++it) {
      if ((*it)->length == length) {
        plans.splice(plans.begin(), plans, it);
        return plans.front();
      }
    }
    auto plan = std::make_shared<Plan>();
    plan->length = length;
    {
      FftwBuffer<double> in(length);
      FftwBuffer<fftw_complex> out(length / 2 + 1);
      std::lock_guard<std::mutex> planner_lock(planner_mutex());
      plan->plan = fftw_plan_dft_r2c_1d(length, in.data, out.data, FFTW_ESTIMATE);
    }
    if (!plan->plan) throw SolverError("FFTW could not plan a transform of length " + std::to_string(length));
    plans.push_front(plan);
    if (static_cast<int>(plans.size()) > kMaxPlans) plans.pop_back();
    return plan;
  }
};

SpectrumAnalyzer::SpectrumAnalyzer() : cache_(std::make_unique<Cache>()) {}
SpectrumAnalyzer::~SpectrumAnalyzer() = default;

int SpectrumAnalyzer::n_cached_plans() const {
  std::lock_guard<std::mutex> lock(cache_->mutex);
  return static_cast<int>(cache_->plans.size());
}

AmplitudeSpectrum SpectrumAnalyzer::amplitude_spectrum(const std::vector<double>& values,
                                                       const Sampling& sampling,
                                                       const SpectrumOptions& options) const {
  const double dt = sampling.time_step;
  const double f = options.excitation_frequency_hz;
  if (!(dt > 0.0) || !std::isfinite(dt)) throw InputError("spectrum: time step must be > 0, got " + format_number(dt));
  if (!(f >= 0.0) || !std::isfinite(f)) throw InputError("spectrum: excitation frequency must be >= 0, got " + format_number(f));
  if (options.periods < 0 || (options.periods > 0 && f == 0.0)) {
    throw InputError("spectrum: periods = " + std::to_string(options.periods) +
                     " needs periods >= 0 and an excitation frequency");
  }
  if (options.subharmonics && options.periods % 2 != 0) {
    throw InputError("spectrum: with sub-harmonics the periods must be even, got " +
                     std::to_string(options.periods));
  }
  const auto n = static_cast<std::int64_t>(values.size());
  for (double x : values) {
    if (!std::isfinite(x)) throw InputError("spectrum: the record holds a non-finite value");
  }

  std::int64_t count = n;
  bool exact = false;
  if (f > 0.0) {
    const double p = 1.0 / (f * dt);
    const double rounded = std::round(p);
    exact = rounded >= 1.0 && std::abs(p - rounded) <= 1e-9 * p;
    const int step = options.subharmonics ? 2 : 1;
    std::int64_t available = static_cast<std::int64_t>(std::floor(n / p + 1e-9));
    available -= available % step;
    const std::int64_t periods = options.periods > 0 ? options.periods : available;
    if (periods < step || periods > available) {
      throw InputError("spectrum: the record of " + std::to_string(n) + " samples holds " +
                       std::to_string(available) + " whole periods of " + format_number(1.0 / f) + " s; " +
                       std::to_string(std::max<std::int64_t>(periods, step)) + " needed");
    }
    count = exact ? periods * static_cast<std::int64_t>(rounded)
                  : static_cast<std::int64_t>(std::floor(periods * p + 1e-9));
  }
  if (count < 2) throw InputError("spectrum: needs at least 2 samples, got " + std::to_string(count));
  if (count > (std::int64_t{1} << 30)) throw InputError("spectrum: record too long for one transform");

  Window window = options.window;
  if (window == Window::automatic) window = exact ? Window::rectangular : Window::flattop;
  const int length = static_cast<int>(count);
  const std::int64_t offset = n - count;
  const std::vector<double> w = window_values(window, length);
  double weight_sum = 0.0;
  for (double wi : w) weight_sum += wi;

  const std::shared_ptr<const Plan> plan = cache_->get(length);
  FftwBuffer<double> in(length);
  FftwBuffer<fftw_complex> out(length / 2 + 1);
  for (int i = 0; i < length; ++i) in.data[i] = w[i] * values[offset + i];
  fftw_execute_dft_r2c(plan->plan, in.data, out.data);

  AmplitudeSpectrum spectrum;
  spectrum.n_samples = length;
  spectrum.resolution_hz = 1.0 / (length * dt);
  spectrum.start_time = sampling.start_time + static_cast<double>(offset) * dt;
  spectrum.window = window;
  const int bins = length / 2 + 1;
  spectrum.frequency_hz.resize(bins);
  spectrum.amplitude.resize(bins);
  for (int k = 0; k < bins; ++k) {
    const bool single = k == 0 || (length % 2 == 0 && k == length / 2);
    spectrum.frequency_hz[k] = k * spectrum.resolution_hz;
    // Bin 0 of a real record is real: the signed mean, as order 0 of a harmonic table.
    spectrum.amplitude[k] = k == 0 ? out.data[0][0] / weight_sum
                                   : (single ? 1.0 : 2.0) * std::hypot(out.data[k][0], out.data[k][1]) / weight_sum;
  }
  return spectrum;
}

std::string spectrum_csv(const AmplitudeSpectrum& spectrum, const std::string& unit) {
  std::string text = "frequency [Hz],amplitude [" + unit + "]\n";
  char buffer[64];
  for (std::size_t k = 0; k < spectrum.frequency_hz.size(); ++k) {
    for (double value : {spectrum.frequency_hz[k], spectrum.amplitude[k]}) {
      auto result = std::to_chars(buffer, buffer + sizeof buffer, value);
      text.append(buffer, result.ptr);
      text += ',';
    }
    text.back() = '\n';
  }
  return text;
}

}  // namespace crackle::spectral
