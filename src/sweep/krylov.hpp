#pragma once
/// \file The matrix-free linear solver of the harmonic balance for many crack pairs (HYBRID.md §4):
/// restarted GMRES on the Jacobian J = I - H dP/dG applied as an action, preconditioned by the
/// linear part with a mean contact stiffness corrected by the harmonic blocks of the pairs that
/// breathe, so that no c(2H+1) square matrix is ever formed.
///
/// **The action.** dP/dG is block diagonal per pair (the force harmonics of a pair depend on its own
/// gap harmonics only): one (r(2H+1))^2 block per pair with a closed sample (r rows per pair), zero
/// for the pairs that stay open over the period, so they drop out of the nonlinear coupling exactly.
/// H is applied per harmonic without forming it: H_k P_k = R P_k + U (D_k (U^T P_k)), U = B Phi
/// (c x m), R the residual flexibility, D_k the modal receptances (HYBRID.md §4).
///
/// **The mean stiffness.** With K the time mean of dlaw/dg per row (diagonal, the harmonic-diagonal
/// part of dP/dG), M_k = I - H_k K = (I - R K) - U D_k (K U)^T per harmonic. (I - R K) is real and
/// the same for all harmonics: its rows of open pairs are identity rows, so only its block on the
/// closing rows is factorised (LU, n_a^3 / 3). The modal part is a rank-m Woodbury correction:
/// M_k^{-1} b = z + Y W_k (K U)^T z, z = (I - R K)^{-1} b, Y = (I - R K)^{-1} U, S = (K U)^T Y (m x m),
/// W_k = D_k (I - S D_k)^{-1}. Exact when every pair is closed or open over the whole period.
///
/// **The pair blocks** (KrylovPreconditioner::pair_blocks, the default). A pair closed for part of
/// the period (n_b "breathing" pairs) couples its harmonics: E = dP/dG - K is nonzero on its rows
/// only, one (r(2H+1))^2 block E_p per breathing pair, and J = M - H E. With Z_k = M_k^{-1} H_k =
/// (I - R K)^{-1} R + Y W_k Y^T (symmetric), Woodbury over the breathing rows P gives exactly
/// J^{-1} = M^{-1} + Z P (I - E_b P^T Z P)^{-1} E_b P^T M^{-1}. The preconditioner keeps the
/// diagonal blocks F_p of P^T Z P only (each pair's harmonics with its own flexibility, screened by
/// the mean stiffness of all the others): one LU of I - E_p F_p per breathing pair. It is J's exact
/// inverse when one pair breathes; what it leaves out is the harmonic coupling between two breathing
/// pairs through Z. (Products of M^{-1} with the inverses of J's own diagonal pair blocks
/// I - H_pp dP_p/dG_p, multiplicative Schwarz, were measured and dropped: a pair's block without its
/// neighbours' contact made the inexact Newton steps worse at 55 pairs and GMRES stall at 168.)
/// Cost per Newton iteration: n_a^3/3 for the factor, the columns (I - R K)^{-1} R P (2 n_a^2 n_b),
/// n_b (2H+1)^3 for the pair blocks; per GMRES iteration O(c^2 (2H+1) + c (2H+1)^2); memory
/// O(c^2 + c (2H+1)^2 + c (2H+1) restart).
///
/// **Bordered systems.** The continuation's [J j; t^T tau] is solved by the same GMRES with the
/// bordered preconditioner [M j; t^T tau], inverted by the bordering lemma with M (which stays
/// regular at the folds where J is singular).
#include <Eigen/Dense>
#include <complex>
#include <functional>
#include <vector>

#include "core/types.hpp"
#include "linalg/gmres.hpp"
#include "reduced/system.hpp"

namespace crackle::sweep {

using linalg::GmresReport;
using linalg::LinearAction;
using linalg::gmres;

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

/// The preconditioner of the matrix-free solves (krylov.hpp's file comment).
enum class KrylovPreconditioner {
  mean_stiffness,  ///< M = I - H_k K, K the time-mean contact stiffness per row
  pair_blocks,     ///< the mean stiffness corrected by the harmonic blocks of the breathing pairs
};

/// Options of the matrix-free solves.
struct KrylovOptions {
  int restart = 120;          ///< Arnoldi vectors kept between restarts
  int max_iterations = 1200;  ///< Arnoldi steps per solve
  KrylovPreconditioner preconditioner = KrylovPreconditioner::pair_blocks;
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
  /// y = M^{-1} x (the preconditioner of KrylovOptions::preconditioner).
  void precondition(const VectorX& x, VectorX& y) const;
  /// y = (I - H_k K)^{-1} x (the mean-stiffness part).
  void precondition_mean(const VectorX& x, VectorX& y) const;
  /// Pairs closed for part of the period (their pair blocks correct the mean stiffness).
  Index breathing_pairs() const { return static_cast<Index>(breathing_.size()); }
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
  // the pair blocks (KrylovPreconditioner::pair_blocks)
  std::vector<std::size_t> breathing_;        ///< entries of derivatives_ with E_p = dP_p/dG_p - K_p != 0
  std::vector<Index> breathing_offset_;       ///< their first row among breathing_rows_
  std::vector<Index> breathing_rows_;         ///< their rows (n_b)
  std::vector<MatrixX> deviation_;            ///< E_p, (r(2H+1))^2 each
  MatrixX flexibility_;                       ///< (I - R K)^{-1} R(:, breathing rows), c x n_b
  MatrixX y_breathing_;                       ///< Y's breathing rows, n_b x m
  std::vector<Eigen::MatrixXcd> modal_flexibility_;  ///< W_k = D_k (I - S D_k)^{-1}, m x m per harmonic
  std::vector<Eigen::PartialPivLU<MatrixX>> local_;  ///< LU of I - E_p F_p per breathing pair
  void setup_pair_blocks();
  /// Solves (I - R K) z = b for the columns of b (c x any).
  MatrixX solve_mean(const MatrixX& b) const;
};

}  // namespace crackle::sweep
