/// \file ARPACK backend: implicitly restarted Lanczos (dsaupd/dseupd) in shift-invert mode 3 with
/// a CHOLMOD factorisation of K - sigma M.
#include <Eigen/Eigenvalues>

#include <algorithm>
#include <numeric>
#include <string>
#include <optional>
#include <vector>

#include "core/errors.hpp"
#include "core/interrupt.hpp"
#include "core/resources.hpp"
#include "linalg/cholmod_factor.hpp"
#include "modal/eigensolver.hpp"

// arpack-ng's C interface (arpack.h also declares the complex routines with C99 _Complex, which
// ISO C++ lacks, so the two routines used here are declared directly). a_int is int (INTERFACE64 0).
extern "C" {
void dsaupd_c(int* ido, char const* bmat, int n, char const* which, int nev, double tol,
              double* resid, int ncv, double* v, int ldv, int* iparam, int* ipntr, double* workd,
              double* workl, int lworkl, int* info);
void dseupd_c(int rvec, char const* howmny, int const* select, double* d, double* z, int ldz,
              double sigma, char const* bmat, int n, char const* which, int nev, double tol,
              double* resid, int ncv, double* v, int ldv, int* iparam, int* ipntr, double* workd,
              double* workl, int lworkl, int* info);
// LAPACK's random vector (ARPACK's dependency), for ARPACK's own start vector.
void dlarnv_(const int* idist, int* iseed, const int* n, double* x);
}

namespace crackle::modal {
namespace {

/// y = A x for a CSR matrix, sequential: one product per Lanczos step is memory-bound, and
/// Eigen's OpenMP split of it stalls whenever another process holds a core.
void multiply(const SparseMatrix& matrix, const double* x, double* y) {
  const Index* outer = matrix.outerIndexPtr();
  const Index* inner = matrix.innerIndexPtr();
  const double* values = matrix.valuePtr();
  for (Index row = 0; row < matrix.rows(); ++row) {
    double sum = 0.0;
    for (Index k = outer[row]; k < outer[row + 1]; ++k) sum += values[k] * x[inner[k]];
    y[row] = sum;
  }
}

std::string arpack_message(int info, bool in_seupd) {
  switch (info) {
    case 1: return "maximum number of iterations reached";
    case 3: return "no shifts could be applied during the implicit restart (increase ncv)";
    case -1: return "n must be positive";
    case -2: return "nev must be positive";
    case -3: return "ncv must satisfy nev < ncv <= n";
    case -7: return "workl too short";
    case -8: return in_seupd ? "error in LAPACK dsteqr" : "error in LAPACK tridiagonal eigenvalue calculation";
    case -9: return "starting vector is zero";
    case -14: return in_seupd ? "dsaupd found no eigenvalues to sufficient accuracy" : "error code -14";
    case -9999: return "could not build an Arnoldi factorisation";
    default: return "error code " + std::to_string(info);
  }
}

}  // namespace

EigenPairs solve_eigenpairs_arpack(const SparseMatrix& stiffness, const SparseMatrix& mass,
                                   const EigenOptions& options) {
  if (!stiffness.isCompressed() || !mass.isCompressed()) {
    SparseMatrix k = stiffness, m = mass;
    k.makeCompressed();
    m.makeCompressed();
    return solve_eigenpairs_arpack(k, m, options);
  }
  const int n = static_cast<int>(stiffness.rows());
  const int nev = options.n_eigenpairs;
  EigenPairs result;
  if (nev >= n) {
    // ARPACK needs nev < ncv <= n; all eigenpairs of a (necessarily small) problem come from
    // LAPACK instead.
    Stopwatch watch;
    const Eigen::GeneralizedSelfAdjointEigenSolver<MatrixX> dense{MatrixX(stiffness), MatrixX(mass)};
    if (dense.info() != Eigen::Success) throw SolverError("ARPACK eigen-solve: dense fallback failed");
    result.eigenvalues = dense.eigenvalues().head(nev);
    result.vectors = dense.eigenvectors().leftCols(nev);
    result.factorization = "dense";
    result.iterations_s = watch.seconds();
    return result;
  }
  result.factorization = "cholmod";

  Stopwatch watch;
  std::optional<CholmodFactor> own;
  if (options.factor) {
    if (options.factor->rows() != n || options.factor->shift() != options.shift) {
      throw SolverError("ARPACK eigen-solve: the given factor is of another matrix (" +
                        std::to_string(options.factor->rows()) + " rows, shift " +
                        format_number(options.factor->shift()) + ") than K - " + format_number(options.shift) +
                        " M of " + std::to_string(n) + " rows");
    }
  } else {
    own.emplace(stiffness, mass, options.shift, "ARPACK eigen-solve");
  }
  CholmodFactor& factor = options.factor ? *options.factor : *own;
  result.factorization_s = watch.seconds();

  watch.restart();
  // Lanczos basis size: SLEPc's default (max(2 nev, nev + 15)), bounded by n.
  const int ncv = std::min(n, std::max(2 * nev, nev + 15));
  const int lworkl = ncv * (ncv + 8);
  std::vector<double> resid(n, 0.0);
  std::vector<double> basis(static_cast<std::size_t>(n) * ncv);
  std::vector<double> workd(3 * static_cast<std::size_t>(n));
  std::vector<double> workl(lworkl);
  std::vector<double> temporary(n);
  int iparam[11] = {};
  int ipntr[14] = {};
  iparam[0] = 1;  // exact shifts
  iparam[2] = options.max_iterations;
  iparam[3] = 1;
  iparam[6] = 3;  // mode 3: shift-invert, OP = (K - sigma M)^{-1} M, B = M
  int ido = 0;
  // The random start ARPACK makes on its first call in a process (dgetv0: dlarnv, uniform on
  // (-1, 1), seed 1, 3, 5, 7), made here for every solve: ARPACK keeps its seed between calls, so
  // that a second solve in the same process (the Python module, a test) would start elsewhere.
  const int distribution = 2;
  int seed[4] = {1, 3, 5, 7};
  dlarnv_(&distribution, seed, &n, resid.data());
  int info = 1;  // start from resid
  const char* which = "LM";
  for (;;) {
    dsaupd_c(&ido, "G", n, which, nev, options.tolerance, resid.data(), ncv, basis.data(), n,
             iparam, ipntr, workd.data(), workl.data(), lworkl, &info);
    if (ido == 99) break;
    poll_interrupt();  // one Lanczos step: a solve with the factor
    double* x = workd.data() + ipntr[0] - 1;
    double* y = workd.data() + ipntr[1] - 1;
    if (ido == -1) {  // y = OP x = (K - sigma M)^{-1} M x
      multiply(mass, x, temporary.data());
      factor.solve(temporary.data(), y);
    } else if (ido == 1) {  // M x is already at ipntr[2]
      factor.solve(workd.data() + ipntr[2] - 1, y);
    } else if (ido == 2) {  // y = M x
      multiply(mass, x, y);
    } else {
      throw SolverError("ARPACK eigen-solve: unexpected reverse-communication request ido = " +
                        std::to_string(ido));
    }
  }
  result.iterations = iparam[2];
  if (info < 0 || info == 3) {
    throw SolverError("ARPACK eigen-solve: dsaupd failed: " + arpack_message(info, false) +
                      " (n = " + std::to_string(n) + ", nev = " + std::to_string(nev) +
                      ", ncv = " + std::to_string(ncv) + ")");
  }
  if (info == 1 || iparam[4] < nev) {
    throw SolverError("ARPACK eigen-solve: only " + std::to_string(iparam[4]) + " of " +
                      std::to_string(nev) + " eigenpairs converged in " +
                      std::to_string(iparam[2]) + " iterations (tolerance " +
                      format_number(options.tolerance) + ", shift " + format_number(options.shift) +
                      ")");
  }

  std::vector<int> select(ncv, 1);
  std::vector<double> values(nev);
  std::vector<double> vectors(static_cast<std::size_t>(n) * nev);
  dseupd_c(1, "A", select.data(), values.data(), vectors.data(), n, options.shift, "G", n, which,
           nev, options.tolerance, resid.data(), ncv, basis.data(), n, iparam, ipntr, workd.data(),
           workl.data(), lworkl, &info);
  if (info != 0) {
    throw SolverError("ARPACK eigen-solve: dseupd failed: " + arpack_message(info, true));
  }
  result.iterations_s = watch.seconds();

  std::vector<int> order(nev);
  std::iota(order.begin(), order.end(), 0);
  std::stable_sort(order.begin(), order.end(), [&](int a, int b) { return values[a] < values[b]; });
  result.eigenvalues.resize(nev);
  result.vectors.resize(n, nev);
  for (int i = 0; i < nev; ++i) {
    result.eigenvalues[i] = values[order[i]];
    result.vectors.col(i) =
        Eigen::Map<const VectorX>(vectors.data() + static_cast<std::size_t>(order[i]) * n, n);
  }
  return result;
}

EigenPairs solve_eigenpairs(const SparseMatrix& stiffness, const SparseMatrix& mass,
                            const EigenOptions& options) {
  if (stiffness.rows() != stiffness.cols() || mass.rows() != mass.cols() ||
      stiffness.rows() != mass.rows()) {
    throw InputError("modal eigen-solve: K is " + std::to_string(stiffness.rows()) + "x" +
                     std::to_string(stiffness.cols()) + " but M is " + std::to_string(mass.rows()) +
                     "x" + std::to_string(mass.cols()));
  }
  if (options.n_eigenpairs < 1 || options.n_eigenpairs > stiffness.rows()) {
    throw InputError("modal eigen-solve: " + std::to_string(options.n_eigenpairs) +
                     " eigenpairs requested of a problem with " + std::to_string(stiffness.rows()) +
                     " DOFs");
  }
  return options.solver == Solver::slepc ? solve_eigenpairs_slepc(stiffness, mass, options)
                                         : solve_eigenpairs_arpack(stiffness, mass, options);
}

}  // namespace crackle::modal
