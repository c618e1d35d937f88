#include <gtest/gtest.h>

#include <Eigen/Eigenvalues>
#include <Eigen/LU>
#include <cmath>
#include <complex>
#include <string>
#include <vector>

#include "core/errors.hpp"
#include "reduced/integrator.hpp"

namespace crackle::reduced {
namespace {


/// One mode, unit modal mass, no pairs, output = q.
ReducedSystem single_mode(double omega, double zeta) {
  ReducedSystem system;
  system.omega = VectorX::Constant(1, omega);
  system.rayleigh_alpha = 2.0 * zeta * omega;
  system.pair_area = VectorX(0);
  system.initial_gap = VectorX(0);
  system.pair_modes = MatrixX(0, 1);
  system.residual = MatrixX(0, 0);
  system.load_modal = VectorX::Ones(1);
  system.load_residual = VectorX(0);
  system.output_modes = MatrixX::Ones(1, 1);
  system.output_residual_pairs = MatrixX(1, 0);
  system.output_residual_load = VectorX::Zero(1);
  return system;
}

/// Amplitude of the sampled signal at angular frequency w over its samples (an integer number of periods).
double amplitude_at(const std::vector<double>& samples, double w, double h) {
  std::complex<double> sum = 0.0;
  for (std::size_t n = 0; n < samples.size(); ++n) sum += samples[n] * std::exp(std::complex<double>(0.0, -w * h * n));
  return 2.0 * std::abs(sum) / samples.size();
}

std::complex<double> receptance(double omega, double zeta, double w) {
  return 1.0 / std::complex<double>(omega * omega - w * w, 2.0 * zeta * omega * w);
}

struct ReceptanceRun {
  double amplitude_error;  // relative to the analytic receptance
  double warped_error;     // relative to the receptance at the trapezoidal (Tustin) warped frequency
  double energy_error;
};

ReceptanceRun forced_response(int steps_per_mode_period) {
  const double omega = 2.0 * kPi, zeta = 0.05, w = 0.5 * omega;  // forcing period = 2 mode periods
  const ReducedSystem system = single_mode(omega, zeta);
  const double h = 1.0 / steps_per_mode_period;
  ReducedIntegrator integrator(system, h, [w](double t) { return std::cos(w * t); });
  const std::complex<double> exact = receptance(omega, zeta, w);
  // Start on the continuous steady state: only the O(h^2) mismatch has to decay.
  integrator.set_initial_state(VectorX::Constant(1, exact.real()), VectorX::Constant(1, -w * exact.imag()));
  const int forcing_period = 2 * steps_per_mode_period;
  integrator.advance(25 * forcing_period);
  std::vector<double> samples;
  for (int n = 0; n < 5 * forcing_period; ++n) {
    samples.push_back(integrator.output(0));
    integrator.step();
  }
  const double amplitude = amplitude_at(samples, w, h);
  const double warped = 2.0 / h * std::tan(w * h / 2.0);
  return {std::abs(amplitude - std::abs(exact)) / std::abs(exact),
          std::abs(amplitude - std::abs(receptance(omega, zeta, warped))) / std::abs(exact),
          integrator.energy_error()};
}

TEST(ReducedIntegrator, ForcedDampedModeMatchesTheReceptanceAtSecondOrder) {
  std::vector<int> steps = {20, 40, 80, 160};
  std::vector<double> errors;
  for (int n : steps) {
    const ReceptanceRun run = forced_response(n);
    errors.push_back(run.amplitude_error);
    // The scheme is the trapezoidal rule: its steady state is the receptance at the warped
    // frequency (2/h) tan(w h/2), exactly; the energy account balances to round-off.
    EXPECT_LT(run.warped_error, 1e-9) << n;
    EXPECT_LT(run.energy_error, 1e-12) << n;
    std::printf("steps per mode period %4d: receptance error %.3e\n", n, run.amplitude_error);
  }
  for (std::size_t k = 1; k < errors.size(); ++k) {
    const double rate = std::log2(errors[k - 1] / errors[k]);
    EXPECT_NEAR(rate, 2.0, 0.05);
  }
  EXPECT_LT(errors[1], 4e-4);  // 40 steps per mode period (80 per forcing period)
  EXPECT_LT(errors[2], 1e-4);  // 80 steps per mode period
}

/// A grounded spring-mass chain, reduced on its lowest modes with the residual flexibility.
struct Chain {
  MatrixX stiffness, mass, pair_rows, outputs;
  VectorX load;
};

Chain make_chain(int n, double spring, double mass) {
  Chain chain;
  chain.stiffness = MatrixX::Zero(n, n);
  for (int i = 0; i < n; ++i) {
    chain.stiffness(i, i) += spring;  // spring to the left neighbour (the ground for i = 0)
    if (i > 0) {
      chain.stiffness(i - 1, i - 1) += spring;
      chain.stiffness(i - 1, i) -= spring;
      chain.stiffness(i, i - 1) -= spring;
    }
  }
  chain.mass = mass * MatrixX::Identity(n, n);
  chain.outputs = MatrixX::Identity(n, n);
  chain.load = VectorX::Zero(n);
  return chain;
}

ReducedSystem reduce(const Chain& chain, int n_modes, bool with_residual = true) {
  Eigen::GeneralizedSelfAdjointEigenSolver<MatrixX> eigen(chain.stiffness, chain.mass);
  const MatrixX phi = eigen.eigenvectors().leftCols(n_modes);  // mass-normalised
  const VectorX omega2 = eigen.eigenvalues().head(n_modes);
  MatrixX residual = chain.stiffness.inverse() - phi * omega2.cwiseInverse().asDiagonal() * phi.transpose();
  if (!with_residual) residual.setZero();
  ReducedSystem system;
  system.omega = omega2.cwiseSqrt();
  system.pair_area = VectorX::Constant(chain.pair_rows.rows(), 1e-4);
  system.initial_gap = VectorX::Zero(chain.pair_rows.rows());
  system.normal_penalty = 1e9;  // eps_N A = 1e5 N/m
  system.pair_modes = chain.pair_rows * phi;
  system.residual = chain.pair_rows * residual * chain.pair_rows.transpose();
  system.load_modal = phi.transpose() * chain.load;
  system.load_residual = chain.pair_rows * residual * chain.load;
  system.output_modes = chain.outputs * phi;
  system.output_residual_pairs = chain.outputs * residual * chain.pair_rows.transpose();
  system.output_residual_load = chain.outputs * residual * chain.load;
  return system;
}

TEST(ReducedIntegrator, StaticLoadGivesTheExactStaticAnswerModalPlusResidual) {
  // 6 masses, 2 modes kept; a pair grounds mass 2 across an initial gap, the load on mass 5 closes it.
  Chain chain = make_chain(6, 1000.0, 1.0);
  chain.pair_rows = MatrixX::Zero(1, 6);
  chain.pair_rows(0, 2) = 1.0;
  chain.load[5] = -100.0;
  ReducedSystem system = reduce(chain, 2);
  system.initial_gap[0] = 1e-3;
  system.rayleigh_alpha = 2.0 * system.omega[0];  // critical damping of mode 1: settles fast
  // Exact: K u = f + B^T p, p = k max(0, -(g0 + B u)); closed: (K + k B^T B) u = f - k B^T g0.
  const double k = system.normal_penalty * system.pair_area[0];
  const VectorX exact = (chain.stiffness + k * chain.pair_rows.transpose() * chain.pair_rows)
                            .lu()
                            .solve(chain.load - k * chain.pair_rows.transpose() * system.initial_gap);
  const double exact_force = -k * (system.initial_gap[0] + exact[2]);
  ASSERT_GT(exact_force, 0.0);

  const double h = reduced_time_step(system, 0.0, 40);
  ReducedIntegrator integrator(system, h, [](double) { return 1.0; });
  integrator.advance(static_cast<Index>(40.0 / (system.omega[0] * h)));  // e^-40
  EXPECT_EQ(integrator.n_closed(), 1);
  EXPECT_NEAR(integrator.pair_forces()[0], exact_force, 1e-10 * exact_force);
  EXPECT_LT((integrator.outputs() - exact).norm(), 1e-11 * exact.norm());
  // The step load closes the gap dynamically: the impact's O(h^2) energy error shows here.
  EXPECT_LT(integrator.energy_error(), 1e-4);

  // Without the residual flexibility the two modes alone miss the static answer.
  const ReducedSystem truncated = reduce(chain, 2, false);
  ReducedSystem truncated_with_gap = truncated;
  truncated_with_gap.initial_gap[0] = 1e-3;
  truncated_with_gap.rayleigh_alpha = system.rayleigh_alpha;
  ReducedIntegrator modal_only(truncated_with_gap, h, [](double) { return 1.0; });
  modal_only.advance(static_cast<Index>(40.0 / (system.omega[0] * h)));
  EXPECT_GT((modal_only.outputs() - exact).norm(), 1e-2 * exact.norm());
}

/// One mode (unit modal mass, omega_open) and one frictionless pair row: g = q + r p, p = k max(0, -g).
ReducedSystem bilinear_oscillator(double omega_open, double residual, double stiffness) {
  ReducedSystem system;
  system.omega = VectorX::Constant(1, omega_open);
  system.pair_area = VectorX::Ones(1);
  system.initial_gap = VectorX::Zero(1);
  system.normal_penalty = stiffness;
  system.pair_modes = MatrixX::Ones(1, 1);
  system.residual = MatrixX::Constant(1, 1, residual);
  system.load_modal = VectorX::Zero(1);
  system.load_residual = VectorX::Zero(1);
  system.output_modes = MatrixX::Ones(1, 1);
  system.output_residual_pairs = MatrixX::Zero(1, 1);
  system.output_residual_load = VectorX::Zero(1);
  return system;
}

TEST(ReducedIntegrator, BilinearOscillatorHasTheExactBilinearPeriod) {
  // Closed: q'' + w_o^2 q = p, p = -k g, g = q + r p  =>  p = -q / (r + 1/k): the contact spring
  // in series with the residual flexibility, w_c^2 = w_o^2 + 1/(r + 1/k). Half a cycle at each.
  const double omega_open = 2.0 * kPi, residual = 2e-3, stiffness = 1e3;
  const double omega_closed = std::sqrt(omega_open * omega_open + 1.0 / (residual + 1.0 / stiffness));
  const double period = kPi / omega_open + kPi / omega_closed;
  const ReducedSystem system = bilinear_oscillator(omega_open, residual, stiffness);
  EXPECT_NEAR(reduced_closed_max_frequency(system), omega_closed / (2.0 * kPi), 1e-12 * omega_closed);
  const double h = 2.0 * kPi / omega_closed / 200.0;
  ReducedIntegrator integrator(system, h, nullptr);
  integrator.set_initial_state(VectorX::Ones(1), VectorX::Zero(1));
  std::vector<double> crossings;  // upward zero crossings of q, linearly interpolated (q'' = 0 there)
  double previous = integrator.output(0);
  int max_iterations = 0;
  while (crossings.size() < 21) {
    integrator.step();
    max_iterations = std::max(max_iterations, integrator.last_iterations());
    const double y = integrator.output(0);
    if (previous < 0.0 && y >= 0.0) crossings.push_back(integrator.time() - h * y / (y - previous));
    previous = y;
  }
  const double measured = (crossings.back() - crossings.front()) / 20.0;
  std::printf("bilinear period %.9f exact %.9f (f_o %.4f, f_c %.4f), relative error %.2e, max iterations %d\n",
              measured, period, omega_open / (2 * kPi), omega_closed / (2 * kPi), measured / period - 1.0,
              max_iterations);
  EXPECT_NEAR(measured / period, 1.0, 1e-3);
  EXPECT_LE(max_iterations, 2);
  EXPECT_LT(integrator.energy_error(), 1e-3);
}

TEST(ReducedIntegrator, UndampedChatteringConservesEnergyOverAThousandPeriods) {
  // 8 masses, 3 modes; two pairs ground masses 3 and 6 (one at contact, one across a gap).
  Chain chain = make_chain(8, 1000.0, 1.0);
  chain.pair_rows = MatrixX::Zero(2, 8);
  chain.pair_rows(0, 3) = 1.0;
  chain.pair_rows(1, 6) = 1.0;
  ReducedSystem system = reduce(chain, 3);
  system.initial_gap[1] = 2e-3;
  const double period = 2.0 * kPi / system.omega[0];
  // The energy error of an impact is O((omega_closed h)^2) with random signs over the impacts
  // (measured: 10 periods 3.6e-4, 1.1e-4, 2.3e-5, 5.6e-6 at 20, 40, 80, 160 steps per closed period).
  // The scale is the full chain's closed frequency (the pair's local stiffness against the nearby
  // mass), well above the reduced model's own closed-limit frequency: with that one (also measured)
  // the error reaches 1e-2.
  const double k = system.normal_penalty * system.pair_area[0];
  const Eigen::GeneralizedSelfAdjointEigenSolver<MatrixX> closed(
      chain.stiffness + k * chain.pair_rows.transpose() * chain.pair_rows, chain.mass, Eigen::EigenvaluesOnly);
  const double closed_frequency = std::sqrt(closed.eigenvalues().maxCoeff()) / (2.0 * kPi);
  EXPECT_LT(reduced_closed_max_frequency(system), 0.5 * closed_frequency);
  const double h = reduced_time_step(system, closed_frequency, 80);
  ReducedIntegrator integrator(system, h, nullptr);
  VectorX velocity = VectorX::Zero(3);
  velocity[0] = 0.1;
  velocity[2] = 0.05;
  integrator.set_initial_state(VectorX::Zero(3), velocity);
  const Index n_steps = static_cast<Index>(1000.0 * period / h);
  Index transitions = 0;
  Index previous_closed = integrator.n_closed();
  double worst = 0.0;  // at the instants both pairs are open (a closed pair holds the closing step's share)
  for (Index n = 0; n < n_steps; ++n) {
    integrator.step();
    transitions += std::abs(integrator.n_closed() - previous_closed);
    previous_closed = integrator.n_closed();
    if (integrator.n_closed() == 0) worst = std::max(worst, integrator.energy_error());
  }
  std::printf("chattering: %d steps, %d open/close transitions, worst energy error %.2e, "
              "iterations per step %.3f, factorisations %ld\n",
              n_steps, transitions, worst, double(integrator.total_iterations()) / n_steps,
              integrator.total_factorizations());
  EXPECT_GT(transitions, 2000);  // both pairs really breathe, about once per period each
  EXPECT_LT(worst, 1e-3);
  EXPECT_EQ(integrator.energy().external_work, 0.0);
  EXPECT_EQ(integrator.energy().damping_dissipation, 0.0);
}

/// Undamped chattering of a 30-mass chain reduced to 20 modes, five pairs, a stiff penalty and the
/// step of 40 per period of the highest retained mode: the closed system's stiffest frequencies
/// (the pairs' penalty in series with the small residual flexibility) are far above that, so a
/// switching step is not resolved. Returns the worst energy error over `periods` of mode 1.
struct SwitchingRun {
  double worst_energy_error = 0.0;
  double closed_over_highest = 0.0;  ///< reduced_closed_max_frequency / highest mode
  long switching_steps = 0, implicit = 0, unconserved = 0;
  Index transitions = 0;
  bool finished = true;
  std::string failure;  ///< the SolverError's message, if one stopped the run
};

SwitchingRun stiff_chattering(bool conserve, double periods, bool guarded = false) {
  Chain chain = make_chain(60, 1000.0, 1.0);
  chain.pair_rows = MatrixX::Zero(5, 60);
  for (int k = 0; k < 5; ++k) chain.pair_rows(k, 10 * k + 9) = 1.0;
  ReducedSystem system = reduce(chain, 20);
  system.residual *= 1e-3;       // a stiff boundary: little static flexibility left beyond the modes
  system.normal_penalty = 1e11;  // eps_N A = 1e7 N/m, 1e4 x the chain's springs
  for (int k = 0; k < 5; ++k) system.initial_gap[k] = k % 2 == 0 ? 0.0 : 1e-3;
  SwitchingRun run;
  const double highest = system.omega.maxCoeff() / (2.0 * kPi);
  run.closed_over_highest = reduced_closed_max_frequency(system) / highest;
  ReducedIntegratorOptions options;
  options.conserve_switching_energy = conserve;
  if (!conserve && !guarded) options.energy_tolerance = 0.0;  // let the plain force's growth show
  ReducedIntegrator integrator(system, reduced_time_step(system, 0.0, 40), nullptr, options);
  VectorX velocity = VectorX::Zero(20);
  velocity[0] = 0.1;
  velocity[3] = 0.05;
  velocity[7] = 0.02;
  integrator.set_initial_state(VectorX::Zero(20), velocity);
  const Index n_steps = static_cast<Index>(periods * 2.0 * kPi / system.omega[0] / integrator.time_step());
  Index previous_closed = integrator.n_closed();
  try {
    for (Index n = 0; n < n_steps; ++n) {
      integrator.step();
      run.transitions += std::abs(integrator.n_closed() - previous_closed);
      previous_closed = integrator.n_closed();
      run.worst_energy_error = std::max(run.worst_energy_error, integrator.energy_error());
      if (run.worst_energy_error > 1.0) break;  // blown up: enough seen
    }
  } catch (const SolverError& error) {
    run.finished = false;  // the state left the finite numbers, or the energy guard stopped it
    run.failure = error.what();
    run.worst_energy_error = std::max(run.worst_energy_error, 1.0);
  }
  run.switching_steps = integrator.switching_steps();
  run.implicit = integrator.implicit_switching_steps();
  run.unconserved = integrator.unconserved_switching_steps();
  return run;
}

TEST(ReducedIntegrator, UnresolvedSwitchingStepsConserveEnergyInsteadOfGainingIt) {
  const SwitchingRun plain = stiff_chattering(false, 300.0);
  const SwitchingRun conserved = stiff_chattering(true, 300.0);
  std::printf("closed/highest frequency %.1f; trapezoidal: worst energy error %.3e (%s); conserving: %.3e, "
              "%ld switching steps (%ld redone with the end-of-step force), %ld not conserved exactly, "
              "%ld transitions\n",
              plain.closed_over_highest, plain.worst_energy_error, plain.finished ? "finite" : "not finite",
              conserved.worst_energy_error, conserved.switching_steps, conserved.implicit, conserved.unconserved,
              static_cast<long>(conserved.transitions));
  EXPECT_GT(plain.closed_over_highest, 10.0);  // the switching steps really are unresolved
  EXPECT_GT(conserved.transitions, 1000);      // and the pairs really breathe
  EXPECT_GT(plain.worst_energy_error, 0.05);   // the plain trapezoidal contact force gains energy
  EXPECT_LT(conserved.worst_energy_error, 1e-3);
  EXPECT_EQ(conserved.unconserved, 0);
}

TEST(ReducedIntegrator, AFailingEnergyBalanceStopsTheRunInsteadOfGoingOn) {
  // The plain trapezoidal force of the test above with the default guard (energy_tolerance 0.05).
  const SwitchingRun guarded = stiff_chattering(false, 300.0, true);
  std::printf("%s\n", guarded.failure.c_str());
  EXPECT_FALSE(guarded.finished);
  EXPECT_NE(guarded.failure.find("energy balance error"), std::string::npos);
  EXPECT_NE(guarded.failure.find("at step"), std::string::npos);
}

/// A block of mass m on one rigid mode (x = q / sqrt(m)), pressed by a load through the massless
/// boundary onto a pair with friction; rows: normal, tangent 1 (along x), tangent 2.
ReducedSystem pressed_block(double mass, double mu, double press) {
  ReducedSystem system;
  system.omega = VectorX::Zero(1);
  system.friction = true;
  system.pair_area = VectorX::Constant(1, 1e-4);
  system.initial_gap = VectorX::Zero(1);
  system.normal_penalty = 1e10;  // eps A = 1e6 N/m
  system.tangential_penalty = 1e10;
  system.friction_coefficient = mu;
  system.pair_modes = MatrixX::Zero(3, 1);
  system.pair_modes(1, 0) = 1.0 / std::sqrt(mass);
  system.residual = 1e-6 * MatrixX::Identity(3, 3);
  system.load_modal = VectorX::Zero(1);
  system.load_residual = VectorX::Zero(3);
  system.load_residual[0] = -press;  // closes the gap by `press` metres per unit of a
  system.output_modes = MatrixX::Constant(1, 1, 1.0 / std::sqrt(mass));  // x
  system.output_residual_pairs = MatrixX::Zero(1, 3);
  system.output_residual_load = VectorX::Zero(1);
  return system;
}

TEST(ReducedIntegrator, SlidingBlockDeceleratesAtMuNOverM) {
  const double mass = 2.0, mu = 0.3, velocity = 1.0;
  const ReducedSystem system = pressed_block(mass, mu, 1e-4);
  const double normal_force = 1e6 * 1e-4 / (1.0 + 1e6 * 1e-6);  // p = k d / (1 + k r) = 50 N
  const double deceleration = mu * normal_force / mass;         // 7.5 m/s^2
  const double h = 1e-4;
  ReducedIntegrator integrator(system, h, [](double) { return 1.0; });
  integrator.set_initial_state(VectorX::Zero(1), VectorX::Constant(1, velocity * std::sqrt(mass)));
  EXPECT_NEAR(integrator.pair_forces()[0], normal_force, 1e-9 * normal_force);
  const double scale = 1.0 / std::sqrt(mass);
  double stop_time = -1.0;
  double worst_acceleration = 0.0;
  long iterations_sliding = 0, steps_sliding = 0;
  while (integrator.time() < 0.3) {
    integrator.step();
    if (integrator.n_slipping() == 1 && stop_time < 0.0) {
      worst_acceleration = std::max(
          worst_acceleration, std::abs(scale * integrator.modal_acceleration()[0] + deceleration) / deceleration);
      iterations_sliding += integrator.last_iterations();
      ++steps_sliding;
    } else if (stop_time < 0.0) {
      stop_time = integrator.time();
    }
  }
  std::printf("sliding block: acceleration error %.2e, stop at %.5f s (exact %.5f), iterations per step %.3f\n",
              worst_acceleration, stop_time, velocity / deceleration, double(iterations_sliding) / steps_sliding);
  EXPECT_LT(worst_acceleration, 1e-3);
  EXPECT_NEAR(stop_time, velocity / deceleration, 2.0 * h);
  EXPECT_NEAR(integrator.output(0), velocity * velocity / (2.0 * deceleration), 1e-3 * 0.0667);
  // Then it sticks, oscillating on the tangential penalty in series with the residual flexibility,
  // its spring force at most mu N: velocity amplitude mu N / sqrt(k m).
  const double tangential_stiffness = 1.0 / (1e-6 + 1.0 / (1e10 * 1e-4));
  EXPECT_LT(std::abs(scale * integrator.modal_velocity()[0]),
            1.01 * mu * normal_force / std::sqrt(tangential_stiffness * mass));
  // The kinetic energy went into friction; the account balances.
  EXPECT_NEAR(integrator.energy().friction_dissipation, 0.5 * mass * velocity * velocity, 2e-3);
  EXPECT_LT(integrator.energy_error(), 1e-6);
  EXPECT_LT(double(iterations_sliding) / steps_sliding, 1.1);
}

// The integrator's contact state per pair (as contact::PenaltyContact::pair_state): the pressed block
// slips (2) until it stops, then sticks (1); released it opens (0); frictionless, closed is 2.
TEST(ReducedIntegrator, PairStateFollowsTheSolvesStickSlipDecision) {
  const double mass = 2.0;
  bool pressed = true;
  const ReducedSystem system = pressed_block(mass, 0.3, 1e-4);
  ReducedIntegrator integrator(system, 1e-4, [&pressed](double) { return pressed ? 1.0 : -1.0; });
  integrator.set_initial_state(VectorX::Zero(1), VectorX::Constant(1, std::sqrt(mass)));  // 1 m/s
  EXPECT_EQ(integrator.pair_state(0), 1);  // the initial static solve: stuck, no tangential force yet
  integrator.step();
  EXPECT_EQ(integrator.pair_state(0), 2);
  EXPECT_EQ(integrator.n_slipping(), 1);
  integrator.advance(2000);  // stops at 1 / 7.5 s = 1334 steps
  EXPECT_EQ(integrator.pair_state(0), 1);
  EXPECT_EQ(integrator.n_slipping(), 0);
  pressed = false;
  integrator.step();
  EXPECT_EQ(integrator.pair_state(0), 0);

  const ReducedSystem bilinear = bilinear_oscillator(2.0 * kPi, 2e-3, 1e3);
  ReducedIntegrator frictionless(bilinear, 1e-2, nullptr);
  frictionless.set_initial_state(VectorX::Constant(1, -1.0), VectorX::Zero(1));
  EXPECT_EQ(frictionless.pair_state(0), 2);
  frictionless.set_initial_state(VectorX::Constant(1, 1.0), VectorX::Zero(1));
  EXPECT_EQ(frictionless.pair_state(0), 0);
}

TEST(ReducedIntegrator, LinearPartIsStableForAnyStep) {
  Chain chain = make_chain(5, 1000.0, 1.0);
  chain.pair_rows = MatrixX::Zero(0, 5);
  chain.load[4] = 1.0;
  const ReducedSystem system = reduce(chain, 5);
  const double h = 10.0 * 2.0 * kPi / system.omega.maxCoeff();
  ReducedIntegrator integrator(system, h, nullptr);
  integrator.set_initial_state(VectorX::Ones(5), VectorX::Ones(5));
  const double initial = integrator.energy().stored();
  double largest = 0.0;
  for (int n = 0; n < 10000; ++n) {
    integrator.step();
    largest = std::max(largest, integrator.energy().stored());
  }
  EXPECT_LT(largest, initial * (1.0 + 1e-12));
  EXPECT_LT(integrator.energy_error(), 1e-10);
  EXPECT_LT(integrator.modal_displacement().norm(), 10.0);
}

TEST(ReducedIntegrator, AnUnsettledContactSolveNamesTheStep) {
  const ReducedSystem system = bilinear_oscillator(2.0 * kPi, 2e-3, 1e3);
  ReducedIntegratorOptions options;
  options.max_contact_iterations = 1;
  ReducedIntegrator integrator(system, 1e-2, nullptr, options);
  integrator.set_initial_state(VectorX::Zero(1), VectorX::Constant(1, -1.0));  // closes at once
  try {
    integrator.step();
    FAIL() << "expected a SolverError";
  } catch (const SolverError& error) {
    EXPECT_NE(std::string(error.what()).find("at step 1 (t = 0.01 s"), std::string::npos) << error.what();
  }
}

TEST(ReducedIntegrator, TimeStepResolvesTheHighestModeOrHarmonic) {
  const ReducedSystem system = single_mode(2.0 * kPi * 50.0, 0.0);
  EXPECT_DOUBLE_EQ(reduced_time_step(system, 10.0, 40), 1.0 / (40 * 50.0));
  EXPECT_DOUBLE_EQ(reduced_time_step(system, 200.0, 40), 1.0 / (40 * 200.0));
  EXPECT_DOUBLE_EQ(reduced_time_step(system, 0.0), 1.0 / (kDefaultStepsPerPeriod * 50.0));
  EXPECT_THROW(reduced_time_step(system, 10.0, 0), InputError);
  EXPECT_THROW(ReducedIntegrator(system, -1.0, nullptr), InputError);
  ReducedSystem broken = system;
  broken.load_modal = VectorX::Zero(3);
  EXPECT_THROW(ReducedIntegrator(broken, 1e-3, nullptr), InputError);
}

}  // namespace
}  // namespace crackle::reduced
