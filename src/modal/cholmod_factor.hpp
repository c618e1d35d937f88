#pragma once
/// \file Sparse Cholesky factorisation by CHOLMOD (supernodal, BLAS-3 through the system BLAS)
/// of the shift-invert matrix K - sigma M, with solves. Used by the ARPACK backend and by the
/// SLEPc backend on one rank (module-internal header).
#include <cholmod.h>

#include <string>
#include <vector>

#include "core/types.hpp"

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

 private:
  std::vector<Index> compressed_ordering(const SparseMatrix& matrix);
  /// SolverError when the analysed factor would not fit in the memory available.
  void check_factor_fits() const;
  [[noreturn]] void fail(const char* what);

  std::string context_;
  Index rows_ = 0;
  cholmod_common common_{};
  cholmod_factor* factor_ = nullptr;
  cholmod_dense* solution_ = nullptr;
  cholmod_dense* work_y_ = nullptr;
  cholmod_dense* work_e_ = nullptr;
};

}  // namespace crackle::modal
