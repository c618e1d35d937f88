/// \file Eigen-solve of one variant with rigid-body handling; MAC and mode pairing.
#include "modal/modal.hpp"

#include <Eigen/Eigenvalues>

#include <algorithm>
#include <cmath>
#include <numeric>
#include <string>

#include "core/errors.hpp"
#include "core/resources.hpp"
#include "linalg/threads.hpp"

namespace crackle::modal {
namespace {


double signed_frequency_hz(double eigenvalue) {
  return std::copysign(std::sqrt(std::abs(eigenvalue)), eigenvalue) / kTwoPi;
}

/// A V for a CSR matrix A and a block of vectors V, sequential and reading A once. (Eigen's own
/// product opens one OpenMP region per column of V, which stalls for whole scheduler slices
/// whenever another process holds a core; this product is memory-bound anyway.)
MatrixX multiply(const SparseMatrix& matrix, const MatrixX& block) {
  const Index* outer = matrix.outerIndexPtr();
  const Index* inner = matrix.innerIndexPtr();
  const double* values = matrix.valuePtr();
  const Index columns = block.cols();
  // Row-major copy of the block, so that each matrix entry updates a contiguous row.
  const Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor> rows = block;
  Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor> product(matrix.rows(), columns);
  for (Index row = 0; row < matrix.rows(); ++row) {
    auto target = product.row(row);
    target.setZero();
    const Index end = matrix.isCompressed() ? outer[row + 1] : outer[row] + matrix.innerNonZeroPtr()[row];
    for (Index k = outer[row]; k < end; ++k) target += values[k] * rows.row(inner[k]);
  }
  return product;
}

/// Eigenvector candidates V with their products M V and K V. Every later step (normalisation,
/// Rayleigh–Ritz, checks) is a small dense operation on these: K and M are read only once each.
struct Basis {
  MatrixX vectors;
  MatrixX mass_vectors;
  MatrixX stiffness_vectors;

  // The tall-skinny dense products (n x k times k x k, k x n times n x k) go through Eigen's
  // cache-blocked GEMM on one thread (linalg::SingleThreadedEigen where they are called): Eigen's
  // OpenMP GEMM would add barriers that stall on a busy machine, and the coefficient-wise
  // lazyProduct they used before ran at a fifth of the blocked speed once k reached a few hundred
  // modes (a reduced model's band x4: docs/benchmarks.md 11.5d).

  /// Right-multiplies all three by `transform` (n_vectors x n_vectors).
  void transform(const MatrixX& transform) {
    vectors = (vectors * transform).eval();
    mass_vectors = (mass_vectors * transform).eval();
    stiffness_vectors = (stiffness_vectors * transform).eval();
  }
  /// max |V^T M V - I|.
  double orthogonality_error() const {
    const MatrixX gram = vectors.transpose() * mass_vectors;
    return (gram - MatrixX::Identity(vectors.cols(), vectors.cols())).cwiseAbs().maxCoeff();
  }
};

/// Scales each column to phi^T M phi = 1 and makes its largest-magnitude entry positive, so that
/// every backend and rank count gives the same shapes for simple eigenvalues.
void normalise(Basis& basis) {
  const Index count = basis.vectors.cols();
  VectorX scale(count);
  for (Index j = 0; j < count; ++j) {
    const double norm = std::sqrt(basis.vectors.col(j).dot(basis.mass_vectors.col(j)));
    if (!(norm > 0.0) || !std::isfinite(norm)) {
      throw SolverError("modal: eigenvector " + std::to_string(j) + " has M-norm " + format_number(norm));
    }
    Index largest = 0;
    basis.vectors.col(j).cwiseAbs().maxCoeff(&largest);
    scale[j] = (basis.vectors(largest, j) < 0.0 ? -1.0 : 1.0) / norm;
  }
  basis.vectors = basis.vectors * scale.asDiagonal();
  basis.mass_vectors = basis.mass_vectors * scale.asDiagonal();
  basis.stiffness_vectors = basis.stiffness_vectors * scale.asDiagonal();
}

/// Rayleigh–Ritz on the computed eigenvectors: solves the small pencil (V^T K V, V^T M V) and
/// rotates V by its eigenvectors. This makes the shapes M-orthonormal to round-off (the
/// backends' purified shift-invert vectors are only orthogonal to about the iteration tolerance)
/// and turns the eigenvalues into Rayleigh quotients; for a degenerate cluster (rigid-body modes)
/// it picks an M-orthonormal basis of the computed subspace.
VectorX rayleigh_ritz(Basis& basis) {
  MatrixX projected_k = basis.vectors.transpose() * basis.stiffness_vectors;
  MatrixX projected_m = basis.vectors.transpose() * basis.mass_vectors;
  projected_k = 0.5 * (projected_k + projected_k.transpose()).eval();
  projected_m = 0.5 * (projected_m + projected_m.transpose()).eval();
  const Eigen::GeneralizedSelfAdjointEigenSolver<MatrixX> solver(projected_k, projected_m);
  if (solver.info() != Eigen::Success) {
    throw SolverError("modal: Rayleigh-Ritz on the computed eigenvectors failed (they are not "
                      "linearly independent in the M inner product)");
  }
  basis.transform(solver.eigenvectors());
  return solver.eigenvalues();
}

}  // namespace

ModeSet solve_modes(const SparseMatrix& stiffness, const SparseMatrix& mass,
                    const ModalOptions& options, int n_rigid_expected) {
  const Index n = static_cast<Index>(stiffness.rows());
  if (options.modes < 1) {
    throw InputError("modal.modes must be at least 1, got " + std::to_string(options.modes));
  }
  const double trace_k = stiffness.diagonal().sum();
  const double trace_m = mass.diagonal().sum();
  if (!(trace_k > 0.0) || !(trace_m > 0.0) || !std::isfinite(trace_k / trace_m)) {
    throw InputError("modal: K and M need positive traces, got tr K = " + format_number(trace_k) +
                     ", tr M = " + format_number(trace_m));
  }
  const double reference = trace_k / trace_m;
  // Zero-energy (rigid-body or mechanism) modes: |lambda| below rigid_tolerance^2 lambda_ref, and
  // at least 1e6 below the largest eigenvalue computed (which is elastic). The second test keeps
  // strongly graded meshes right: their tiny elements make tr K / tr M so large that the first
  // test alone would call the lowest bending mode of a clamped beam a zero-energy mode.
  const double rigid_eigenvalue = options.rigid_tolerance * options.rigid_tolerance * reference;
  double elastic_scale = 0.0;  // largest |lambda| of the last solve
  auto zero_energy = [&](double eigenvalue) {
    return std::abs(eigenvalue) < rigid_eigenvalue &&
           (std::abs(eigenvalue) < 1e-6 * elastic_scale || elastic_scale < rigid_eigenvalue);
  };

  EigenOptions eigen;
  eigen.solver = options.solver;
  eigen.factorization = options.factorization;
  eigen.tolerance = options.tolerance;
  eigen.max_iterations = options.max_iterations;
  eigen.shift = options.shift.value_or(-options.shift_fraction * reference);
  eigen.factor = options.factor;
  int n_rigid_request = std::max(0, n_rigid_expected);
  eigen.n_eigenpairs = options.modes + n_rigid_request;
  if (eigen.n_eigenpairs > n) {
    throw InputError("modal.modes = " + std::to_string(options.modes) + " elastic modes" +
                     (n_rigid_request > 0 ? " plus " + std::to_string(n_rigid_request) + " rigid-body modes" : "") +
                     " exceed the " + std::to_string(n) + " free DOFs of the problem");
  }

  ModeSet result;
  result.n_rigid_expected = n_rigid_expected;
  result.report.solver = solver_name(options.solver);
  result.report.shift = eigen.shift;
  result.report.reference_eigenvalue = reference;
  EigenPairs pairs;
  int n_rigid = 0;
  for (int attempt = 1;; ++attempt) {
    Stopwatch solve_watch;
    pairs = solve_eigenpairs(stiffness, mass, eigen);
    result.report.solve_s += solve_watch.seconds();
    result.report.attempts = attempt;
    result.report.factorization_s += pairs.factorization_s;
    result.report.iterations_s += pairs.iterations_s;
    elastic_scale = pairs.eigenvalues.cwiseAbs().maxCoeff();
    n_rigid = 0;
    for (Index i = 0; i < pairs.eigenvalues.size(); ++i) n_rigid += zero_energy(pairs.eigenvalues[i]);
    if (eigen.n_eigenpairs - n_rigid >= options.modes) break;
    // More zero-energy modes than the topology predicted (a mechanism): ask for more.
    const int wanted = options.modes + n_rigid + 6;
    if (eigen.n_eigenpairs >= n || attempt >= 4) {
      throw InputError("modal: only " + std::to_string(eigen.n_eigenpairs - n_rigid) + " of the " +
                       std::to_string(options.modes) + " elastic modes requested exist beside " +
                       std::to_string(n_rigid) + " zero-energy modes (" + std::to_string(n) +
                       " free DOFs)");
    }
    eigen.n_eigenpairs = std::min<int>(wanted, n);
  }
  result.report.factorization = pairs.factorization;
  result.report.n_ranks = pairs.n_ranks;
  result.report.iterations = pairs.iterations;
  result.report.n_eigenpairs = eigen.n_eigenpairs;

  // Rigid modes have the smallest |lambda| and come first in ascending order (K is PSD, so the
  // only negative eigenvalues are round-off around 0).
  const int n_kept = n_rigid + options.modes;
  Stopwatch postprocess_watch;
  const linalg::SingleThreadedEigen one_thread;  // the Basis products (see there)
  Basis basis;
  basis.vectors = pairs.vectors.leftCols(n_kept);
  basis.mass_vectors = multiply(mass, basis.vectors);
  basis.stiffness_vectors = multiply(stiffness, basis.vectors);
  normalise(basis);
  result.backend_orthogonality_error = basis.orthogonality_error();
  const VectorX eigenvalues = rayleigh_ritz(basis);
  normalise(basis);
  for (int i = 0; i < n_rigid; ++i) {
    if (!zero_energy(eigenvalues[i])) {
      throw SolverError("modal: zero-energy modes are not the lowest eigenvalues (lambda_" +
                        std::to_string(i) + " = " + format_number(eigenvalues[i]) + ")");
    }
  }
  result.orthogonality_error = basis.orthogonality_error();
  for (int i = n_rigid; i < n_kept; ++i) {
    const auto mass_phi = basis.mass_vectors.col(i);
    const VectorX residual = basis.stiffness_vectors.col(i) - eigenvalues[i] * mass_phi;
    result.max_residual =
        std::max(result.max_residual, residual.norm() / (std::max(std::abs(eigenvalues[i]), 1e-12 * reference) *
                                                         mass_phi.norm()));
  }
  const MatrixX& vectors = basis.vectors;
  result.report.postprocess_s = postprocess_watch.seconds();
  result.rigid_frequencies_hz = eigenvalues.head(n_rigid).unaryExpr(&signed_frequency_hz);
  result.frequencies_hz = eigenvalues.tail(options.modes).unaryExpr(&signed_frequency_hz);
  result.rigid_shapes = vectors.leftCols(n_rigid);
  result.shapes = vectors.rightCols(options.modes);
  return result;
}

MatrixX mac_matrix(const MatrixX& a, const MatrixX& b, const SparseMatrix* weight) {
  const MatrixX weighted_b = weight ? multiply(*weight, b) : b;
  const MatrixX weighted_a = weight ? multiply(*weight, a) : a;
  const MatrixX cross = a.transpose().lazyProduct(weighted_b);
  const VectorX norm_a = (a.cwiseProduct(weighted_a)).colwise().sum().transpose();
  const VectorX norm_b = (b.cwiseProduct(weighted_b)).colwise().sum().transpose();
  MatrixX mac(a.cols(), b.cols());
  for (Index i = 0; i < a.cols(); ++i) {
    for (Index j = 0; j < b.cols(); ++j) mac(i, j) = cross(i, j) * cross(i, j) / (norm_a[i] * norm_b[j]);
  }
  return mac;
}

std::vector<ModePair> pair_modes(const VectorX& f_uncracked, const VectorX& f_open, const MatrixX& mac) {
  std::vector<ModePair> pairs;
  std::vector<char> row_done(mac.rows(), 0);
  std::vector<char> column_done(mac.cols(), 0);
  const Index n_pairs = std::min(mac.rows(), mac.cols());
  for (Index k = 0; k < n_pairs; ++k) {
    Index best_row = -1;
    Index best_column = -1;
    for (Index i = 0; i < mac.rows(); ++i) {
      if (row_done[i]) continue;
      for (Index j = 0; j < mac.cols(); ++j) {
        if (column_done[j]) continue;
        if (best_row < 0 || mac(i, j) > mac(best_row, best_column)) {
          best_row = i;
          best_column = j;
        }
      }
    }
    row_done[best_row] = column_done[best_column] = 1;
    ModePair pair;
    pair.uncracked_mode = static_cast<int>(best_row);
    pair.open_mode = static_cast<int>(best_column);
    pair.f_uncracked_hz = f_uncracked[best_row];
    pair.f_open_hz = f_open[best_column];
    pair.ratio = pair.f_open_hz / pair.f_uncracked_hz;
    pair.mac = mac(best_row, best_column);
    pair.f_bilinear_hz = 2.0 * pair.f_uncracked_hz * pair.f_open_hz / (pair.f_uncracked_hz + pair.f_open_hz);
    pair.paired = pair.mac >= kPairingMac;
    pairs.push_back(pair);
  }
  std::sort(pairs.begin(), pairs.end(),
            [](const ModePair& a, const ModePair& b) { return a.uncracked_mode < b.uncracked_mode; });
  return pairs;
}

}  // namespace crackle::modal
