#pragma once
/// \file The CHOLMOD factors of K (shift 0) of one model's variants, shared by the modal stage, the
/// reduced model and the static release.
#include <map>
#include <memory>

#include "core/types.hpp"
#include "linalg/cholmod_factor.hpp"
#include "mesh/mesh.hpp"

namespace crackle::modal {

using linalg::CholmodFactor;

/// The CHOLMOD factors of K itself (shift 0, the free DOFs of a held body) of one model's variants,
/// made at the first use and shared by every solve on that K: the modal stage's eigen-solve, the
/// reduced model's eigen-solves and its static images. A factor is only worth keeping while another
/// stage will use it: the owner makes a store for the variants it keeps and drops it after.
class StiffnessFactors {
 public:
  /// The factor of `stiffness` (the variant's K over its free DOFs), made at the first call; null when
  /// K is not positive definite (a free body, a mechanism) or its factor does not fit in memory: the
  /// caller then solves on its own (shifted) terms. A K other than the one factorised (another size,
  /// pattern or diagonal) is factorised again.
  CholmodFactor* factor(mesh::Variant variant, const SparseMatrix& stiffness);

 private:
  struct Entry {
    Index rows = 0, nonzeros = 0;
    double diagonal_sum = 0.0;
    std::unique_ptr<CholmodFactor> factor;  ///< null: K could not be factorised
  };
  std::map<mesh::Variant, Entry> entries_;
};

}  // namespace crackle::modal
