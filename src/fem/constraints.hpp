#pragma once
/// \file Dirichlet constraints (MODEL.md eq. 5) and their elimination.
#include <string>
#include <vector>

#include "core/types.hpp"
#include "mesh/mesh.hpp"

namespace crackle::fem {

/// Prescribed displacement `values[c]` of component `components[c]` on every node of `nodes`.
/// `source` names where it came from (e.g. "boundary[0] (face x-)") for error messages.
struct DirichletCondition {
  std::vector<Index> nodes;
  std::vector<int> components;
  std::vector<double> values;
  std::string source;
};

/// The constrained DOFs of one DOF map and the numbering of the free ones.
struct Constraints {
  std::vector<char> fixed;         ///< per DOF: 1 if prescribed
  VectorX values;                  ///< per DOF: prescribed value (0 where free)
  std::vector<Index> free_index;   ///< per DOF: index among the free DOFs, or -1
  std::vector<Index> free_dofs;    ///< free DOFs in increasing order
  Index n_free() const { return static_cast<Index>(free_dofs.size()); }
};

/// Throws InputError naming both sources if one DOF gets two different values.
Constraints make_constraints(const mesh::DofMap& dofs, const std::vector<DirichletCondition>& conditions);

/// The free-free block of a matrix over all DOFs (Dirichlet DOFs eliminated).
SparseMatrix restrict_to_free(const SparseMatrix& matrix, const Constraints& constraints);
/// The same block made in the matrix's own storage (an assembled K or M handed over): the kept
/// entries move forward in place, so no second matrix of the same size is allocated and zeroed.
SparseMatrix restrict_to_free(SparseMatrix&& matrix, const Constraints& constraints);

/// Entries of a vector over all DOFs at the free DOFs, and back (zeros, or the prescribed values,
/// at fixed DOFs).
VectorX restrict_to_free(const VectorX& full, const Constraints& constraints);
VectorX expand_from_free(const VectorX& free, const Constraints& constraints, bool with_prescribed_values);

/// Right-hand side over the free DOFs of A u = f with the prescribed values moved over:
/// \f$f_f - A_{fc} \bar u_c\f$.
VectorX free_right_hand_side(const SparseMatrix& matrix, const VectorX& full_rhs,
                             const Constraints& constraints);

}  // namespace crackle::fem
