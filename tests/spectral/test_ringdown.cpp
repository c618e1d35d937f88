#include <gtest/gtest.h>

#include <cmath>
#include <complex>
#include <cstdio>
#include <vector>
#include <nlohmann/json.hpp>

#include "core/errors.hpp"
#include "spectral/ringdown.hpp"
#include "synthetic.hpp"
#include "output/spectrum_json.hpp"

using namespace crackle;
using namespace crackle::spectral;
using namespace crackle::spectral::testing;

namespace {

/// A linear mode ringing down: A e^{-zeta w_n t} cos(w_d t + phi), w_d = w_n sqrt(1 - zeta^2).
struct DampedMode {
  double damped_frequency = 164.1;  // f_d [Hz]
  double zeta = 0.005;
  double amplitude = 1.3;
  double phase = 0.4;
  double omega_d() const { return 2.0 * M_PI * damped_frequency; }
  double omega_n() const { return omega_d() / std::sqrt(1.0 - zeta * zeta); }
  double sigma() const { return zeta * omega_n(); }
  double operator()(double t) const {
    return amplitude * std::exp(-sigma() * t) * std::cos(omega_d() * t + phase);
  }
};

/// The exact free vibration of an undamped bilinear oscillator: half a sine at w_o while
/// x > 0 (crack open), half a sine at w_u while x < 0 (closed), amplitudes A_o w_o = A_u w_u so
/// that displacement and velocity are continuous at the crossings; x = 0 rising at t = shift.
struct Bilinear {
  double f_open = 140.0;    // [Hz]
  double f_closed = 164.1;  // [Hz]
  double amplitude_open = 1.0;
  double shift = 0.0021;  // [s]
  double omega_o() const { return 2.0 * M_PI * f_open; }
  double omega_u() const { return 2.0 * M_PI * f_closed; }
  double half_open() const { return M_PI / omega_o(); }
  double period() const { return M_PI / omega_o() + M_PI / omega_u(); }
  double frequency() const { return 2.0 * f_open * f_closed / (f_open + f_closed); }
  double operator()(double t) const {
    double tau = std::fmod(t - shift, period());
    if (tau < 0.0) tau += period();
    if (tau <= half_open()) return amplitude_open * std::sin(omega_o() * tau);
    const double amplitude_closed = amplitude_open * omega_o() / omega_u();
    return -amplitude_closed * std::sin(omega_u() * (tau - half_open()));
  }
  /// C_k = (2/T) int_0^T x(shift + s) e^{-i 2 pi k s / T} ds by composite Simpson on each
  /// smooth half (2 x 20000 intervals: error ~ 1e-15 for k <= 3); |C_k| = A_k.
  std::complex<double> coefficient(int k) const {
    const auto integrate = [&](double a, double b) {
      const int intervals = 20000;
      const double h = (b - a) / intervals;
      std::complex<double> sum = 0.0;
      for (int j = 0; j <= intervals; ++j) {
        const double s = a + j * h;
        const double weight = (j == 0 || j == intervals) ? 1.0 : (j % 2 == 1 ? 4.0 : 2.0);
        sum += weight * (*this)(shift + s) * std::polar(1.0, -2.0 * M_PI * k * s / period());
      }
      return sum * h / 3.0;
    };
    return 2.0 / period() * (integrate(0.0, half_open()) + integrate(half_open(), period()));
  }
};

/// Single-DOF oscillator m x'' + c x' + k x = p(t) under a half-sine pulse.
struct Oscillator {
  double mass = 2.0;         // [kg]
  double stiffness = 2.0e5;  // [N/m]
  double zeta = 0.02;
  double pulse_start = 0.01;      // [s]
  double pulse_duration = 0.005;  // 50 samples at 10 kHz; first zero of |P| at 300 Hz
  double pulse_peak = 100.0;      // [N]
  double damping() const { return 2.0 * zeta * std::sqrt(stiffness * mass); }
  double natural_frequency() const { return std::sqrt(stiffness / mass) / (2.0 * M_PI); }
  double force(double t) const {
    return half_sine_pulse(t, pulse_start, pulse_duration, pulse_peak);
  }
  /// The exact FRF 1 / (k - m w^2 + i c w).
  std::complex<double> frf(double f) const {
    const double w = 2.0 * M_PI * f;
    return 1.0 / std::complex<double>(stiffness - mass * w * w, damping() * w);
  }
  /// Response at t_i = i dt, i < n, from rest, by RK4 with `substeps` steps per sample; the
  /// pulse starts and ends on sample times, so the force is smooth within every step.
  std::vector<double> response(double dt, long n, int substeps) const {
    std::vector<double> x(n);
    double position = 0.0;
    double velocity = 0.0;
    const double h = dt / substeps;
    const auto acceleration = [&](double t, double q, double v) {
      return (force(t) - damping() * v - stiffness * q) / mass;
    };
    for (long i = 0; i < n; ++i) {
      x[i] = position;
      for (int s = 0; s < substeps; ++s) {
        const double t = i * dt + s * h;
        const double k1x = velocity, k1v = acceleration(t, position, velocity);
        const double k2x = velocity + 0.5 * h * k1v;
        const double k2v = acceleration(t + 0.5 * h, position + 0.5 * h * k1x, k2x);
        const double k3x = velocity + 0.5 * h * k2v;
        const double k3v = acceleration(t + 0.5 * h, position + 0.5 * h * k2x, k3x);
        const double k4x = velocity + h * k3v;
        const double k4v = acceleration(t + h, position + h * k3x, k4x);
        position += h / 6.0 * (k1x + 2.0 * k2x + 2.0 * k3x + k4x);
        velocity += h / 6.0 * (k1v + 2.0 * k2v + 2.0 * k3v + k4v);
      }
    }
    return x;
  }
};

}  // namespace

TEST(Ringdown, DampedLinearModeFrequencyDampingAndNoHarmonics) {
  const DampedMode mode;
  // ~100.37 samples per period (not a whole number), 60 periods, sample 0 at t = 0.01 s.
  const Sampling sampling{1.0 / (100.37 * mode.damped_frequency), 0.01};
  const auto samples = sample(mode, sampling, static_cast<long>(60 * 100.37));
  const RingdownAnalysis analysis = analyse_ringdown(samples, sampling, RingdownOptions{});

  const double frequency_error = std::abs(analysis.frequency_hz / mode.damped_frequency - 1.0);
  const double zeta_error = std::abs(analysis.damping_ratio / mode.zeta - 1.0);
  const double sigma_error = std::abs(analysis.decay_rate_per_s / mode.sigma() - 1.0);
  const double natural_error =
      std::abs(analysis.natural_frequency_hz / (mode.omega_n() / (2.0 * M_PI)) - 1.0);
  std::printf(
      "[ measured ] damped mode: |df|/f %.2e, |dzeta|/zeta %.2e, |dsigma|/sigma %.2e, "
      "|df_n|/f_n %.2e, A2/A1 %.2e, A3/A1 %.2e\n",
      frequency_error, zeta_error, sigma_error, natural_error, analysis.at(2.0).relative_amplitude,
      analysis.at(3.0).relative_amplitude);
  EXPECT_LT(frequency_error, 1e-5);
  EXPECT_LT(zeta_error, 1e-2);
  EXPECT_LT(natural_error, 1e-5);
  EXPECT_LT(analysis.at(2.0).relative_amplitude, 1e-6);
  EXPECT_LT(analysis.at(3.0).relative_amplitude, 1e-6);
  EXPECT_LT(analysis.decay_fit_residual, 1e-6);  // an exact exponential

  // With the decay removed, A_1 and phi_1 are those at the analysis start (absolute time).
  const RingdownHarmonic& first = analysis.at(1.0);
  EXPECT_NEAR(first.amplitude, mode.amplitude * std::exp(-mode.sigma() * analysis.start_time),
              1e-5 * mode.amplitude);
  EXPECT_NEAR(std::remainder(first.phase_rad - mode.phase, 2.0 * M_PI), 0.0, 1e-5);
  EXPECT_EQ(first.relative_amplitude, 1.0);

  // Envelope: consecutive windows of 4 periods; A_1 per window is the mean envelope over the
  // window up to the leakage of -f (~ zeta / 2).
  ASSERT_EQ(analysis.window_periods, 4);
  ASSERT_EQ(static_cast<int>(analysis.envelope.size()), analysis.periods / 4);
  for (const EnvelopeWindow& window : analysis.envelope) {
    EXPECT_NEAR(window.end_time - window.start_time, 4.0 / analysis.frequency_hz, 1e-12);
    const double centre = 0.5 * (window.start_time + window.end_time);
    const double expected = mode.amplitude * std::exp(-mode.sigma() * centre);
    EXPECT_NEAR(window.amplitude[0] / expected, 1.0, 5e-3);
  }
}

TEST(Ringdown, ExactBilinearWaveformFrequencyAndHarmonics) {
  const Bilinear bilinear;
  const double f = bilinear.frequency();
  const Sampling sampling{1.0 / (99.63 * f), 0.0137};
  const auto samples = sample(bilinear, sampling, static_cast<long>(60 * 99.63));
  const RingdownAnalysis analysis = analyse_ringdown(samples, sampling, RingdownOptions{});

  const double frequency_error = std::abs(analysis.frequency_hz / f - 1.0);
  const std::complex<double> c1 = bilinear.coefficient(1);
  const double exact_2 = std::abs(bilinear.coefficient(2)) / std::abs(c1);
  const double exact_3 = std::abs(bilinear.coefficient(3)) / std::abs(c1);
  const double error_2 = std::abs(analysis.at(2.0).relative_amplitude - exact_2);
  const double error_3 = std::abs(analysis.at(3.0).relative_amplitude - exact_3);
  std::printf(
      "[ measured ] bilinear f %.6f Hz: |df|/f %.2e; A2/A1 %.6e (exact %.6e, error %.2e); "
      "A3/A1 %.6e (exact %.6e, error %.2e); zeta %.2e\n",
      analysis.frequency_hz, frequency_error, analysis.at(2.0).relative_amplitude, exact_2, error_2,
      analysis.at(3.0).relative_amplitude, exact_3, error_3, analysis.damping_ratio);
  EXPECT_LT(frequency_error, 1e-5);
  // Relative to each ratio (A2/A1 ~ 4e-2, A3/A1 ~ 1e-3 here): the stricter reading of "1e-3".
  EXPECT_LT(error_2, 1e-3 * exact_2);
  EXPECT_LT(error_3, 1e-3 * exact_3);
  EXPECT_LT(std::abs(analysis.damping_ratio), 1e-6);  // undamped
  EXPECT_NEAR(analysis.at(1.0).amplitude, std::abs(c1), 1e-6 * std::abs(c1));
}

TEST(Ringdown, SubharmonicOrders) {
  const double f = 37.5;
  const std::vector<Component> truth = {{0.5, 0.05, 1.1}, {1.0, 1.0, 0.3}, {2.0, 0.02, -0.5}};
  const Sampling sampling{1.0 / (53.3 * f), -0.2};
  const auto samples = sample([&](double t) { return evaluate(truth, f, t); }, sampling,
                              static_cast<long>(40 * 53.3));
  RingdownOptions options;
  options.max_order = 2;
  options.subharmonics = true;
  const RingdownAnalysis analysis = analyse_ringdown(samples, sampling, options);
  EXPECT_NEAR(analysis.frequency_hz, f, 1e-6 * f);
  ASSERT_EQ(analysis.harmonics.size(), 4u);
  EXPECT_EQ(analysis.periods % 2, 0);
  EXPECT_NEAR(analysis.at(0.5).relative_amplitude, 0.05, 1e-6);
  EXPECT_NEAR(analysis.at(1.5).relative_amplitude, 0.0, 1e-6);
  EXPECT_NEAR(analysis.at(2.0).relative_amplitude, 0.02, 1e-6);
  EXPECT_NEAR(std::remainder(analysis.at(0.5).phase_rad - 1.1, 2.0 * M_PI), 0.0, 1e-4);
}

TEST(Ringdown, StartTimeSkipsTheDrive) {
  // A forced tone at 60 Hz until t = 0.5 s, then the free ring-down of the mode.
  const DampedMode mode;
  const Sampling sampling{1.0 / 20000.0, 0.0};
  const auto samples = sample(
      [&](double t) { return t < 0.5 ? 3.0 * std::sin(2.0 * M_PI * 60.0 * t) : mode(t - 0.5); },
      sampling, 20000);
  RingdownOptions options;
  options.start_time = 0.5;
  const RingdownAnalysis analysis = analyse_ringdown(samples, sampling, options);
  EXPECT_NEAR(analysis.start_time, 0.5, 1e-12);
  EXPECT_NEAR(analysis.frequency_hz, mode.damped_frequency, 1e-6 * mode.damped_frequency);
  EXPECT_NEAR(analysis.damping_ratio, mode.zeta, 1e-2 * mode.zeta);
}

TEST(Ringdown, BadRecordsAreInputErrors) {
  const DampedMode mode;
  const Sampling sampling{1.0 / (100.37 * mode.damped_frequency), 0.0};
  // 3 periods: too short.
  EXPECT_THROW(analyse_ringdown(sample(mode, sampling, 301), sampling, {}), InputError);
  // No oscillation: a constant, a pure exponential decay.
  EXPECT_THROW(analyse_ringdown(std::vector<double>(5000, 2.5), sampling, {}), InputError);
  EXPECT_THROW(
      analyse_ringdown(sample([](double t) { return std::exp(-20.0 * t); }, sampling, 5000),
                       sampling, {}),
      InputError);
  // Start time past the record, too few samples, bad options.
  RingdownOptions late;
  late.start_time = 1e3;
  EXPECT_THROW(analyse_ringdown(sample(mode, sampling, 5000), sampling, late), InputError);
  EXPECT_THROW(analyse_ringdown({1.0, -1.0, 1.0}, sampling, {}), InputError);
  RingdownOptions bad;
  bad.max_order = 0;
  EXPECT_THROW(analyse_ringdown(sample(mode, sampling, 5000), sampling, bad), InputError);
  // Too coarse for order 3 (10 samples per period of f).
  const Sampling coarse{1.0 / (10.0 * mode.damped_frequency), 0.0};
  EXPECT_THROW(analyse_ringdown(sample(mode, coarse, 500), coarse, {}), InputError);
  try {
    analyse_ringdown(sample(mode, sampling, 301), sampling, {});
  } catch (const InputError& error) {
    EXPECT_NE(std::string(error.what()).find("periods"), std::string::npos) << error.what();
  }
}

TEST(Ringdown, Json) {
  const DampedMode mode;
  const Sampling sampling{1.0 / (100.37 * mode.damped_frequency), 0.0};
  const RingdownAnalysis analysis =
      analyse_ringdown(sample(mode, sampling, 6000), sampling, RingdownOptions{});
  const nlohmann::json json = output::ringdown_json(analysis);
  EXPECT_EQ(json.at("frequency_hz").get<double>(), analysis.frequency_hz);
  EXPECT_EQ(json.at("damping_ratio").get<double>(), analysis.damping_ratio);
  EXPECT_EQ(json.at("periods").get<int>(), analysis.periods);
  ASSERT_EQ(json.at("harmonics").size(), 3u);
  EXPECT_TRUE(json.at("harmonics")[1].at("order").is_number_integer());
  EXPECT_EQ(json.at("harmonics")[1].at("order").get<int>(), 2);
  EXPECT_EQ(json.at("envelope").at("amplitude").size(), analysis.envelope.size());
  EXPECT_EQ(json.at("envelope").at("amplitude")[0].size(), 3u);
  EXPECT_EQ(json.at("envelope").at("orders")[0].get<int>(), 1);
}

TEST(HalfSinePulse, ValuesAndAnalyticSpectrum) {
  const double start = 0.01, duration = 0.002, peak = 100.0;
  EXPECT_EQ(half_sine_pulse(0.0, start, duration, peak), 0.0);
  EXPECT_NEAR(half_sine_pulse(start + 0.5 * duration, start, duration, peak), peak, 1e-12);
  EXPECT_EQ(half_sine_pulse(start + 1.01 * duration, start, duration, peak), 0.0);
  EXPECT_NEAR(half_sine_pulse_spectrum(0.0, duration, peak), 2.0 * peak * duration / M_PI, 1e-15);
  EXPECT_NEAR(half_sine_pulse_spectrum(0.5 / duration, duration, peak), 0.5 * peak * duration,
              1e-15);
  EXPECT_NEAR(half_sine_pulse_spectrum(1.5 / duration, duration, peak), 0.0,
              1e-15 * peak * duration);
  EXPECT_GT(half_sine_pulse_spectrum(1.4 / duration, duration, peak), 0.0);
  // Against the Fourier integral by the midpoint rule on 2e5 points.
  for (double f : {0.0, 123.0, 500.0, 1000.0, 2600.0}) {
    std::complex<double> integral = 0.0;
    const int points = 200000;
    const double h = duration / points;
    for (int j = 0; j < points; ++j) {
      const double t = start + (j + 0.5) * h;
      integral += half_sine_pulse(t, start, duration, peak) * std::polar(h, -2.0 * M_PI * f * t);
    }
    EXPECT_NEAR(half_sine_pulse_spectrum(f, duration, peak), std::abs(integral),
                1e-9 * peak * duration)
        << f;
  }
  EXPECT_THROW(half_sine_pulse(0.0, 0.0, 0.0, 1.0), InputError);
}

TEST(Frf, SingleDofUnderHalfSinePulse) {
  const Oscillator oscillator;
  const double dt = 1e-4;
  const long n = 20000;  // T = 2 s: the response decays by e^{-zeta w_n T} ~ 3e-6 by the end
  const Sampling sampling{dt, 0.0};
  const auto force = sample([&](double t) { return oscillator.force(t); }, sampling, n);
  const auto response = oscillator.response(dt, n, 10);
  const double f_max = 1.0 / oscillator.pulse_duration;  // below the first zero 1.5/d
  const FrequencyResponse frf = estimate_frf(response, force, sampling, 0.0, f_max);
  const double resolution = 1.0 / (n * dt);
  EXPECT_DOUBLE_EQ(frf.resolution_hz, resolution);
  ASSERT_EQ(frf.frequency_hz.size(), static_cast<std::size_t>(f_max / resolution) + 1);

  // Static limit: H(0) = int x / int p = 1/k once the response has died out.
  EXPECT_NEAR(frf.magnitude[0] * oscillator.stiffness, 1.0, 1e-3);
  EXPECT_NEAR(frf.magnitude[1] * oscillator.stiffness, 1.0, 1e-3);

  // The whole band against the exact FRF.
  double worst = 0.0;
  for (std::size_t i = 0; i < frf.frequency_hz.size(); ++i) {
    const std::complex<double> exact = oscillator.frf(frf.frequency_hz[i]);
    worst = std::max(worst, std::abs(frf.response[i] - exact) / std::abs(exact));
    EXPECT_NEAR(frf.magnitude[i], std::abs(frf.response[i]), 1e-15 * frf.magnitude[i]);
  }

  const std::vector<double> peaks = frf_peaks(frf, 0.5);
  ASSERT_EQ(peaks.size(), 1u);
  const double f_n = oscillator.natural_frequency();
  const double exact_peak = f_n * std::sqrt(1.0 - 2.0 * oscillator.zeta * oscillator.zeta);
  std::printf(
      "[ measured ] FRF: max |H - H_exact|/|H_exact| %.2e over 0..%.0f Hz; peak %.4f Hz, "
      "exact %.4f Hz (1/T = %.2f Hz), |H(0)| k - 1 = %.2e\n",
      worst, f_max, peaks[0], exact_peak, resolution,
      frf.magnitude[0] * oscillator.stiffness - 1.0);
  // The sampled pulse (50 samples) is not the continuous one: its DFT differs from P(f) by
  // (pi/50)^2/12 = 3e-4 at f = 0 (the trapezoidal rule) and by aliasing that grows with f.
  EXPECT_LT(worst, 2e-3);
  EXPECT_LT(std::abs(peaks[0] - exact_peak), resolution);

  // The band stops where the force vanishes: around the first zero of the pulse spectrum.
  const FrequencyResponse wide = estimate_frf(response, force, sampling, 0.0, 1000.0, 1e-3);
  for (double f : wide.frequency_hz) {
    EXPECT_GT(
        half_sine_pulse_spectrum(f, oscillator.pulse_duration, oscillator.pulse_peak),
        0.5e-3 * half_sine_pulse_spectrum(0.0, oscillator.pulse_duration, oscillator.pulse_peak));
  }
  EXPECT_LT(wide.frequency_hz.size(), static_cast<std::size_t>(1000.0 / resolution) + 1);

  EXPECT_THROW(estimate_frf(response, std::vector<double>(n - 1, 0.0), sampling, 0.0, 100.0),
               InputError);
  EXPECT_THROW(estimate_frf(response, std::vector<double>(n, 0.0), sampling, 0.0, 100.0),
               InputError);
  EXPECT_THROW(estimate_frf(response, force, sampling, 200.0, 100.0), InputError);
}
