#pragma once
/// \file Sparse Cholesky factorisation by CHOLMOD (supernodal, BLAS-3 through the system BLAS)
/// of the shift-invert matrix K - sigma M, with solves. Used by the ARPACK backend and by the
/// SLEPc backend on one rank, by the reduced model's eigen-solves and static images and by the static
/// release (through modal::StiffnessFactors when they share one factor of K).
#include <cholmod.h>

#include <memory>
#include <string>
#include <vector>

#include "core/types.hpp"

namespace crackle::linalg {

class CholmodFactor {
 public:
  /// Forms K - sigma M (full symmetric CSR, same size; K itself when sigma = 0), analyses it
  /// (fill-reducing ordering of the compressed graph, see compressed_ordering) and factorises it.
  /// `context` prefixes every error message (e.g. "ARPACK eigen-solve"). SolverError if K - sigma M
  /// is not positive definite, or if the analysed factor would not fit in the memory available
  /// (before factorising). With a host's interrupt check installed the analysis and the
  /// factorisation run on a worker that a stop leaves behind (Interrupted at once;
  /// core/interrupt.hpp).
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
  /// True for a supernodal factor (the BLAS-3 one CHOLMOD chooses for the larger 3D problems).
  bool supernodal() const { return state_->factor->is_super != 0; }

 private:
  /// CHOLMOD's workspace and the factor, shared with the worker that factorises while a host's
  /// interrupt check is installed (core/interrupt.hpp run_interruptible): an interrupted
  /// factorisation finishes on that worker and frees them there.
  struct State {
    State();
    ~State();
    State(const State&) = delete;
    State& operator=(const State&) = delete;
    cholmod_common common{};
    cholmod_factor* factor = nullptr;
    cholmod_sparse* permuted = nullptr;  ///< tril(P A P') until the numeric factorisation has read it
    cholmod_dense* solution = nullptr;
    cholmod_dense* work_y = nullptr;
    cholmod_dense* work_e = nullptr;
  };
  /// Orders, analyses and factorises `matrix` into `state` (the constructor's work, on its thread or
  /// on a worker). `release`, when given, owns `matrix` and is reset once it has been read.
  static void factorise(State& state, const std::string& context, const SparseMatrix& matrix,
                        std::shared_ptr<SparseMatrix>* release);
  /// SolverError unless the numeric factorisation succeeded.
  void check_factorised() const;
  static std::vector<Index> compressed_ordering(State& state, const std::string& context,
                                                const SparseMatrix& matrix);
  /// SolverError when the analysed factor would not fit in the memory available.
  static void check_factor_fits(const State& state, const std::string& context, Index rows);
  [[noreturn]] static void fail(const State& state, const std::string& context, const char* what);

  std::string context_;
  Index rows_ = 0;
  double shift_ = 0.0;
  std::shared_ptr<State> state_ = std::make_shared<State>();
};

}  // namespace crackle::linalg
