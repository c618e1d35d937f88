#include "spectral/ringdown.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <string>

#include "core/errors.hpp"
#include "core/types.hpp"
#include "spectral/spectrum.hpp"
#include "spectral/window.hpp"

namespace crackle::spectral {
namespace {

constexpr int kMinPeriods = 4;
constexpr int kMinSamplesPerPeriod = 4;  ///< of the highest order
constexpr int kStencil = 8;              ///< Lagrange interpolation points


void check_time_step(const char* who, double dt) {
  if (!(dt > 0.0) || !std::isfinite(dt)) {
    throw InputError(std::string(who) + ": time step must be > 0, got " + format_number(dt));
  }
}

void check_finite(const char* who, const std::vector<double>& values, const char* what) {
  for (double x : values) {
    if (!std::isfinite(x))
      throw InputError(std::string(who) + ": the " + what + " holds a non-finite value");
  }
}

/// A uniformly sampled record: value i at t0 + i dt.
struct Record {
  const double* values = nullptr;
  std::int64_t size = 0;
  double t0 = 0.0;
  double dt = 0.0;

  /// x(t) by 8-point Lagrange interpolation (one-sided stencils at the ends).
  double at(double t) const {
    const double u = (t - t0) / dt;
    std::int64_t base = static_cast<std::int64_t>(std::floor(u)) - (kStencil / 2 - 1);
    base = std::clamp<std::int64_t>(base, 0, size - kStencil);
    const double r = u - static_cast<double>(base);
    const double nearest = std::round(r);
    if (std::abs(r - nearest) <= 1e-12 && nearest >= 0.0 && nearest < kStencil) {
      return values[base + static_cast<std::int64_t>(nearest)];
    }
    double sum = 0.0;
    for (int j = 0; j < kStencil; ++j) {
      double weight = 1.0;
      for (int m = 0; m < kStencil; ++m) {
        if (m != j) weight *= (r - m) / static_cast<double>(j - m);
      }
      sum += weight * values[base + j];
    }
    return sum;
  }
};

/// Complex amplitudes A_k e^{i phi_k} (phases at absolute time) of the orders over `periods`
/// whole periods of f from `begin`: rectangular DFT on a grid of P points per period
/// interpolated from the record, P = ceil(1/(f dt)) so that the grid is at least as fine as
/// the samples. Every order is an exact bin of the grid (with sub-harmonics `periods` is even).
std::vector<std::complex<double>> window_amplitudes(const Record& record, double frequency,
                                                    double begin, int periods,
                                                    const std::vector<double>& orders) {
  const int points = static_cast<int>(std::ceil(1.0 / (frequency * record.dt) - 1e-9));
  const double step = 1.0 / (frequency * points);
  const std::int64_t count = static_cast<std::int64_t>(periods) * points;
  std::vector<std::complex<double>> sums(orders.size(), 0.0);
  std::vector<double> base_phase(orders.size());
  for (std::size_t o = 0; o < orders.size(); ++o) {
    base_phase[o] = kTwoPi * std::fmod(orders[o] * frequency * begin, 1.0);
  }
  for (std::int64_t j = 0; j < count; ++j) {
    const double x = record.at(begin + static_cast<double>(j) * step);
    for (std::size_t o = 0; o < orders.size(); ++o) {
      // k j / P reduced exactly: k j is a whole or half number.
      const double turns =
          std::fmod(orders[o] * static_cast<double>(j), static_cast<double>(points)) / points;
      sums[o] += x * std::polar(1.0, -(base_phase[o] + kTwoPi * turns));
    }
  }
  for (auto& s : sums) s *= 2.0 / static_cast<double>(count);
  return sums;
}

/// Hann-windowed DTFT of a mean-free record about its centre time, and d/df of it.
struct WindowedDtft {
  std::vector<double> weighted;  ///< w_i (x_i - mean)
  std::vector<double> tau;       ///< t_i - t_centre [s]

  /// g(f) = Re(conj(X) dX/df) = (1/2) d|X|^2/df.
  double slope(double f) const {
    std::complex<double> value = 0.0;
    std::complex<double> derivative = 0.0;
    for (std::size_t i = 0; i < weighted.size(); ++i) {
      const std::complex<double> term = weighted[i] * std::polar(1.0, -kTwoPi * f * tau[i]);
      value += term;
      derivative += term * std::complex<double>(0.0, -kTwoPi * tau[i]);
    }
    return std::real(std::conj(value) * derivative);
  }
};

/// Root of g in [a, b] with g(a) > 0 > g(b), Illinois regula falsi.
double maximise_magnitude(const WindowedDtft& dtft, double a, double b) {
  double ga = dtft.slope(a);
  double gb = dtft.slope(b);
  if (!(ga > 0.0 && gb < 0.0)) return 0.5 * (a + b);  // caller keeps the coarse estimate
  int side = 0;
  double c = 0.5 * (a + b);
  for (int iteration = 0; iteration < 200; ++iteration) {
    c = (a * gb - b * ga) / (gb - ga);
    if (!(c > a && c < b)) c = 0.5 * (a + b);
    if (b - a <= 1e-14 * std::abs(c)) break;
    const double gc = dtft.slope(c);
    if (gc == 0.0) break;
    if (gc < 0.0) {
      b = c;
      gb = gc;
      if (side == -1) ga *= 0.5;
      side = -1;
    } else {
      a = c;
      ga = gc;
      if (side == 1) gb *= 0.5;
      side = 1;
    }
  }
  return c;
}

std::vector<double> ringdown_orders(const RingdownOptions& options) {
  std::vector<double> orders;
  for (int twice = options.subharmonics ? 1 : 2; twice <= 2 * options.max_order;
       twice += options.subharmonics ? 1 : 2) {
    orders.push_back(0.5 * twice);
  }
  return orders;
}

}  // namespace

const RingdownHarmonic& RingdownAnalysis::at(double order) const {
  for (const RingdownHarmonic& h : harmonics) {
    if (h.order == order) return h;
  }
  throw InputError("ring-down analysis has no order " + format_number(order));
}

RingdownAnalysis analyse_ringdown(const std::vector<double>& samples, const Sampling& sampling,
                                  const RingdownOptions& options) {
  const char* who = "ring-down";
  const double dt = sampling.time_step;
  check_time_step(who, dt);
  if (options.max_order < 1) {
    throw InputError("ring-down: max_order must be >= 1, got " + std::to_string(options.max_order));
  }
  if (options.window_periods < 1 || (options.subharmonics && options.window_periods % 2 != 0)) {
    throw InputError("ring-down: window_periods must be >= 1 (even with sub-harmonics), got " +
                     std::to_string(options.window_periods));
  }
  if (std::isnan(options.start_time)) throw InputError("ring-down: start_time is NaN");
  check_finite(who, samples, "record");

  // The analysed part: samples at or after options.start_time.
  const auto n_all = static_cast<std::int64_t>(samples.size());
  std::int64_t first = 0;
  if (options.start_time > sampling.start_time) {
    first = static_cast<std::int64_t>(
        std::ceil((options.start_time - sampling.start_time) / dt - 1e-9));
  }
  const std::int64_t n = n_all - first;
  if (n < 4 * kStencil) {
    throw InputError("ring-down: " + std::to_string(std::max<std::int64_t>(n, 0)) +
                     " samples at or after start time " + format_number(options.start_time) +
                     " s; at least " + std::to_string(4 * kStencil) + " needed");
  }
  if (n > (std::int64_t{1} << 27)) throw InputError("ring-down: record too long");
  const Record record{samples.data() + first, n,
                      sampling.start_time + static_cast<double>(first) * dt, dt};
  const double duration = static_cast<double>(n) * dt;

  double mean = 0.0;
  for (std::int64_t i = 0; i < n; ++i) mean += record.values[i];
  mean /= static_cast<double>(n);
  double spread = 0.0;
  for (std::int64_t i = 0; i < n; ++i) spread = std::max(spread, std::abs(record.values[i] - mean));
  if (!(spread > 1e-300) || spread <= 1e-14 * std::abs(mean)) {
    throw InputError("ring-down: the record is constant (" + format_number(mean) + "): no oscillation");
  }

  // 1. Coarse frequency: peak of the Hann-windowed record zero-padded to >= 4n points.
  WindowedDtft dtft;
  {
    const std::vector<double> hann = window_values(Window::hann, static_cast<int>(n));
    dtft.weighted.resize(n);
    dtft.tau.resize(n);
    const double centre = 0.5 * static_cast<double>(n - 1);
    for (std::int64_t i = 0; i < n; ++i) {
      dtft.weighted[i] = hann[i] * (record.values[i] - mean);
      dtft.tau[i] = (static_cast<double>(i) - centre) * dt;
    }
  }
  std::int64_t padded = 1;
  while (padded < 4 * n) padded *= 2;
  std::vector<double> zero_padded(padded, 0.0);
  std::copy(dtft.weighted.begin(), dtft.weighted.end(), zero_padded.begin());
  SpectrumOptions spectrum_options;
  spectrum_options.window = Window::rectangular;
  const AmplitudeSpectrum spectrum =
      SpectrumAnalyzer().amplitude_spectrum(zero_padded, Sampling{dt, 0.0}, spectrum_options);
  const double bin = spectrum.resolution_hz;
  const auto lowest = static_cast<std::size_t>(std::ceil(2.0 / (duration * bin)));  // >= 2/T
  const std::size_t bins = spectrum.amplitude.size();
  if (lowest + 2 >= bins) throw InputError("ring-down: record too short");
  std::size_t peak = lowest;
  for (std::size_t k = lowest; k + 1 < bins; ++k) {
    if (spectrum.amplitude[k] > spectrum.amplitude[peak]) peak = k;
  }
  if (peak == lowest || !(spectrum.amplitude[peak] > 0.0)) {
    throw InputError("ring-down: no spectral peak above 2/T = " + format_number(2.0 / duration) +
                     " Hz: the record does not oscillate or holds fewer than " +
                     std::to_string(kMinPeriods) + " periods");
  }
  double coarse = spectrum.frequency_hz[peak];
  {
    const double left = std::log(spectrum.amplitude[peak - 1]);
    const double middle = std::log(spectrum.amplitude[peak]);
    const double right = std::log(spectrum.amplitude[peak + 1]);
    const double curvature = left - 2.0 * middle + right;
    if (curvature < 0.0) coarse += 0.5 * (left - right) / curvature * bin;
  }
  if (coarse * duration < kMinPeriods) {
    throw InputError("ring-down: the record of " + format_number(duration) + " s holds " +
                     format_number(coarse * duration) + " periods of its dominant frequency " + format_number(coarse) +
                     " Hz; at least " + std::to_string(kMinPeriods) + " needed");
  }

  // Refinement: the maximum of |X_w(f)| within one bin 1/T of the coarse peak.
  double frequency = maximise_magnitude(dtft, coarse - 1.0 / duration, coarse + 1.0 / duration);
  if (std::abs(frequency - coarse) >= 1.0 / duration) frequency = coarse;

  const std::vector<double> orders = ringdown_orders(options);
  const double highest = orders.back() * frequency;
  if (highest * kMinSamplesPerPeriod * dt > 1.0) {
    throw InputError("ring-down: order " + format_number(orders.back()) + " of " + format_number(frequency) +
                     " Hz has " + format_number(1.0 / (highest * dt)) + " samples per period; at least " +
                     std::to_string(kMinSamplesPerPeriod) + " needed (lower max_order)");
  }
  const int step = options.subharmonics ? 2 : 1;
  const double last_time = record.t0 + static_cast<double>(n - 1) * dt;
  int periods = static_cast<int>(std::floor((last_time - record.t0) * frequency));
  periods -= periods % step;
  if (periods < kMinPeriods) {
    throw InputError("ring-down: " + std::to_string(periods) + " whole periods of " +
                     format_number(frequency) + " Hz in the record; at least " + std::to_string(kMinPeriods) +
                     " needed");
  }

  RingdownAnalysis analysis;
  analysis.frequency_hz = frequency;
  analysis.mean = mean;
  analysis.start_time = record.t0;
  analysis.periods = periods;
  analysis.end_time = record.t0 + periods / frequency;

  // 2. Envelope over consecutive windows of whole periods, and the decay of the fundamental.
  int window = std::min(options.window_periods, std::max(1, periods / 3));
  window -= window % step;
  window = std::max(window, step);
  analysis.window_periods = window;
  const std::size_t fundamental =
      static_cast<std::size_t>(std::find(orders.begin(), orders.end(), 1.0) - orders.begin());
  const int n_windows = periods / window;
  std::vector<double> centres;
  std::vector<double> log_amplitudes;
  for (int w = 0; w < n_windows; ++w) {
    EnvelopeWindow envelope;
    envelope.start_time = record.t0 + static_cast<double>(w) * window / frequency;
    envelope.end_time = record.t0 + static_cast<double>(w + 1) * window / frequency;
    for (const auto& c :
         window_amplitudes(record, frequency, envelope.start_time, window, orders)) {
      envelope.amplitude.push_back(std::abs(c));
    }
    if (envelope.amplitude[fundamental] > 0.0) {
      centres.push_back(0.5 * (envelope.start_time + envelope.end_time));
      log_amplitudes.push_back(std::log(envelope.amplitude[fundamental]));
    }
    analysis.envelope.push_back(std::move(envelope));
  }
  if (centres.size() < 2) {
    throw InputError("ring-down: the fundamental vanishes in all but " +
                     std::to_string(centres.size()) + " envelope windows");
  }
  {
    double t_mean = 0.0;
    double y_mean = 0.0;
    for (std::size_t i = 0; i < centres.size(); ++i) {
      t_mean += centres[i];
      y_mean += log_amplitudes[i];
    }
    t_mean /= static_cast<double>(centres.size());
    y_mean /= static_cast<double>(centres.size());
    double stt = 0.0;
    double sty = 0.0;
    for (std::size_t i = 0; i < centres.size(); ++i) {
      stt += (centres[i] - t_mean) * (centres[i] - t_mean);
      sty += (centres[i] - t_mean) * (log_amplitudes[i] - y_mean);
    }
    const double slope = sty / stt;
    double residual = 0.0;
    for (std::size_t i = 0; i < centres.size(); ++i) {
      const double r = log_amplitudes[i] - (y_mean + slope * (centres[i] - t_mean));
      residual += r * r;
    }
    analysis.decay_rate_per_s = -slope;
    analysis.decay_fit_residual = std::sqrt(residual / static_cast<double>(centres.size()));
  }
  const double sigma = analysis.decay_rate_per_s;
  analysis.logarithmic_decrement = sigma / frequency;
  const double delta = analysis.logarithmic_decrement;
  analysis.damping_ratio = delta / std::sqrt(kTwoPi * kTwoPi + delta * delta);
  analysis.natural_frequency_hz = std::hypot(frequency, sigma / kTwoPi);

  // 3. Harmonics over all whole periods of the record with the decay removed.
  std::vector<double> compensated(n);
  for (std::int64_t i = 0; i < n; ++i) {
    compensated[i] = record.values[i] * std::exp(sigma * static_cast<double>(i) * dt);
  }
  const Record flat{compensated.data(), n, record.t0, dt};
  const auto amplitudes = window_amplitudes(flat, frequency, record.t0, periods, orders);
  const double a1 = std::abs(amplitudes[fundamental]);
  for (std::size_t o = 0; o < orders.size(); ++o) {
    RingdownHarmonic h;
    h.order = orders[o];
    h.frequency_hz = orders[o] * frequency;
    h.amplitude = std::abs(amplitudes[o]);
    h.relative_amplitude = a1 > 0.0 ? h.amplitude / a1 : std::numeric_limits<double>::quiet_NaN();
    h.phase_rad = std::arg(amplitudes[o]);
    analysis.harmonics.push_back(h);
  }
  return analysis;
}

FrequencyResponse estimate_frf(const std::vector<double>& response,
                               const std::vector<double>& force, const Sampling& sampling,
                               double f_min, double f_max, double force_threshold) {
  const char* who = "frequency response";
  check_time_step(who, sampling.time_step);
  if (response.size() != force.size() || response.size() < 2) {
    throw InputError("frequency response: response and force need the same length >= 2, got " +
                     std::to_string(response.size()) + " and " + std::to_string(force.size()));
  }
  if (!(f_min <= f_max) || !std::isfinite(f_min) || !std::isfinite(f_max)) {
    throw InputError("frequency response: needs f_min <= f_max, got " + format_number(f_min) + " and " +
                     format_number(f_max));
  }
  if (!(force_threshold >= 0.0 && force_threshold < 1.0)) {
    throw InputError("frequency response: force threshold must be in [0, 1), got " +
                     format_number(force_threshold));
  }
  check_finite(who, response, "response");
  check_finite(who, force, "force");

  const auto n = static_cast<std::int64_t>(force.size());
  const double resolution = 1.0 / (static_cast<double>(n) * sampling.time_step);
  const std::int64_t nyquist = n / 2;

  // Single-bin DFT by phasor recurrence, reseeded every 256 samples.
  const auto dft = [&](const std::vector<double>& x, std::int64_t k) {
    std::complex<double> sum = 0.0;
    std::complex<double> phasor = 1.0;
    const std::complex<double> step = std::polar(1.0, -kTwoPi * static_cast<double>(k) / n);
    for (std::int64_t i = 0; i < n; ++i) {
      if (i % 256 == 0) phasor = std::polar(1.0, -kTwoPi * static_cast<double>((k * i) % n) / n);
      sum += x[i] * phasor;
      phasor *= step;
    }
    return sum;
  };

  // |F_k| / N over all bins (FFT), for the threshold.
  SpectrumOptions spectrum_options;
  spectrum_options.window = Window::rectangular;
  const AmplitudeSpectrum force_spectrum =
      SpectrumAnalyzer().amplitude_spectrum(force, sampling, spectrum_options);
  // Peak amplitudes are 2|F_k|/N except at 0 and Nyquist; compare |F_k| itself.
  std::vector<double> force_magnitude(force_spectrum.amplitude);
  for (std::size_t k = 1; k < force_magnitude.size(); ++k) {
    if (!(n % 2 == 0 && static_cast<std::int64_t>(k) == nyquist)) force_magnitude[k] *= 0.5;
  }
  const double force_max = *std::max_element(force_magnitude.begin(), force_magnitude.end());
  if (!(force_max > 0.0)) throw InputError("frequency response: the force record is zero");

  FrequencyResponse frf;
  frf.resolution_hz = resolution;
  const auto k_begin =
      std::max<std::int64_t>(0, static_cast<std::int64_t>(std::ceil(f_min / resolution - 1e-9)));
  const auto k_end = std::min<std::int64_t>(
      nyquist, static_cast<std::int64_t>(std::floor(f_max / resolution + 1e-9)));
  for (std::int64_t k = k_begin; k <= k_end; ++k) {
    if (!(force_magnitude[k] > force_threshold * force_max)) continue;
    const std::complex<double> h = dft(response, k) / dft(force, k);
    frf.frequency_hz.push_back(static_cast<double>(k) * resolution);
    frf.response.push_back(h);
    frf.magnitude.push_back(std::abs(h));
    frf.phase_rad.push_back(std::arg(h));
  }
  if (frf.frequency_hz.empty()) {
    throw InputError("frequency response: no bin in [" + format_number(f_min) + ", " + format_number(f_max) +
                     "] Hz where the force exceeds " + format_number(force_threshold) + " of its maximum");
  }
  return frf;
}

std::vector<double> frf_peaks(const FrequencyResponse& frf, double relative_threshold) {
  std::vector<double> peaks;
  const std::size_t n = frf.magnitude.size();
  if (n < 3) return peaks;
  const double largest = *std::max_element(frf.magnitude.begin(), frf.magnitude.end());
  const double gap = 1.5 * frf.resolution_hz;  // neighbours must be adjacent bins
  for (std::size_t i = 1; i + 1 < n; ++i) {
    const double left = frf.magnitude[i - 1];
    const double middle = frf.magnitude[i];
    const double right = frf.magnitude[i + 1];
    if (frf.frequency_hz[i] - frf.frequency_hz[i - 1] > gap ||
        frf.frequency_hz[i + 1] - frf.frequency_hz[i] > gap) {
      continue;
    }
    if (!(middle > left && middle >= right && middle >= relative_threshold * largest)) continue;
    const double curvature = left - 2.0 * middle + right;
    const double offset = curvature < 0.0 ? 0.5 * (left - right) / curvature : 0.0;
    peaks.push_back(frf.frequency_hz[i] + offset * (frf.frequency_hz[i + 1] - frf.frequency_hz[i]));
  }
  return peaks;
}

double half_sine_pulse(double t, double start, double duration, double peak) {
  if (!(duration > 0.0))
    throw InputError("half-sine pulse: duration must be > 0, got " + format_number(duration));
  if (t < start || t > start + duration) return 0.0;
  return peak * std::sin(M_PI * (t - start) / duration);
}

double half_sine_pulse_spectrum(double frequency_hz, double duration, double peak) {
  if (!(duration > 0.0))
    throw InputError("half-sine pulse: duration must be > 0, got " + format_number(duration));
  const double u = std::abs(frequency_hz) * duration;
  const double v = 0.5 - u;
  const double sinc = v == 0.0 ? 1.0 : std::sin(M_PI * v) / (M_PI * v);
  return std::abs(peak) * duration * std::abs(sinc) / (1.0 + 2.0 * u);
}

}  // namespace crackle::spectral
