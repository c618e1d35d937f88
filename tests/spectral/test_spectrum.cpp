#include <gtest/gtest.h>

#include <cmath>
#include <complex>
#include <random>
#include <sstream>
#include <thread>

#include "core/errors.hpp"
#include "spectral/spectrum.hpp"
#include "spectral/window.hpp"
#include "synthetic.hpp"

using namespace crackle;
using namespace crackle::spectral;
using namespace crackle::spectral::testing;

namespace {
constexpr double kF = 37.5;

/// Direct one-sided peak-amplitude DFT, the definition the FFT must reproduce.
std::vector<double> direct_spectrum(const std::vector<double>& x) {
  const int n = static_cast<int>(x.size());
  std::vector<double> amplitude(n / 2 + 1);
  for (int k = 0; k <= n / 2; ++k) {
    std::complex<double> sum = 0.0;
    for (int i = 0; i < n; ++i) sum += x[i] * std::polar(1.0, -2 * M_PI * double(k) * i / n);
    const bool single = k == 0 || (n % 2 == 0 && k == n / 2);
    amplitude[k] = k == 0 ? sum.real() / n : (single ? 1.0 : 2.0) * std::abs(sum) / n;  // bin 0: signed mean
  }
  return amplitude;
}
}  // namespace

TEST(Window, NamesRoundTripAndUnknownIsAnInputError) {
  for (Window w : {Window::automatic, Window::rectangular, Window::hann, Window::flattop}) {
    EXPECT_EQ(parse_window(window_name(w)), w);
  }
  EXPECT_THROW(parse_window("hamming"), InputError);
}

TEST(Window, CoherentGainsAreTheKnownConstants) {
  const auto sum = [](const std::vector<double>& w) {
    double s = 0;
    for (double x : w) s += x;
    return s;
  };
  EXPECT_NEAR(sum(window_values(Window::hann, 1000)), 500.0, 1e-9);
  EXPECT_NEAR(sum(window_values(Window::flattop, 1000)), 215.57895, 1e-6);
  EXPECT_EQ(sum(window_values(Window::rectangular, 7)), 7.0);
  EXPECT_NEAR(window_values(Window::hann, 8)[4], 1.0, 1e-15);  // periodic: peak at n/2
}

TEST(Spectrum, FftMatchesTheDirectTransformForEvenAndOddLengths) {
  std::mt19937 generator(7);
  std::uniform_real_distribution<double> uniform(-1.0, 1.0);
  SpectrumAnalyzer analyzer;
  for (int n : {64, 75}) {
    std::vector<double> x(n);
    for (double& v : x) v = uniform(generator);
    SpectrumOptions options;
    options.window = Window::rectangular;
    const AmplitudeSpectrum spectrum = analyzer.amplitude_spectrum(x, {0.01, 0.0}, options);
    const auto expected = direct_spectrum(x);
    ASSERT_EQ(spectrum.amplitude.size(), expected.size());
    for (std::size_t k = 0; k < expected.size(); ++k) {
      EXPECT_NEAR(spectrum.amplitude[k], expected[k], 1e-13) << "n " << n << " bin " << k;
      EXPECT_NEAR(spectrum.frequency_hz[k], k / (n * 0.01), 1e-9);
    }
  }
}

TEST(Spectrum, HarmonicsFallOnExactBinsOfWholePeriods) {
  const auto truth = rich_content();
  const Sampling sampling{1.0 / (kF * 64), 0.002};
  // 20.5 periods: auto cuts to the last 20 (even with sub-harmonics), rectangular.
  const auto values = sample([&](double t) { return evaluate(truth, kF, t); }, sampling, 1312);
  SpectrumOptions options;
  options.excitation_frequency_hz = kF;
  options.subharmonics = true;
  SpectrumAnalyzer analyzer;
  const AmplitudeSpectrum spectrum = analyzer.amplitude_spectrum(values, sampling, options);
  EXPECT_EQ(spectrum.window, Window::rectangular);
  EXPECT_EQ(spectrum.n_samples, 20 * 64);
  EXPECT_NEAR(spectrum.resolution_hz, kF / 20, 1e-12);
  EXPECT_NEAR(spectrum.start_time, sampling.start_time + 32 * sampling.time_step, 1e-15);
  for (std::size_t k = 0; k < spectrum.amplitude.size(); ++k) {
    const double order = spectrum.frequency_hz[k] / kF;
    const std::complex<double> complex_amplitude = expected(truth, std::round(2 * order) / 2);
    // Bin 0 is the signed mean (real), the others peak amplitudes.
    const double expected_amplitude = k == 0 ? complex_amplitude.real() : std::abs(complex_amplitude);
    const bool on_order = std::abs(order * 2 - std::round(order * 2)) < 1e-9;
    EXPECT_NEAR(spectrum.amplitude[k], on_order ? expected_amplitude : 0.0, 1e-12) << "bin " << k;
  }
}

TEST(Spectrum, FlatTopReadsPeakAmplitudesBetweenBins) {
  const auto truth = rich_content();
  const Sampling sampling{1.0 / (kF * 50.37), 0.0};
  const auto values = sample([&](double t) { return evaluate(truth, kF, t); }, sampling, 3000);
  SpectrumOptions options;
  options.excitation_frequency_hz = kF;
  options.subharmonics = true;
  SpectrumAnalyzer analyzer;
  const AmplitudeSpectrum spectrum = analyzer.amplitude_spectrum(values, sampling, options);
  EXPECT_EQ(spectrum.window, Window::flattop);
  for (const Component& c : truth) {
    if (c.order == 0.0) continue;
    double peak = 0.0;
    for (std::size_t k = 0; k < spectrum.amplitude.size(); ++k) {
      if (std::abs(spectrum.frequency_hz[k] - c.order * kF) < 1.5 * spectrum.resolution_hz) {
        peak = std::max(peak, spectrum.amplitude[k]);
      }
    }
    EXPECT_NEAR(peak, c.amplitude, 2e-3 * c.amplitude + 1e-4) << "order " << c.order;
  }
}

TEST(Spectrum, PlansAreCachedByLengthAndSharedAcrossThreads) {
  SpectrumAnalyzer analyzer;
  SpectrumOptions options;
  const Sampling sampling{1e-3, 0.0};
  std::vector<std::vector<double>> records;
  for (int n = 100; n < 112; ++n) {
    std::vector<double> x(n);
    for (int i = 0; i < n; ++i) x[i] = std::sin(0.1 * i * i) + 0.01 * n;
    records.push_back(x);
  }
  analyzer.amplitude_spectrum(records[0], sampling, options);
  analyzer.amplitude_spectrum(records[0], sampling, options);
  EXPECT_EQ(analyzer.n_cached_plans(), 1);
  std::vector<AmplitudeSpectrum> serial;
  for (const auto& x : records) serial.push_back(analyzer.amplitude_spectrum(x, sampling, options));
  EXPECT_EQ(analyzer.n_cached_plans(), 8);  // bounded

  std::vector<std::thread> threads;
  std::vector<int> mismatches(4, 0);
  for (int thread = 0; thread < 4; ++thread) {
    threads.emplace_back([&, thread] {
      for (int repeat = 0; repeat < 20; ++repeat) {
        for (std::size_t r = thread; r < records.size(); r += 2) {
          const AmplitudeSpectrum s = analyzer.amplitude_spectrum(records[r], sampling, options);
          if (s.amplitude != serial[r].amplitude) ++mismatches[thread];
        }
      }
    });
  }
  for (auto& t : threads) t.join();
  EXPECT_EQ(mismatches, (std::vector<int>{0, 0, 0, 0}));
}

TEST(Spectrum, CsvHasUnitsInTheHeaderAndOneLinePerBin) {
  SpectrumAnalyzer analyzer;
  SpectrumOptions options;
  options.window = Window::rectangular;
  const AmplitudeSpectrum spectrum =
      analyzer.amplitude_spectrum(std::vector<double>(10, 2.0), {0.5, 0.0}, options);
  const std::string csv = spectrum_csv(spectrum, "m");
  std::istringstream lines(csv);
  std::string line;
  std::getline(lines, line);
  EXPECT_EQ(line, "frequency [Hz],amplitude [m]");
  std::getline(lines, line);
  EXPECT_EQ(line, "0,2");  // the mean of a constant
  int count = 1;
  while (std::getline(lines, line)) ++count;
  EXPECT_EQ(count, 6);
}

TEST(Spectrum, BadInputIsAnInputError) {
  SpectrumAnalyzer analyzer;
  SpectrumOptions options;
  EXPECT_THROW(analyzer.amplitude_spectrum({1.0}, {0.1, 0.0}, options), InputError);
  EXPECT_THROW(analyzer.amplitude_spectrum({1.0, 2.0}, {0.0, 0.0}, options), InputError);
  options.periods = 2;  // periods without a frequency
  EXPECT_THROW(analyzer.amplitude_spectrum({1.0, 2.0, 3.0}, {0.1, 0.0}, options), InputError);
  options.excitation_frequency_hz = 5.0;  // period of 2 samples: the record holds 1
  EXPECT_THROW(analyzer.amplitude_spectrum({1.0, 2.0, 3.0}, {0.1, 0.0}, options), InputError);
}
