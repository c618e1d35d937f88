// Harmonic balance on hand-built reduced systems (HYBRID.md §4-5): the linear receptance, a bilinear
// oscillator against an independent time integration, continuation through a fold with Hill's
// stability, and a period-doubled (nu = 2) branch.
#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <Eigen/Eigenvalues>
#include <chrono>
#include <cmath>
#include <complex>
#include <cstdio>

#include "sweep/harmonic_balance.hpp"

namespace crackle::sweep {
namespace {

using Complex = std::complex<double>;
constexpr double kPi = 3.14159265358979323846;

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
    ti.steps_per_period = 4000;
    VectorX q = VectorX::Zero(1), v = VectorX::Zero(1);
    double t = 0.0;
    ti.run(q, v, t, 250);  // e^{-zeta w t}: transients decayed far below 1e-8
    const auto ref = ti.harmonics(q, v, t, 0, 3);
    std::printf("  Omega = %.2f: A1 = %.6e A2/A1 = %.4e A3/A1 = %.4e (time integration)\n", omega, std::abs(ref[1]),
                std::abs(ref[2]) / std::abs(ref[1]), std::abs(ref[3]) / std::abs(ref[1]));
    for (int harmonics : {5, 10, 20, 40}) {
      HarmonicBalanceOptions opt;
      opt.harmonics = harmonics;
      opt.time_samples = 16 * harmonics;
      HarmonicBalance hb(s, opt);
      const Solution sol = hb.solve(omega);
      double err[3];
      for (int k = 1; k <= 3; ++k) err[k - 1] = std::abs(sol.outputs(0, k) - ref[k]) / std::abs(ref[1]);
      std::printf("    H = %2d: |dA1| %.2e |dA2| %.2e |dA3| %.2e  top share %.2e%s  Newton %d\n", harmonics, err[0],
                  err[1], err[2], sol.top_harmonic_share, sol.harmonics_flagged ? " (flagged)" : "", sol.iterations);
      if (harmonics == 40)
        for (int k = 0; k < 3; ++k) EXPECT_LT(err[k], 1e-4) << "Omega " << omega << " order " << k + 1;
      if (harmonics == 5) EXPECT_GT(err[0] + err[1] + err[2], 1e-6);  // the truncation shows
    }
  }
}

}  // namespace
}  // namespace crackle::sweep
