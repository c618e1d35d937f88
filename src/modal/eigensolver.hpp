#pragma once
/// \file Sparse generalized symmetric eigen-solvers for K phi = omega^2 M phi (MODEL.md eqs. 25a,
/// 25c) by shift-and-invert around a shift sigma: the eigenvalues of (K - sigma M)^{-1} M are
/// theta = 1 / (lambda - sigma), so the eigenvalues lambda nearest sigma converge first.
///
/// Two interchangeable backends:
///  - SLEPc Krylov–Schur (EPSGHEP, STSINVERT, KSPPREONLY) over PETSC_COMM_WORLD with the matrices
///    distributed by row ranges; sparse Cholesky by MUMPS (PCCHOLESKY) or, on one rank, by
///    crackle's CHOLMOD factor (linalg/cholmod_factor.hpp) behind a PCSHELL with a shell ST operator;
///  - ARPACK dsaupd/dseupd in mode 3 (shift-invert, B = M) with a CHOLMOD factorisation of
///    K - sigma M, sequential (under MPI every rank solves the whole problem).
#include <memory>
#include <string>

#include "core/mpi_session.hpp"
#include "core/types.hpp"
#include "core/words.hpp"

namespace crackle::linalg {
class CholmodFactor;
}

namespace crackle::modal {

using linalg::CholmodFactor;

/// Eigen-solver backend (the scene's modal.solver adds auto: pipeline/modal_command.cpp resolves it).
enum class Solver { slepc, arpack };
inline constexpr Words<Solver, 2> kSolverWords{{{"slepc", Solver::slepc}, {"arpack", Solver::arpack}}};

/// Sparse direct Cholesky used by the SLEPc backend.
enum class Factorization {
  automatic,  ///< CHOLMOD on one rank (fastest measured), MUMPS on several (CHOLMOD is sequential)
  cholmod,
  mumps,
};
inline constexpr Words<Factorization, 3> kFactorizationWords{{{"automatic", Factorization::automatic},
                                                              {"cholmod", Factorization::cholmod},
                                                              {"mumps", Factorization::mumps}}};

inline const char* solver_name(Solver solver) { return text_of(kSolverWords, solver); }
inline const char* factorization_name(Factorization factorization) {
  return text_of(kFactorizationWords, factorization);
}

/// What one raw eigen-solve is asked to do.
struct EigenOptions {
  int n_eigenpairs = 10;       ///< eigenpairs nearest the shift to compute (rigid ones included)
  double shift = 0.0;          ///< sigma [rad^2/s^2]; negative for bodies with rigid-body modes
  Solver solver = Solver::slepc;
  Factorization factorization = Factorization::automatic;
  double tolerance = 1e-10;    ///< relative residual tolerance of the iteration
  int max_iterations = 1000;   ///< restarts (Krylov–Schur) or Arnoldi iterations (ARPACK)
  /// ARPACK only: a factor of K - shift M the caller made (same K, M and shift), used instead of
  /// factorising again; several solves on one matrix (a static solve beside) then pay one factor.
  CholmodFactor* factor = nullptr;
};

/// Raw eigenpairs as the backend returned them (every rank holds all of them).
struct EigenPairs {
  VectorX eigenvalues;  ///< lambda = omega^2 [rad^2/s^2], ascending
  MatrixX vectors;      ///< one column per eigenvalue, over the DOFs of K
  double factorization_s = 0.0;  ///< symbolic + numeric factorisation of K - sigma M
  double iterations_s = 0.0;     ///< Krylov iterations, solves and eigenvector extraction
  int iterations = 0;            ///< restarts (SLEPc) or Arnoldi update iterations (ARPACK)
  int n_ranks = 1;               ///< MPI ranks the solve was distributed over
  std::string factorization;     ///< package that factorised K - sigma M ("cholmod", "mumps")
};

/// Solves K x = lambda M x for the `n_eigenpairs` eigenvalues nearest `shift` with the chosen
/// backend. K symmetric positive semi-definite, M symmetric positive definite, same size.
/// SolverError (with the backend's message) if the factorisation or the iteration fails.
/// The SLEPc backend needs SLEPc initialised (SlepcSession or SlepcInitialize in main) and is
/// collective over PETSC_COMM_WORLD; every rank must pass the same K and M.
EigenPairs solve_eigenpairs(const SparseMatrix& stiffness, const SparseMatrix& mass,
                            const EigenOptions& options);

EigenPairs solve_eigenpairs_slepc(const SparseMatrix& stiffness, const SparseMatrix& mass,
                                  const EigenOptions& options);
EigenPairs solve_eigenpairs_arpack(const SparseMatrix& stiffness, const SparseMatrix& mass,
                                   const EigenOptions& options);

/// Initialises SLEPc (and PETSc, MPI) for its lifetime; finalises in the destructor. PETSc reads
/// its options from argv and PETSC_OPTIONS. Throws SolverError if initialisation fails.
///
/// `Start::on_first_use` defers the initialisation to the first eigen-solve by SLEPc (`start()`,
/// called by the SLEPc backend): a `crackle run` or `sweep` that finds its modes in the cache, or
/// solves with ARPACK, never pays MPI's start-up (~0.35 s, half of a cached reduced case). argc and
/// argv must outlive the session.
class SlepcSession {
 public:
  enum class Start { now, on_first_use };
  SlepcSession(int* argc, char*** argv, Start start = Start::now);
  ~SlepcSession();
  SlepcSession(const SlepcSession&) = delete;
  SlepcSession& operator=(const SlepcSession&) = delete;

  /// Initialises the deferred session, if there is one and it has not started.
  static void start();

 private:
  void initialise();

  int* argc_ = nullptr;
  char*** argv_ = nullptr;
  bool owns_ = false;
  std::unique_ptr<MpiSessionFolder> session_folder_;  ///< when this session started MPI on its own
};

/// Rank of this process in PETSC_COMM_WORLD (0 when MPI is not initialised).
int mpi_rank();
/// Size of PETSC_COMM_WORLD (1 when MPI is not initialised).
int mpi_size();

}  // namespace crackle::modal
