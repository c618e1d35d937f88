/// \file SLEPc backend: Krylov–Schur with shift-and-invert and a sparse direct Cholesky.
#include <slepceps.h>

#include <algorithm>
#include <memory>
#include <numeric>
#include <string>
#include <vector>

#include "core/errors.hpp"
#include "core/interrupt.hpp"
#include "core/resources.hpp"
#include "linalg/cholmod_factor.hpp"
#include "modal/eigensolver.hpp"
#include "modal/petsc_check.hpp"

namespace crackle::modal {
namespace detail {
namespace {

/// Innermost message of the error being unwound, and the functions it went through.
thread_local std::string g_error_message;
thread_local std::string g_error_trace;

PetscErrorCode record_error(MPI_Comm, int line, const char* function, const char* file,
                            PetscErrorCode code, PetscErrorType type, const char* message, void*) {
  if (type == PETSC_ERROR_INITIAL) {
    g_error_message = (message && *message) ? message : "";
    g_error_trace.clear();
  }
  if (!g_error_trace.empty()) g_error_trace += " <- ";
  g_error_trace += std::string(function ? function : "?") + " (" + (file ? file : "?") + ":" +
                   std::to_string(line) + ")";
  return code;
}

}  // namespace

PetscErrorCapture::PetscErrorCapture() {
  g_error_message.clear();
  g_error_trace.clear();
  PetscPushErrorHandler(record_error, nullptr);
}

PetscErrorCapture::~PetscErrorCapture() { PetscPopErrorHandler(); }

void check_petsc(PetscErrorCode code, const char* call, const char* context) {
  if (code == 0) return;
  const char* generic = nullptr;
  PetscErrorMessage(code, &generic, nullptr);
  std::string message = std::string(context) + ": " + call + " failed with PETSc error " +
                        std::to_string(static_cast<int>(code));
  if (generic) message += " (" + std::string(generic) + ")";
  if (!g_error_message.empty()) message += ": " + g_error_message;
  if (!g_error_trace.empty()) message += " [in " + g_error_trace + "]";
  g_error_message.clear();
  g_error_trace.clear();
  throw SolverError(message);
}

}  // namespace detail

namespace {

using detail::Owned;
using OwnedMat = Owned<Mat, MatDestroy>;
using OwnedVec = Owned<Vec, VecDestroy>;
using OwnedEps = Owned<EPS, EPSDestroy>;
using OwnedScatter = Owned<VecScatter, VecScatterDestroy>;

constexpr const char* kContext = "SLEPc eigen-solve";

bool slepc_is_initialised() {
  PetscBool initialised = PETSC_FALSE;
  SlepcInitialized(&initialised);
  return initialised == PETSC_TRUE;
}

/// First row and end row of this rank's block of a matrix with n rows (PETSc's default split).
std::pair<PetscInt, PetscInt> row_range(PetscInt n, int rank, int size) {
  const PetscInt base = n / size;
  const PetscInt extra = n % size;
  const PetscInt begin = rank * base + std::min<PetscInt>(rank, extra);
  return {begin, begin + base + (rank < extra ? 1 : 0)};
}

/// A distributed AIJ matrix (SeqAIJ on one rank, MPIAIJ on several) from the rows
/// [begin, end) of a CSR matrix every rank holds. Marked symmetric so that PCCHOLESKY accepts it.
void create_distributed(const SparseMatrix& matrix, PetscInt begin, PetscInt end, OwnedMat& out) {
  const PetscInt n = static_cast<PetscInt>(matrix.rows());
  const Index* outer = matrix.outerIndexPtr();
  const Index* inner = matrix.innerIndexPtr();
  const double* values = matrix.valuePtr();
  std::vector<PetscInt> local_outer(static_cast<std::size_t>(end - begin + 1));
  for (PetscInt row = begin; row <= end; ++row) local_outer[row - begin] = outer[row] - outer[begin];
  const PetscInt* columns = inner + outer[begin];
  const PetscScalar* entries = values + outer[begin];

  CRACKLE_PETSC(kContext, MatCreate(PETSC_COMM_WORLD, out.address()));
  CRACKLE_PETSC(kContext, MatSetSizes(out, end - begin, end - begin, n, n));
  CRACKLE_PETSC(kContext, MatSetType(out, MATAIJ));
  // Only the call matching the actual type (Seq or MPI) acts; the other is a no-op.
  CRACKLE_PETSC(kContext, MatSeqAIJSetPreallocationCSR(out, local_outer.data(), columns, entries));
  CRACKLE_PETSC(kContext, MatMPIAIJSetPreallocationCSR(out, local_outer.data(), columns, entries));
  CRACKLE_PETSC(kContext, MatSetOption(out, MAT_SYMMETRIC, PETSC_TRUE));
  CRACKLE_PETSC(kContext, MatSetOption(out, MAT_SYMMETRY_ETERNAL, PETSC_TRUE));
}

}  // namespace

int mpi_rank() {
  int initialised = 0;
  MPI_Initialized(&initialised);
  if (!initialised) return 0;
  int rank = 0;
  MPI_Comm_rank(slepc_is_initialised() ? PETSC_COMM_WORLD : MPI_COMM_WORLD, &rank);
  return rank;
}

int mpi_size() {
  int initialised = 0;
  MPI_Initialized(&initialised);
  if (!initialised) return 1;
  int size = 1;
  MPI_Comm_size(slepc_is_initialised() ? PETSC_COMM_WORLD : MPI_COMM_WORLD, &size);
  return size;
}

namespace {
SlepcSession* deferred_session = nullptr;  ///< the session waiting for its first use, if any
}  // namespace

SlepcSession::SlepcSession(int* argc, char*** argv, Start start) : argc_(argc), argv_(argv) {
  if (start == Start::now) {
    initialise();
  } else {
    deferred_session = this;
  }
}

void SlepcSession::initialise() {
  if (slepc_is_initialised()) return;
  int mpi_started = 0;
  MPI_Initialized(&mpi_started);
  if (!mpi_started) session_folder_ = std::make_unique<MpiSessionFolder>();
  const PetscErrorCode code = SlepcInitialize(argc_, argv_, nullptr, nullptr);
  if (code != 0) throw SolverError("SlepcInitialize failed with error " + std::to_string(code));
  owns_ = true;
}

void SlepcSession::start() {
  if (deferred_session) deferred_session->initialise();
}

SlepcSession::~SlepcSession() {
  if (deferred_session == this) deferred_session = nullptr;
  if (owns_) SlepcFinalize();
  session_folder_.reset();  // after MPI_Finalize
}

namespace {

/// PCSHELL application y = (K - sigma M)^{-1} x with crackle's CHOLMOD factor (one rank): the
/// node-compressed ordering of linalg/cholmod_factor.hpp, which PETSc's own CHOLMOD interface does not
/// use. Errors become PETSc error codes: nothing may unwind through PETSc's C frames.
PetscErrorCode apply_cholmod_factor(PC pc, Vec x, Vec y) {
  void* context = nullptr;
  PetscErrorCode code = PCShellGetContext(pc, &context);
  if (code) return code;
  const PetscScalar* in = nullptr;
  PetscScalar* out = nullptr;
  if ((code = VecGetArrayRead(x, &in)) || (code = VecGetArray(y, &out))) return code;
  PetscErrorCode result = 0;
  try {
    static_cast<CholmodFactor*>(context)->solve(in, out);
  } catch (const std::exception& error) {
    result = PetscError(PETSC_COMM_SELF, __LINE__, "apply_cholmod_factor", __FILE__, PETSC_ERR_LIB,
                        PETSC_ERROR_INITIAL, "%s", error.what());
  }
  if ((code = VecRestoreArrayRead(x, &in)) || (code = VecRestoreArray(y, &out))) return code;
  return result;
}

/// SLEPc's basic stopping test, with a poll for a host's stop after each restart
/// (core/interrupt.hpp): a stop ends the solve as "converged by the user" and sets the flag that
/// `context` points to; the caller throws Interrupted after EPSSolve returns.
PetscErrorCode stop_when_interrupted(EPS eps, PetscInt iterations, PetscInt max_iterations, PetscInt n_converged,
                                     PetscInt n_wanted, EPSConvergedReason* reason, void* context) {
  if (interrupt_requested()) {
    *static_cast<bool*>(context) = true;
    *reason = EPS_CONVERGED_USER;
    return 0;
  }
  return EPSStoppingBasic(eps, iterations, max_iterations, n_converged, n_wanted, reason, nullptr);
}

}  // namespace

EigenPairs solve_eigenpairs_slepc(const SparseMatrix& stiffness, const SparseMatrix& mass,
                                  const EigenOptions& options) {
  if (!stiffness.isCompressed() || !mass.isCompressed()) {
    SparseMatrix k = stiffness, m = mass;
    k.makeCompressed();
    m.makeCompressed();
    return solve_eigenpairs_slepc(k, m, options);
  }
  SlepcSession::start();
  if (!slepc_is_initialised()) {
    throw SolverError(
        "SLEPc eigen-solve: SLEPc is not initialised (create a modal::SlepcSession or call "
        "SlepcInitialize in main)");
  }
  const PetscInt n = static_cast<PetscInt>(stiffness.rows());
  detail::PetscErrorCapture capture;

  int rank = 0;
  int size = 1;
  MPI_Comm_rank(PETSC_COMM_WORLD, &rank);
  MPI_Comm_size(PETSC_COMM_WORLD, &size);

  // Factorisation package. On one rank CHOLMOD (supernodal, BLAS-3 through OpenBLAS) is the
  // fastest: bench_modal, 45k DOFs (12^3 p = 2 cube), 10 modes: factorisation 2.1 s + iterations
  // 3.3 s, against 3.3 s + 5.0 s for MUMPS (its triangular solves are slower too); at 192k DOFs
  // 8.9 s against 14.0 s in total. CHOLMOD is sequential, so several ranks use MUMPS, the
  // parallel sparse Cholesky PETSc offers.
  Factorization factorization = options.factorization;
  if (factorization == Factorization::automatic) {
    factorization = size == 1 ? Factorization::cholmod : Factorization::mumps;
  }
  if (factorization == Factorization::cholmod && size > 1) {
    throw InputError("modal: factorization 'cholmod' is sequential and cannot run on " +
                     std::to_string(size) + " MPI ranks; use 'mumps' or 'automatic'");
  }
  const MatSolverType package =
      factorization == Factorization::cholmod ? MATSOLVERCHOLMOD : MATSOLVERMUMPS;

  const auto [begin, end] = row_range(n, rank, size);
  OwnedMat k_matrix;
  OwnedMat m_matrix;
  create_distributed(stiffness, begin, end, k_matrix);
  create_distributed(mass, begin, end, m_matrix);

  OwnedEps eps;
  CRACKLE_PETSC(kContext, EPSCreate(PETSC_COMM_WORLD, eps.address()));
  CRACKLE_PETSC(kContext, EPSSetOperators(eps, k_matrix, m_matrix));
  CRACKLE_PETSC(kContext, EPSSetProblemType(eps, EPS_GHEP));
  CRACKLE_PETSC(kContext, EPSSetType(eps, EPSKRYLOVSCHUR));
  CRACKLE_PETSC(kContext, EPSSetDimensions(eps, options.n_eigenpairs, PETSC_DEFAULT, PETSC_DEFAULT));
  CRACKLE_PETSC(kContext, EPSSetTolerances(eps, options.tolerance, options.max_iterations));
  CRACKLE_PETSC(kContext, EPSSetWhichEigenpairs(eps, EPS_TARGET_MAGNITUDE));
  CRACKLE_PETSC(kContext, EPSSetTarget(eps, options.shift));
  ST st = nullptr;
  KSP ksp = nullptr;
  PC pc = nullptr;
  CRACKLE_PETSC(kContext, EPSGetST(eps, &st));
  CRACKLE_PETSC(kContext, STSetType(st, STSINVERT));
  CRACKLE_PETSC(kContext, STGetKSP(st, &ksp));
  CRACKLE_PETSC(kContext, KSPSetType(ksp, KSPPREONLY));
  CRACKLE_PETSC(kContext, KSPGetPC(ksp, &pc));
  // CHOLMOD (one rank) is crackle's own factor behind a shell preconditioner; MUMPS goes through
  // PETSc's interface.
  std::unique_ptr<CholmodFactor> cholmod;
  Stopwatch watch;
  if (factorization == Factorization::cholmod) {
    cholmod = std::make_unique<CholmodFactor>(stiffness, mass, options.shift, "SLEPc eigen-solve");
    // KSPPREONLY never applies K - sigma M itself: a shell operator spares ST assembling it.
    CRACKLE_PETSC(kContext, STSetMatMode(st, ST_MATMODE_SHELL));
    CRACKLE_PETSC(kContext, PCSetType(pc, PCSHELL));
    CRACKLE_PETSC(kContext, PCShellSetContext(pc, cholmod.get()));
    CRACKLE_PETSC(kContext, PCShellSetApply(pc, apply_cholmod_factor));
  } else {
    CRACKLE_PETSC(kContext, PCSetType(pc, PCCHOLESKY));
    CRACKLE_PETSC(kContext, PCFactorSetMatSolverType(pc, package));
  }
  // Command-line / PETSC_OPTIONS overrides (-eps_view, -eps_ncv, ...).
  CRACKLE_PETSC(kContext, EPSSetFromOptions(eps));

  EigenPairs result;
  result.n_ranks = size;
  result.factorization = factorization_name(factorization);

  CRACKLE_PETSC(kContext, EPSSetUp(eps));
  CRACKLE_PETSC(kContext, KSPSetUp(ksp));  // the numeric factorisation of K - sigma M (MUMPS)
  if (!cholmod) {
    // A failed factorisation (e.g. K - sigma M singular) is reported by PETSc only as a flag.
    Mat factor = nullptr;
    MatFactorError error = MAT_FACTOR_NOERROR;
    CRACKLE_PETSC(kContext, PCFactorGetMatrix(pc, &factor));
    CRACKLE_PETSC(kContext, MatFactorGetError(factor, &error));
    if (error != MAT_FACTOR_NOERROR) {
      throw SolverError("SLEPc eigen-solve: Cholesky factorisation of K - sigma M (sigma = " +
                        format_number(options.shift) + ") with " + result.factorization +
                        " failed (PETSc MatFactorError " + std::to_string(error) +
                        "): K - sigma M is not positive definite");
    }
  }
  result.factorization_s = watch.seconds();

  watch.restart();
  bool interrupted = false;
  if (interrupt_check_installed()) {
    CRACKLE_PETSC(kContext, EPSSetStoppingTestFunction(eps, stop_when_interrupted, &interrupted, nullptr));
  }
  CRACKLE_PETSC(kContext, EPSSolve(eps));
  if (interrupted) throw Interrupted("interrupted");
  PetscInt n_converged = 0;
  PetscInt iterations = 0;
  CRACKLE_PETSC(kContext, EPSGetConverged(eps, &n_converged));
  CRACKLE_PETSC(kContext, EPSGetIterationNumber(eps, &iterations));
  result.iterations = static_cast<int>(iterations);
  if (n_converged < options.n_eigenpairs) {
    throw SolverError("SLEPc eigen-solve: only " + std::to_string(n_converged) + " of " +
                      std::to_string(options.n_eigenpairs) + " eigenpairs converged in " +
                      std::to_string(iterations) + " restarts (tolerance " +
                      format_number(options.tolerance) + ", shift " +
                      format_number(options.shift) + ")");
  }

  // Eigenvectors are distributed; gather each onto every rank.
  OwnedVec vector;
  OwnedVec gathered;
  OwnedScatter scatter;
  CRACKLE_PETSC(kContext, MatCreateVecs(k_matrix, vector.address(), nullptr));
  CRACKLE_PETSC(kContext, VecScatterCreateToAll(vector, scatter.address(), gathered.address()));
  const int count = options.n_eigenpairs;
  result.eigenvalues.resize(count);
  result.vectors.resize(n, count);
  for (int i = 0; i < count; ++i) {
    PetscScalar eigenvalue = 0.0;
    CRACKLE_PETSC(kContext, EPSGetEigenpair(eps, i, &eigenvalue, nullptr, vector, nullptr));
    CRACKLE_PETSC(kContext, VecScatterBegin(scatter, vector, gathered, INSERT_VALUES, SCATTER_FORWARD));
    CRACKLE_PETSC(kContext, VecScatterEnd(scatter, vector, gathered, INSERT_VALUES, SCATTER_FORWARD));
    const PetscScalar* values = nullptr;
    CRACKLE_PETSC(kContext, VecGetArrayRead(gathered, &values));
    std::copy(values, values + n, result.vectors.col(i).data());
    CRACKLE_PETSC(kContext, VecRestoreArrayRead(gathered, &values));
    result.eigenvalues[i] = eigenvalue;
  }
  result.iterations_s = watch.seconds();

  // Ascending order (the target ordering |lambda - sigma| already is for sigma below the
  // spectrum; sort anyway so every backend returns the same order).
  std::vector<int> order(count);
  std::iota(order.begin(), order.end(), 0);
  std::stable_sort(order.begin(), order.end(),
                   [&](int a, int b) { return result.eigenvalues[a] < result.eigenvalues[b]; });
  EigenPairs sorted = result;
  for (int i = 0; i < count; ++i) {
    sorted.eigenvalues[i] = result.eigenvalues[order[i]];
    sorted.vectors.col(i) = result.vectors.col(order[i]);
  }
  return sorted;
}

}  // namespace crackle::modal
