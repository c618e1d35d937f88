#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>

#include "spectral/plot.hpp"
#include "spectral/signature.hpp"
#include "spectral/spectrum.hpp"
#include "synthetic.hpp"
#include "output/spectrum_json.hpp"

using namespace crackle;
using namespace crackle::spectral;
using namespace crackle::spectral::testing;
namespace fs = std::filesystem;

namespace {
constexpr double kF = 37.5;

HarmonicTable rich_table(bool subharmonics) {
  const auto truth = rich_content();
  const Sampling sampling{1.0 / (kF * 64), 0.0};
  HarmonicOptions options;
  options.excitation_frequency_hz = kF;
  options.max_order = 3;
  options.subharmonics = subharmonics;
  return extract_harmonics(sample([&](double t) { return evaluate(truth, kF, t); }, sampling, 20 * 64),
                           sampling, options);
}

fs::path scratch(const std::string& name) {
  const fs::path dir = fs::temp_directory_path() / ("crackle-test-spectral-" + std::to_string(::getpid()));
  fs::create_directories(dir);
  return dir / name;
}

std::string read_prefix(const fs::path& path, std::size_t n) {
  std::ifstream in(path, std::ios::binary);
  std::string text(n, '\0');
  in.read(&text[0], static_cast<std::streamsize>(n));
  text.resize(static_cast<std::size_t>(in.gcount()));
  return text;
}
}  // namespace

TEST(Signature, DamageIndicesAreAmplitudeRatios) {
  const DamageIndices indices = damage_indices(rich_table(true));
  EXPECT_NEAR(indices.a2_over_a1, 0.1, 1e-10);
  EXPECT_NEAR(indices.a3_over_a1, 0.03, 1e-10);
  EXPECT_NEAR(indices.a_half_over_a1, 0.05, 1e-10);
  EXPECT_NEAR(indices.beta, 0.1 / (1.0 * 1.0), 1e-10);
  EXPECT_TRUE(std::isnan(damage_indices(rich_table(false)).a_half_over_a1));
}

TEST(Signature, ProbeJsonHasThePublicKeyNames) {
  const nlohmann::json probe = output::probe_json("z", rich_table(true));
  EXPECT_EQ(probe["component"], "z");
  const auto& harmonics = probe["harmonics"];
  ASSERT_EQ(harmonics.size(), 7u);
  EXPECT_EQ(harmonics[0]["order"], 0);
  EXPECT_EQ(harmonics[1]["order"], 0.5);
  EXPECT_TRUE(harmonics[2]["order"].is_number_integer());  // "order": 1, not 1.0
  EXPECT_EQ(harmonics[2]["order"], 1);
  EXPECT_NEAR(harmonics[2]["frequency_hz"].get<double>(), kF, 1e-12);
  EXPECT_NEAR(harmonics[2]["amplitude"].get<double>(), 1.0, 1e-10);
  EXPECT_NEAR(harmonics[2]["phase_rad"].get<double>(), -1.2, 1e-10);
  for (const auto& h : harmonics) EXPECT_EQ(h.size(), 4u);
  const auto& indices = probe["indices"];
  EXPECT_EQ(indices.size(), 4u);
  EXPECT_NEAR(indices["A2/A1"].get<double>(), 0.1, 1e-10);
  EXPECT_NEAR(indices["A3/A1"].get<double>(), 0.03, 1e-10);
  EXPECT_NEAR(indices["A1/2/A1"].get<double>(), 0.05, 1e-10);
  EXPECT_NEAR(indices["beta"].get<double>(), 0.1, 1e-10);
  EXPECT_EQ(probe.size(), 3u);
  // Without sub-harmonics the index is null, and the JSON still parses back.
  const nlohmann::json plain = output::probe_json("x", rich_table(false));
  EXPECT_TRUE(plain["indices"]["A1/2/A1"].is_null());
  EXPECT_EQ(nlohmann::json::parse(plain.dump()), plain);
}

TEST(Signature, SteadyStateJson) {
  SteadyState state;
  EXPECT_TRUE(output::steady_state_json(state)["change"].is_null());
  state.settled = true;
  state.periods_used = 42;
  state.change = 1e-7;
  const nlohmann::json json = output::steady_state_json(state);
  EXPECT_EQ(json["settled"], true);
  EXPECT_EQ(json["periods_used"], 42);
  EXPECT_EQ(json["change"], 1e-7);
}

TEST(Plot, MissingGnuplotIsANoteNotAFailure) {
  PlotOptions options;
  options.gnuplot = "/nonexistent/gnuplot";
  const fs::path png = scratch("missing.png");
  const PlotResult result = plot_time_history(png, {0.0, 1.0, 0.0}, {0.1, 0.0}, options);
  EXPECT_FALSE(result.written);
  EXPECT_NE(result.note.find("not found"), std::string::npos) << result.note;
  EXPECT_FALSE(fs::exists(png));
  EXPECT_TRUE(fs::exists(result.data));
  EXPECT_TRUE(fs::exists(result.script));
  // An unwritable folder is also only a note.
  const PlotResult nowhere =
      plot_time_history(scratch("no-such-dir") / "x" / "a.png", {0.0, 1.0}, {0.1, 0.0}, options);
  EXPECT_FALSE(nowhere.written);
  EXPECT_FALSE(nowhere.note.empty());
}

TEST(Plot, TimeHistoryAndSpectrumArePngFiles) {
  PlotOptions options;
  if (!gnuplot_available(options)) GTEST_SKIP() << "gnuplot not installed";
  const auto truth = rich_content();
  const Sampling sampling{1.0 / (kF * 64), 0.0};
  const auto values = sample([&](double t) { return evaluate(truth, kF, t); }, sampling, 20 * 64);
  options.title = "probe 'tip' z";
  const std::string signature("\x89PNG\r\n\x1a\n", 8);

  const PlotResult history = plot_time_history(scratch("history.png"), values, sampling, options);
  ASSERT_TRUE(history.written) << history.note;
  EXPECT_EQ(read_prefix(history.png, 8), signature);
  EXPECT_GT(fs::file_size(history.png), 1000u);
  EXPECT_EQ(history.data, scratch("history.dat"));
  EXPECT_EQ(history.script, scratch("history.gp"));

  SpectrumAnalyzer analyzer;
  SpectrumOptions spectrum_options;
  spectrum_options.excitation_frequency_hz = kF;
  spectrum_options.subharmonics = true;
  const AmplitudeSpectrum spectrum = analyzer.amplitude_spectrum(values, sampling, spectrum_options);
  HarmonicOptions orders;
  orders.max_order = 3;
  orders.subharmonics = true;
  const PlotResult plot =
      plot_spectrum(scratch("spectrum.png"), spectrum, kF, harmonic_orders(orders), options);
  ASSERT_TRUE(plot.written) << plot.note;
  EXPECT_EQ(read_prefix(plot.png, 8), signature);
  const std::string script = read_prefix(plot.script, 100000);
  EXPECT_NE(script.find("set logscale y"), std::string::npos);
  EXPECT_NE(script.find("'3/2'"), std::string::npos);
  EXPECT_NE(read_prefix(plot.data, 100).find("# frequency [Hz]  amplitude [m]"), std::string::npos);
}
