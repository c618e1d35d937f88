// Harmonic balance on hand-built reduced systems (HYBRID.md §4-5): the linear receptance, a bilinear
// oscillator against an independent time integration, continuation through a fold with Hill's
// stability (the monodromy against Hill's method), and a period-doubled (nu = 2) branch.
#include <gtest/gtest.h>

#include <optional>
#include <utility>

#include <Eigen/Dense>
#include <Eigen/Eigenvalues>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <complex>
#include <cstdio>
#include <cstdlib>
#include <cstdlib>

#include "core/errors.hpp"
#include "sweep/branch_switching.hpp"
#include "sweep/harmonic_balance.hpp"

namespace crackle::sweep {
namespace {

using Complex = std::complex<double>;

/// A 1-DOF oscillator with one pair row: q'' + 2 zeta w q' + w^2 q = f a(t) + b p,
/// g = g0 + b q + r p + rf a(t), p = k max(0, -g). The output row is q itself.
reduced::ReducedSystem one_dof(double w, double zeta, double b, double r, double f, double rf, double k, double g0) {
  reduced::ReducedSystem s;
  s.omega = VectorX::Constant(1, w);
  s.rayleigh_alpha = 2.0 * zeta * w;  // zeta = alpha / (2 w)
  s.pair_area = VectorX::Constant(1, 1.0);
  s.initial_gap = VectorX::Constant(1, g0);
  s.normal_penalty = k;
  s.pair_modes = MatrixX::Constant(1, 1, b);
  s.residual = MatrixX::Constant(1, 1, r);
  s.load_modal = VectorX::Constant(1, f);
  s.load_residual = VectorX::Constant(1, rf);
  s.output_modes = MatrixX::Identity(1, 1);
  s.output_residual_pairs = MatrixX::Zero(1, 1);
  s.output_residual_load = VectorX::Zero(1);
  return s;
}

/// Independent reference: RK4 on the modal equations with one pair row (p closed by hand through R),
/// run to steady state; harmonics of the outputs (= modal coordinates) over the last base period.
struct TimeIntegration {
  const reduced::ReducedSystem& s;
  double omega;  // load frequency
  int nu = 1;    // harmonics are of Omega / nu
  int steps_per_period = 4000;

  double force(const VectorX& q, double t) const {
    const double k = s.normal_penalty * s.pair_area[0];
    const double free_gap = s.initial_gap[0] + s.pair_modes.row(0).dot(q) + s.load_residual[0] * std::cos(omega * t);
    return free_gap < 0.0 ? -k * free_gap / (1.0 + k * s.residual(0, 0)) : 0.0;
  }
  VectorX acceleration(const VectorX& q, const VectorX& v, double t) const {
    VectorX a = s.load_modal * std::cos(omega * t) + s.pair_modes.row(0).transpose() * force(q, t);
    for (Index r = 0; r < q.size(); ++r) {
      const double w = s.omega[r];
      a[r] -= 2.0 * s.damping_ratio(r) * w * v[r] + w * w * q[r];
    }
    return a;
  }
  /// Advances (q, v) over `periods` base periods (2 pi nu / Omega) from time t (a whole number of load periods).
  void run(VectorX& q, VectorX& v, double& t, int periods, std::vector<VectorX>* samples = nullptr) const {
    const double dt = 2.0 * kPi * nu / omega / steps_per_period;
    for (int p = 0; p < periods; ++p)
      for (int i = 0; i < steps_per_period; ++i) {
        if (samples) samples->push_back(q);
        const VectorX k1q = v, k1v = acceleration(q, v, t);
        const VectorX k2q = v + 0.5 * dt * k1v, k2v = acceleration(q + 0.5 * dt * k1q, k2q, t + 0.5 * dt);
        const VectorX k3q = v + 0.5 * dt * k2v, k3v = acceleration(q + 0.5 * dt * k2q, k3q, t + 0.5 * dt);
        const VectorX k4q = v + dt * k3v, k4v = acceleration(q + dt * k3q, k4q, t + dt);
        q += dt / 6.0 * (k1q + 2.0 * k2q + 2.0 * k3q + k4q);
        v += dt / 6.0 * (k1v + 2.0 * k2v + 2.0 * k3v + k4v);
        t += dt;
      }
  }
  /// Complex amplitude (a - i b convention) of coordinate `r` at harmonic k of the base frequency,
  /// over one base period sampled from (q, v) at t.
  std::vector<Complex> harmonics(VectorX q, VectorX v, double t, Index r, int max_k) const {
    std::vector<VectorX> samples;
    run(q, v, t, 1, &samples);
    std::vector<Complex> out(max_k + 1, 0.0);
    const int n = static_cast<int>(samples.size());
    for (int k = 0; k <= max_k; ++k) {
      Complex sum = 0.0;
      for (int j = 0; j < n; ++j) sum += samples[j][r] * std::polar(1.0, -2.0 * kPi * k * j / n);
      out[k] = sum * (k == 0 ? 1.0 : 2.0) / static_cast<double>(n);
    }
    return out;
  }
};

/// Initial modal state (q, v) at t = 0 of a harmonic-balance solution.
void initial_state(const Solution& sol, VectorX& q, VectorX& v) {
  const double w0 = sol.omega / sol.subharmonic;
  q = VectorX::Zero(sol.modal.rows());
  v = VectorX::Zero(sol.modal.rows());
  for (Index k = 0; k < sol.modal.cols(); ++k) {
    q += sol.modal.col(k).real();
    v += (sol.modal.col(k) * Complex(0.0, k * w0)).real();
  }
}

// ---------------------------------------------------------------------------------------------

TEST(HarmonicBalance, LinearEqualsReceptanceResponse) {
  // 3-DOF chain, all modes kept (no residual flexibility): the reduced model is exact, so the HB
  // gaps and outputs must equal a direct complex solve of (K - W^2 M + i W C) u = f.
  MatrixX mass = Eigen::Vector3d(1.0, 2.0, 1.5).asDiagonal();
  MatrixX stiffness(3, 3);
  stiffness << 300, -100, 0, -100, 250, -150, 0, -150, 200;
  const double alpha = 0.3, beta = 2e-4;
  Eigen::GeneralizedSelfAdjointEigenSolver<MatrixX> eig(stiffness, mass);
  const MatrixX phi = eig.eigenvectors();  // M-orthonormal
  MatrixX b(2, 3);
  b << 1, -1, 0, 0, 1, -1;
  MatrixX c(2, 3);
  c << 1, 0, 0, 0, 0, 1;
  const VectorX f = Eigen::Vector3d(1e-4, 0.0, -2e-4);
  reduced::ReducedSystem s;
  s.omega = eig.eigenvalues().cwiseSqrt();
  s.rayleigh_alpha = alpha;
  s.rayleigh_beta = beta;
  s.pair_area = VectorX::Ones(2);
  s.initial_gap = VectorX::Constant(2, 1.0);  // a metre apart: never in contact
  s.normal_penalty = 1e12;
  s.pair_modes = b * phi;
  s.residual = MatrixX::Zero(2, 2);
  s.load_modal = phi.transpose() * f;
  s.load_residual = VectorX::Zero(2);
  s.output_modes = c * phi;
  s.output_residual_pairs = MatrixX::Zero(2, 2);
  s.output_residual_load = VectorX::Zero(2);

  HarmonicBalanceOptions opt;
  opt.harmonics = 5;
  HarmonicBalance hb(s, opt);
  for (double omega : {3.0, 8.0, 15.0, 30.0}) {
    const Solution sol = hb.solve(omega);
    const Eigen::MatrixXcd dyn = stiffness.cast<Complex>() - omega * omega * mass.cast<Complex>() +
                                 Complex(0.0, omega) * (alpha * mass + beta * stiffness).cast<Complex>();
    const Eigen::VectorXcd u = dyn.partialPivLu().solve(f.cast<Complex>());
    const Eigen::VectorXcd g = b.cast<Complex>() * u;
    const Eigen::VectorXcd y = c.cast<Complex>() * u;
    const double ref = g.cwiseAbs().maxCoeff();
    for (Index i = 0; i < 2; ++i) {
      EXPECT_NEAR(sol.gaps[i], 1.0, 1e-15);                         // order 0: g0 only
      EXPECT_NEAR(sol.gaps[2 + i], g[i].real(), 1e-10 * ref);       // a_1
      EXPECT_NEAR(sol.gaps[4 + i], -g[i].imag(), 1e-10 * ref);      // b_1
      EXPECT_NEAR(std::abs(sol.outputs(i, 1) - y[i]), 0.0, 1e-10 * y.cwiseAbs().maxCoeff());
      EXPECT_NEAR(sol.amplitude(i, 1.0), std::abs(y[i]), 1e-10 * y.cwiseAbs().maxCoeff());
      EXPECT_NEAR(sol.phase(i, 1.0), std::arg(y[i]), 1e-9);
      EXPECT_EQ(std::abs(sol.outputs(i, 0)), 0.0);
    }
    EXPECT_LT(sol.gaps.segment(6, 4 * 2).cwiseAbs().maxCoeff(), 1e-16 * ref + 1e-300);  // orders 2..5
    for (Index k = 2; k <= 5; ++k) EXPECT_LT(sol.outputs.col(k).cwiseAbs().maxCoeff(), 1e-16 * y.cwiseAbs().maxCoeff());
    EXPECT_LE(sol.iterations, 1);
    EXPECT_TRUE(hb.hill_stability(sol).stable);
  }
}

TEST(HarmonicBalance, RigidModeHasNoStaticReceptance) {
  // A free body: mode 0 rigid (omega 0), mode 1 elastic. At k >= 1 the rigid mode's receptance is
  // -1/omega^2; at k = 0 it is left out and the mean load it would see is reported.
  reduced::ReducedSystem s = one_dof(1.5, 0.02, 0.8, 0.05, 1e-6, 0.0, 2.0, 1.0);
  s.omega = Eigen::Vector2d(0.0, 1.5);
  s.pair_modes = MatrixX(1, 2);
  s.pair_modes << 0.3, 0.8;
  s.load_modal = Eigen::Vector2d(2e-7, 1e-6);
  s.output_modes = MatrixX::Identity(2, 2);
  s.output_residual_pairs = MatrixX::Zero(2, 1);
  s.output_residual_load = VectorX::Zero(2);
  HarmonicBalanceOptions opt;
  opt.harmonics = 4;
  {
    HarmonicBalance hb(s, opt);  // g0 = 1 m: open
    const Solution sol = hb.solve(1.1);
    EXPECT_NEAR(std::abs(sol.outputs(0, 1) - Complex(-2e-7 / (1.1 * 1.1))), 0.0, 1e-20);
    EXPECT_EQ(sol.rigid_imbalance, 0.0);
  }
  s.initial_gap[0] = -1e-7;  // preloaded: a mean contact force the rigid mode would carry
  HarmonicBalance hb(s, opt);
  const Solution sol = hb.solve(1.1);
  EXPECT_GT(sol.forces[0], 0.0);
  EXPECT_NEAR(sol.rigid_imbalance, 0.3 * sol.forces[0], 1e-12 * sol.forces[0]);
}

TEST(HarmonicBalance, JacobianMatchesFiniteDifferences) {
  const auto s = one_dof(1.0, 0.05, 1.0, 0.1, 1e-6, 5e-8, 3.0, 0.0);
  HarmonicBalanceOptions opt;
  opt.harmonics = 4;
  HarmonicBalance hb(s, opt);
  const double omega = 1.2;
  VectorX g = hb.linear_gaps(omega);
  g[3] += 2e-7;
  VectorX d_omega;
  const MatrixX jac = hb.jacobian(omega, g, &d_omega);
  const double h = 1e-6 * hb.gap_scale() * 1e-3;
  for (Index j = 0; j < g.size(); ++j) {
    VectorX gp = g, gm = g;
    gp[j] += h;
    gm[j] -= h;
    const VectorX fd = (hb.residual(omega, gp) - hb.residual(omega, gm)) / (2 * h) * hb.gap_scale();
    EXPECT_LT((fd - jac.col(j)).cwiseAbs().maxCoeff(), 1e-5) << "column " << j;
  }
  const VectorX fd = (hb.residual(omega + 1e-6, g) - hb.residual(omega - 1e-6, g)) / 2e-6;
  EXPECT_LT((fd - d_omega).cwiseAbs().maxCoeff(), 1e-6 * fd.cwiseAbs().maxCoeff());
}

TEST(HarmonicBalance, BilinearOscillatorMatchesTimeIntegration) {
  // Closed at rest (g0 = 0): open w = 1, closed sqrt(1 + k/(1 + k r)) = 1.82; residual flexibility
  // r and a direct load on the gap rf exercise R and r_f. Gaps ~ 1e-6 m exercise the scaling.
  const auto s = one_dof(1.0, 0.05, 1.0, 0.1, 1e-6, 5e-8, 3.0, 0.0);
  std::printf("  H-convergence of A1, A2, A3 (relative to the time integration's A1)\n");
  for (double omega : {0.7, 1.29, 2.1}) {
    TimeIntegration ti{s, omega};
    ti.steps_per_period = 16000;
    VectorX q = VectorX::Zero(1), v = VectorX::Zero(1);
    double t = 0.0;
    ti.run(q, v, t, 250);  // e^{-zeta w t}: transients decayed far below 1e-8
    const auto ref = ti.harmonics(q, v, t, 0, 3);
    std::printf("  Omega = %.2f: A1 = %.6e A2/A1 = %.4e A3/A1 = %.4e (time integration)\n", omega, std::abs(ref[1]),
                std::abs(ref[2]) / std::abs(ref[1]), std::abs(ref[3]) / std::abs(ref[1]));
    for (int harmonics : {5, 10, 20, 40}) {
      HarmonicBalanceOptions opt;
      opt.harmonics = harmonics;
      opt.time_samples = 0;  // default 4096
      HarmonicBalance hb(s, opt);
      const Solution sol = hb.solve(omega);
      double err[3];
      for (int k = 1; k <= 3; ++k) err[k - 1] = std::abs(sol.outputs(0, k) - ref[k]) / std::abs(ref[1]);
      std::printf("    H = %2d: |dA1| %.2e |dA2| %.2e |dA3| %.2e  top share %.2e%s  Newton %d\n", harmonics, err[0],
                  err[1], err[2], sol.top_harmonic_share, sol.harmonics_flagged ? " (flagged)" : "", sol.iterations);
      if (harmonics == 40)
        for (int k = 0; k < 3; ++k) EXPECT_LT(err[k], 2e-5) << "Omega " << omega << " order " << k + 1;
      if (harmonics == 5) EXPECT_GT(err[0] + err[1] + err[2], 1e-6);  // the truncation shows
      if (harmonics == 40) {  // raising H from a converged H = 10 point lands on the same solution
        HarmonicBalanceOptions low = opt;
        low.harmonics = 10;
        low.time_samples = 160;
        HarmonicBalance hb_low(s, low);
        const Solution start = hb_low.solve(omega);
        const Solution raised = hb.solve(omega, resize_harmonics(start.gaps, 1, harmonics));
        EXPECT_LT((raised.gaps - sol.gaps).cwiseAbs().maxCoeff(), 1e-9 * sol.gaps.cwiseAbs().maxCoeff());
      }
    }
  }
}


/// m modes, c pairs with random coupling, half of them closed at rest (g0 < 0).
reduced::ReducedSystem random_system(Index m, Index c, unsigned seed) {
  std::srand(seed);
  reduced::ReducedSystem s;
  s.omega = VectorX::LinSpaced(m, 1.0, 1.0 + 0.7 * (m - 1));
  s.rayleigh_alpha = 0.02;
  s.rayleigh_beta = 0.002;
  s.pair_area = VectorX::Constant(c, 0.5);
  s.initial_gap = 1e-7 * VectorX::Random(c);
  s.normal_penalty = 4.0;
  s.pair_modes = MatrixX::Random(c, m);
  const MatrixX a = MatrixX::Random(c, c);
  s.residual = 0.01 * (a * a.transpose() / c + MatrixX::Identity(c, c));
  s.load_modal = 1e-6 * VectorX::Random(m);
  s.load_residual = 1e-8 * VectorX::Random(c);
  s.output_modes = MatrixX::Random(2, m);
  s.output_residual_pairs = 0.01 * MatrixX::Random(2, c);
  s.output_residual_load = 1e-8 * VectorX::Random(2);
  return s;
}

TEST(HarmonicBalance, CoupledPairsJacobianAndCost) {
  {
    const auto s = random_system(4, 5, 7);
    HarmonicBalanceOptions opt;
    opt.harmonics = 3;
    HarmonicBalance hb(s, opt);
    const double omega = 1.7;
    const Solution sol = hb.solve(omega);
    int closed = 0;
    for (Index i = 0; i < 5; ++i) closed += sol.forces[i] > 0.0;
    EXPECT_GT(closed, 0);
    const MatrixX jac = hb.jacobian(omega, sol.gaps);
    const double h = 1e-9 * hb.gap_scale();
    double worst = 0.0;
    for (Index j = 0; j < sol.gaps.size(); ++j) {
      VectorX gp = sol.gaps, gm = sol.gaps;
      gp[j] += h;
      gm[j] -= h;
      const VectorX fd = (hb.residual(omega, gp) - hb.residual(omega, gm)) / (2 * h) * hb.gap_scale();
      worst = std::max(worst, (fd - jac.col(j)).cwiseAbs().maxCoeff());
    }
    EXPECT_LT(worst, 1e-4);
    // outputs: Y_1 = C Phi Q_1 + C G_res B^T P_1 + C G_res f
    const Eigen::VectorXcd p1 = sol.forces.segment(5, 5).cast<Complex>() - Complex(0, 1) * sol.forces.segment(10, 5).cast<Complex>();
    const Eigen::VectorXcd y1 = s.output_modes.cast<Complex>() * sol.modal.col(1) + s.output_residual_pairs.cast<Complex>() * p1 +
                                s.output_residual_load.cast<Complex>();
    EXPECT_LT((y1 - sol.outputs.col(1)).cwiseAbs().maxCoeff(), 1e-12 * y1.cwiseAbs().maxCoeff());
  }
  std::printf("  cost of one Newton iteration (residual + Jacobian + LU), m = 10 modes, N = 4096\n");
  const bool long_table = std::getenv("CRACKLE_SWEEP_COST") != nullptr;  // adds 128 pairs and H = 40
  for (Index c : {1, 8, 32, 128}) {
    for (int harmonics : {5, 10, 20, 40}) {
      if (!long_table && (c > 32 || harmonics > 20)) continue;
      const auto s = random_system(10, c, 11);
      HarmonicBalanceOptions opt;
      opt.harmonics = harmonics;
      HarmonicBalance hb(s, opt);
      VectorX g = hb.linear_gaps(2.0);
      const auto start = std::chrono::steady_clock::now();
      const VectorX r = hb.residual(2.0, g);
      const MatrixX jac = hb.jacobian(2.0, g);
      const auto mid = std::chrono::steady_clock::now();
      const VectorX step = jac.partialPivLu().solve(r);
      const auto end = std::chrono::steady_clock::now();
      EXPECT_TRUE(step.allFinite());
      std::printf("    pairs %3d H %2d unknowns %5d: residual+Jacobian %8.2f ms, LU %8.2f ms\n", int(c), harmonics,
                  int(hb.n_unknowns()), std::chrono::duration<double, std::milli>(mid - start).count(),
                  std::chrono::duration<double, std::milli>(end - mid).count());
    }
  }
}

/// One pair with friction (rows: normal, t1, t2) on `m` modes; R = 0 unless set.
reduced::ReducedSystem friction_system(const MatrixX& pair_modes, const VectorX& load_modal, const VectorX& omega,
                                       double zeta, double g0, double eps_n, double eps_t, double mu) {
  reduced::ReducedSystem s;
  s.omega = omega;
  s.rayleigh_alpha = 2.0 * zeta * omega[0];
  s.friction = true;
  s.pair_area = VectorX::Constant(1, 1.0);
  s.initial_gap = VectorX::Constant(1, g0);
  s.normal_penalty = eps_n;
  s.tangential_penalty = eps_t;
  s.friction_coefficient = mu;
  s.pair_modes = pair_modes;
  s.residual = MatrixX::Zero(3, 3);
  s.load_modal = load_modal;
  s.load_residual = VectorX::Zero(3);
  s.output_modes = MatrixX::Identity(omega.size(), omega.size());
  s.output_residual_pairs = MatrixX::Zero(omega.size(), 3);
  s.output_residual_load = VectorX::Zero(omega.size());
  return s;
}

TEST(Friction, FullStickEqualsLinearSprings) {
  // Always closed (deep preload) and never slipping (mu huge): for k >= 1 the pair acts as linear
  // springs diag(eps_N A, eps_T A, eps_T A), G_k = (I + H_k K)^{-1} E_k exactly.
  MatrixX bphi(3, 2);
  bphi << 0.5, -0.2, 0.8, 0.3, -0.1, 0.9;
  auto s = friction_system(bphi, Eigen::Vector2d(1e-6, -5e-7), Eigen::Vector2d(1.0, 1.6), 0.03, -1e-3, 2.0, 1.5, 1e6);
  s.residual = 0.05 * MatrixX::Identity(3, 3);
  s.residual(0, 1) = s.residual(1, 0) = 0.01;
  s.load_residual = Eigen::Vector3d(1e-8, 0.0, -2e-8);
  HarmonicBalanceOptions opt;
  opt.harmonics = 3;
  HarmonicBalance hb(s, opt);
  for (double omega : {0.8, 1.3, 2.0}) {
    const Solution sol = hb.solve(omega);
    Eigen::MatrixXcd h(3, 3);
    Eigen::VectorXcd e(3);
    Eigen::VectorXcd d(2);
    for (Index r = 0; r < 2; ++r) {
      const double w = s.omega[r];
      d[r] = 1.0 / Complex(w * w - omega * omega, 2.0 * s.damping_ratio(r) * w * omega);
    }
    h = bphi.cast<Complex>() * d.asDiagonal() * bphi.transpose().cast<Complex>() + s.residual.cast<Complex>();
    e = bphi.cast<Complex>() * d.asDiagonal() * s.load_modal.cast<Complex>() + s.load_residual.cast<Complex>();
    const Eigen::Matrix3cd k = Eigen::Vector3cd(2.0, 1.5, 1.5).asDiagonal();
    const Eigen::VectorXcd g1 = (Eigen::Matrix3cd::Identity() + h * k).partialPivLu().solve(e);
    for (Index i = 0; i < 3; ++i) {
      EXPECT_NEAR(sol.gaps[3 + i], g1[i].real(), 1e-10 * g1.cwiseAbs().maxCoeff()) << "Omega " << omega;
      EXPECT_NEAR(sol.gaps[6 + i], -g1[i].imag(), 1e-10 * g1.cwiseAbs().maxCoeff()) << "Omega " << omega;
    }
    EXPECT_LT(sol.gaps.tail(4 * 3).cwiseAbs().maxCoeff(), 1e-12 * g1.cwiseAbs().maxCoeff());
    EXPECT_LE(sol.iterations, 2);
  }
}

TEST(Friction, JenkinsOscillatorMatchesTimeIntegration) {
  // One mode moving a preloaded pair tangentially (constant pressure eps_N |g0|): a Jenkins
  // (spring-slider) oscillator, stuck w = sqrt(3), slipping w = 1. HB with the marched return
  // mapping against RK4 with the slider force as a state.
  MatrixX bphi(3, 1);
  bphi << 0.0, 1.0, 0.0;
  const double eps_t = 2.0, mu = 0.5, pressure = 1e-6;
  const auto s = friction_system(bphi, VectorX::Constant(1, 1e-6), VectorX::Constant(1, 1.0), 0.02, -1e-6, 1.0, eps_t, mu);
  HarmonicBalanceOptions opt;
  opt.harmonics = 15;
  HarmonicBalance hb(s, opt);
  {  // Jacobian against finite differences in a partially slipping state
    const double omega = 1.5;
    const Solution sol = hb.solve(omega);
    const MatrixX jac = hb.jacobian(omega, sol.gaps);
    const double h = 1e-7 * hb.gap_scale();
    double worst = 0.0;
    for (Index j = 0; j < sol.gaps.size(); ++j) {
      VectorX gp = sol.gaps, gm = sol.gaps;
      gp[j] += h;
      gm[j] -= h;
      const VectorX fd = (hb.residual(omega, gp) - hb.residual(omega, gm)) / (2 * h) * hb.gap_scale();
      worst = std::max(worst, (fd - jac.col(j)).cwiseAbs().maxCoeff());
    }
    std::printf("  friction Jacobian vs finite differences: max difference %.2e (Newton took %d iterations)\n", worst,
                sol.iterations);
    EXPECT_LT(worst, 1e-3);
  }
  const double limit = mu * pressure;
  for (double omega : {1.2, 1.5, 2.2}) {
    const Solution sol = hb.solve(omega);
    // RK4 on (q, v, t): dt/dt = -eps_T dq/dt while |t| < limit or unloading, else 0
    auto rhs = [&](const Eigen::Vector3d& y, double time) {
      const double q = y[0], v = y[1], t = y[2];
      const bool slipping = std::abs(t) >= limit && -eps_t * v * t > 0.0;
      (void)q;
      return Eigen::Vector3d(v, 1e-6 * std::cos(omega * time) + t - 2.0 * 0.02 * v - q, slipping ? 0.0 : -eps_t * v);
    };
    const int steps = 20000;
    const double dt = 2.0 * kPi / omega / steps;
    Eigen::Vector3d y = Eigen::Vector3d::Zero();
    double time = 0.0;
    std::vector<double> q_last;
    for (int period = 0; period < 200; ++period)
      for (int i = 0; i < steps; ++i) {
        if (period == 199) q_last.push_back(y[0]);
        const Eigen::Vector3d k1 = rhs(y, time), k2 = rhs(y + 0.5 * dt * k1, time + 0.5 * dt),
                              k3 = rhs(y + 0.5 * dt * k2, time + 0.5 * dt), k4 = rhs(y + dt * k3, time + dt);
        y += dt / 6.0 * (k1 + 2.0 * k2 + 2.0 * k3 + k4);
        y[2] = std::clamp(y[2], -limit, limit);
        time += dt;
      }
    Complex a1 = 0.0, a3 = 0.0;
    for (int j = 0; j < steps; ++j) {
      a1 += q_last[j] * std::polar(2.0 / steps, -2.0 * kPi * j / steps);
      a3 += q_last[j] * std::polar(2.0 / steps, -6.0 * kPi * j / steps);
    }
    std::printf("  Jenkins Omega %.1f: HB A1 %.5e A3/A1 %.4e | RK4 A1 %.5e A3/A1 %.4e\n", omega, sol.amplitude(0, 1.0),
                sol.ratios(0).third, std::abs(a1), std::abs(a3) / std::abs(a1));
    EXPECT_NEAR(std::abs(sol.outputs(0, 1) - a1), 0.0, 2e-4 * std::abs(a1));
    EXPECT_NEAR(std::abs(sol.outputs(0, 3) - a3), 0.0, 2e-4 * std::abs(a1));
  }
}

TEST(Friction, CostOfOneNewtonIteration) {
  std::printf("  with friction (3 rows per pair, tangent marched over 2N = 8192 samples), m = 10 modes\n");
  for (Index pairs : {1, 8}) {
    for (int harmonics : {5, 10, 20}) {
      reduced::ReducedSystem s = random_system(10, 3 * pairs, 5);
      s.friction = true;
      s.pair_area = VectorX::Constant(pairs, 0.5);
      s.initial_gap = -1e-7 * VectorX::Ones(pairs);
      s.tangential_penalty = 3.0;
      s.friction_coefficient = 0.3;
      HarmonicBalanceOptions opt;
      opt.harmonics = harmonics;
      HarmonicBalance hb(s, opt);
      const VectorX g = hb.linear_gaps(2.0);
      const auto start = std::chrono::steady_clock::now();
      const VectorX r = hb.residual(2.0, g);
      const MatrixX jac = hb.jacobian(2.0, g);
      const auto mid = std::chrono::steady_clock::now();
      const VectorX step = jac.partialPivLu().solve(r);
      const auto end = std::chrono::steady_clock::now();
      EXPECT_TRUE(step.allFinite());
      EXPECT_GT((jac - MatrixX::Identity(jac.rows(), jac.cols())).cwiseAbs().maxCoeff(), 0.0);  // in contact
      std::printf("    pairs %3d H %2d unknowns %5d: residual+Jacobian %8.2f ms, LU %8.2f ms\n", int(pairs), harmonics,
                  int(hb.n_unknowns()), std::chrono::duration<double, std::milli>(mid - start).count(),
                  std::chrono::duration<double, std::milli>(end - mid).count());
    }
  }
}

/// Largest distance from a multiplier of `a` to the nearest one of `b`.
double multiplier_distance(const ComplexVectorX& a, const ComplexVectorX& b) {
  double worst = 0.0;
  for (Index i = 0; i < a.size(); ++i) {
    double nearest = 1e300;
    for (Index j = 0; j < b.size(); ++j) nearest = std::min(nearest, std::abs(a[i] - b[j]));
    worst = std::max(worst, nearest);
  }
  return worst;
}

TEST(Stability, MonodromyAgreesWithHillAsHGrows) {
  // Four modes, five pairs, some closed at rest: Hill's truncated multipliers approach the monodromy's
  // (the exact ones of the sampled orbit) as H grows, and both give the same unstable counts.
  const auto s = random_system(4, 5, 7);
  std::vector<double> errors;
  for (int harmonics : {4, 8, 16}) {
    HarmonicBalanceOptions opt;
    opt.harmonics = harmonics;
    HarmonicBalance hb(s, opt);
    const Solution sol = hb.solve(1.7);
    const Stability hill = hb.hill_stability(sol);
    const Stability floquet = hb.floquet_stability(sol);
    ASSERT_EQ(floquet.multipliers.size(), 8);
    ASSERT_EQ(hill.multipliers.size(), 8);
    errors.push_back(std::max(multiplier_distance(floquet.multipliers, hill.multipliers),
                              multiplier_distance(hill.multipliers, floquet.multipliers)));
    std::printf("    H %2d: max |rho_floquet - rho_hill| %.3e, max Re lambda floquet %+.5e hill %+.5e\n", harmonics,
                errors.back(), floquet.max_real_part, hill.max_real_part);
    EXPECT_EQ(hill.stable, floquet.stable);
    EXPECT_EQ(hill.unstable_positive, floquet.unstable_positive);
    EXPECT_EQ(hill.unstable_negative, floquet.unstable_negative);
    EXPECT_EQ(hill.unstable_complex, floquet.unstable_complex);
  }
  EXPECT_LT(errors.back(), 1e-3);
  EXPECT_LT(errors.back(), 0.1 * errors.front());
}

TEST(Continuation, FoldOfAHardeningClearanceOscillator) {
  // Open at rest with a clearance g0 = 5 um, light damping (Q = 50): once |q| > g0 the contact
  // stiffens the oscillator (w = 1 open, 2 closed), the resonance bends to the right and the branch
  // turns back twice.
  const auto s = one_dof(1.0, 0.01, 1.0, 0.0, 0.5e-6, 0.0, 3.0, 5e-6);
  HarmonicBalanceOptions opt;
  opt.harmonics = 10;
  HarmonicBalance hb(s, opt);
  ContinuationOptions copt;
  copt.initial_step = 0.05;
  copt.max_step = 0.1;
  const auto branch = continue_branch(hb, 0.6, 1.8, copt);
  ASSERT_GT(branch.size(), 10u);
  EXPECT_GT(branch.back().solution.omega, 1.8);
  std::vector<std::size_t> folds;
  for (std::size_t i = 0; i < branch.size(); ++i) {
    const auto& p = branch[i];
    EXPECT_TRUE(p.solution.converged);
    if (p.fold) folds.push_back(i);
    if (p.fold || p.stability_change || i % 10 == 0)
      std::printf("    Omega %.5f A1 %.4e  dOmega/ds %+.3f  max Re lambda %+.2e  unstable +%d -%d c%d%s%s\n",
                  p.solution.omega, p.solution.amplitude(0, 1.0), p.tangent_omega, p.stability.max_real_part,
                  p.stability.unstable_positive, p.stability.unstable_negative, p.stability.unstable_complex,
                  p.fold ? " FOLD" : "", p.stability_change ? " STABILITY CHANGE" : "");
  }
  std::printf("  %zu points, %zu folds\n", branch.size(), folds.size());
  ASSERT_EQ(folds.size(), 2u);
  const double omega_upper = branch[folds[0]].solution.omega;
  const double omega_lower = branch[folds[1]].solution.omega;
  EXPECT_GT(omega_upper - omega_lower, 0.1);  // the branch turns back in frequency
  // Hill: stable outside the folds, unstable (one real multiplier > 1) between them
  for (std::size_t i = 0; i < branch.size(); ++i) {
    const bool middle = i >= folds[0] && i < folds[1];
    EXPECT_EQ(branch[i].stability.stable, !middle) << "point " << i << " Omega " << branch[i].solution.omega;
    if (middle) {
      EXPECT_EQ(branch[i].stability.unstable_positive, 1);
      EXPECT_EQ(branch[i].stability.unstable_negative + branch[i].stability.unstable_complex, 0);
    }
    EXPECT_TRUE(branch[i].stability_change == (i == folds[0] || i == folds[1])) << "point " << i;
  }

  // Three coexisting solutions at Omega = 1.15: Newton from the nearest point of each part.
  const double omega = 1.15;
  auto nearest = [&](std::size_t from, std::size_t to) {
    std::size_t best = from;
    for (std::size_t i = from; i < to; ++i)
      if (std::abs(branch[i].solution.omega - omega) < std::abs(branch[best].solution.omega - omega)) best = i;
    return hb.solve(omega, branch[best].solution.gaps);
  };
  const Solution lower = nearest(0, folds[0]);
  const Solution middle = nearest(folds[0], folds[1]);
  const Solution upper = nearest(folds[1], branch.size());
  // nearest(0, folds[0]) lies on the resonant (high) part before the upper fold
  const double a_high = lower.amplitude(0, 1.0), a_mid = middle.amplitude(0, 1.0), a_low = upper.amplitude(0, 1.0);
  std::printf("  Omega = 1.15: A1 high %.5e (stable %d) middle %.5e (stable %d) low %.5e (stable %d)\n", a_high,
              hb.hill_stability(lower).stable, a_mid, hb.hill_stability(middle).stable, a_low,
              hb.hill_stability(upper).stable);
  ASSERT_GT(a_high, 1.2 * a_mid);
  ASSERT_GT(a_mid, 1.2 * a_low);
  EXPECT_TRUE(hb.hill_stability(lower).stable);
  EXPECT_FALSE(hb.hill_stability(middle).stable);
  EXPECT_TRUE(hb.hill_stability(upper).stable);

  // Time integration started from each HB state: the stable ones stay, the unstable one drifts to
  // one of the stable ones.
  TimeIntegration ti{s, omega};
  ti.steps_per_period = 2000;
  auto settle = [&](const Solution& sol) {
    VectorX q, v;
    initial_state(sol, q, v);
    double t = 0.0;
    ti.run(q, v, t, 300);  // e^{-zeta w t} ~ 1e-8
    return std::abs(ti.harmonics(q, v, t, 0, 1)[1]);
  };
  const double ti_high = settle(lower), ti_mid = settle(middle), ti_low = settle(upper);
  std::printf("  time integration from them, after 300 periods: A1 %.5e, %.5e, %.5e\n", ti_high, ti_mid, ti_low);
  EXPECT_NEAR(ti_high, a_high, 1e-3 * a_high);
  EXPECT_NEAR(ti_low, a_low, 1e-3 * a_low);
  EXPECT_GT(std::abs(ti_mid - a_mid), 0.2 * a_mid);
  EXPECT_LT(std::min(std::abs(ti_mid - a_high) / a_high, std::abs(ti_mid - a_low) / a_low), 1e-3);
}

/// The bilinear oscillator of the period-doubling tests: closed at rest (g0 = 0), open w = 1, closed
/// w = 2 (bilinear frequency 4/3), 1 % damping; its period-one branch over 2.0 .. 2.6 rad/s, H = 10.
struct DoublingOscillator {
  reduced::ReducedSystem s = one_dof(1.0, 0.01, 1.0, 0.0, 1e-6, 0.0, 3.0, 0.0);
  HarmonicBalanceOptions opt1 = [] {
    HarmonicBalanceOptions options;
    options.harmonics = 10;
    return options;
  }();
  HarmonicBalance hb1{s, opt1};
  ContinuationOptions copt = [] {
    ContinuationOptions options;
    options.initial_step = 0.02;
    options.max_step = 0.02;
    return options;
  }();
  std::vector<BranchPoint> branch = continue_branch(hb1, 2.0, 2.6, copt);
  /// The period-two solver with 20 harmonics of Omega/2 (the period-one solver's orders).
  static HarmonicBalanceOptions period_two_options() {
    HarmonicBalanceOptions options;
    options.harmonics = 20;
    options.subharmonic = 2;
    return options;
  }
};

TEST(Continuation, PeriodDoublingOfABilinearOscillator) {
  // Driven near twice the bilinear frequency, the period-one response loses stability through -1 and
  // a period-two response (A1/2) takes over (the time integration below settles on it).
  const DoublingOscillator oscillator;
  const auto& [s, opt1, hb1, copt, branch] = oscillator;
  std::size_t doubling = branch.size();
  int n_doubling = 0, n_fold = 0;
  for (std::size_t i = 0; i < branch.size(); ++i) {
    n_fold += branch[i].fold;
    if (branch[i].period_doubling) {
      ++n_doubling;
      doubling = i;
    }
  }
  ASSERT_EQ(n_doubling, 1);
  EXPECT_EQ(n_fold, 0);
  const double omega_pd = branch[doubling].solution.omega;
  std::printf("  period doubling flagged at Omega = %.4f (previous point %.4f); critical lambda = %.4f%+.4fi\n", omega_pd,
              branch[doubling - 1].solution.omega, branch[doubling].stability.critical_exponent.real(),
              branch[doubling].stability.critical_exponent.imag());
  EXPECT_GT(omega_pd, 2.2);
  EXPECT_LT(omega_pd, 2.35);
  for (std::size_t i = 0; i < branch.size(); ++i) {
    EXPECT_EQ(branch[i].stability.stable, i < doubling);
    EXPECT_EQ(branch[i].stability.unstable_negative, i < doubling ? 0 : 1);
  }
  // the critical multiplier is real negative: Im lambda = Omega/2 (mod Omega)
  const double shift = branch[doubling].stability.critical_exponent.imag() / omega_pd;
  EXPECT_NEAR(std::abs(shift - std::floor(shift)), 0.5, 1e-4);

  // nu = 2 at Omega = 2.5, from the period-one point and the critical eigenvector
  const double omega = 2.5;
  const Solution one = hb1.solve(omega);
  const Stability one_stability = hb1.hill_stability(one);
  HarmonicBalanceOptions opt2;
  opt2.harmonics = 40;
  opt2.subharmonic = 2;
  HarmonicBalance hb2(s, opt2);
  Solution two;
  bool found = false;
  for (double amplitude : {0.5, 1.0, 2.0, 4.0}) {
    const VectorX guess = period_doubled_guess(s, one, one_stability, opt2.harmonics, amplitude * one.amplitude(0, 1.0));
    try {
      two = hb2.solve(omega, guess);
    } catch (const SolverError&) {
      continue;
    }
    if (two.amplitude(0, 0.5) > 0.01 * two.amplitude(0, 1.0)) {
      found = true;
      break;
    }
  }
  ASSERT_TRUE(found);
  const Stability two_stability = hb2.hill_stability(two);

  TimeIntegration ti{s, omega};
  ti.nu = 2;
  ti.steps_per_period = 8000;
  VectorX q, v;
  initial_state(one, q, v);
  q[0] *= 1.01;  // the unstable period-one state, perturbed
  double t = 0.0;
  ti.run(q, v, t, 400);
  const auto ref = ti.harmonics(q, v, t, 0, 2);
  std::printf("  Omega = %.2f: nu = 2 HB A1/2 %.5e A1 %.5e (stable %d) | time integration A1/2 %.5e A1 %.5e\n", omega,
              two.amplitude(0, 0.5), two.amplitude(0, 1.0), two_stability.stable, std::abs(ref[1]), std::abs(ref[2]));
  EXPECT_NEAR(two.amplitude(0, 0.5), std::abs(ref[1]), 0.05 * std::abs(ref[1]));
  EXPECT_NEAR(two.amplitude(0, 1.0), std::abs(ref[2]), 0.05 * std::abs(ref[2]));
  EXPECT_TRUE(two_stability.stable);
  EXPECT_FALSE(one_stability.stable);
  EXPECT_EQ(one.amplitude(0, 0.5), 0.0);  // a period-one solution has no order 1/2
  EXPECT_NEAR(two.ratios(0).half, std::abs(ref[1]) / std::abs(ref[2]), 0.1 * std::abs(ref[1]) / std::abs(ref[2]));
}

/// Continues the period-two branch of `hb2` from `start` past Omega = 2.5 and returns {its solution at
/// 2.5 (Newton from the branch's two points around it), the solution Newton finds at 2.5 from the
/// period-one point's critical mode (amplitude `size`)}: two routes that should give one solution.
/// Empty when the branch did not pass 2.5.
std::optional<std::pair<Solution, Solution>> two_routes_to_two_and_a_half(const reduced::ReducedSystem& s, const HarmonicBalance& hb1,
                                                           const HarmonicBalance& hb2, const Solution& start,
                                                           const ContinuationOptions& copt, double size) {
  std::vector<BranchPoint> period_two;
  continue_branch(hb2, start.omega, 2.6, copt, [&](const BranchPoint& point) {
    period_two.push_back(point);
    return point.solution.omega < 2.5;
  }, &start);
  if (period_two.size() < 2 || period_two.back().solution.omega < 2.5) return std::nullopt;
  const BranchPoint& after = period_two.back();
  const BranchPoint& before = period_two[period_two.size() - 2];
  const double w = (2.5 - before.solution.omega) / (after.solution.omega - before.solution.omega);
  const Solution fixed = hb2.solve(2.5, (1.0 - w) * before.solution.gaps + w * after.solution.gaps);
  const Solution one = hb1.solve(2.5);
  const Solution from_mode =
      hb2.solve(2.5, period_doubled_guess(s, one, hb1.hill_stability(one), hb2.options().harmonics, size));
  return std::make_pair(fixed, from_mode);
}

TEST(Continuation, BranchOffAtAPeriodDoublingReachesTheFixedFrequencySolution) {
  // The oscillator of the test above. From the period-one solution just past its doubling, written in
  // nu = 2 harmonics, Keller's corrector along the critical mode (Omega free) lands on the period-two
  // branch at the requested distance; continued from there, the branch passes Omega = 2.5 through the
  // solution that Newton finds at that fixed frequency from the critical mode: two routes, one solution.
  const DoublingOscillator oscillator;
  const auto& [s, opt1, hb1, copt, branch] = oscillator;
  std::size_t doubling = 0;
  while (doubling < branch.size() && !branch[doubling].period_doubling) ++doubling;
  ASSERT_LT(doubling, branch.size());
  const Solution& one = branch[doubling].solution;
  HarmonicBalanceOptions opt2;
  opt2.harmonics = 20;
  opt2.subharmonic = 2;
  HarmonicBalance hb2(s, opt2);
  Solution base;
  base.omega = one.omega;
  base.gaps = period_doubled_guess(s, one, Stability(), opt2.harmonics, 0.0);
  const double size = one.gaps.cwiseAbs().maxCoeff();
  const VectorX direction = period_doubled_guess(s, one, branch[doubling].stability, opt2.harmonics, size) - base.gaps;
  const double step = 0.05 * size;
  const Solution start = branch_off(hb2, base, direction, step, copt);
  EXPECT_LE(start.residual, opt2.tolerance);
  EXPECT_NEAR(direction.normalized().dot(start.gaps - base.gaps), step, 1e-9 * size);  // the arclength constraint
  EXPECT_GT(start.amplitude(0, 0.5), 0.0);
  std::printf("  branch off at Omega = %.5f (doubling flagged between %.5f and %.5f): A1/2 %.4e\n", start.omega,
              branch[doubling - 1].solution.omega, one.omega, start.amplitude(0, 0.5));
  EXPECT_GT(start.omega, branch[doubling - 1].solution.omega - 0.05);
  EXPECT_LT(start.omega, 2.5);

  const auto routes = two_routes_to_two_and_a_half(s, hb1, hb2, start, copt, size);
  ASSERT_TRUE(routes) << "the period-two branch did not pass Omega = 2.5";
  const auto& [fixed, from_mode] = *routes;
  std::printf("  Omega = 2.5: A1/2 from the branch %.8e, from the critical mode %.8e\n", fixed.amplitude(0, 0.5),
              from_mode.amplitude(0, 0.5));
  EXPECT_NEAR(fixed.amplitude(0, 0.5), from_mode.amplitude(0, 0.5), 1e-8 * from_mode.amplitude(0, 0.5));
  EXPECT_GT(fixed.amplitude(0, 0.5), fixed.amplitude(0, 1.0));
}

TEST(BranchSwitching, ThePeriodTwoStartIsFoundWhereTheOddBlockTurnsSingular) {
  // The oscillator above, its period-one branch with harmonics 10 of Omega; the period-two solver
  // with 20 of Omega/2 (the same orders). period_two_start finds the doubling between the branch
  // points that the monodromy flags, and lands on a period-two solution whose odd share is well above
  // the joined threshold; continued, that branch passes Omega = 2.5 through the solution Newton finds
  // there from the critical mode.
  const DoublingOscillator oscillator;
  const auto& [s, opt1, hb1, copt, branch] = oscillator;
  std::size_t doubling = 0;
  while (doubling < branch.size() && !branch[doubling].period_doubling) ++doubling;
  ASSERT_LT(doubling, branch.size());
  const HarmonicBalanceOptions opt2 = DoublingOscillator::period_two_options();
  const HarmonicBalance hb2(s, opt2);
  const std::optional<Solution> start = period_two_start(s, hb1, hb2, branch, copt);
  ASSERT_TRUE(start.has_value());
  EXPECT_LE(start->residual, opt2.tolerance);
  EXPECT_GT(period_two_share(*start, s.n_rows()), 10.0 * kJoinedShare);
  EXPECT_GT(start->omega, branch[doubling - 1].solution.omega - 0.05);
  EXPECT_LT(start->omega, branch[doubling].solution.omega + 0.05);
  std::printf("  period-two start at Omega = %.5f (doubling flagged between %.5f and %.5f), share %.3f\n",
              start->omega, branch[doubling - 1].solution.omega, branch[doubling].solution.omega,
              period_two_share(*start, s.n_rows()));
  // A period-one solution written in nu = 2 harmonics has no odd part.
  Solution embedded;
  embedded.gaps = period_doubled_guess(s, branch.front().solution, Stability(), opt2.harmonics, 0.0);
  EXPECT_EQ(period_two_share(embedded, s.n_rows()), 0.0);
  EXPECT_EQ(odd_part(embedded, odd_unknowns(s.n_rows(), opt2.harmonics)).norm(), 0.0);
  EXPECT_EQ(odd_unknowns(s.n_rows(), opt2.harmonics).size(), static_cast<std::size_t>(2 * 10 * s.n_rows()));
  // Continued up, the branch passes 2.5 through the fixed-frequency solution.
  const double size = branch[doubling].solution.gaps.cwiseAbs().maxCoeff();
  const auto routes = two_routes_to_two_and_a_half(s, hb1, hb2, *start, copt, size);
  ASSERT_TRUE(routes) << "the period-two branch did not pass Omega = 2.5";
  const auto& [fixed, from_mode] = *routes;
  EXPECT_NEAR(fixed.amplitude(0, 0.5), from_mode.amplitude(0, 0.5), 1e-8 * from_mode.amplitude(0, 0.5));
  // Before the doubling there is no period-two branch to switch to.
  const std::vector<BranchPoint> stable(branch.begin(), branch.begin() + static_cast<std::ptrdiff_t>(doubling) - 1);
  EXPECT_FALSE(period_two_start(s, hb1, hb2, stable, copt).has_value());
}

TEST(Continuation, SolveAtRecordsTheFixedFrequencySolutionBetweenTwoSteps) {
  // The oscillator above. With solve_at, the continued branches (period one, and period two from its
  // start) hold a point at exactly each requested Omega, between the two continued points around it,
  // equal to the solution Newton finds there by itself; the interpolation between those two points,
  // which is what a reader of the branch had before, is off by more.
  const DoublingOscillator oscillator;
  const auto& [s, opt1, hb1, copt, branch] = oscillator;
  ContinuationOptions landing = copt;
  landing.solve_at = {2.1234, 2.5, 3.0};  // 3.0 lies outside both ranges: no point there
  const std::vector<BranchPoint> one = continue_branch(hb1, 2.0, 2.6, landing);
  std::vector<std::size_t> at;
  for (std::size_t i = 0; i < one.size(); ++i)
    if (one[i].solution.omega == 2.1234 || one[i].solution.omega == 2.5) at.push_back(i);
  ASSERT_EQ(at.size(), 2u);
  EXPECT_EQ(one.size(), branch.size() + 2);  // the continued points are the same ones
  const Solution direct = hb1.solve(2.1234);
  EXPECT_NEAR(one[at[0]].solution.amplitude(0, 1.0), direct.amplitude(0, 1.0), 1e-10 * direct.amplitude(0, 1.0));
  EXPECT_LT(one[at[0] - 1].solution.omega, 2.1234);
  EXPECT_GT(one[at[0] + 1].solution.omega, 2.1234);
  EXPECT_TRUE(one[at[0]].stability.stable);   // before the doubling
  EXPECT_FALSE(one[at[1]].stability.stable);  // after it

  const HarmonicBalance hb2(s, DoublingOscillator::period_two_options());
  const std::optional<Solution> start = period_two_start(s, hb1, hb2, branch, copt);
  ASSERT_TRUE(start.has_value());
  const std::vector<BranchPoint> two = continue_branch(hb2, start->omega, 2.6, landing, ProgressCallback(), &*start);
  std::size_t i = 0;
  while (i < two.size() && two[i].solution.omega != 2.5) ++i;
  ASSERT_LT(i, two.size()) << "no point at Omega = 2.5 on the period-two branch";
  ASSERT_GT(i, 0u);
  ASSERT_LT(i + 1, two.size());
  std::size_t doubling = 0;
  while (doubling < branch.size() && !branch[doubling].period_doubling) ++doubling;
  ASSERT_LT(doubling, branch.size());
  const auto routes =
      two_routes_to_two_and_a_half(s, hb1, hb2, *start, copt, branch[doubling].solution.gaps.cwiseAbs().maxCoeff());
  ASSERT_TRUE(routes);
  const double exact = routes->second.ratios(0).half;
  const Solution& before = two[i - 1].solution;
  const Solution& after = two[i + 1].solution;
  const double w = (2.5 - before.omega) / (after.omega - before.omega);
  const double between = (1.0 - w) * before.ratios(0).half + w * after.ratios(0).half;
  std::printf("  Omega = 2.5: A1/2/A1 solved there %.10f, Newton from the critical mode %.10f, interpolated between "
              "Omega %.4f and %.4f %.10f\n", two[i].solution.ratios(0).half, exact, before.omega, after.omega, between);
  EXPECT_NEAR(two[i].solution.ratios(0).half, exact, 1e-8 * exact);
  EXPECT_GT(std::abs(between - exact), 100.0 * std::abs(two[i].solution.ratios(0).half - exact));
  EXPECT_TRUE(two[i].stability.stable);
}

}  // namespace
}  // namespace crackle::sweep
