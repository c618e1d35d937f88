#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "core/errors.hpp"
#include "core/quadrature.hpp"
#include "spectral/harmonics.hpp"
#include "spectral/steady_monitor.hpp"
#include "synthetic.hpp"

using namespace crackle;
using namespace crackle::spectral;
using namespace crackle::spectral::testing;

namespace {

constexpr double kF = 37.5;  // excitation frequency [Hz] of the synthetic tests

/// Largest |C_table - C_expected| over the table's orders, relative to `scale`.
double worst_error(const HarmonicTable& table, const std::vector<Component>& truth, double scale) {
  double worst = 0.0;
  for (const Harmonic& h : table.harmonics) {
    worst = std::max(worst, std::abs(h.complex_amplitude() - expected(truth, h.order)) / scale);
  }
  return worst;
}

/// Phase difference wrapped to (-pi, pi].
double phase_gap(double a, double b) { return std::remainder(a - b, 2.0 * M_PI); }

HarmonicOptions rich_options() {
  HarmonicOptions options;
  options.excitation_frequency_hz = kF;
  options.max_order = 3;
  options.subharmonics = true;
  return options;
}

}  // namespace

TEST(Harmonics, OrdersAreAscendingWithTheMeanFirst) {
  HarmonicOptions options = rich_options();
  EXPECT_EQ(harmonic_orders(options), (std::vector<double>{0, 0.5, 1, 1.5, 2, 2.5, 3}));
  options.subharmonics = false;
  EXPECT_EQ(harmonic_orders(options), (std::vector<double>{0, 1, 2, 3}));
}

TEST(Harmonics, ExactPeriodRecordRecoversEveryAmplitudeAndAbsolutePhase) {
  const auto truth = rich_content();
  const Sampling sampling{1.0 / (kF * 64), 0.0123};  // 64 samples a period, t0 != 0
  const auto values = sample([&](double t) { return evaluate(truth, kF, t); }, sampling, 20 * 64);
  const HarmonicTable table = extract_harmonics(values, sampling, rich_options());

  EXPECT_EQ(table.method, Method::exact_bins);
  EXPECT_EQ(table.window, Window::rectangular);
  EXPECT_EQ(table.periods, 20);
  EXPECT_NEAR(table.start_time, sampling.start_time, 1e-12);
  ASSERT_EQ(table.harmonics.size(), 7u);
  for (const Harmonic& h : table.harmonics) {
    const std::complex<double> c = expected(truth, h.order);
    EXPECT_DOUBLE_EQ(h.frequency_hz, h.order * kF);
    if (std::abs(c) == 0.0) {
      EXPECT_LT(std::abs(h.amplitude), 1e-13) << "order " << h.order;
      continue;
    }
    if (h.order == 0.0) {
      EXPECT_NEAR(h.amplitude, -0.3, 1e-9 * 0.3);  // signed mean, phase 0
      EXPECT_EQ(h.phase_rad, 0.0);
      continue;
    }
    EXPECT_NEAR(h.amplitude, std::abs(c), 1e-9 * std::abs(c)) << "order " << h.order;
    EXPECT_NEAR(phase_gap(h.phase_rad, std::arg(c)), 0.0, 1e-9) << "order " << h.order;
  }
  // Half orders are exact bins only over an even number of periods.
  HarmonicOptions odd = rich_options();
  odd.periods = 19;
  EXPECT_THROW(extract_harmonics(values, sampling, odd), InputError);
}

TEST(Harmonics, RecordStartingInADecayingTransientUsesTheSettledEnd) {
  const auto truth = rich_content();
  const Sampling sampling{1.0 / (kF * 64), 0.0};
  const double tau = 3.0 / kF;  // decay time of 3 periods, at the incommensurate order 1.37
  const auto signal = [&](double t) {
    return evaluate(truth, kF, t) + 0.5 * std::exp(-t / tau) * std::cos(2 * M_PI * 1.37 * kF * t);
  };
  const auto values = sample(signal, sampling, 120 * 64);
  HarmonicOptions options = rich_options();
  options.periods = 8;  // the last 8 periods: the transient is below 1e-16 there
  const HarmonicTable settled = extract_harmonics(values, sampling, options);
  EXPECT_NEAR(settled.start_time, 112.0 / kF, 1e-12);
  for (const Harmonic& h : settled.harmonics) {
    const std::complex<double> c = expected(truth, h.order);
    const double scale = std::abs(c) > 0 ? std::abs(c) : 1.0;
    EXPECT_LT(std::abs(h.complex_amplitude() - c) / scale, 1e-9) << "order " << h.order;
  }
  // The whole record still carries the transient: the window choice matters.
  options.periods = 0;
  const HarmonicTable whole = extract_harmonics(values, sampling, options);
  EXPECT_EQ(whole.periods, 120);
  EXPECT_GT(worst_error(whole, truth, 1.0), 1e-4);
}

TEST(Harmonics, NoiseAveragesOutAtTheExpectedRate) {
  const auto truth = rich_content();
  const Sampling sampling{1.0 / (kF * 64), 0.0};
  const long n = 200 * 64;
  auto values = sample([&](double t) { return evaluate(truth, kF, t); }, sampling, n);
  std::mt19937 generator(12345);
  std::normal_distribution<double> noise(0.0, 1e-2);
  for (double& x : values) x += noise(generator);
  const HarmonicTable table = extract_harmonics(values, sampling, rich_options());
  // Standard error of a complex amplitude: sigma sqrt(2/N) = 1.25e-4; allow 8 of them.
  const double error = worst_error(table, truth, 1.0);
  EXPECT_LT(error, 8 * 1e-2 * std::sqrt(2.0 / n));
  EXPECT_GT(error, 1e-6);  // the noise is really there
}

TEST(Harmonics, NonIntegerPeriodIsResampledWithoutLeakage) {
  const auto truth = rich_content();
  const Sampling sampling{1.0 / (kF * 50.37), 0.004};  // 50.37 samples a period
  const auto values = sample([&](double t) { return evaluate(truth, kF, t); }, sampling, 2100);
  HarmonicOptions options = rich_options();
  options.periods = 40;
  const HarmonicTable table = extract_harmonics(values, sampling, options);
  EXPECT_EQ(table.method, Method::resampled);
  EXPECT_EQ(table.window, Window::rectangular);
  EXPECT_NEAR(table.end_time - table.start_time, 40.0 / kF, 1e-12);
  for (const Harmonic& h : table.harmonics) {
    const std::complex<double> c = expected(truth, h.order);
    const double scale = std::abs(c) > 0 ? std::abs(c) : 1.0;
    EXPECT_LT(std::abs(h.complex_amplitude() - c) / scale, 1e-3) << "order " << h.order;
  }
  // 8-point interpolation at 17 samples per period of order 3 does much better than asked.
  EXPECT_LT(worst_error(table, truth, 1.0), 1e-5);
}

TEST(Harmonics, HannAndFlatTopHandleNonIntegerRecords) {
  const auto truth = rich_content();
  const Sampling sampling{1.0 / (kF * 50.37), 0.004};
  const auto values = sample([&](double t) { return evaluate(truth, kF, t); }, sampling, 2100);
  for (Window window : {Window::hann, Window::flattop}) {
    HarmonicOptions options = rich_options();
    options.periods = 40;
    options.window = window;
    const HarmonicTable table = extract_harmonics(values, sampling, options);
    EXPECT_EQ(table.method, Method::windowed);
    EXPECT_EQ(table.window, window);
    EXPECT_LT(worst_error(table, truth, 1.0), 1e-3) << window_name(window);
  }
  // Too coarse to resample (6.8 samples a period of order 3): auto falls back to Hann.
  const Sampling coarse{1.0 / (kF * 20.37), 0.0};
  const auto coarse_values =
      sample([&](double t) { return evaluate(truth, kF, t); }, coarse, 40 * 21);
  HarmonicOptions options = rich_options();
  const HarmonicTable table = extract_harmonics(coarse_values, coarse, options);
  EXPECT_EQ(table.method, Method::windowed);
  EXPECT_EQ(table.window, Window::hann);
  EXPECT_EQ(table.periods, 40);
  EXPECT_LT(worst_error(table, truth, 1.0), 1e-3);
}

TEST(Harmonics, BadInputIsAnInputError) {
  const Sampling sampling{1.0 / (kF * 64), 0.0};
  const std::vector<double> values(64 * 3, 1.0);
  HarmonicOptions options = rich_options();
  options.excitation_frequency_hz = 0.0;
  EXPECT_THROW(extract_harmonics(values, sampling, options), InputError);
  options = rich_options();
  options.max_order = 40;  // 40 f is above the Nyquist frequency 32 f
  EXPECT_THROW(extract_harmonics(values, sampling, options), InputError);
  options = rich_options();
  options.periods = 4;  // the record holds 3
  EXPECT_THROW(extract_harmonics(values, sampling, options), InputError);
  options.subharmonics = false;
  options.periods = 3;
  EXPECT_NO_THROW(extract_harmonics(values, sampling, options));
  EXPECT_THROW(extract_harmonics(std::vector<double>(40, 1.0), sampling, options), InputError);
}

// ---- the exact waveform of a free bilinear oscillator

namespace {

/// Free vibration of a bilinear oscillator: stiffness k_c (angular frequency w_c) while x > 0,
/// k_o (w_o) while x < 0. Velocity is continuous at the switches, so the two half-waves have
/// different amplitudes: x = A sin(w_c t) on [0, pi/w_c), then -(A w_c/w_o) sin(w_o (t - pi/w_c)).
struct Bilinear {
  double w_c = 2 * M_PI * 50.0;
  double w_o = 0.8 * 2 * M_PI * 50.0;
  double amplitude = 1e-3;
  double period() const { return M_PI / w_c + M_PI / w_o; }
  double operator()(double t) const {
    const double s = t - period() * std::floor(t / period());
    if (s < M_PI / w_c) return amplitude * std::sin(w_c * s);
    return -(amplitude * w_c / w_o) * std::sin(w_o * (s - M_PI / w_c));
  }
  /// c_k = (2/T) int_0^T x e^{-i k w t} dt (c_0: the mean) by 24-point Gauss-Legendre on 16
  /// panels of each smooth half-wave (the integrand is analytic on each).
  std::complex<double> fourier(int k) const {
    const Rule1D rule = gauss_legendre(24);
    const double w = 2 * M_PI / period();
    std::complex<double> sum = 0.0;
    const double edges[3] = {0.0, M_PI / w_c, period()};
    for (int half = 0; half < 2; ++half) {
      const int panels = 16;
      const double length = (edges[half + 1] - edges[half]) / panels;
      for (int p = 0; p < panels; ++p) {
        const double a = edges[half] + p * length;
        for (int q = 0; q < rule.size(); ++q) {
          const double t = a + 0.5 * length * (rule.points[q] + 1.0);
          const double x = half == 0 ? amplitude * std::sin(w_c * t)
                                     : -(amplitude * w_c / w_o) * std::sin(w_o * (t - M_PI / w_c));
          sum += 0.5 * length * rule.weights[q] * x * std::polar(1.0, -k * w * t);
        }
      }
    }
    return (k == 0 ? 1.0 : 2.0) * sum / period();
  }
};

}  // namespace

TEST(Harmonics, BilinearOscillatorMatchesItsFourierIntegral) {
  const Bilinear oscillator;
  // The fundamental of the waveform is the bilinear frequency 2 w_o w_c / (w_o + w_c).
  const double f = oscillator.w_o * oscillator.w_c / (oscillator.w_o + oscillator.w_c) / M_PI;
  EXPECT_NEAR(1.0 / oscillator.period(), f, 1e-12 * f);
  // The quadrature itself against the closed-form mean.
  const double mean = (2 * oscillator.amplitude / oscillator.w_c -
                       2 * oscillator.amplitude * oscillator.w_c / (oscillator.w_o * oscillator.w_o)) /
                      oscillator.period();
  EXPECT_NEAR(oscillator.fourier(0).real(), mean, 1e-15);

  HarmonicOptions options;
  options.excitation_frequency_hz = f;
  options.max_order = 6;
  for (double samples_per_period : {1000.0, 1000.37}) {
    const Sampling sampling{1.0 / (f * samples_per_period), 0.0};
    const auto values = sample(oscillator, sampling, std::lround(6.2 * samples_per_period));
    const HarmonicTable table = extract_harmonics(values, sampling, options);
    EXPECT_EQ(table.method, samples_per_period == 1000.0 ? Method::exact_bins : Method::resampled);
    EXPECT_EQ(table.periods, 6);
    const double a1 = std::abs(oscillator.fourier(1));
    for (int k = 0; k <= 6; ++k) {
      const std::complex<double> exact = oscillator.fourier(k);
      EXPECT_LT(std::abs(table.at(k).complex_amplitude() - exact) / a1, 1e-6)
          << "order " << k << " at " << samples_per_period << " samples a period";
      if (table.method == Method::exact_bins) {  // only aliasing of order ~1000 remains
        EXPECT_LT(std::abs(table.at(k).complex_amplitude() - exact) / a1, 1e-9) << "order " << k;
      }
    }
    // The breathing produces even harmonics (a symmetric oscillator would not).
    EXPECT_GT(table.amplitude(2) / table.amplitude(1), 1e-2);
  }
}

// ---- incremental accumulator and steady state

TEST(HarmonicAccumulator, EqualsBatchExtractionOverTheSameWindow) {
  const auto truth = rich_content();
  for (double samples_per_period : {64.0, 50.37}) {
    const Sampling sampling{1.0 / (kF * samples_per_period), 0.01};
    const auto values =
        sample([&](double t) { return evaluate(truth, kF, t); }, sampling, 30 * 64);
    HarmonicOptions options = rich_options();
    options.periods = 20;
    const HarmonicTable batch = extract_harmonics(values, sampling, options);
    // An accumulator started at the batch window's start, fed the whole record step by step.
    HarmonicAccumulator accumulator(options, sampling.time_step, batch.start_time);
    int completed = 0;
    for (std::size_t i = 0; i < values.size(); ++i) {
      completed += accumulator.add(sampling.start_time + i * sampling.time_step, values[i]);
    }
    completed += accumulator.finish();
    EXPECT_EQ(completed, 20);
    EXPECT_EQ(accumulator.n_periods(), 20);
    EXPECT_EQ(accumulator.exact_grid(), samples_per_period == 64.0);
    const HarmonicTable incremental = accumulator.table(0, 20);
    EXPECT_EQ(incremental.method, batch.method);
    ASSERT_EQ(incremental.harmonics.size(), batch.harmonics.size());
    for (std::size_t k = 0; k < batch.harmonics.size(); ++k) {
      EXPECT_NEAR(std::abs(incremental.harmonics[k].complex_amplitude() -
                           batch.harmonics[k].complex_amplitude()),
                  0.0, 1e-12);
    }
    EXPECT_LT(worst_error(incremental, truth, 1.0), 1e-5);
  }
}

TEST(HarmonicAccumulator, PeriodsCompleteOnTheFlyAndPhasesStayAbsolute) {
  const auto truth = rich_content();
  HarmonicOptions options = rich_options();
  const double dt = 1.0 / (kF * 64);
  HarmonicAccumulator accumulator(options, dt, 0.0);
  EXPECT_EQ(accumulator.points_per_period(), 64);
  for (int i = 0; i < 64 * 6; ++i) {
    const int completed = accumulator.add(i * dt, evaluate(truth, kF, i * dt));
    // On the exact grid a period completes at its last step, with no delay.
    EXPECT_EQ(completed, (i + 1) % 64 == 0 ? 1 : 0) << "step " << i;
  }
  EXPECT_EQ(accumulator.n_periods(), 6);
  // Any even pair of periods gives the same absolute-phase table.
  for (int first : {0, 1, 4}) {
    EXPECT_LT(worst_error(accumulator.table(first, 2), truth, 1.0), 1e-12) << first;
  }
  EXPECT_THROW(accumulator.table(0, 3), InputError);  // odd with sub-harmonics
  EXPECT_THROW(accumulator.table(5, 2), InputError);  // period 6 is not complete
  EXPECT_THROW(accumulator.add(5 * dt, 0.0), InputError);  // time going backwards
  HarmonicAccumulator late(options, dt, 0.0);
  EXPECT_THROW(late.add(0.5 * dt, 0.0), InputError);  // first sample after period 0 began
}

TEST(HarmonicAccumulator, VariableTimeStepsAreInterpolated) {
  const auto truth = rich_content();
  HarmonicOptions options = rich_options();
  const double dt = 1.0 / (kF * 200);
  HarmonicAccumulator accumulator(options, dt, 0.0);
  double t = 0.0;
  for (int i = 0; accumulator.n_periods() < 10; ++i) {
    accumulator.add(t, evaluate(truth, kF, t));
    t += dt * (1.0 + 0.3 * std::sin(0.37 * i));  // steps between 0.7 dt and 1.3 dt
  }
  EXPECT_EQ(accumulator.last_table(10).method, Method::resampled);
  EXPECT_LT(worst_error(accumulator.last_table(10), truth, 1.0), 1e-8);
}

TEST(PeriodTable, OnePeriodOfSeveralSignalsIsTheBatchTableWithPhasesAtItsStart) {
  // Two signals over one period T = 2 / f (the base period of an f/2 response): column k of the
  // period table is order k / 2 of f, with its phase at the period's start t0.
  const auto truth = rich_content();
  std::vector<Component> scaled = truth;
  for (Component& c : scaled) c = {c.order, 2.5 * c.amplitude, c.order == 0.0 ? 0.0 : c.phase + 0.4};
  const int n = 128, harmonics = 6;
  const Sampling sampling{2.0 / (kF * n), 0.0123};
  Eigen::MatrixXd samples(2, n);
  for (int j = 0; j < n; ++j) {
    const double t = sampling.start_time + j * sampling.time_step;
    samples(0, j) = evaluate(truth, kF, t);
    samples(1, j) = evaluate(scaled, kF, t);
  }
  const Eigen::MatrixXcd table = period_harmonics(samples, harmonics);
  ASSERT_EQ(table.rows(), 2);
  ASSERT_EQ(table.cols(), harmonics + 1);
  HarmonicOptions options = rich_options();
  options.periods = 2;
  for (int row = 0; row < 2; ++row) {
    std::vector<double> record(n);
    for (int j = 0; j < n; ++j) record[j] = samples(row, j);
    const HarmonicTable batch = extract_harmonics(record, sampling, options);
    for (int k = 0; k <= harmonics; ++k) {
      const double order = 0.5 * k;
      const std::complex<double> at_start =
          batch.at(order).complex_amplitude() * std::polar(1.0, 2.0 * M_PI * order * kF * sampling.start_time);
      EXPECT_LT(std::abs(table(row, k) - at_start), 1e-12) << "row " << row << ", order " << order;
      const std::complex<double> exact =
          expected(row == 0 ? truth : scaled, order) * std::polar(1.0, 2.0 * M_PI * order * kF * sampling.start_time);
      EXPECT_LT(std::abs(table(row, k) - exact), 1e-12) << "row " << row << ", order " << order;
    }
  }
}

TEST(PeriodTable, ChangeIsTheLargestOverTheRowsRelativeToEachRowsA1) {
  Eigen::MatrixXcd now = Eigen::MatrixXcd::Zero(3, 3), previous = Eigen::MatrixXcd::Zero(3, 3);
  now(0, 1) = 2.0;  // row 0: A1 = 2, its order 2 moved by 0.1
  now(0, 2) = std::complex<double>(0.5, 0.1);
  previous.row(0) = now.row(0);
  previous(0, 2) = 0.5;
  now(1, 1) = 0.5;  // row 1: A1 = 0.5, its mean moved by 0.1
  now(1, 0) = 0.3;
  previous.row(1) = now.row(1);
  previous(1, 0) = 0.2;
  EXPECT_NEAR(period_table_change(now, previous, {0}, 1), 0.1 / 2.0, 1e-15);
  EXPECT_NEAR(period_table_change(now, previous, {0, 1}, 1), 0.1 / 0.5, 1e-15);
  EXPECT_EQ(period_table_change(now, now, {0, 1, 2}, 1), 0.0);
  EXPECT_EQ(period_table_change(now, previous, {2}, 1), 0.0);  // a silent row that did not change
  previous(2, 0) = 1e-3;
  EXPECT_EQ(period_table_change(now, previous, {2}, 1), 1.0);  // A1 = 0 and changed: counts 1
}

TEST(SteadyState, ChangeIsTheLargestComplexDifferenceOverA1) {
  HarmonicTable now, previous;
  now.harmonics = {{0, 0, 0.2, 0}, {1, kF, 2.0, 0.3}, {2, 2 * kF, 0.5, 0.0}};
  previous.harmonics = {{0, 0, 0.2, 0}, {1, kF, 2.0, 0.3}, {2, 2 * kF, 0.5, 0.1}};
  EXPECT_NEAR(table_change(now, previous), 0.5 * 2 * std::sin(0.05) / 2.0, 1e-15);
  previous.harmonics[0].amplitude = 0.1;  // a shift of the mean counts as well
  EXPECT_NEAR(table_change(now, previous), 0.1 / 2.0, 1e-15);
  EXPECT_EQ(table_change(now, now), 0.0);
  now.harmonics[1].amplitude = 0.0;
  EXPECT_TRUE(std::isinf(table_change(now, previous)));
  previous.harmonics.pop_back();
  EXPECT_THROW(table_change(now, previous), InputError);
}

TEST(SteadyState, DampedTransientSettlesBeforeTheLimitWithTheSteadyTable) {
  const auto truth = rich_content();
  const Sampling sampling{1.0 / (kF * 64), 0.0};
  const double tau = 5.0 / kF;
  const auto signal = [&](double t) {
    return evaluate(truth, kF, t) + 0.3 * std::exp(-t / tau) * std::cos(2 * M_PI * 0.8 * kF * t);
  };
  const auto values = sample(signal, sampling, 300 * 64);
  HarmonicOptions options = rich_options();
  SteadyStateCriterion criterion;
  criterion.window_periods = 4;
  criterion.tolerance = 1e-6;
  criterion.max_periods = 300;
  const SteadyStateRun run = detect_steady_state(values, sampling, options, criterion);
  EXPECT_TRUE(run.state.settled);
  EXPECT_FALSE(run.state.limit_reached);
  EXPECT_LT(run.state.change, 1e-6);
  EXPECT_GT(run.state.periods_used, 2 * criterion.window_periods);
  EXPECT_LT(run.state.periods_used, 150);
  EXPECT_EQ(run.table.periods, 4);
  EXPECT_NEAR(run.table.end_time, run.state.periods_used / kF, 1e-12);
  // The same table as the settled end of the full record, within a few tolerances.
  options.periods = 4;
  const HarmonicTable full = extract_harmonics(values, sampling, options);
  ASSERT_EQ(full.harmonics.size(), run.table.harmonics.size());
  EXPECT_LT(table_change(full, run.table), 5 * criterion.tolerance);
  EXPECT_LT(worst_error(run.table, truth, 1.0), 5 * criterion.tolerance);
  // ...and it really had to wait: the first windows differ by much more.
  HarmonicAccumulator early(options, sampling.time_step, 0.0);
  for (int i = 0; i < 8 * 64; ++i) early.add(i * sampling.time_step, values[i]);
  const SteadyState first = early.steady_state(criterion);
  EXPECT_FALSE(first.settled);
  EXPECT_GT(first.change, 1e-3);
  EXPECT_DOUBLE_EQ(first.change, table_change(early.table(4, 4), early.table(0, 4)));
}

TEST(SteadyState, StopsAtThePeriodLimitWhenNotSettled) {
  const auto truth = rich_content();
  const Sampling sampling{1.0 / (kF * 64), 0.0};
  const auto signal = [&](double t) {
    return evaluate(truth, kF, t) + 0.3 * std::exp(-t * kF / 50.0) * std::cos(2 * M_PI * 0.8 * kF * t);
  };
  const auto values = sample(signal, sampling, 100 * 64);
  SteadyStateCriterion criterion;
  criterion.tolerance = 1e-9;
  criterion.max_periods = 20;
  const SteadyStateRun run = detect_steady_state(values, sampling, rich_options(), criterion);
  EXPECT_FALSE(run.state.settled);
  EXPECT_TRUE(run.state.limit_reached);
  EXPECT_EQ(run.state.periods_used, 20);
  EXPECT_GT(run.state.change, 1e-9);
  criterion.max_periods = 0;
  criterion.window_periods = 3;  // odd with sub-harmonics
  EXPECT_THROW(detect_steady_state(values, sampling, rich_options(), criterion), InputError);
  criterion.window_periods = 4;
  EXPECT_THROW(detect_steady_state(std::vector<double>(64 * 3, 0.0), sampling, rich_options(),
                                   criterion),
               InputError);
}

// The run's steady-state controller over several probes (spectral::SteadyStateMonitor): it settles
// when the slowest channel does, at the period a single-channel detection of that channel gives;
// before its first check it says when that comes; without a tolerance it never settles; the window
// is made even with sub-harmonics; every sample is kept.
TEST(SteadyStateMonitor, SettlesWithTheSlowestChannelAndSaysWhenItFirstChecks) {
  const auto truth = rich_content();
  const Sampling sampling{1.0 / (kF * 64), 0.0};
  const auto slow = [&](double t) {
    return evaluate(truth, kF, t) + 0.3 * std::exp(-t * kF / 8.0) * std::cos(2 * M_PI * 0.8 * kF * t);
  };
  const auto fast = [&](double t) { return evaluate(truth, kF, t); };
  const int steps = 300 * 64;
  const auto slow_values = sample(slow, sampling, steps);
  const auto fast_values = sample(fast, sampling, steps);

  SteadyStateMonitor monitor(rich_options(), sampling.time_step, 2, 3, 1e-6, 10);
  EXPECT_EQ(monitor.window_periods(), 4);  // 3 made even: sub-harmonics
  EXPECT_NE(monitor.progress_note(0.0).find("first check at period 10"), std::string::npos)
      << monitor.progress_note(0.0);
  int stopped = -1;
  for (int i = 0; i < steps && stopped < 0; ++i) {
    const double time = i * sampling.time_step;
    if (monitor.add(time, [&](std::size_t c) { return c == 0 ? fast_values[i] : slow_values[i]; })) stopped = i;
  }
  ASSERT_GE(stopped, 0) << "never settled";
  ASSERT_TRUE(monitor.verdict().has_value());
  EXPECT_TRUE(monitor.verdict()->settled);
  EXPECT_LT(monitor.verdict()->change, 1e-6);
  EXPECT_EQ(monitor.values(1).size(), static_cast<std::size_t>(stopped + 1));
  EXPECT_NE(monitor.progress_note(1.0).find("steady state: change"), std::string::npos) << monitor.progress_note(1.0);

  // The slow channel alone, checked the same way, settles at the same period.
  SteadyStateCriterion criterion;
  criterion.window_periods = 4;
  criterion.tolerance = 1e-6;
  criterion.max_periods = 300;
  const SteadyStateRun alone = detect_steady_state(slow_values, sampling, rich_options(), criterion);
  ASSERT_TRUE(alone.state.settled);
  EXPECT_EQ(monitor.verdict()->periods_used, std::max(10, alone.state.periods_used));
  EXPECT_GT(monitor.verdict()->periods_used, 10);  // the slow channel made it wait

  SteadyStateMonitor never(rich_options(), sampling.time_step, 1, 4, 0.0, 10);
  HarmonicAccumulator plain(rich_options(), sampling.time_step, 0.0);
  for (int i = 0; i < 40 * 64; ++i) {
    EXPECT_FALSE(never.add(i * sampling.time_step, [&](std::size_t) { return fast_values[i]; }));
    plain.add(i * sampling.time_step, fast_values[i]);
  }
  EXPECT_EQ(never.progress_note(1.0), "");
  EXPECT_FALSE(never.verdict().has_value());
  EXPECT_EQ(never.accumulator(0).n_periods(), plain.n_periods());
  EXPECT_EQ(table_change(never.accumulator(0).last_table(4), plain.last_table(4)), 0.0);
}
