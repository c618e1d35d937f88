#pragma once
/// \file The matrix-free linear solver of the harmonic balance for many crack pairs (HYBRID.md §4):
/// restarted GMRES on the Jacobian J = I - H dP/dG applied as an action, preconditioned by the
/// linear part with a mean contact stiffness, so that no c(2H+1) square matrix is ever formed.
///
/// **The action.** dP/dG is block diagonal per pair (the force harmonics of a pair depend on its own
/// gap harmonics only): one (r(2H+1))^2 block per pair with a closed sample (r rows per pair), zero
/// for the pairs that stay open over the period, so they drop out of the nonlinear coupling exactly.
/// H is applied per harmonic without forming it: H_k P_k = R P_k + U (D_k (U^T P_k)), U = B Phi
/// (c x m), R the residual flexibility, D_k the modal receptances (HYBRID.md §4).
///
/// **The preconditioner.** With K the time mean of dlaw/dg per row (diagonal, the harmonic-diagonal
/// part of dP/dG), M_k = I - H_k K = (I - R K) - U D_k (K U)^T per harmonic. (I - R K) is real and
/// the same for all harmonics: its rows of open pairs are identity rows, so only its block on the
/// closing rows is factorised (LU, n_a^3 / 3). The modal part is a rank-m Woodbury correction:
/// M_k^{-1} b = z + Y D_k (I - S D_k)^{-1} (K U)^T z, z = (I - R K)^{-1} b, Y = (I - R K)^{-1} U,
/// S = (K U)^T Y (m x m). Cost per Newton iteration: n_a^3/3 for the factor, then per GMRES
/// iteration O(c^2 (2H+1) + c (2H+1)^2); memory O(c^2 + c (2H+1)^2 + c (2H+1) restart).
///
/// **Bordered systems.** The continuation's [J j; t^T tau] is solved by the same GMRES with the
/// bordered preconditioner [M j; t^T tau], inverted by the bordering lemma with M (which stays
/// regular at the folds where J is singular).
#include <Eigen/Dense>
#include <complex>
#include <functional>
#include <vector>

#include "core/types.hpp"
#include "reduced/system.hpp"

namespace crackle::sweep {

/// y = A x for GMRES (x and y of the same size; y is resized by the caller).
using LinearAction = std::function<void(const VectorX& x, VectorX& y)>;

/// Result of one GMRES solve.
struct GmresReport {
  int iterations = 0;             ///< Arnoldi steps taken (all restarts)
  double relative_residual = 0.0; ///< ||b - A x|| / ||b|| at the end
  bool converged = false;
};

/// Restarted GMRES with right preconditioning (the residual it monitors is the true one): solves
/// A x = b from x (its initial guess, zero if empty) to ||b - A x|| <= tolerance ||b||, at most
/// `max_iterations` Arnoldi steps, restarting every `restart`.
GmresReport gmres(const LinearAction& apply, const LinearAction& precondition, const VectorX& b, VectorX& x,
                  double tolerance, int max_iterations, int restart);

/// Relative tolerance of an inexact Newton step whose right-hand side has 2-norm `norm`: superlinear
/// forcing min(1e-2, norm), never tighter than half the Newton `tolerance` needs (clamped to [1e-14, 0.5]).
double inexact_forcing(double norm, double tolerance);

/// dP/dG of one pair: rows `first` .. `first + rows - 1`, (rows (2H+1))^2, index component * rows + local
/// row on both sides (component 0 = mean, 2k-1 = cos k, 2k = sin k).
struct PairDerivative {
  Index first = 0;
  int rows = 1;
  MatrixX block;
};

/// Options of the matrix-free solves.
struct KrylovOptions {
  int restart = 120;          ///< Arnoldi vectors kept between restarts
  int max_iterations = 1200;  ///< Arnoldi steps per solve
};

/// Statistics of the Krylov solves of one solver (summed over its linearisations).
struct KrylovStatistics {
  long solves = 0;
  long iterations = 0;
  int max_iterations = 0;     ///< the most Arnoldi steps of one solve
  long factorisations = 0;    ///< preconditioner factors (closing rows' LU)
  long unconverged = 0;       ///< solves that stopped at max_iterations
};

/// The Jacobian J = I - H dP/dG of one harmonic-balance point as an action, with its preconditioner.
/// Unknown layout as HarmonicBalance (index = component * c + row).
/// g = H p per harmonic without forming H (real layout, c rows): R p + U D_k U^T p, or only the modal
/// part without R (`residual` false: the Omega derivative, with the derivatives of D_k in `modal`).
void apply_receptance(const reduced::ReducedSystem& system, const std::vector<Eigen::VectorXcd>& modal,
                      const VectorX& p, VectorX& g, bool residual = true);

class KrylovJacobian {
 public:
  /// `modal` holds D_r(k Omega / nu) for k = 0..H (m entries each; 0 for a rigid mode at k = 0).
  KrylovJacobian(const reduced::ReducedSystem& system, int harmonics, std::vector<Eigen::VectorXcd> modal,
                 std::vector<PairDerivative> derivatives, const KrylovOptions& options);

  Index size() const { return c_ * (2 * H_ + 1); }
  /// y = J x.
  void apply(const VectorX& x, VectorX& y) const;
  /// y = M^{-1} x (the mean-stiffness preconditioner).
  void precondition(const VectorX& x, VectorX& y) const;
  /// Solves J x = b to ||J x - b|| <= tolerance ||b||.
  VectorX solve(const VectorX& b, double tolerance, GmresReport* report = nullptr) const;
  /// Solves [J column; row^T] x = b (n + 1 unknowns, `row` of n + 1 entries) to the relative tolerance.
  VectorX solve_bordered(const VectorX& column, const VectorX& row, const VectorX& b, double tolerance,
                         GmresReport* report = nullptr) const;
  /// Rows with a closed sample (the nonlinear unknowns' rows).
  Index closing_rows() const { return static_cast<Index>(active_.size()); }

 private:
  const reduced::ReducedSystem& system_;
  Index c_ = 0;
  Index m_ = 0;
  int H_ = 0;
  KrylovOptions options_;
  std::vector<Eigen::VectorXcd> modal_;
  std::vector<PairDerivative> derivatives_;
  std::vector<Index> active_;            ///< rows with a nonzero mean stiffness
  VectorX mean_stiffness_;               ///< K per row (c)
  Eigen::PartialPivLU<MatrixX> closed_;  ///< LU of (I - R K) on the active rows
  MatrixX y_;                            ///< (I - R K)^{-1} U, c x m
  MatrixX ku_;                           ///< K U, c x m
  MatrixX coupling_;                     ///< R(:, active) K_a, c x n_a
  std::vector<Eigen::PartialPivLU<Eigen::MatrixXcd>> woodbury_;  ///< I - S D_k per harmonic
  /// Solves (I - R K) z = b for the columns of b (c x any).
  MatrixX solve_mean(const MatrixX& b) const;
};

}  // namespace crackle::sweep
