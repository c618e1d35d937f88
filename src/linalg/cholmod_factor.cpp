/// \file CHOLMOD factorisation with a node-compressed fill-reducing ordering, and solves.
#include "linalg/cholmod_factor.hpp"

#include <algorithm>
#include <utility>
#include <vector>

#include "core/errors.hpp"
#include "core/interrupt.hpp"
#include "core/resources.hpp"

namespace crackle::linalg {

/// Fill-reducing ordering computed on the compressed graph: consecutive rows with the same
/// pattern (the three DOFs of a node) form one vertex. CHOLMOD's default choice (AMD, then METIS
/// when AMD's fill is poor) runs on a graph with a third of the vertices and a ninth of the
/// edges, and the ordering is expanded back to DOFs: the DOFs of a node stay together, as they
/// would be eliminated anyway.
std::vector<Index> CholmodFactor::compressed_ordering(State& state, const std::string& context,
                                                      const SparseMatrix& matrix) {
  const Index n = matrix.rows();
  const Index* outer = matrix.outerIndexPtr();
  const Index* inner = matrix.innerIndexPtr();
  std::vector<Index> group_start{0};  // first row of each group, then n
  std::vector<Index> group_of(n, 0);
  for (Index row = 1; row < n; ++row) {
    const Index previous = group_start.back();
    const Index length = outer[row + 1] - outer[row];
    const bool same = length == outer[previous + 1] - outer[previous] &&
                      std::equal(inner + outer[row], inner + outer[row + 1], inner + outer[previous]);
    if (!same) group_start.push_back(row);
    group_of[row] = static_cast<Index>(group_start.size()) - 1;
  }
  const Index groups = static_cast<Index>(group_start.size());
  group_start.push_back(n);
  // Pattern of the compressed graph (symmetric, every group's row of its first DOF).
  std::vector<Index> pointers{0};
  std::vector<Index> indices;
  indices.reserve(static_cast<std::size_t>(matrix.nonZeros() / 4));
  for (Index g = 0; g < groups; ++g) {
    const Index row = group_start[g];
    for (Index k = outer[row]; k < outer[row + 1]; ++k) {
      const Index column = group_of[inner[k]];
      if (indices.size() == static_cast<std::size_t>(pointers.back()) || indices.back() != column) {
        indices.push_back(column);
      }
    }
    pointers.push_back(static_cast<Index>(indices.size()));
  }
  cholmod_sparse graph{};
  graph.nrow = graph.ncol = static_cast<std::size_t>(groups);
  graph.nzmax = indices.size();
  graph.p = pointers.data();
  graph.i = indices.data();
  graph.stype = 1;
  graph.itype = CHOLMOD_INT;
  graph.xtype = CHOLMOD_PATTERN;
  graph.dtype = CHOLMOD_DOUBLE;
  graph.sorted = 0;
  graph.packed = 1;
  cholmod_factor* symbolic = cholmod_analyze(&graph, &state.common);
  if (!symbolic || state.common.status < CHOLMOD_OK) fail(state, context, "cholmod_analyze (compressed graph)");
  const auto* group_order = static_cast<const Index*>(symbolic->Perm);
  std::vector<Index> permutation;
  permutation.reserve(static_cast<std::size_t>(n));
  for (Index i = 0; i < groups; ++i) {
    const Index g = group_order[i];
    for (Index row = group_start[g]; row < group_start[g + 1]; ++row) permutation.push_back(row);
  }
  cholmod_free_factor(&symbolic, &state.common);
  return permutation;
}

namespace {
/// CHOLMOD's view of a symmetric CSR matrix (read as CSC it is the same matrix; stype = 1 reads
/// the upper triangle). The matrix must outlive the view.
cholmod_sparse view_of(const SparseMatrix& matrix) {
  cholmod_sparse view{};
  view.nrow = view.ncol = static_cast<std::size_t>(matrix.rows());
  view.nzmax = static_cast<std::size_t>(matrix.nonZeros());
  view.p = const_cast<Index*>(matrix.outerIndexPtr());
  view.i = const_cast<Index*>(matrix.innerIndexPtr());
  view.x = const_cast<double*>(matrix.valuePtr());
  view.stype = 1;
  view.itype = CHOLMOD_INT;
  view.xtype = CHOLMOD_REAL;
  view.dtype = CHOLMOD_DOUBLE;
  view.sorted = 0;  // no promise needed: CHOLMOD permutes (and so sorts) the matrix anyway
  view.packed = 1;
  return view;
}

/// True when every entry of `mass` has a place in `stiffness` (both compressed, columns sorted).
bool pattern_within(const SparseMatrix& mass, const SparseMatrix& stiffness) {
  if (!stiffness.isCompressed() || mass.rows() != stiffness.rows()) return false;
  const Index* columns = stiffness.innerIndexPtr();
  for (Index row = 0; row < stiffness.rows(); ++row) {
    Index k = stiffness.outerIndexPtr()[row];
    const Index end = stiffness.outerIndexPtr()[row + 1];
    for (SparseMatrix::InnerIterator it(mass, row); it; ++it) {
      while (k < end && columns[k] < it.col()) ++k;
      if (k == end || columns[k] != it.col()) return false;
    }
  }
  return true;
}

/// A copy of a compressed matrix in blocks of rows, with a poll for a host's stop between them
/// (seconds at 10^5 DOFs of order 4, mostly the first touch of the new pages).
SparseMatrix copy_in_blocks(const SparseMatrix& matrix) {
  SparseMatrix result(matrix.rows(), matrix.cols());
  result.resizeNonZeros(matrix.nonZeros());
  std::copy_n(matrix.outerIndexPtr(), matrix.rows() + 1, result.outerIndexPtr());
  constexpr Index kBlock = 4096;
  for (Index first = 0; first < matrix.rows(); first += kBlock) {
    poll_interrupt();
    const Index begin = matrix.outerIndexPtr()[first];
    const Index end = matrix.outerIndexPtr()[std::min(first + kBlock, Index(matrix.rows()))];
    std::copy(matrix.innerIndexPtr() + begin, matrix.innerIndexPtr() + end, result.innerIndexPtr() + begin);
    std::copy(matrix.valuePtr() + begin, matrix.valuePtr() + end, result.valuePtr() + begin);
  }
  return result;
}

/// K - sigma M on K's pattern (pattern_within(mass, stiffness)): a copy of K and one merge pass,
/// with the same values as Eigen's general sparse sum, which builds the union pattern through a
/// temporary. One named result, so that it is returned without a copy (Eigen 3.4's SparseMatrix
/// has no move constructor).
SparseMatrix shifted_on_stiffness_pattern(const SparseMatrix& stiffness, const SparseMatrix& mass, double shift) {
  SparseMatrix result = copy_in_blocks(stiffness);
  const Index* columns = result.innerIndexPtr();
  for (Index row = 0; row < result.rows(); ++row) {
    Index k = result.outerIndexPtr()[row];
    for (SparseMatrix::InnerIterator it(mass, row); it; ++it) {
      while (columns[k] < it.col()) ++k;
      result.valuePtr()[k] -= shift * it.value();
    }
  }
  return result;
}

}  // namespace

CholmodFactor::State::State() {
  cholmod_start(&common);
  common.print = 0;
  common.error_handler = nullptr;
}

CholmodFactor::State::~State() {
  cholmod_free_sparse(&permuted, &common);
  cholmod_free_dense(&solution, &common);
  cholmod_free_dense(&work_y, &common);
  cholmod_free_dense(&work_e, &common);
  cholmod_free_factor(&factor, &common);
  cholmod_finish(&common);
}

CholmodFactor::CholmodFactor(const SparseMatrix& stiffness, const SparseMatrix& mass, double shift,
                             std::string context)
    : context_(std::move(context)), rows_(stiffness.rows()), shift_(shift) {
  // With a host's interrupt check installed the ordering, the analysis and the factorisation, which
  // have no place to poll for a stop, run on a worker that owns the state and the matrix
  // (core/interrupt.hpp): an interruption returns at once and leaves the worker to finish. K is then
  // copied (and the copy freed as soon as it has been read, before the factor's values are
  // allocated); otherwise K itself is factorised here (no copy: a static solve holds one matrix
  // less).
  const bool on_worker = interrupt_check_installed();
  const bool copy = shift != 0.0 || !stiffness.isCompressed() || on_worker;
  // Made in place: Eigen 3.4's SparseMatrix has no move assignment, and assigning a temporary
  // copies it (a second pass over a matrix of a gigabyte at 10^5 DOFs of order 4).
  SparseMatrix shifted = shift != 0.0 ? (pattern_within(mass, stiffness)
                                             ? shifted_on_stiffness_pattern(stiffness, mass, shift)
                                             : SparseMatrix(stiffness - shift * mass))
                         : !copy                     ? SparseMatrix()
                         : stiffness.isCompressed() ? copy_in_blocks(stiffness)
                                                    : SparseMatrix(stiffness);
  shifted.makeCompressed();
  if (!on_worker) {
    factorise(*state_, context_, copy ? shifted : stiffness, nullptr);
  } else {
    auto owned = std::make_shared<SparseMatrix>();
    owned->swap(shifted);
    // The worker's lambda is the matrix's only owner, so that factorise can free it.
    run_interruptible([state = state_, context = context_, owned = std::move(owned)]() mutable {
      const SparseMatrix& matrix = *owned;
      factorise(*state, context, matrix, &owned);
    });
  }
  check_factorised();
}

void CholmodFactor::factorise(State& state, const std::string& context, const SparseMatrix& matrix,
                              std::shared_ptr<SparseMatrix>* release) {
  const bool poll = release == nullptr;  // on the caller's thread (a worker leaves the polls to it)
  cholmod_sparse view = view_of(matrix);
  std::vector<Index> permutation = compressed_ordering(state, context, matrix);
  if (poll) poll_interrupt();
  state.common.nmethods = 1;
  state.common.method[0].ordering = CHOLMOD_GIVEN;
  state.factor = cholmod_analyze_p(&view, permutation.data(), nullptr, 0, &state.common);
  if (!state.factor || state.common.status < CHOLMOD_OK) fail(state, context, "cholmod_analyze");
  check_factor_fits(state, context, matrix.rows());
  if (poll) poll_interrupt();
  if (!state.factor->is_super) {  // a small or sparse factor (simplicial LDL')
    cholmod_factorize(&view, state.factor, &state.common);
    return;
  }
  // What cholmod_factorize does for a supernodal factor of an upper-stored matrix, in two steps:
  // S = tril(P A P'), after which A is not read again (a copy of it is freed), and the numeric
  // factorisation of S.
  state.permuted = cholmod_ptranspose(&view, 1, static_cast<int*>(state.factor->Perm), nullptr, 0, &state.common);
  if (!state.permuted) fail(state, context, "cholmod_ptranspose");
  if (release) release->reset();
  if (poll) poll_interrupt();
  double beta[2] = {0.0, 0.0};
  cholmod_super_numeric(state.permuted, nullptr, beta, state.factor, &state.common);
  cholmod_free_sparse(&state.permuted, &state.common);
}

void CholmodFactor::check_factorised() const {
  const State& state = *state_;
  if (state.common.status == CHOLMOD_OK) return;
  if (state.common.status == CHOLMOD_NOT_POSDEF) {
    throw SolverError(context_ + ": CHOLMOD found K - sigma M not positive definite (pivot at column " +
                      std::to_string(state.factor->minor) + " of " + std::to_string(rows_) + ")");
  }
  fail(state, context_, "cholmod_factorize");
}

void CholmodFactor::check_factor_fits(const State& state, const std::string& context, Index rows) {
  // The symbolic analysis knows the factor's size: its values (xsize for a supernodal factor, else
  // one per nonzero of L) and, for a simplicial one, a row index each. Refuse here, in a second, a
  // factorisation the kernel would kill the process for after minutes.
  const cholmod_factor& factor = *state.factor;
  const double entries = factor.is_super ? static_cast<double>(factor.xsize) : state.common.lnz;
  const double needed = 8.0 * entries + (factor.is_super ? 0.0 : 4.0 * state.common.lnz);
  std::string source;
  const double available = available_memory_bytes(&source);
  if (needed <= available) return;
  throw SolverError(context + ": the Cholesky factor of " + std::to_string(rows) + " DOFs needs about " +
                    bytes_text(needed) + " (" + format_number(state.common.lnz) + " nonzeros), more than the " +
                    bytes_text(available) + " available (" + source +
                    "); use fewer cells or a lower mesh.box.order, or run crackle modal under mpirun (MUMPS)");
}

CholmodFactor::~CholmodFactor() = default;

void CholmodFactor::solve(const double* x, double* y, Index columns) {
  cholmod_dense rhs{};
  rhs.nrow = rhs.d = static_cast<std::size_t>(rows_);
  rhs.ncol = static_cast<std::size_t>(columns);
  rhs.nzmax = rhs.nrow * rhs.ncol;
  rhs.xtype = CHOLMOD_REAL;
  rhs.dtype = CHOLMOD_DOUBLE;
  rhs.x = const_cast<double*>(x);
  if (!cholmod_solve2(CHOLMOD_A, state_->factor, &rhs, nullptr, &state_->solution, nullptr, &state_->work_y, &state_->work_e, &state_->common)) {
    fail(*state_, context_, "cholmod_solve2");
  }
  const auto* values = static_cast<const double*>(state_->solution->x);
  std::copy(values, values + rows_ * columns, y);
}

void CholmodFactor::fail(const State& state, const std::string& context, const char* what) {
  throw SolverError(context + ": " + what + " failed (CHOLMOD status " + std::to_string(state.common.status) + ")");
}

}  // namespace crackle::linalg
