#include "fem/constraints.hpp"

#include <algorithm>
#include <cassert>
#include <string>

#include "core/errors.hpp"
#include "core/interrupt.hpp"

namespace crackle::fem {

Constraints make_constraints(const mesh::DofMap& dofs, const std::vector<DirichletCondition>& conditions) {
  // eq. (5): u_i = u-bar_i on Gamma_u, one prescribed value per DOF.
  const Index n_dofs = dofs.n_dofs();
  Constraints constraints;
  constraints.fixed.assign(n_dofs, 0);
  constraints.values = VectorX::Zero(n_dofs);
  std::vector<int> owner(n_dofs, -1);  // condition that fixed each DOF first
  for (std::size_t i = 0; i < conditions.size(); ++i) {
    const DirichletCondition& condition = conditions[i];
    if (condition.components.size() != condition.values.size()) {
      throw InputError(condition.source + ": " + std::to_string(condition.components.size()) +
                       " components but " + std::to_string(condition.values.size()) + " values");
    }
    for (std::size_t k = 0; k < condition.components.size(); ++k) {
      const int component = condition.components[k];
      const double value = condition.values[k];
      if (component < 0 || component > 2) {
        throw InputError(condition.source + ": displacement component " + std::to_string(component) +
                         " is not 0, 1 or 2 (x, y, z)");
      }
      for (Index node : condition.nodes) {
        if (node < 0 || node >= static_cast<Index>(dofs.dof_node.size())) {
          throw InputError(condition.source + ": node " + std::to_string(node) + " not in a mesh of " +
                           std::to_string(dofs.dof_node.size()) + " nodes");
        }
        const Index dof = dofs.dof(node, component);
        if (owner[dof] >= 0 && constraints.values[dof] != value) {
          throw InputError(
              "displacement " + std::string(axis_name(component)) + " of node " + std::to_string(node) +
              " is prescribed twice: " + format_number(constraints.values[dof]) + " by " +
              conditions[owner[dof]].source + " and " + format_number(value) + " by " + condition.source);
        }
        if (owner[dof] < 0) owner[dof] = static_cast<int>(i);
        constraints.fixed[dof] = 1;
        constraints.values[dof] = value;
      }
    }
  }
  constraints.free_index.assign(n_dofs, -1);
  for (Index dof = 0; dof < n_dofs; ++dof) {
    if (constraints.fixed[dof]) continue;
    constraints.free_index[dof] = static_cast<Index>(constraints.free_dofs.size());
    constraints.free_dofs.push_back(dof);
  }
  return constraints;
}

SparseMatrix restrict_to_free(const SparseMatrix& matrix, const Constraints& constraints) {
  assert(matrix.rows() == static_cast<Index>(constraints.fixed.size()));
  assert(matrix.cols() == static_cast<Index>(constraints.fixed.size()));
  const Index n = constraints.n_free();
  // Count, then fill: free_index is increasing, so sorted columns stay sorted.
  std::vector<Index> row_start(n + 1, 0);
  for (Index i = 0; i < n; ++i) {
    if ((i & 4095) == 4095) poll_interrupt();  // a large K takes seconds (a host may stop it)
    Index count = 0;
    for (SparseMatrix::InnerIterator it(matrix, constraints.free_dofs[i]); it; ++it) {
      if (constraints.free_index[it.col()] >= 0) ++count;
    }
    row_start[i + 1] = row_start[i] + count;
  }
  SparseMatrix result(n, n);
  result.resizeNonZeros(row_start[n]);
  std::copy(row_start.begin(), row_start.end(), result.outerIndexPtr());
  Index* columns = result.innerIndexPtr();
  double* values = result.valuePtr();
  for (Index i = 0; i < n; ++i) {
    if ((i & 4095) == 4095) poll_interrupt();
    Index k = row_start[i];
    for (SparseMatrix::InnerIterator it(matrix, constraints.free_dofs[i]); it; ++it) {
      const Index column = constraints.free_index[it.col()];
      if (column < 0) continue;
      columns[k] = column;
      values[k] = it.value();
      ++k;
    }
  }
  return result;
}

namespace {

/// The free-free block of a compressed `matrix` in its own storage: the kept entries move forward,
/// and the result takes the arrays over (no entry copied twice, no allocation of their size: Eigen
/// 3.4's SparseMatrix has no move constructor, and makeCompressed() would reallocate them).
SparseMatrix compact_to_free(SparseMatrix& matrix, const Constraints& constraints) {
  assert(matrix.isCompressed());
  assert(matrix.rows() == static_cast<Index>(constraints.fixed.size()));
  assert(matrix.cols() == static_cast<Index>(constraints.fixed.size()));
  const Index n = constraints.n_free();
  Index* outer = matrix.outerIndexPtr();
  Index* columns = matrix.innerIndexPtr();
  double* values = matrix.valuePtr();
  // Rows in increasing order, each entry written at or before where it was read (k counts the
  // entries kept so far, at most those read so far): the compaction never overwrites an entry still
  // to be read. outer[free_dofs[i]] is read before outer[i] is written (free_dofs[i] >= i).
  Index k = 0;
  for (Index i = 0; i < n; ++i) {
    if ((i & 4095) == 4095) poll_interrupt();
    const Index row = constraints.free_dofs[i];
    const Index begin = outer[row], end = outer[row + 1];
    outer[i] = k;
    for (Index e = begin; e < end; ++e) {
      const Index column = constraints.free_index[columns[e]];
      if (column < 0) continue;
      columns[k] = column;
      values[k] = values[e];
      ++k;
    }
  }
  outer[n] = k;
  SparseMatrix result(n, n);  // compressed, n + 1 row starts
  std::copy(outer, outer + n + 1, result.outerIndexPtr());
  result.data().swap(matrix.data());  // the compacted arrays, at their size (their capacity kept)
  result.data().resize(k);
  return result;
}

}  // namespace

SparseMatrix restrict_to_free(SparseMatrix&& matrix, const Constraints& constraints) {
  if (!matrix.isCompressed()) return restrict_to_free(static_cast<const SparseMatrix&>(matrix), constraints);
  return compact_to_free(matrix, constraints);
}

VectorX restrict_to_free(const VectorX& full, const Constraints& constraints) {
  assert(full.size() == static_cast<Index>(constraints.fixed.size()));
  VectorX free(constraints.n_free());
  for (Index i = 0; i < constraints.n_free(); ++i) free[i] = full[constraints.free_dofs[i]];
  return free;
}

VectorX expand_from_free(const VectorX& free, const Constraints& constraints, bool with_prescribed_values) {
  assert(free.size() == constraints.n_free());
  VectorX full = with_prescribed_values ? constraints.values : VectorX::Zero(constraints.values.size());
  for (Index i = 0; i < constraints.n_free(); ++i) full[constraints.free_dofs[i]] = free[i];
  return full;
}

VectorX free_right_hand_side(const SparseMatrix& matrix, const VectorX& full_rhs,
                             const Constraints& constraints) {
  assert(full_rhs.size() == static_cast<Index>(constraints.fixed.size()));
  VectorX rhs(constraints.n_free());
  for (Index i = 0; i < constraints.n_free(); ++i) {
    const Index dof = constraints.free_dofs[i];
    double value = full_rhs[dof];
    for (SparseMatrix::InnerIterator it(matrix, dof); it; ++it) {
      if (constraints.fixed[it.col()]) value -= it.value() * constraints.values[it.col()];
    }
    rhs[i] = value;
  }
  return rhs;
}

}  // namespace crackle::fem
