// The matrix-free harmonic balance (krylov.hpp) against the dense one on the same reduced systems
// of many coupled crack pairs: the Jacobian action and preconditioner, a breathing point and a
// continuation branch through a super-harmonic resonance (GMRES itself: tests/linalg).
#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <random>

#include "sweep/harmonic_balance.hpp"
#include "sweep/krylov.hpp"

namespace crackle::sweep {
namespace {

/// m modes, c pairs on a line: the pair modes vary smoothly along the crack (bending-like shapes),
/// the residual flexibility decays with the distance between pairs (a crack face's Green function),
/// the penalty is stiff against it (eps_N A R_ii = `stiffness_ratio`), the load opens and closes the
/// crack about a gap g0.
reduced::ReducedSystem crack_system(Index m, Index c, double g0, double stiffness_ratio, double zeta) {
  reduced::ReducedSystem s;
  s.omega.resize(m);
  for (Index r = 0; r < m; ++r) s.omega[r] = 1.0 + 1.9 * r + 0.3 * r * r;
  s.rayleigh_alpha = 2.0 * zeta * s.omega[0];  // zeta at the first mode (alpha only)
  s.pair_area = VectorX::Constant(c, 1.0 / c);
  s.initial_gap = VectorX::Constant(c, g0);
  s.pair_modes.resize(c, m);
  s.residual.resize(c, c);
  std::mt19937 random(3);
  std::uniform_real_distribution<double> jitter(-0.1, 0.1);
  for (Index i = 0; i < c; ++i) {
    const double x = (i + 0.5) / c;  // position along the crack
    for (Index r = 0; r < m; ++r)
      s.pair_modes(i, r) = 0.03 * (std::cos(3.14159 * r * x) * (1.0 + 0.5 * x) + jitter(random));
    // an exponential kernel: symmetric positive definite on any set of points
    for (Index j = 0; j < c; ++j) s.residual(i, j) = 0.02 * std::exp(-5.0 * std::abs(x - (j + 0.5) / c));
  }
  const double diagonal = s.residual(0, 0);
  s.normal_penalty = stiffness_ratio / (diagonal / c);  // eps_N A R_ii = ratio with A = 1/c
  s.load_modal = VectorX::Zero(m);
  s.load_modal[0] = 3e-5;
  if (m > 1) s.load_modal[1] = 1e-5;
  s.load_residual = VectorX::Constant(c, 1e-8);
  s.output_modes = MatrixX::Ones(1, m);
  s.output_residual_pairs = MatrixX::Constant(1, c, 0.01 / c);
  s.output_residual_load = VectorX::Constant(1, 0.01);
  return s;
}

HarmonicBalanceOptions solver_options(LinearSolver solver, int harmonics) {
  HarmonicBalanceOptions o;
  o.harmonics = harmonics;
  o.solver = solver;
  o.tolerance = 1e-11;
  o.max_iterations = 20;
  return o;
}

double relative_difference(const VectorX& a, const VectorX& b) {
  return (a - b).cwiseAbs().maxCoeff() / b.cwiseAbs().maxCoeff();
}

int closing_pairs(const Solution& sol, Index c) {
  int count = 0;
  for (Index i = 0; i < c; ++i) count += sol.forces[i] > 0.0;
  return count;
}

TEST(Krylov, ActionAndPreconditionerOfAClosedCrack) {
  // every pair closed over the whole period: dP/dG = -eps_N A I, so the mean-stiffness preconditioner
  // is the exact inverse of the Jacobian
  Eigen::setNbThreads(1);
  const Index c = 30;
  auto s = crack_system(4, c, 0.0, 2.0, 0.02);
  s.initial_gap.setConstant(-1.0);
  const int harmonics = 4;
  const HarmonicBalance dense(s, solver_options(LinearSolver::dense, harmonics));
  const double omega = 0.7;
  const VectorX gaps = dense.linear_gaps(omega);
  const MatrixX jac = dense.jacobian(omega, gaps);
  std::vector<Eigen::VectorXcd> modal(harmonics + 1, Eigen::VectorXcd(4));
  for (int k = 0; k <= harmonics; ++k)
    for (Index r = 0; r < 4; ++r) {
      const double w = s.omega[r], wk = k * omega, zeta = s.damping_ratio(r);
      modal[k][r] = 1.0 / std::complex<double>(w * w - wk * wk, 2.0 * zeta * w * wk);
    }
  std::vector<PairDerivative> blocks;
  for (Index i = 0; i < c; ++i)
    blocks.push_back({i, 1, -s.normal_penalty * s.pair_area[i] * MatrixX::Identity(2 * harmonics + 1, 2 * harmonics + 1)});
  const KrylovJacobian kj(s, harmonics, modal, blocks, KrylovOptions());
  EXPECT_EQ(kj.breathing_pairs(), 0);  // no harmonic coupling: the pair blocks have nothing to correct
  const VectorX x = VectorX::LinSpaced(jac.rows(), -1.0, 2.0);
  VectorX y, z;
  kj.apply(x, y);
  EXPECT_LT(relative_difference(y, jac * x), 1e-12);
  kj.precondition(y, z);
  EXPECT_LT(relative_difference(z, x), 1e-10);
}

TEST(Krylov, PairBlocksInvertTheJacobianOfOnePair) {
  // one pair (normal only, then normal and tangential rows): J is its own pair block, so the pair-block
  // preconditioners are J's exact inverse (the mean stiffness alone is not: the block couples harmonics)
  const int harmonics = 4;
  const int nc = 2 * harmonics + 1;
  std::mt19937 random(7);
  std::normal_distribution<double> normal;
  for (const int rows : {1, 3}) {
    auto s = crack_system(4, rows, 0.0, 20.0, 0.02);
    const double omega = 0.7;
    std::vector<Eigen::VectorXcd> modal(harmonics + 1, Eigen::VectorXcd(4));
    for (int k = 0; k <= harmonics; ++k)
      for (Index r = 0; r < 4; ++r) {
        const double w = s.omega[r], wk = k * omega, zeta = s.damping_ratio(r);
        modal[k][r] = 1.0 / std::complex<double>(w * w - wk * wk, 2.0 * zeta * w * wk);
      }
    // a slope of a pair closed for part of the period: a stiff mean plus harmonic coupling
    MatrixX block = MatrixX::NullaryExpr(rows * nc, rows * nc, [&](Index, Index) { return normal(random); });
    block = -s.normal_penalty * s.pair_area[0] * (0.5 * MatrixX::Identity(rows * nc, rows * nc) + 0.2 * block);
    const std::vector<PairDerivative> blocks = {{0, rows, block}};
    const Index n = rows * nc;
    MatrixX jac(n, n);
    VectorX unit, column;
    for (const auto kind : {KrylovPreconditioner::mean_stiffness, KrylovPreconditioner::pair_blocks}) {
      KrylovOptions options;
      options.preconditioner = kind;
      const KrylovJacobian kj(s, harmonics, modal, blocks, options);
      EXPECT_EQ(kj.breathing_pairs(), kind == KrylovPreconditioner::pair_blocks ? 1 : 0);
      for (Index j = 0; j < n; ++j) {
        unit = VectorX::Unit(n, j);
        kj.apply(unit, column);
        jac.col(j) = column;
      }
      const VectorX x = VectorX::LinSpaced(n, -1.0, 2.0);
      VectorX z;
      kj.precondition(jac * x, z);
      const double error = relative_difference(z, x);
      std::printf("  %d row(s), preconditioner %d: |M^-1 J x - x| / |x| = %.2e\n", rows, int(kind), error);
      if (kind == KrylovPreconditioner::mean_stiffness)
        EXPECT_GT(error, 1e-3);
      else
        EXPECT_LT(error, 1e-10);
    }
  }
}

TEST(Krylov, BreathingPointAgreesWithDense) {
  // 80 pairs, 6 modes, closed at rest (g0 = 0): a breathing crack, the pairs closing for part of the period
  Eigen::setNbThreads(1);
  const Index c = 60;
  const auto s = crack_system(6, c, 0.0, 20.0, 0.02);
  const int harmonics = 6;
  const HarmonicBalance dense(s, solver_options(LinearSolver::dense, harmonics));
  const HarmonicBalance krylov(s, solver_options(LinearSolver::krylov, harmonics));
  ASSERT_FALSE(dense.matrix_free());
  ASSERT_TRUE(krylov.matrix_free());
  const double omega = 0.55;
  // the residual without the c x c receptances equals the dense one
  const VectorX guess = dense.linear_gaps(omega);
  EXPECT_LT(relative_difference(krylov.linear_gaps(omega), guess), 1e-13);
  EXPECT_LT(relative_difference(krylov.residual(omega, 0.5 * guess), dense.residual(omega, 0.5 * guess)), 1e-12);
  // the matrix-free solve against the dense Jacobian's LU at the linear guess (some pairs closed)
  const MatrixX jac = dense.jacobian(omega, guess);
  const VectorX b = VectorX::LinSpaced(jac.rows(), -1.0, 1.0);
  const VectorX x_dense = jac.partialPivLu().solve(b);
  const auto lin = krylov.linearize(omega, guess, false);
  const VectorX x_krylov = lin->solve(b, 1e-13);
  const long linear_iterations = krylov.krylov_statistics().iterations;
  // the same solve with the mean stiffness alone (the pair blocks' harmonic coupling left out)
  HarmonicBalanceOptions mean_options = solver_options(LinearSolver::krylov, harmonics);
  mean_options.krylov.preconditioner = KrylovPreconditioner::mean_stiffness;
  const HarmonicBalance mean(s, mean_options);
  const VectorX x_mean = mean.linearize(omega, guess, false)->solve(b, 1e-13);
  const long mean_iterations = mean.krylov_statistics().iterations;
  std::printf("  one solve to 1e-13 at the linear guess: %ld GMRES iterations (%ld with the mean stiffness alone)\n",
              linear_iterations, mean_iterations);
  EXPECT_LE(linear_iterations, 500);
  EXPECT_LT(linear_iterations, mean_iterations);
  EXPECT_LT(relative_difference(x_krylov, x_dense), 1e-10);
  EXPECT_LT(relative_difference(x_mean, x_dense), 1e-10);

  const Solution a = dense.solve(omega);
  const Solution k = krylov.solve(omega);
  const int closing = closing_pairs(a, c);
  const double diff = relative_difference(k.gaps, a.gaps);
  const KrylovStatistics st = krylov.krylov_statistics();
  std::printf("  Omega %.2f: %d of %d pairs closed on average, %d/%d Newton iterations (dense/krylov), gap "
              "harmonics differ by %.2e relative; GMRES %ld solves, %ld iterations, at most %d\n",
              omega, closing, int(c), a.iterations, k.iterations, diff, st.solves, st.iterations, st.max_iterations);
  EXPECT_GT(closing, 0);
  EXPECT_LT(closing, int(c));
  EXPECT_LT(diff, 1e-8);
  EXPECT_LT(relative_difference(k.forces, a.forces), 1e-8);
  EXPECT_NEAR(k.ratios(0).second, a.ratios(0).second, 1e-8 * a.ratios(0).second);
  EXPECT_EQ(st.unconverged, 0);
  // the Newton solves (inexact, forcing min(1e-2, |r|)): bounded, a few dozen each on average
  EXPECT_LE(double(st.iterations - linear_iterations) / double(st.solves - 1), 80.0);
}

/// The peak of `value` along a branch: its frequency by a parabola through the largest point and its
/// neighbours, and its value.
std::pair<double, double> peak(const std::vector<BranchPoint>& branch, double (*value)(const Solution&)) {
  std::size_t best = 0;
  for (std::size_t i = 1; i < branch.size(); ++i)
    if (value(branch[i].solution) > value(branch[best].solution)) best = i;
  if (best == 0 || best + 1 == branch.size()) return {branch[best].solution.omega, value(branch[best].solution)};
  const double x0 = branch[best - 1].solution.omega, x1 = branch[best].solution.omega, x2 = branch[best + 1].solution.omega;
  const double y0 = value(branch[best - 1].solution), y1 = value(branch[best].solution), y2 = value(branch[best + 1].solution);
  const double d1 = (y1 - y0) / (x1 - x0), d2 = (y2 - y1) / (x2 - x1), curvature = (d2 - d1) / (x2 - x0);
  const double x = 0.5 * (x0 + x1) - d1 / (2.0 * curvature);
  return {x, y1 + (x - x1) * ((y2 - y0) / (x2 - x0)) + curvature * (x - x1) * (x - x1)};
}

/// Both solvers along the same continuation; returns the two branches.
std::pair<std::vector<BranchPoint>, std::vector<BranchPoint>> both_branches(const reduced::ReducedSystem& s, int harmonics,
                                                                            double from, double to, double step,
                                                                            KrylovStatistics& statistics) {
  // a gap scale well above the gaps keeps the arclength mostly in frequency (as the sweep command does)
  HarmonicBalanceOptions od = solver_options(LinearSolver::dense, harmonics), ok = solver_options(LinearSolver::krylov, harmonics);
  od.gap_scale = ok.gap_scale = 30.0 * HarmonicBalance(s, od).gap_scale();
  const HarmonicBalance dense(s, od);
  const HarmonicBalance krylov(s, ok);
  ContinuationOptions copt;
  copt.max_points = 400;
  copt.initial_step = copt.max_step = step;
  copt.hill_at_events = false;
  auto a = continue_branch(dense, from, to, copt);
  auto b = continue_branch(krylov, from, to, copt);
  statistics = krylov.krylov_statistics();
  return {std::move(a), std::move(b)};
}

TEST(Krylov, SuperHarmonicBranchAgreesWithDense) {
  // the breathing crack swept through half its bilinear resonance: the peak of A2/A1
  Eigen::setNbThreads(1);
  const Index c = 40;
  const auto s = crack_system(4, c, 0.0, 20.0, 0.01);
  KrylovStatistics st;
  const auto [dense, krylov] = both_branches(s, 5, 0.45, 0.56, 0.01, st);
  ASSERT_FALSE(dense.empty());
  ASSERT_FALSE(krylov.empty());
  EXPECT_GT(dense.back().solution.omega, 0.56);
  EXPECT_GT(krylov.back().solution.omega, 0.56);
  auto second = [](const Solution& sol) { return sol.ratios(0).second; };
  const auto pd = peak(dense, second), pk = peak(krylov, second);
  std::size_t same = 0;
  double worst = 0.0;
  for (std::size_t i = 0; i < std::min(dense.size(), krylov.size()); ++i)
    if (std::abs(dense[i].solution.omega - krylov[i].solution.omega) <= 1e-12 * dense[i].solution.omega) {
      ++same;
      worst = std::max(worst, relative_difference(krylov[i].solution.gaps, dense[i].solution.gaps));
    }
  std::printf("  %zu / %zu points (dense / krylov), %zu at the same frequency, gaps within %.2e there; A2/A1 peak "
              "%.6f at %.6f rad/s (dense), %.6f at %.6f (krylov); GMRES %ld solves, %ld iterations, at most %d\n",
              dense.size(), krylov.size(), same, worst, pd.second, pd.first, pk.second, pk.first, st.solves,
              st.iterations, st.max_iterations);
  EXPECT_GT(pd.second, 2.0 * second(dense.front().solution));  // a peak inside the range
  // the step adaptation follows the corrector's iteration counts, which the inexact solves can change
  // by one: the two branches share some points only, and their peaks are interpolated between points
  EXPECT_NEAR(pk.first, pd.first, 1e-5 * pd.first);
  EXPECT_NEAR(pk.second, pd.second, 1e-5 * pd.second);
  EXPECT_GE(same, 5u);
  EXPECT_LT(worst, 1e-8);
  EXPECT_EQ(st.unconverged, 0);
}

}  // namespace
}  // namespace crackle::sweep
