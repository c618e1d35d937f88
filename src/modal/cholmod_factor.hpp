#pragma once
/// \file Sparse Cholesky factorisation by CHOLMOD (supernodal, BLAS-3 through the system BLAS)
/// of the shift-invert matrix K - sigma M, with solves. Used by the ARPACK backend and by the
/// SLEPc backend on one rank (module-internal header).
#include <cholmod.h>

#include <map>
#include <memory>
#include <string>
#include <vector>

#include "core/types.hpp"
#include "mesh/mesh.hpp"

namespace crackle::modal {

class CholmodFactor {
 public:
  /// Forms K - sigma M (full symmetric CSR, same size; K itself when sigma = 0), analyses it (fill-reducing ordering of the
  /// compressed graph, see compressed_ordering) and factorises it. `context` prefixes every error
  /// message (e.g. "ARPACK eigen-solve"). SolverError if K - sigma M is not positive definite, or
  /// if the analysed factor would not fit in the memory available (before factorising).
  CholmodFactor(const SparseMatrix& stiffness, const SparseMatrix& mass, double shift, std::string context);
  ~CholmodFactor();
  CholmodFactor(const CholmodFactor&) = delete;
  CholmodFactor& operator=(const CholmodFactor&) = delete;

  /// y = A^{-1} x (x and y of length n, may not alias); `columns` right-hand sides at once (x and y
  /// n x columns, column-major: one blocked, BLAS-3 solve).
  void solve(const double* x, double* y, Index columns = 1);

  /// sigma of the factorised K - sigma M [rad^2/s^2].
  double shift() const { return shift_; }
  Index rows() const { return rows_; }

 private:
  std::vector<Index> compressed_ordering(const SparseMatrix& matrix);
  /// SolverError when the analysed factor would not fit in the memory available.
  void check_factor_fits() const;
  [[noreturn]] void fail(const char* what);

  std::string context_;
  Index rows_ = 0;
  double shift_ = 0.0;
  cholmod_common common_{};
  cholmod_factor* factor_ = nullptr;
  cholmod_dense* solution_ = nullptr;
  cholmod_dense* work_y_ = nullptr;
  cholmod_dense* work_e_ = nullptr;
};

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
  /// Factors made (not counting the times one was shared).
  int made() const { return made_; }

 private:
  struct Entry {
    Index rows = 0, nonzeros = 0;
    double diagonal_sum = 0.0;
    std::unique_ptr<CholmodFactor> factor;  ///< null: K could not be factorised
  };
  std::map<mesh::Variant, Entry> entries_;
  int made_ = 0;
};

}  // namespace crackle::modal
