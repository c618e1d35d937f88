// Order 0 has one sign convention everywhere: the signed mean (harmonics.hpp), in the harmonic
// table, in its JSON (spectrum.json) and in bin 0 of the amplitude spectrum (spectrum_<probe>.csv).
#include <gtest/gtest.h>

#include <cmath>
#include <string>
#include <vector>
#include <nlohmann/json.hpp>

#include "spectral/harmonics.hpp"
#include "spectral/signature.hpp"
#include "spectral/spectrum.hpp"
#include "output/spectrum_json.hpp"

namespace crackle::spectral {
namespace {

TEST(OrderZero, IsTheSignedMeanInTheTableTheJsonAndTheSpectrum) {
  // x(t) = -3.94e-6 + 1e-5 cos(2 pi f t), 100 samples per period, 8 periods.
  const double f = 10.0, dt = 1.0 / (100 * f), mean = -3.94e-6;
  std::vector<double> x(800);
  for (std::size_t i = 0; i < x.size(); ++i) x[i] = mean + 1e-5 * std::cos(2 * M_PI * f * i * dt);
  const Sampling sampling{dt, 0.0};

  HarmonicOptions harmonic_options;
  harmonic_options.excitation_frequency_hz = f;
  harmonic_options.max_order = 2;
  const HarmonicTable table = extract_harmonics(x, sampling, harmonic_options);
  EXPECT_NEAR(table.amplitude(0.0), mean, 1e-18);
  const nlohmann::json json = output::harmonics_json(table);
  ASSERT_EQ(json[0]["order"], 0);
  EXPECT_NEAR(json[0]["amplitude"].get<double>(), mean, 1e-18);

  SpectrumOptions spectrum_options;
  spectrum_options.excitation_frequency_hz = f;
  SpectrumAnalyzer analyzer;
  const AmplitudeSpectrum spectrum = analyzer.amplitude_spectrum(x, sampling, spectrum_options);
  EXPECT_NEAR(spectrum.amplitude[0], mean, 1e-18);
  EXPECT_NEAR(spectrum.amplitude[8], 1e-5, 1e-17);  // 8 periods: f on bin 8
  const std::string csv = spectrum_csv(spectrum, "m");
  const std::string first_row = csv.substr(csv.find('\n') + 1, csv.find('\n', csv.find('\n') + 1) - csv.find('\n') - 1);
  EXPECT_EQ(first_row.substr(0, 3), "0,-") << first_row;
  EXPECT_NEAR(std::stod(first_row.substr(2)), mean, 1e-18);
}

}  // namespace
}  // namespace crackle::spectral
