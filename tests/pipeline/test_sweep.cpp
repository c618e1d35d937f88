// The sweep pipeline on reduced systems written by hand: the scene's sweep: section (defaults,
// file:line errors), the linear sweep against the receptance, a bilinear oscillator's
// super-harmonic resonance at f_b/2, harmonic balance against the stepped sine, the stepped sine's
// jumps at the folds of a clearance oscillator, the period-doubled branch against the stepped sine,
// the files, and the windows the accuracy's refinement sweeps re-solve.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <complex>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <sstream>

#include <Eigen/Eigenvalues>
#include <nlohmann/json.hpp>

#include "core/errors.hpp"
#include "io/csv.hpp"
#include "pipeline/sweep.hpp"
#include "pipeline/sweep_windows.hpp"
#include "scene/scene.hpp"

namespace crackle::pipeline {
namespace {


std::string beam_scene(const std::string& sweep, const std::string& contact = "{penalty: auto}") {
  return "mesh:\n"
         "  box: {size: [0.2, 0.02, 0.01], cells: [40, 4, 2], order: 2}\n"
         "material: {E: 210.0e9, nu: 0.3, rho: 7850.0}\n"
         "boundary:\n"
         "  - {face: x-, fix: [x, y, z]}\n"
         "crack:\n"
         "  plane: {normal: x, at: 0.05}\n"
         "  region: {y: [0.0, 0.02], z: [0.007, 0.01]}\n"
         "  contact: " + contact + "\n"
         "transient:\n"
         "  excitation: {face: x+, direction: z, amplitude: 20.0, frequency: {mode: 1, ratio: 0.5}}\n"
         "  damping: {ratio: 0.05, at: {mode: 1}}\n"
         "  periods: 60\n"
         "  probes:\n"
         "    - {name: tip, point: [0.2, 0.01, 0.01]}\n"
         "    - {name: side, point: [0.2, 0.0, 0.005], component: y}\n" +
         sweep;
}

std::string error_of(const std::string& text) {
  try {
    scene::parse_scene(text, "sweep.yaml");
  } catch (const InputError& error) {
    return error.what();
  }
  return "(no error)";
}

TEST(SweepScene, DefaultsAndModeRelativeRange) {
  const scene::Scene scene = scene::parse_scene(
      beam_scene("sweep:\n  frequency: {from: {mode: 1, ratio: 0.45}, to: {mode: 1, ratio: 0.55}}\n"), "sweep.yaml");
  ASSERT_TRUE(scene.sweep);
  const scene::SweepSection& sweep = *scene.sweep;
  EXPECT_EQ(sweep.from.mode, 1);
  EXPECT_EQ(sweep.from.ratio, 0.45);
  EXPECT_EQ(sweep.to.ratio, 0.55);
  EXPECT_EQ(sweep.from.of, scene::ModeOf::bilinear);
  EXPECT_FALSE(sweep.from.hz);
  EXPECT_EQ(sweep.harmonics, 15);
  EXPECT_EQ(sweep.subharmonic, 1);
  EXPECT_EQ(sweep.method, scene::SweepMethod::harmonic_balance);
  EXPECT_EQ(sweep.solver, LinearSolver::automatic);
  EXPECT_TRUE(sweep.stability);
  EXPECT_EQ(sweep.points, 200);
  const std::vector<SweepProbe> probes = sweep_probes(scene);
  ASSERT_EQ(probes.size(), 2u);
  EXPECT_EQ(probes[0].row, 2);  // tip, the excitation direction z
  EXPECT_EQ(probes[1].row, 4);  // side, y of probe 1
  // Hz as scalars; stability defaults off with friction.
  const scene::Scene hz = scene::parse_scene(
      beam_scene("sweep:\n  frequency: {from: 400, to: 300}\n  method: stepped_sine\n", "{friction: 0.3}"), "s.yaml");
  EXPECT_EQ(*hz.sweep->from.hz, 400.0);
  EXPECT_EQ(*hz.sweep->to.hz, 300.0);
  EXPECT_FALSE(hz.sweep->stability);
  EXPECT_EQ(hz.sweep->method, scene::SweepMethod::stepped_sine);
}

TEST(SweepScene, BadKeysNameFileAndLine) {
  const std::string range = "  frequency: {from: {mode: 1, ratio: 0.45}, to: {mode: 1, ratio: 0.55}}\n";
  EXPECT_EQ(error_of(beam_scene("sweep:\n" + range + "  harmonics: 0\n")),
            "sweep.yaml:19: sweep.harmonics: expected an integer in 1..200, got 0");
  EXPECT_EQ(error_of(beam_scene("sweep:\n" + range + "  subharmonic: 3\n")),
            "sweep.yaml:19: sweep.subharmonic: expected an integer in 1..2, got 3");
  EXPECT_EQ(error_of(beam_scene("sweep:\n" + range + "  method: sine\n")).substr(0, 40),
            "sweep.yaml:19: sweep.method: expected on");
  EXPECT_EQ(error_of(beam_scene("sweep:\n" + range + "  harmonic: 5\n")).substr(0, 32),
            "sweep.yaml:19: sweep.harmonic: e");
  EXPECT_EQ(error_of(beam_scene("sweep:\n  harmonics: 5\n")).substr(0, 37), "sweep.yaml:17: sweep.frequency: expec");
  EXPECT_EQ(error_of(beam_scene("sweep:\n  frequency: {from: {mode: 1, ratio: 0.5}, to: {mode: 1, ratio: 0.5}}\n")),
            "sweep.yaml:18: sweep.frequency.to: expected a frequency other than sweep.frequency.from, got the same");
  EXPECT_EQ(error_of(beam_scene("sweep:\n  frequency: {from: {hz: 1, mode: 1}, to: 5}\n")),
            "sweep.yaml:18: sweep.frequency.from: expected exactly one of hz, mode, got hz and mode");
  EXPECT_EQ(error_of(beam_scene("sweep:\n  frequency: {from: -1, to: 5}\n")),
            "sweep.yaml:18: sweep.frequency.from.hz: expected a positive number, got -1");
  EXPECT_EQ(error_of(beam_scene("sweep:\n" + range + "  stability: true\n", "{friction: 0.3}")),
            "sweep.yaml:19: sweep.stability: expected false with friction (Hill's method is frictionless), got true");
  EXPECT_EQ(error_of(beam_scene("sweep:\n" + range + "  method: stepped_sine\n  solve_at: [100]\n")),
            "sweep.yaml:20: sweep.solve_at: expected sweep.method: harmonic_balance (stepped_sine runs at its own "
            "frequencies), got sweep.method: stepped_sine");
  EXPECT_EQ(error_of(beam_scene("sweep:\n" + range + "  solve_at: [100, -1]\n")).substr(0, 42),
            "sweep.yaml:19: sweep.solve_at[1]: expected");
}

/// A few modes with pairs a metre apart (never in contact): a linear body. Outputs: 3 rows.
reduced::ReducedSystem linear_system() {
  MatrixX stiffness(3, 3), mass = MatrixX::Identity(3, 3);
  stiffness << 2.0e4, -1.0e4, 0, -1.0e4, 2.0e4, -1.0e4, 0, -1.0e4, 1.5e4;
  mass.diagonal() << 1.0, 2.0, 0.5;
  Eigen::GeneralizedSelfAdjointEigenSolver<MatrixX> eig(stiffness, mass);
  const MatrixX phi = eig.eigenvectors();
  MatrixX b(2, 3), c(3, 3);
  b << 1, -1, 0, 0, 1, -1;
  c << 1, 0, 0, 0, 1, 0, 0, 0, 1;
  reduced::ReducedSystem s;
  s.omega = eig.eigenvalues().cwiseSqrt();
  s.rayleigh_alpha = 2.0;
  s.rayleigh_beta = 1e-4;
  s.pair_area = VectorX::Ones(2);
  s.initial_gap = VectorX::Constant(2, 1.0);
  s.normal_penalty = 1e9;
  s.pair_modes = b * phi;
  s.residual = MatrixX::Identity(2, 2) * 1e-9;
  s.load_modal = phi.transpose() * Eigen::Vector3d(0.0, 0.0, 3.0);
  s.load_residual = VectorX::Zero(2);
  s.output_modes = c * phi;
  s.output_residual_pairs = MatrixX::Zero(3, 2);
  s.output_residual_load = Eigen::Vector3d(1e-7, 0.0, 2e-7);
  return s;
}

/// The receptance response of output `row` at Omega: C Phi D Phi^T f + C G_res f.
std::complex<double> receptance(const reduced::ReducedSystem& s, Index row, double omega) {
  std::complex<double> y = s.output_residual_load[row];
  for (Index r = 0; r < s.n_modes(); ++r) {
    const double w = s.omega[r];
    y += s.output_modes(row, r) * s.load_modal[r] /
         std::complex<double>(w * w - omega * omega, 2.0 * s.damping_ratio(r) * w * omega);
  }
  return y;
}

SweepSettings settings_for(double from_hz, double to_hz, int harmonics, int points) {
  SweepSettings settings;
  settings.from_hz = from_hz;
  settings.to_hz = to_hz;
  settings.section.harmonics = harmonics;
  settings.section.points = points;
  settings.probes = {{"a", 0, 0}, {"c", 2, 2}};
  return settings;
}

TEST(SweepLinear, HarmonicBalanceIsTheReceptance) {
  const reduced::ReducedSystem s = linear_system();
  const double f1 = s.omega[0] / kTwoPi, f2 = s.omega[1] / kTwoPi;
  const SweepSettings settings = settings_for(0.5 * f1, 0.5 * (f1 + f2), 5, 60);
  const SweepResult result = harmonic_balance_sweep(s, settings);
  ASSERT_TRUE(result.completed);
  ASSERT_GE(result.points.size(), 60u);
  EXPECT_TRUE(result.events.empty());
  EXPECT_TRUE(result.warnings.empty()) << result.warnings.front();
  double worst = 0.0, higher = 0.0;
  for (const SweepPoint& point : result.points) {
    EXPECT_TRUE(point.stable);
    for (Index row : {0, 2}) {
      const std::complex<double> expected = receptance(s, row, point.solution.omega);
      const std::complex<double> got = std::polar(point.solution.amplitude(row, 1.0), point.solution.phase(row, 1.0));
      worst = std::max(worst, std::abs(got - expected) / std::abs(expected));
      for (int k = 2; k <= 5; ++k) higher = std::max(higher, point.solution.amplitude(row, k) / std::abs(expected));
      higher = std::max(higher, point.solution.amplitude(row, 0.0) / std::abs(expected));
    }
  }
  EXPECT_LT(worst, 1e-10);
  EXPECT_LT(higher, 1e-13);

  // sweep.solve_at: one more point at exactly each frequency inside the range (the receptance there);
  // one outside the range is a warning, not a silent nothing
  SweepSettings at = settings;
  const double inside = 0.7 * f1 + 0.3 * (0.5 * (f1 + f2)), outside = 2.0 * f2;
  at.section.solve_at_hz = {inside, outside};
  const SweepResult landed = harmonic_balance_sweep(s, at);
  EXPECT_EQ(landed.points.size(), result.points.size() + 1);
  std::size_t found = 0;
  for (const SweepPoint& point : landed.points) {
    if (std::abs(point.frequency_hz() - inside) > 1e-12 * inside) continue;
    ++found;
    const std::complex<double> expected = receptance(s, 0, point.solution.omega);
    EXPECT_NEAR(point.solution.amplitude(0, 1.0), std::abs(expected), 1e-10 * std::abs(expected));
  }
  EXPECT_EQ(found, 1u);
  ASSERT_EQ(landed.warnings.size(), 1u);
  EXPECT_NE(landed.warnings.front().find("sweep.solve_at: " + crackle::format_number(outside) + " Hz lies outside the range"),
            std::string::npos) << landed.warnings.front();
}

TEST(SweepLinear, SteppedSineIsTheReceptance) {
  const reduced::ReducedSystem s = linear_system();
  const double f1 = s.omega[0] / kTwoPi;
  SweepSettings settings = settings_for(0.8 * f1, 1.2 * f1, 3, 5);
  settings.section.method = scene::SweepMethod::stepped_sine;
  settings.section.tolerance = 1e-9;
  const SweepResult result = stepped_sine_sweep(s, settings);
  ASSERT_EQ(result.points.size(), 10u);
  EXPECT_TRUE(result.warnings.empty()) << result.warnings.front();
  for (std::size_t i = 0; i < result.points.size(); ++i) {
    const SweepPoint& point = result.points[i];
    EXPECT_EQ(point.direction, i < 5 ? 1 : -1);
    EXPECT_DOUBLE_EQ(point.frequency_hz(), result.points[9 - i].frequency_hz());
    const std::complex<double> expected = receptance(s, 2, point.solution.omega);
    const std::complex<double> got = std::polar(point.solution.amplitude(2, 1.0), point.solution.phase(2, 1.0));
    // Average acceleration at >= 120 steps per period of the highest mode: (omega h)^2 / 12 ~ 2e-4 in frequency.
    EXPECT_LT(std::abs(got - expected) / std::abs(expected), 5e-3) << point.frequency_hz();
    EXPECT_LT(point.solution.amplitude(2, 2.0), 1e-9 * std::abs(expected));
  }
}

/// A bilinear oscillator (HYBRID.md §4 with one mode and one pair): open stiffness 1, closed 4,
/// so omega_b = 2 * 1 * 2 / 3 = 4/3 rad/s. Output row 0 = q.
reduced::ReducedSystem bilinear_oscillator() {
  reduced::ReducedSystem s;
  s.omega = VectorX::Constant(1, 1.0);
  s.rayleigh_alpha = 2.0 * 0.02;
  s.pair_area = VectorX::Ones(1);
  s.initial_gap = VectorX::Zero(1);
  s.normal_penalty = 3.0;
  s.pair_modes = MatrixX::Ones(1, 1);
  s.residual = MatrixX::Zero(1, 1);
  s.load_modal = VectorX::Constant(1, 1e-3);
  s.load_residual = VectorX::Zero(1);
  s.output_modes = MatrixX::Ones(3, 1);
  s.output_residual_pairs = MatrixX::Zero(3, 1);
  s.output_residual_load = VectorX::Zero(3);
  return s;
}

constexpr double kBilinearHz = 4.0 / 3.0 / kTwoPi;

TEST(SweepBilinear, SuperHarmonicPeakAtHalfTheBilinearFrequency) {
  const reduced::ReducedSystem s = bilinear_oscillator();
  SweepSettings settings = settings_for(0.42 * kBilinearHz, 0.58 * kBilinearHz, 20, 200);
  settings.bilinear_hz = kBilinearHz;
  const SweepResult result = harmonic_balance_sweep(s, settings);
  ASSERT_TRUE(result.completed);
  ASSERT_GE(result.points.size(), 200u);
  const nlohmann::json document = output::sweep_json(result, file_settings(settings));
  const double peak_hz = document["probes"]["a"]["peak_a2_over_a1"]["frequency_hz"];
  EXPECT_NEAR(peak_hz / (0.5 * kBilinearHz), 1.0, 5e-3);
  EXPECT_GT(document["probes"]["a"]["peak_a2_over_a1"]["value"].get<double>(), 0.05);
  // Continuation through the resonance in a few hundred points (not thousands), each converged.
  EXPECT_LT(result.points.size(), 600u);
  for (const SweepPoint& point : result.points) EXPECT_LE(point.solution.residual, 1e-10);
}

TEST(SweepBilinear, HarmonicBalanceMatchesTheSteppedSine) {
  const reduced::ReducedSystem s = bilinear_oscillator();
  // The stepped sine resolves orders up to 10 (160 steps per period of the 10th); HB at H = 40.
  SweepSettings hb = settings_for(0.46 * kBilinearHz, 0.54 * kBilinearHz, 10, 4);
  hb.section.method = scene::SweepMethod::stepped_sine;
  hb.section.tolerance = 1e-7;
  hb.section.max_periods = 600;
  const SweepResult stepped = stepped_sine_sweep(s, hb);
  ASSERT_TRUE(stepped.warnings.empty()) << stepped.warnings.front();
  SweepSettings continuation = settings_for(0.45 * kBilinearHz, 0.55 * kBilinearHz, 40, 50);
  continuation.section.stability = false;
  const SweepResult branch = harmonic_balance_sweep(s, continuation);
  sweep::HarmonicBalanceOptions options;
  options.harmonics = 40;
  const sweep::HarmonicBalance balance(s, options);
  for (std::size_t i = 0; i < 4; ++i) {
    const SweepPoint& point = stepped.points[i];
    const SweepPoint* nearest = &branch.points.front();
    for (const SweepPoint& candidate : branch.points)
      if (std::abs(candidate.solution.omega - point.solution.omega) < std::abs(nearest->solution.omega - point.solution.omega))
        nearest = &candidate;
    const sweep::Solution solution = balance.solve(point.solution.omega, nearest->solution.gaps);
    for (int k = 1; k <= 3; ++k) {
      const double reference = solution.amplitude(0, k);
      EXPECT_NEAR(point.solution.amplitude(0, k) / reference, 1.0, 5e-3) << "f " << point.frequency_hz() << " A" << k;
    }
    // Up and down agree where there is one branch.
    EXPECT_NEAR(stepped.points[7 - i].solution.amplitude(0, 1) / point.solution.amplitude(0, 1), 1.0, 1e-6);
  }
}

/// One mode (omega 1, damping ratio `zeta`), one pair row with gap g0 (b = 1, R = 0), penalty k:
/// q'' + 2 zeta q' + q = f cos(Omega t) + k max(0, -g0 - q). Output rows = q.
reduced::ReducedSystem oscillator(double zeta, double penalty, double gap, double load) {
  reduced::ReducedSystem s = bilinear_oscillator();
  s.rayleigh_alpha = 2.0 * zeta;
  s.normal_penalty = penalty;
  s.initial_gap = VectorX::Constant(1, gap);
  s.load_modal = VectorX::Constant(1, load);
  return s;
}

TEST(SweepStability, SteppedSineJumpsWhereTheBranchFoldsAndTheMiddleIsUnstable) {
  // A clearance (g0 = 5e-6) hardening oscillator, light damping: the resonance leans right, a stepped
  // sine up falls off the upper branch, a stepped sine down jumps onto it, at different frequencies.
  const reduced::ReducedSystem s = oscillator(0.01, 3.0, 5e-6, 0.5e-6);
  const double from = 1.0 / kTwoPi, to = 1.3 / kTwoPi;
  constexpr std::size_t kSteps = 21;  // 0.015 rad/s apart
  SweepSettings stepped = settings_for(from, to, 3, kSteps);  // A1 only: a coarser step
  stepped.section.method = scene::SweepMethod::stepped_sine;
  stepped.section.tolerance = 1e-5;
  stepped.section.max_periods = 3000;
  const SweepResult lab = stepped_sine_sweep(s, stepped);
  ASSERT_TRUE(lab.warnings.empty()) << lab.warnings.front();
  // the largest drop of A1 going up, the largest rise going down: [f_i, f_i+1] around each jump
  std::size_t up = 0, down = 0;
  const auto a1 = [&](std::size_t i) { return lab.points[i].solution.amplitude(0, 1.0); };
  const std::size_t n = kSteps;
  for (std::size_t i = 0; i + 1 < n; ++i) {
    if (a1(i) - a1(i + 1) > a1(up) - a1(up + 1)) up = i;                      // up: points 0..n-1, rising f
    if (a1(n + i + 1) - a1(n + i) > a1(n + down + 1) - a1(n + down)) down = i;  // down: n..2n-1, falling f
  }
  const double jump_up[2] = {lab.points[up].frequency_hz(), lab.points[up + 1].frequency_hz()};
  const double jump_down[2] = {lab.points[n + down + 1].frequency_hz(), lab.points[n + down].frequency_hz()};
  std::printf("  stepped sine: up falls %.3e -> %.3e between %.5f and %.5f rad/s, down rises %.3e -> %.3e between "
              "%.5f and %.5f rad/s\n", a1(up), a1(up + 1), kTwoPi * jump_up[0], kTwoPi * jump_up[1], a1(n + down),
              a1(n + down + 1), kTwoPi * jump_down[1], kTwoPi * jump_down[0]);
  ASSERT_GT(a1(up), 1.5 * a1(up + 1));
  ASSERT_GT(a1(n + down + 1), 1.5 * a1(n + down));
  ASSERT_GT(jump_up[0], jump_down[1]);  // hysteresis: the two jumps do not overlap

  SweepSettings settings = settings_for(from, to, 10, 100);
  const SweepResult branch = harmonic_balance_sweep(s, settings);
  ASSERT_TRUE(branch.completed);
  std::vector<SweepEvent> folds;
  for (const SweepEvent& event : branch.events)
    if (event.kind == "fold") folds.push_back(event);
  ASSERT_EQ(folds.size(), 2u);
  std::printf("  harmonic balance: folds at %.5f and %.5f rad/s\n", kTwoPi * folds[0].frequency_hz,
              kTwoPi * folds[1].frequency_hz);
  // the upper fold where the stepped sine up falls off, the lower one where the stepped sine down jumps
  // up (a finite frequency step may leave the shrinking basin of the upper branch one step early)
  const double step = (to - from) / double(n - 1);
  EXPECT_GE(folds[0].frequency_hz, jump_up[0]);
  EXPECT_LE(folds[0].frequency_hz, jump_up[1]);
  EXPECT_GE(folds[1].frequency_hz, jump_down[0] - step);
  EXPECT_LE(folds[1].frequency_hz, jump_down[1]);
  // unstable between the folds (one real multiplier > 1), stable outside, Hill agreeing at both changes
  for (std::size_t i = 0; i < branch.points.size(); ++i) {
    const bool middle = i >= folds[0].point && i < folds[1].point;
    EXPECT_EQ(branch.points[i].stable, !middle) << "point " << i << " at " << branch.points[i].frequency_hz() << " Hz";
  }
  for (const SweepEvent& event : folds) EXPECT_EQ(event.hill_check, 1);
  // sweep.json says so per event
  const nlohmann::json document = output::sweep_json(branch, file_settings(settings));
  int agreeing = 0;
  for (const nlohmann::json& event : document["events"])
    if (event["kind"] == "fold") agreeing += event.value("hill_agrees", false) ? 1 : 0;
  EXPECT_EQ(agreeing, 2);
}

TEST(SweepStability, PeriodDoublingAndTheSubharmonicBranchMatchTheSteppedSine) {
  // Bilinear (closed at rest, stiffness 1 open, 4 closed; f_b = 4/3 rad/s), 1 % damping, driven near
  // 2 f_b: the period-one response loses stability through -1 and a period-two one (A1/2) takes over.
  const reduced::ReducedSystem s = oscillator(0.01, 3.0, 0.0, 1e-6);
  const double from = 2.0 / kTwoPi, to = 2.6 / kTwoPi;
  SweepSettings settings = settings_for(from, to, 20, 60);
  settings.section.subharmonic = 2;
  const SweepResult result = harmonic_balance_sweep(s, settings);
  ASSERT_TRUE(result.completed);
  std::vector<double> doublings;
  for (const SweepEvent& event : result.events) {
    if (event.kind != "period_doubling") continue;
    doublings.push_back(event.frequency_hz);
    EXPECT_EQ(event.hill_check, 1);
    EXPECT_EQ(result.points[event.point].segment, 0);
  }
  ASSERT_GE(doublings.size(), 1u);
  std::printf("  period doubling of the period-one branch at %.4f rad/s\n", kTwoPi * doublings.front());
  EXPECT_GT(kTwoPi * doublings.front(), 2.2);
  EXPECT_LT(kTwoPi * doublings.front(), 2.35);
  std::size_t period_two = 0;
  for (const SweepPoint& point : result.points) {
    if (point.segment == 0) {
      EXPECT_EQ(point.solution.subharmonic, 1);
      continue;
    }
    ++period_two;
    EXPECT_EQ(point.solution.subharmonic, 2);
    EXPECT_GE(point.frequency_hz(), doublings.front() * (1.0 - 1e-3));  // born at the doubling
  }
  ASSERT_GT(period_two, 5u);
  // the stepped sine (the reduced transient to steady state) at 2.5 rad/s, started from 2.45
  SweepSettings stepped = settings_for(2.45 / kTwoPi, 2.5 / kTwoPi, 6, 2);  // orders up to 3: a coarser step
  stepped.section.method = scene::SweepMethod::stepped_sine;
  stepped.section.subharmonic = 2;
  stepped.section.tolerance = 1e-7;
  stepped.section.max_periods = 2000;
  const SweepResult lab = stepped_sine_sweep(s, stepped);
  ASSERT_TRUE(lab.warnings.empty()) << lab.warnings.front();
  const sweep::Solution& reference = lab.points[1].solution;
  const SweepPoint* nearest = nullptr;
  for (const SweepPoint& point : result.points)
    if (point.segment > 0 && (!nearest || std::abs(point.solution.omega - 2.5) < std::abs(nearest->solution.omega - 2.5)))
      nearest = &point;
  sweep::HarmonicBalanceOptions options;
  options.harmonics = 20;
  options.subharmonic = 2;
  const sweep::HarmonicBalance balance(s, options);
  const sweep::Solution solution = balance.solve(2.5, nearest->solution.gaps);
  std::printf("  2.5 rad/s: HB A1/2 %.5e A1 %.5e | stepped sine A1/2 %.5e A1 %.5e (%d periods)\n",
              solution.amplitude(0, 0.5), solution.amplitude(0, 1.0), reference.amplitude(0, 0.5),
              reference.amplitude(0, 1.0), lab.points[1].periods);
  EXPECT_GT(reference.amplitude(0, 0.5), reference.amplitude(0, 1.0));  // the transient is on a period-two orbit
  EXPECT_NEAR(solution.amplitude(0, 0.5) / reference.amplitude(0, 0.5), 1.0, 0.05);
  EXPECT_NEAR(solution.amplitude(0, 1.0) / reference.amplitude(0, 1.0), 1.0, 0.05);
  EXPECT_TRUE(balance.floquet_stability(solution).stable);
}

TEST(SweepFiles, TableJsonAndPlot) {
  const reduced::ReducedSystem s = bilinear_oscillator();
  SweepSettings settings = settings_for(0.45 * kBilinearHz, 0.55 * kBilinearHz, 6, 20);
  settings.bilinear_hz = kBilinearHz;
  const SweepResult result = harmonic_balance_sweep(s, settings);
  const io::CsvTable table = output::sweep_table(result, file_settings(settings));
  ASSERT_EQ(table.headers.front(), "excitation frequency [Hz]");
  for (const std::string header : {"a u_x A1 [m]", "a u_x phase1 [rad]", "a u_x A6 [m]", "c u_z A0 [m]",
                                   "c u_z A2/A1 [-]", "c u_z A3/A1 [-]", "c u_z A1/2/A1 [-]",
                                   "stable [1 yes, 0 no, -1 not computed]", "newton iterations [-]", "residual [-]",
                                   "branch period [excitation periods]"}) {
    EXPECT_NE(std::find(table.headers.begin(), table.headers.end(), header), table.headers.end()) << header;
  }
  for (const auto& column : table.columns) EXPECT_EQ(column.size(), result.points.size());
  const nlohmann::json document = output::sweep_json(result, file_settings(settings));
  for (const char* key : {"settings", "bilinear_hz", "points", "events", "warnings", "probes", "completed"})
    EXPECT_TRUE(document.contains(key)) << key;
  EXPECT_EQ(document["settings"]["harmonics"], 6);
  const std::filesystem::path folder = std::filesystem::temp_directory_path() / "crackle-sweep-plot";
  std::filesystem::create_directories(folder);
  const plot::PlotResult drawn = plot_sweep(folder / "sweep_a.png", result, settings, 0);
  EXPECT_TRUE(std::filesystem::exists(folder / "sweep_a.dat"));
  if (plot::gnuplot_available(plot::PlotOptions())) EXPECT_TRUE(drawn.written) << drawn.note;
}

const std::vector<std::string> kPeakKeys = {"peak_a1", "peak_a2_over_a1", "peak_a3_over_a1"};

// The bilinear oscillator's sweep through f_b/2 continued over windows around its peaks only (as the
// accuracy's refinement sweeps are) finds the peaks of the whole range's sweep, in a fraction of its
// points, started from that sweep's branch or from the linear solution alike; a window that misses a
// peak says so (window_edge) and is refused.
TEST(SweepWindows, TheWindowsAroundThePeaksFindTheWholeRangesPeaks) {
  const reduced::ReducedSystem s = oscillator(0.05, 3.0, 0.0, 1e-3);  // the bilinear one, damped 5 %
  SweepSettings settings = settings_for(0.42 * kBilinearHz, 0.58 * kBilinearHz, 20, 200);
  settings.section.stability = false;
  const SweepResult whole = harmonic_balance_sweep(s, settings);
  ASSERT_TRUE(whole.completed);
  const nlohmann::json document = output::sweep_json(whole, file_settings(settings));
  // the peaks converged in the sampling: the whole range at ten times the points
  SweepSettings finer = settings;
  finer.section.points = 2000;
  const nlohmann::json fine = output::sweep_json(harmonic_balance_sweep(s, finer), file_settings(finer));
  const SweepWindows windows = sweep_windows(document, kPeakKeys);
  ASSERT_FALSE(windows.windows.empty()) << windows.reason;
  EXPECT_LT(windows.covered, 0.3);
  EXPECT_EQ(windows.peaks.size(), 2 * kPeakKeys.size());  // two probes
  for (std::size_t w = 0; w + 1 < windows.windows.size(); ++w)
    EXPECT_LT(windows.windows[w].second, windows.windows[w + 1].first);  // ascending, disjoint

  for (const bool started : {true, false}) {
    SweepSettings windowed = settings;
    windowed.windows = windows.windows;
    if (started) windowed.window_starts = window_starts(whole, settings.from_hz, settings.to_hz, 20, windows.windows);
    const SweepResult part = harmonic_balance_sweep(s, windowed);
    ASSERT_TRUE(part.completed) << (part.warnings.empty() ? "" : part.warnings.front());
    EXPECT_LT(part.points.size(), whole.points.size() / 2);
    EXPECT_EQ(part.points.back().segment + 1, static_cast<int>(windows.windows.size()));
    const nlohmann::json found = output::sweep_json(part, file_settings(windowed));
    EXPECT_EQ(found["settings"]["windows"].size(), windows.windows.size());
    std::string why;
    EXPECT_TRUE(windows_hold(windows, found, why)) << why;
    for (const auto& [pointer, index] : windows.peaks) {
      const nlohmann::json::json_pointer at(pointer);
      EXPECT_FALSE(found[at]["window_edge"].get<bool>()) << pointer;
      // the same branch sampled at other frequencies: as close to the converged peak as the whole
      // range's sweep (measured: 0.2-0.4 times its error for A2/A1 and A3/A1, equal for A1)
      const double converged = fine[at]["value"].get<double>();
      const double error = std::abs(found[at]["value"].get<double>() / converged - 1.0);
      const double whole_error = std::abs(document[at]["value"].get<double>() / converged - 1.0);
      EXPECT_LE(error, std::max(2.0 * whole_error, 1e-5)) << pointer << " started " << started;
      EXPECT_NEAR(found[at]["frequency_hz"].get<double>() / fine[at]["frequency_hz"].get<double>(), 1.0, 1e-4)
          << pointer;
    }
  }

  // A window beside the A2/A1 peak, not around it: its largest value is the window's end.
  const nlohmann::json::json_pointer a2("/probes/a/peak_a2_over_a1");
  const double at = (document[a2]["frequency_hz"].get<double>() - settings.from_hz) / (settings.to_hz - settings.from_hz);
  SweepWindows beside = windows;
  beside.windows = {{at - 0.1, at - 0.02}};
  beside.peaks = {{"/probes/a/peak_a2_over_a1", 0}};
  SweepSettings off = settings;
  off.windows = beside.windows;
  const nlohmann::json missed = output::sweep_json(harmonic_balance_sweep(s, off), file_settings(off));
  EXPECT_TRUE(missed[a2]["window_edge"].get<bool>());
  std::string why;
  EXPECT_FALSE(windows_hold(beside, missed, why));
  EXPECT_NE(why.find("peak_a2_over_a1"), std::string::npos) << why;
}

// No windows where a start inside the range could land on another branch (a fold), where the points
// are no branch (a stepped sine), where the sweep stopped early, or where they would cover most of it.
TEST(SweepWindows, TheWholeRangeWhereAWindowCouldMissTheBranch) {
  const reduced::ReducedSystem s = oscillator(0.01, 3.0, 5e-6, 0.5e-6);
  SweepSettings settings = settings_for(1.0 / kTwoPi, 1.3 / kTwoPi, 10, 100);
  const nlohmann::json folded = output::sweep_json(harmonic_balance_sweep(s, settings), file_settings(settings));
  SweepWindows windows = sweep_windows(folded, kPeakKeys);
  EXPECT_TRUE(windows.windows.empty());
  EXPECT_NE(windows.reason.find("fold"), std::string::npos) << windows.reason;

  const reduced::ReducedSystem b = bilinear_oscillator();
  SweepSettings plain = settings_for(0.42 * kBilinearHz, 0.58 * kBilinearHz, 20, 200);
  plain.section.stability = false;
  nlohmann::json document = output::sweep_json(harmonic_balance_sweep(b, plain), file_settings(plain));
  ASSERT_FALSE(sweep_windows(document, kPeakKeys).windows.empty());
  nlohmann::json stepped = document;
  stepped["settings"]["method"] = "stepped_sine";
  EXPECT_NE(sweep_windows(stepped, kPeakKeys).reason.find("stepped sine"), std::string::npos);
  nlohmann::json stopped = document;
  stopped["completed"] = false;
  EXPECT_NE(sweep_windows(stopped, kPeakKeys).reason.find("did not reach"), std::string::npos);
  nlohmann::json coarse = document;
  coarse["settings"]["points"] = 10;  // windows of 35 % of the range each
  windows = sweep_windows(coarse, kPeakKeys);
  EXPECT_TRUE(windows.windows.empty());
  EXPECT_NE(windows.reason.find("% of the range"), std::string::npos) << windows.reason;
}

}  // namespace
}  // namespace crackle::pipeline
