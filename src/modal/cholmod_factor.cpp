/// \file CHOLMOD factorisation with a node-compressed fill-reducing ordering, and solves.
#include "modal/cholmod_factor.hpp"

#include <algorithm>
#include <utility>
#include <vector>

#include "core/errors.hpp"
#include "core/resources.hpp"

namespace crackle::modal {

/// Fill-reducing ordering computed on the compressed graph: consecutive rows with the same
/// pattern (the three DOFs of a node) form one vertex. CHOLMOD's default choice (AMD, then METIS
/// when AMD's fill is poor) runs on a graph with a third of the vertices and a ninth of the
/// edges, and the ordering is expanded back to DOFs: the DOFs of a node stay together, as they
/// would be eliminated anyway.
std::vector<Index> CholmodFactor::compressed_ordering(const SparseMatrix& matrix) {
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
  cholmod_factor* symbolic = cholmod_analyze(&graph, &common_);
  if (!symbolic || common_.status < CHOLMOD_OK) fail("cholmod_analyze (compressed graph)");
  const auto* group_order = static_cast<const Index*>(symbolic->Perm);
  std::vector<Index> permutation;
  permutation.reserve(static_cast<std::size_t>(n));
  for (Index i = 0; i < groups; ++i) {
    const Index g = group_order[i];
    for (Index row = group_start[g]; row < group_start[g + 1]; ++row) permutation.push_back(row);
  }
  cholmod_free_factor(&symbolic, &common_);
  return permutation;
}

CholmodFactor::CholmodFactor(const SparseMatrix& stiffness, const SparseMatrix& mass, double shift,
                             std::string context)
    : context_(std::move(context)), rows_(stiffness.rows()), shift_(shift) {
  // Without a shift K itself is factorised (no copy: a static solve holds one matrix less).
  const bool copy = shift != 0.0 || !stiffness.isCompressed();
  SparseMatrix shifted;
  if (copy) {
    shifted = shift != 0.0 ? SparseMatrix(stiffness - shift * mass) : stiffness;
    shifted.makeCompressed();
  }
  const SparseMatrix& matrix = copy ? shifted : stiffness;
  cholmod_start(&common_);
  common_.print = 0;
  common_.error_handler = nullptr;
  // A symmetric CSR matrix read as CSC is the same matrix; stype = 1 reads the upper triangle.
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
  std::vector<Index> permutation = compressed_ordering(matrix);
  common_.nmethods = 1;
  common_.method[0].ordering = CHOLMOD_GIVEN;
  factor_ = cholmod_analyze_p(&view, permutation.data(), nullptr, 0, &common_);
  if (!factor_ || common_.status < CHOLMOD_OK) fail("cholmod_analyze");
  check_factor_fits();
  if (!cholmod_factorize(&view, factor_, &common_) || common_.status != CHOLMOD_OK) {
    if (common_.status == CHOLMOD_NOT_POSDEF) {
      throw SolverError(context_ + ": CHOLMOD found K - sigma M not positive definite (pivot at column " +
                        std::to_string(factor_->minor) + " of " + std::to_string(matrix.rows()) + ")");
    }
    fail("cholmod_factorize");
  }
}

void CholmodFactor::check_factor_fits() const {
  // The symbolic analysis knows the factor's size: its values (xsize for a supernodal factor, else
  // one per nonzero of L) and, for a simplicial one, a row index each. Refuse here, in a second, a
  // factorisation the kernel would kill the process for after minutes.
  const double entries = factor_->is_super ? static_cast<double>(factor_->xsize) : common_.lnz;
  const double needed = 8.0 * entries + (factor_->is_super ? 0.0 : 4.0 * common_.lnz);
  std::string source;
  const double available = available_memory_bytes(&source);
  if (needed <= available) return;
  throw SolverError(context_ + ": the Cholesky factor of " + std::to_string(rows_) + " DOFs needs about " +
                    bytes_text(needed) + " (" + format_number(common_.lnz) + " nonzeros), more than the " +
                    bytes_text(available) + " available (" + source +
                    "); use fewer cells or a lower mesh.box.order, or run crackle modal under mpirun (MUMPS)");
}

CholmodFactor::~CholmodFactor() {
  cholmod_free_dense(&solution_, &common_);
  cholmod_free_dense(&work_y_, &common_);
  cholmod_free_dense(&work_e_, &common_);
  cholmod_free_factor(&factor_, &common_);
  cholmod_finish(&common_);
}

void CholmodFactor::solve(const double* x, double* y, Index columns) {
  cholmod_dense rhs{};
  rhs.nrow = rhs.d = static_cast<std::size_t>(rows_);
  rhs.ncol = static_cast<std::size_t>(columns);
  rhs.nzmax = rhs.nrow * rhs.ncol;
  rhs.xtype = CHOLMOD_REAL;
  rhs.dtype = CHOLMOD_DOUBLE;
  rhs.x = const_cast<double*>(x);
  if (!cholmod_solve2(CHOLMOD_A, factor_, &rhs, nullptr, &solution_, nullptr, &work_y_, &work_e_, &common_)) {
    fail("cholmod_solve2");
  }
  const auto* values = static_cast<const double*>(solution_->x);
  std::copy(values, values + rows_ * columns, y);
}

CholmodFactor* StiffnessFactors::factor(mesh::Variant variant, const SparseMatrix& stiffness) {
  const double diagonal_sum = stiffness.diagonal().sum();
  auto found = entries_.find(variant);
  if (found != entries_.end() && found->second.rows == stiffness.rows() &&
      found->second.nonzeros == stiffness.nonZeros() && found->second.diagonal_sum == diagonal_sum) {
    return found->second.factor.get();
  }
  Entry entry{stiffness.rows(), stiffness.nonZeros(), diagonal_sum, nullptr};
  entries_.erase(variant);  // the old factor goes before the new one is made
  try {
    const SparseMatrix no_mass;
    entry.factor = std::make_unique<CholmodFactor>(stiffness, no_mass, 0.0, "the factor of K");
    ++made_;
  } catch (const SolverError&) {
    entry.factor.reset();
  }
  return entries_.emplace(variant, std::move(entry)).first->second.factor.get();
}

void CholmodFactor::fail(const char* what) {
  throw SolverError(context_ + ": " + what + " failed (CHOLMOD status " + std::to_string(common_.status) + ")");
}

}  // namespace crackle::modal
