#pragma once
/// \file Sparse Cholesky factorisation by CHOLMOD (supernodal, BLAS-3 through the system BLAS)
/// of a symmetric positive definite CSR matrix, with solves. Used by the ARPACK
/// backend (module-internal header).
#include <cholmod.h>

#include <string>
#include <vector>

#include "core/types.hpp"

namespace crackle::modal {

class CholmodFactor {
 public:
  /// Analyses (fill-reducing ordering of the compressed graph, see compressed_ordering) and factorises
  /// `matrix` (full symmetric CSR; only its upper triangle is read). `context` prefixes every
  /// error message (e.g. "ARPACK eigen-solve"). SolverError if A is not positive definite.
  CholmodFactor(const SparseMatrix& matrix, std::string context);
  ~CholmodFactor();
  CholmodFactor(const CholmodFactor&) = delete;
  CholmodFactor& operator=(const CholmodFactor&) = delete;

  /// y = A^{-1} x (x and y of length n, may not alias).
  void solve(const double* x, double* y);

 private:
  std::vector<Index> compressed_ordering(const SparseMatrix& matrix);
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
