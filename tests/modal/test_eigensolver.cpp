// Eigen-solver backends against a pencil with a known spectrum: linear finite elements of a bar,
// K = (E A / h) tridiag(-1, 2, -1), M = (rho A h / 6) tridiag(1, 4, 1), whose discrete eigenvalues
// are lambda_k = (6 E / (rho h^2)) (1 - cos theta_k) / (2 + cos theta_k),
// theta_k = k pi / (n + 1) fixed-fixed (n interior nodes) and k pi / N free-free (N elements).
#include <gtest/gtest.h>
#include <petscsys.h>

#include <Eigen/Eigenvalues>

#include <array>
#include <cmath>
#include <string>
#include <vector>

#include "core/errors.hpp"
#include "core/interrupt.hpp"
#include "linalg/cholmod_factor.hpp"
#include "modal/eigensolver.hpp"
#include "modal/modal.hpp"

namespace crackle::modal {
namespace {

constexpr double kYoung = 2.0e11;
constexpr double kDensity = 7800.0;

struct BarPencil {
  SparseMatrix stiffness;
  SparseMatrix mass;
  std::vector<double> exact;  ///< ascending eigenvalues
};

/// Bar of length 1 with `elements` elements; fixed-fixed (interior nodes only) or free-free.
BarPencil bar_pencil(int elements, bool free_free) {
  const double h = 1.0 / elements;
  const int first = free_free ? 0 : 1;
  const int n = free_free ? elements + 1 : elements - 1;
  std::vector<Eigen::Triplet<double, Index>> k, m;
  for (int e = 0; e < elements; ++e) {
    const int nodes[2] = {e - first, e + 1 - first};
    for (int a = 0; a < 2; ++a) {
      for (int b = 0; b < 2; ++b) {
        if (nodes[a] < 0 || nodes[a] >= n || nodes[b] < 0 || nodes[b] >= n) continue;
        k.emplace_back(nodes[a], nodes[b], (a == b ? 1.0 : -1.0) * kYoung / h);
        m.emplace_back(nodes[a], nodes[b], (a == b ? 2.0 : 1.0) * kDensity * h / 6.0);
      }
    }
  }
  BarPencil pencil;
  pencil.stiffness.resize(n, n);
  pencil.mass.resize(n, n);
  pencil.stiffness.setFromTriplets(k.begin(), k.end());
  pencil.mass.setFromTriplets(m.begin(), m.end());
  for (int mode = free_free ? 0 : 1; mode <= (free_free ? elements : elements - 1); ++mode) {
    const double theta = mode * kPi / elements;
    pencil.exact.push_back(6.0 * kYoung / (kDensity * h * h) * (1.0 - std::cos(theta)) / (2.0 + std::cos(theta)));
  }
  return pencil;
}

void expect_spectrum(const EigenPairs& pairs, const BarPencil& pencil, int offset, double tolerance) {
  for (Index i = 0; i < pairs.eigenvalues.size(); ++i) {
    const double exact = pencil.exact[offset + i];
    EXPECT_NEAR(pairs.eigenvalues[i], exact, tolerance * exact) << "eigenvalue " << i;
  }
}

/// The 8 lowest eigenpairs of the fixed-fixed bar of 2000 elements by the given backend, checked
/// against the exact discrete spectrum to 1e-10.
EigenPairs solve_fixed_fixed_bar(EigenOptions options) {
  const BarPencil pencil = bar_pencil(2000, false);
  options.n_eigenpairs = 8;
  options.shift = -1.0;
  const EigenPairs pairs = solve_eigenpairs(pencil.stiffness, pencil.mass, options);
  expect_spectrum(pairs, pencil, 0, 1e-10);
  return pairs;
}

TEST(Eigensolver, SlepcCholmodFixedFixedBar) {
  EigenOptions options;
  options.factorization = Factorization::cholmod;
  EXPECT_EQ(solve_fixed_fixed_bar(options).factorization, "cholmod");
}

TEST(Eigensolver, SlepcMumpsFixedFixedBar) {
  EigenOptions options;
  options.factorization = Factorization::mumps;
  EXPECT_EQ(solve_fixed_fixed_bar(options).factorization, "mumps");
}

TEST(Eigensolver, ArpackFixedFixedBar) {
  EigenOptions options;
  options.solver = Solver::arpack;
  solve_fixed_fixed_bar(options);
}

// The caller's factor of K serves several solves (the reduced model's eigen-solves and static
// images): the spectrum is the exact one, and a factor of another matrix is refused.
TEST(Eigensolver, ArpackSolvesWithTheCallersFactor) {
  const BarPencil pencil = bar_pencil(2000, false);
  CholmodFactor factor(pencil.stiffness, pencil.mass, 0.0, "test");
  EigenOptions options;
  options.solver = Solver::arpack;
  options.shift = 0.0;
  options.factor = &factor;
  for (int pairs : {4, 8}) {
    options.n_eigenpairs = pairs;
    const EigenPairs solved = solve_eigenpairs(pencil.stiffness, pencil.mass, options);
    ASSERT_EQ(solved.eigenvalues.size(), pairs);
    expect_spectrum(solved, pencil, 0, 1e-10);
  }
  // The same factor for a static solve afterwards: K x = b against the dense solution.
  const VectorX b = VectorX::LinSpaced(pencil.stiffness.rows(), 1.0, 2.0);
  VectorX x(b.size());
  factor.solve(b.data(), x.data());
  EXPECT_LT((pencil.stiffness * x - b).norm(), 1e-10 * b.norm());
  options.shift = -1.0;
  EXPECT_THROW(solve_eigenpairs(pencil.stiffness, pencil.mass, options), SolverError);
  const BarPencil other = bar_pencil(1000, false);
  options.shift = 0.0;
  EXPECT_THROW(solve_eigenpairs(other.stiffness, other.mass, options), SolverError);
}

namespace {
int polls = 0;
int polls_allowed = 0;
/// A host's check that asks to stop from its (polls_allowed + 1)-th call on.
bool stop_after_allowed_polls() { return ++polls > polls_allowed; }
}  // namespace

TEST(Eigensolver, AHostsInterruptCheckFactorisesOnAWorkerAndStopsAtOnce) {
  // With a host's check installed (the Python module) the numeric factorisation runs on a worker
  // (core/interrupt.hpp): the same factor as on the caller's thread, and a stop leaves at once.
  // The 7-point Laplacian of a 16^3 grid plus the identity: a supernodal factor, as for a body.
  const Index side = 16, n = side * side * side;
  std::vector<Eigen::Triplet<double>> entries;
  const auto at = [side](Index i, Index j, Index k) { return (i * side + j) * side + k; };
  const auto couple = [&entries](Index a, Index b) {
    entries.emplace_back(a, b, -1.0);
    entries.emplace_back(b, a, -1.0);
  };
  for (Index i = 0; i < side; ++i) {
    for (Index j = 0; j < side; ++j) {
      for (Index k = 0; k < side; ++k) {
        const Index row = at(i, j, k);
        entries.emplace_back(row, row, 7.0);
        if (i + 1 < side) couple(row, at(i + 1, j, k));
        if (j + 1 < side) couple(row, at(i, j + 1, k));
        if (k + 1 < side) couple(row, at(i, j, k + 1));
      }
    }
  }
  SparseMatrix laplacian(n, n);
  laplacian.setFromTriplets(entries.begin(), entries.end());
  const SparseMatrix no_mass;
  const VectorX b = VectorX::LinSpaced(n, 1.0, 2.0);
  VectorX here(n), on_worker(n);
  CholmodFactor local(laplacian, no_mass, 0.0, "test");
  ASSERT_TRUE(local.supernodal());
  local.solve(b.data(), here.data());
  EXPECT_LT((laplacian * here - b).norm(), 1e-12 * b.norm());
  const InterruptCheck previous = set_interrupt_check(&stop_after_allowed_polls);
  polls = 0;
  polls_allowed = 1000000;
  CholmodFactor factor(laplacian, no_mass, 0.0, "test");
  factor.solve(b.data(), on_worker.data());
  EXPECT_EQ((here - on_worker).norm(), 0.0);
  EXPECT_GE(polls, 2) << "no poll before the numeric factorisation";
  polls = polls_allowed = 0;  // a stop asked for before the factorisation returns at once
  EXPECT_THROW(CholmodFactor(laplacian, no_mass, 0.0, "test"), Interrupted);
  const BarPencil pencil = bar_pencil(2000, false);
  // A stop at the second poll: in the factorisation, at SLEPc's next restart or ARPACK's next step.
  EigenOptions options;
  options.n_eigenpairs = 4;
  options.shift = -1.0;
  for (const Solver solver : {Solver::slepc, Solver::arpack}) {
    options.solver = solver;
    polls = 0;
    polls_allowed = 1;
    EXPECT_THROW(solve_eigenpairs(pencil.stiffness, pencil.mass, options), Interrupted);
    EXPECT_GE(polls, 2) << "the solve stopped before its factorisation was made";
  }
  set_interrupt_check(previous);
  wait_for_abandoned_work();
}

TEST(Eigensolver, BackendsAgreeToRoundOff) {
  const BarPencil pencil = bar_pencil(3000, false);
  EigenOptions options;
  options.n_eigenpairs = 12;
  options.shift = -1.0;
  const EigenPairs slepc = solve_eigenpairs(pencil.stiffness, pencil.mass, options);
  options.solver = Solver::arpack;
  const EigenPairs arpack = solve_eigenpairs(pencil.stiffness, pencil.mass, options);
  for (int i = 0; i < options.n_eigenpairs; ++i) {
    EXPECT_NEAR(slepc.eigenvalues[i], arpack.eigenvalues[i], 1e-10 * arpack.eigenvalues[i]);
  }
}

/// Two-component bar: component x fixed at both ends, y at the left end only, numbered node by
/// node with a dense 2x2 coupling pattern (x-y entries stored as zeros, as in elasticity), so
/// CHOLMOD's ordering sees node groups of two DOFs and single-DOF nodes at the right end.
TEST(Eigensolver, ArpackOrderingOfNodeGroupsMatchesDenseSolve) {
  const int elements = 300;
  const double h = 1.0 / elements;
  // DOF of (node, component) or -1 where fixed.
  std::vector<std::array<int, 2>> dof(elements + 1);
  int n = 0;
  for (int node = 0; node <= elements; ++node) {
    dof[node][0] = node == 0 || node == elements ? -1 : n++;
    dof[node][1] = node == 0 ? -1 : n++;
  }
  const double young[2] = {kYoung, 3.0 * kYoung};
  std::vector<Eigen::Triplet<double, Index>> k, m;
  for (int e = 0; e < elements; ++e) {
    for (int a = 0; a < 2; ++a) {
      for (int b = 0; b < 2; ++b) {
        for (int ci = 0; ci < 2; ++ci) {
          for (int cj = 0; cj < 2; ++cj) {
            const int row = dof[e + a][ci], column = dof[e + b][cj];
            if (row < 0 || column < 0) continue;
            const double same = ci == cj ? 1.0 : 0.0;
            k.emplace_back(row, column, same * (a == b ? 1.0 : -1.0) * young[ci] / h);
            m.emplace_back(row, column, same * (a == b ? 2.0 : 1.0) * kDensity * h / 6.0);
          }
        }
      }
    }
  }
  SparseMatrix stiffness(n, n), mass(n, n);
  stiffness.setFromTriplets(k.begin(), k.end());
  mass.setFromTriplets(m.begin(), m.end());
  const Eigen::GeneralizedSelfAdjointEigenSolver<MatrixX> dense{MatrixX(stiffness), MatrixX(mass)};
  EigenOptions options;
  options.n_eigenpairs = 10;
  options.shift = -1.0;
  options.solver = Solver::arpack;
  const EigenPairs arpack = solve_eigenpairs(stiffness, mass, options);
  for (int i = 0; i < options.n_eigenpairs; ++i) {
    EXPECT_NEAR(arpack.eigenvalues[i], dense.eigenvalues()[i], 1e-9 * dense.eigenvalues()[i]) << i;
  }
}

TEST(Eigensolver, SolveModesNormalisesAndSeparatesRigidModes) {
  const BarPencil pencil = bar_pencil(1000, true);
  for (const Solver solver : {Solver::slepc, Solver::arpack}) {
    ModalOptions options;
    options.modes = 6;
    options.solver = solver;
    const ModeSet modes = solve_modes(pencil.stiffness, pencil.mass, options, 1);
    ASSERT_EQ(modes.n_rigid(), 1);
    ASSERT_EQ(modes.n_modes(), 6);
    EXPECT_EQ(modes.report.attempts, 1);
    for (int i = 0; i < 6; ++i) {
      const double exact_hz = std::sqrt(pencil.exact[1 + i]) / (2.0 * kPi);
      EXPECT_NEAR(modes.frequencies_hz[i], exact_hz, 1e-10 * exact_hz);
    }
    EXPECT_LT(modes.orthogonality_error, 1e-9) << solver_name(solver);
    EXPECT_LT(modes.max_residual, 1e-8);
    EXPECT_LT(std::abs(modes.rigid_frequencies_hz[0]), 1e-6 * modes.frequencies_hz[0]);
    // The rigid mode of a bar is a uniform translation: constant, mass-normalised, positive.
    const VectorX& rigid = modes.rigid_shapes.col(0);
    EXPECT_NEAR(rigid.minCoeff(), rigid.maxCoeff(), 1e-8 * rigid.maxCoeff());
    EXPECT_NEAR(rigid.dot(pencil.mass * rigid), 1.0, 1e-12);
  }
}

TEST(Eigensolver, UnexpectedZeroModeTriggersRetry) {
  const BarPencil pencil = bar_pencil(500, true);
  ModalOptions options;
  options.modes = 4;
  const ModeSet modes = solve_modes(pencil.stiffness, pencil.mass, options, 0);
  EXPECT_EQ(modes.n_rigid(), 1);
  EXPECT_EQ(modes.n_modes(), 4);
  EXPECT_EQ(modes.report.attempts, 2);
  const double exact_hz = std::sqrt(pencil.exact[1]) / (2.0 * kPi);
  EXPECT_NEAR(modes.frequencies_hz[0], exact_hz, 1e-10 * exact_hz);
}

TEST(Eigensolver, TooManyModesIsAnInputError) {
  const BarPencil pencil = bar_pencil(10, false);
  ModalOptions options;
  options.modes = 12;
  EXPECT_THROW(solve_modes(pencil.stiffness, pencil.mass, options, 0), InputError);
  options.modes = 9;
  EXPECT_THROW(solve_modes(pencil.stiffness, pencil.mass, options, 1), InputError);
}

TEST(Eigensolver, PetscErrorBecomesSolverError) {
  // A bad PETSc option makes EPSSetFromOptions fail inside PETSc: it must surface as a
  // SolverError naming the call and PETSc's message, not abort the process.
  const BarPencil pencil = bar_pencil(50, false);
  EigenOptions options;
  options.n_eigenpairs = 3;
  options.shift = -1.0;
  ASSERT_EQ(PetscOptionsSetValue(nullptr, "-eps_type", "no_such_solver"), 0);
  try {
    solve_eigenpairs(pencil.stiffness, pencil.mass, options);
    ADD_FAILURE() << "no exception";
  } catch (const SolverError& error) {
    EXPECT_NE(std::string(error.what()).find("no_such_solver"), std::string::npos) << error.what();
    EXPECT_NE(std::string(error.what()).find("EPSSetFromOptions"), std::string::npos) << error.what();
  }
  ASSERT_EQ(PetscOptionsClearValue(nullptr, "-eps_type"), 0);
  EXPECT_NO_THROW(solve_eigenpairs(pencil.stiffness, pencil.mass, options));
}

TEST(Eigensolver, MacOfIdenticalAndOrthogonalShapes) {
  MatrixX a = MatrixX::Identity(4, 2);
  MatrixX b(4, 2);
  b << 2, 0, 0, 1, 0, 1, 0, 0;
  const MatrixX mac = mac_matrix(a, b, nullptr);
  EXPECT_DOUBLE_EQ(mac(0, 0), 1.0);
  EXPECT_DOUBLE_EQ(mac(0, 1), 0.0);
  EXPECT_DOUBLE_EQ(mac(1, 1), 0.5);
  const std::vector<ModePair> pairs = pair_modes(VectorX::Constant(2, 10.0), VectorX::Constant(2, 8.0), mac);
  ASSERT_EQ(pairs.size(), 2u);
  EXPECT_EQ(pairs[0].open_mode, 0);
  EXPECT_EQ(pairs[1].open_mode, 1);
  EXPECT_NEAR(pairs[0].f_bilinear_hz, 2.0 * 10 * 8 / 18.0, 1e-12);
  EXPECT_NEAR(pairs[0].ratio, 0.8, 1e-15);
  EXPECT_TRUE(pairs[0].paired);
  EXPECT_TRUE(pairs[1].paired);  // MAC 0.5: the threshold itself still pairs
}

/// An uncracked mode whose open partner was not computed takes a leftover open mode with a low
/// MAC: it is reported unpaired, not as a frequency ratio.
TEST(Eigensolver, LowMacPairIsMarkedUnpaired) {
  MatrixX mac(2, 2);
  mac << 0.98, 0.01, 0.02, 0.09;
  const std::vector<ModePair> pairs = pair_modes(VectorX::LinSpaced(2, 10.0, 20.0), VectorX::LinSpaced(2, 9.0, 15.0), mac);
  ASSERT_EQ(pairs.size(), 2u);
  EXPECT_TRUE(pairs[0].paired);
  EXPECT_EQ(pairs[1].open_mode, 1);
  EXPECT_FALSE(pairs[1].paired);
  EXPECT_DOUBLE_EQ(pairs[1].mac, 0.09);
}

}  // namespace
}  // namespace crackle::modal
