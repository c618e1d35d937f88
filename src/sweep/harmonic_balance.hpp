#pragma once
/// \file Harmonic balance with alternating frequency/time (AFT) on the condensed reduced model
/// (HYBRID.md §4), Newton with the analytic Jacobian, and the stability (HYBRID.md §5) by the monodromy
/// matrix of the linearisation (every point) and by Hill's method (its check).
///
/// **Unknowns.** The pair-row gaps are periodic in \f$\tau = (\Omega/\nu)t\f$:
/// \f$g(\tau) = G_0 + \sum_{k=1}^{H} (a_k \cos k\tau + b_k \sin k\tau)\f$. They are stored real, block by
/// harmonic component: component 0 is \f$G_0\f$, component \f$2k-1\f$ is \f$a_k\f$, component \f$2k\f$ is
/// \f$b_k\f$, each block holding the c pair rows (`index = component * c + row`). The complex
/// amplitude of harmonic k is \f$a_k - i b_k\f$, so that \f$a\cos + b\sin = \mathrm{Re}[(a - ib)e^{ik\tau}]\f$
/// and the receptances \f$D(\omega) = 1/(\omega_r^2 - \omega^2 + 2i\zeta_r\omega_r\omega)\f$ of HYBRID.md §4
/// apply as written.
///
/// **Load phase.** \f$a(t) = \cos(\Omega t)\f$: the load is the cosine coefficient of harmonic
/// \f$k = \nu\f$ (value 1), every other load coefficient is 0. Output phases are relative to it: an
/// output \f$A\cos(\Omega t + \varphi)\f$ has phase \f$\varphi\f$ (a lagging response has \f$\varphi<0\f$).
///
/// **Rigid modes.** A mode with \f$\omega_r = 0\f$ has no static receptance; it is left out of the
/// k = 0 balance. That is exact only when the mean load it sees is zero,
/// \f$\phi_r^T(\hat f F_0 + B^T P_0) = 0\f$, which the solver does not impose: `Solution::rigid_imbalance`
/// reports it, and the sweep is meant for fixed (or statically balanced) bodies for now.
///
/// **Contact law.** Per sample, normal rows: \f$p = \varepsilon_N A \max(0, -g)\f$ (MODEL.md eq. 25d).
/// With friction (3 rows per pair) the tangential rows follow Coulomb's return mapping (eq. 15,
/// `contact::coulomb_return_mapping`) on the sample-to-sample increments of the tangential gaps,
/// marched over two periods from a zero traction at \f$\tau_0\f$; the second period is kept (its
/// history is that of the periodic orbit once the first period has slipped; in permanent stick
/// the mean tangential force stays the one of that start). Its Jacobian is propagated exactly
/// through the march. The stability is frictionless only (both methods throw with friction).
#include <complex>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "core/choices.hpp"
#include "core/types.hpp"
#include "reduced/system.hpp"
#include "sweep/krylov.hpp"

namespace crackle::sweep {

using ComplexVectorX = Eigen::VectorXcd;
using ComplexMatrixX = Eigen::MatrixXcd;

/// How the Newton and continuation steps solve with the Jacobian (core/choices.hpp: the scene's
/// sweep.solver as it is).
using crackle::LinearSolver;

/// Options of the harmonic-balance solver.
struct HarmonicBalanceOptions {
  LinearSolver solver = LinearSolver::automatic;
  /// automatic: the dense solver up to this many unknowns c(2H+1). Measured crossover (docs/benchmarks.md
  /// 9.1): below it the dense LU is as fast, above it GMRES wins and its cost grows about as c^2.
  Index dense_limit = 1500;
  KrylovOptions krylov;
  int harmonics = 10;        ///< H: harmonics 0..H of the base frequency Omega/nu
  int subharmonic = 1;       ///< nu: 1, or 2 for period-doubled branches
  int time_samples = 0;      ///< N samples per period for AFT; 0 = smallest power of two >= max(4H, 4096)
  double gap_scale = 0.0;    ///< scale of the gap unknowns [m]; 0 = automatic (max |g0|, static gap response)
  /// Drive frequency Omega [rad/s] at which the automatic scale also looks at the linear gap response:
  /// it is at least kDynamicScaleShare of it. A crack outboard of a point load sees almost no static
  /// gap (no moment beyond the load in a cantilever), so the static scale alone is orders too small and
  /// the continuation's arclength is all gap harmonics (thousands of points). 0: the static one only.
  double scale_frequency = 0.0;
  double tolerance = 1e-10;  ///< Newton converged when the scaled residual max norm is below this
  int max_iterations = 50;   ///< Newton iterations per solve
  double top_share = 0.25;   ///< the "top harmonics" are k > (1 - top_share) H (at least k = H)
  double top_threshold = 1e-3;  ///< flag a point whose top-harmonic share of the gap response exceeds this
};

/// Amplitude ratios of one output row to its first order A1 (0 where A1 = 0).
struct OrderRatios {
  double second = 0.0;  ///< A2/A1
  double third = 0.0;   ///< A3/A1
  double half = 0.0;    ///< A1/2 / A1 (0 unless nu = 2)
};

/// One periodic solution.
struct Solution {
  double omega = 0.0;          ///< Omega, the load's angular frequency [rad/s]
  int subharmonic = 1;         ///< nu
  VectorX gaps;                ///< gap harmonics G, c (2H+1) reals [m], layout as in the file comment
  VectorX forces;              ///< pair-force harmonics P, same layout [N]
  ComplexMatrixX modal;        ///< modal amplitudes Q_k = D(omega_k)(Phi^T B^T P_k + Phi^T f F_k), m x (H+1)
  ComplexMatrixX outputs;      ///< Y_k at the probes, o x (H+1) complex (real part = cos coefficient)
  int iterations = 0;          ///< Newton iterations taken
  double residual = 0.0;       ///< final scaled residual max norm
  bool converged = false;
  double top_harmonic_share = 0.0;  ///< ||G_{k > (1-top_share)H}|| / ||G_{k >= 1}|| (H-convergence indicator)
  bool harmonics_flagged = false;   ///< top_harmonic_share > top_threshold: raise H
  double rigid_imbalance = 0.0;     ///< max over rigid modes of |phi_r^T (f F_0 + B^T P_0)| [N], see file comment

  /// Amplitude of output `row` at order `order` of Omega (order 1 = the load frequency; 0.5 needs
  /// nu = 2); 0 for an order the solution does not hold (1/2 with nu = 1, above H/nu).
  double amplitude(Index row, double order) const;
  /// Phase [rad] of output `row` at `order`, relative to the load cos(Omega t); 0 where amplitude() is.
  double phase(Index row, double order) const;
  /// A2/A1, A3/A1, A1/2/A1 of output `row`.
  OrderRatios ratios(Index row) const;
};

/// Stability of a periodic solution (Floquet exponents by the monodromy matrix or Hill's method).
struct Stability {
  ComplexVectorX exponents;    ///< the 2m selected Floquet exponents lambda [1/s]
  ComplexVectorX multipliers;  ///< exp(lambda T), T = 2 pi nu / Omega
  bool stable = true;          ///< every Re lambda <= tolerance
  double max_real_part = 0.0;  ///< max Re lambda [1/s]
  /// Unstable multipliers (|rho| > 1) classified: real > 0 (fold side), real < 0 (period-doubling
  /// side), complex pairs (Neimark-Sacker side).
  int unstable_positive = 0;
  int unstable_negative = 0;
  int unstable_complex = 0;
  /// The exponent of largest real part and its Hill eigenvector: modal harmonics s_k of the base
  /// frequency Omega/nu, m x (2H+1), column k + H for k = -H..H (delta q = Re e^{lambda t} sum s_k e^{ik Omega t/nu}).
  std::complex<double> critical_exponent;
  ComplexMatrixX critical_mode;
};

/// The linearisation of the scaled residual at one point: J = dr/dG s (= I - H dP/dG) and dr/dOmega,
/// with the solves Newton and the continuation need. Dense (LU, reused while the bordering is the
/// same) or matrix-free (GMRES, krylov.hpp) as HarmonicBalance::matrix_free() says.
class Linearization {
 public:
  virtual ~Linearization() = default;
  /// dr/dOmega [1/(rad/s)], empty unless asked for.
  const VectorX& d_omega() const { return d_omega_; }
  /// Solves J x = b; `tolerance` is the relative residual an iterative solve stops at.
  virtual VectorX solve(const VectorX& b, double tolerance) = 0;
  /// Solves [J column; row^T] x = b (n + 1 unknowns; `row` has n + 1 entries).
  virtual VectorX solve_bordered(const VectorX& column, const VectorX& row, const VectorX& b, double tolerance) = 0;

 protected:
  VectorX d_omega_;
};

/// Harmonic balance of a reduced system. Borrows the system: it must outlive this object. The
/// constructor makes the FFTW plans (FFTW's planner is not thread-safe: construct from one thread);
/// the const members may then run concurrently.
class HarmonicBalance {
 public:
  HarmonicBalance(const reduced::ReducedSystem& system, const HarmonicBalanceOptions& options);
  ~HarmonicBalance();
  HarmonicBalance(const HarmonicBalance&) = delete;
  HarmonicBalance& operator=(const HarmonicBalance&) = delete;

  Index n_rows() const;             ///< c, pair rows
  int n_harmonics() const;          ///< H
  int n_samples() const;            ///< N
  Index n_unknowns() const;         ///< c (2H+1)
  double gap_scale() const;         ///< [m]
  const HarmonicBalanceOptions& options() const;

  /// The solution without contact (p = 0): the receptance response, a good first guess where the
  /// response is nearly linear.
  VectorX linear_gaps(double omega) const;

  /// Newton from `guess` (gap harmonics [m]; empty = linear_gaps(omega)). Throws SolverError if
  /// Newton does not converge.
  Solution solve(double omega, const VectorX& guess = VectorX()) const;

  /// Scaled residual r = (G - g0 delta_k0 - H P(G) - E F) / s at gaps G [m].
  VectorX residual(double omega, const VectorX& gaps) const;
  /// Jacobian dr/dG * s (dimensionless, = I - H dP/dG) and, if `d_omega` is not null, dr/dOmega.
  MatrixX jacobian(double omega, const VectorX& gaps, VectorX* d_omega = nullptr) const;

  /// Whether the solves are matrix-free (LinearSolver::krylov, or automatic above dense_limit).
  bool matrix_free() const;
  /// The linearisation at (Omega, G [m]), with dr/dOmega when `d_omega`. Matrix-free, it never forms
  /// the c(2H+1) square Jacobian (jacobian() does: use it on small problems only).
  std::unique_ptr<Linearization> linearize(double omega, const VectorX& gaps, bool d_omega) const;
  /// GMRES statistics summed over this solver's linearisations so far (zeros when dense).
  KrylovStatistics krylov_statistics() const;
  /// Bytes the solver needs at least for c pair rows, m modes and H harmonics, dense or
  /// matrix-free (the Jacobian and its factor or the Krylov basis and the preconditioner's factor,
  /// the receptances and the AFT samples).
  static double memory_bytes(Index rows, Index modes, int harmonics, bool matrix_free,
                             const KrylovOptions& krylov = KrylovOptions());
  /// Whether the options select the matrix-free solver for c pair rows.
  static bool selects_matrix_free(const HarmonicBalanceOptions& options, Index rows);

  /// Harmonics of the pair forces P(G) by AFT (same layout as the gaps) [N].
  VectorX pair_forces(const VectorX& gaps) const;

  /// Fills forces, modal amplitudes, outputs and the H-convergence indicator of a converged point.
  void complete(Solution& solution) const;

  /// Hill's method (HYBRID.md §5) on a converged solution. `tolerance` on Re lambda [1/s]
  /// (0 = 1e-6 times the lowest nonzero modal frequency).
  Stability hill_stability(const Solution& solution, double tolerance = 0.0) const;

  /// Floquet multipliers of the same linearisation (frictionless contact stiffness condensed through
  /// the massless boundary, HYBRID.md §5) from its monodromy matrix over one base period: the
  /// condensed stiffness is held piecewise constant around the N AFT samples of the orbit, so each run
  /// of samples with one active set propagates by one matrix exponential of size 2m. Exact for the
  /// sampled orbit (no harmonic truncation) and about a hundred times cheaper than Hill's
  /// eigen-solve (~1.4 ms against ~0.12 s per point on the beam, m = 3, H = 15); the exponents are log(rho)/T (Im in (-w0/2, w0/2]), the critical
  /// mode in Hill's layout (harmonics of e^{-lambda t} q(t)). Same `tolerance` as hill_stability().
  Stability floquet_stability(const Solution& solution, double tolerance = 0.0) const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

/// Gap harmonics truncated or zero-padded to `harmonics` (rows = c): restart a point with more
/// harmonics when `Solution::harmonics_flagged` says so.
VectorX resize_harmonics(const VectorX& gaps, Index rows, int harmonics);

/// A first guess for the nu = 2 branch born at a period doubling of `period_one` (nu = 1): its gaps
/// on the even harmonics of Omega/2 and the critical Hill eigenvector of `stability`, mapped to the
/// gaps through B Phi, on the odd ones, scaled so that its largest gap harmonic is `amplitude` [m].
/// `harmonics` is H of the nu = 2 solver (2H of the nu = 1 one keeps the same resolution).
VectorX period_doubled_guess(const reduced::ReducedSystem& system, const Solution& period_one,
                             const Stability& stability, int harmonics, double amplitude);

/// Options of the pseudo-arclength continuation.
struct ContinuationOptions {
  double initial_step = 0.02;   ///< arclength step in the scaled space (x = G/s, Omega/Omega_from)
  double min_step = 1e-6;
  double max_step = 0.2;
  int target_iterations = 4;    ///< step adapted towards this corrector iteration count
  int max_points = 2000;
  bool stability = true;        ///< Floquet multipliers (HarmonicBalance::floquet_stability) at every point
  /// Where the unstable counts change between two points (a fold, a bifurcation), also Hill's method
  /// at both: BranchPoint::hill_check says whether it finds the same counts.
  bool hill_at_events = true;
  bool hill_everywhere = false; ///< Hill's method instead of the monodromy at every point (slow: a reference)
  /// Frequencies [rad/s] where the branch is also solved exactly: where a step crosses one (no fold
  /// between its ends), Newton at that fixed Omega from the step's chord gives a point, recorded between
  /// the step's two. A value read there is the solution's own, not an interpolation between points
  /// whose places move with the step control (a forward model differentiated in its parameters needs
  /// that). Skipped where Newton fails or lands farther from the chord than the step is long.
  std::vector<double> solve_at;
};

/// A point of a branch.
struct BranchPoint {
  Solution solution;
  Stability stability;          ///< Floquet (or Hill's); empty when ContinuationOptions::stability is false
  double tangent_omega = 0.0;   ///< d Omega / ds of the unit tangent (sign change = fold)
  bool fold = false;            ///< a fold (turning point in Omega) lies between the previous point and this one
  bool period_doubling = false; ///< a multiplier crossed -1 between the previous point and this one
  bool stability_change = false;///< the number of unstable multipliers changed
  /// With ContinuationOptions::hill_at_events, where the unstable counts changed: 1 when Hill's
  /// method finds the same counts as the monodromy at this point and the previous one, 0 when not;
  /// -1 where it did not run.
  int hill_check = -1;
};

/// Progress callback: the point just added; return false to stop.
using ProgressCallback = std::function<bool(const BranchPoint&)>;

/// Pseudo-arclength continuation in (G, Omega) from `omega_from` to `omega_to` [rad/s], starting
/// from the linear solution at `omega_from` (or from `start` when given). Tangent predictor,
/// Keller's corrector with the arclength constraint, step adapted to the iteration count; passes
/// folds. Ends when Omega leaves [min, max] of the two ends or after max_points; if the corrector
/// fails down to min_step it returns the branch so far (check the last point's Omega). Hill's
/// method needs a frictionless system (set `stability` off with friction).
std::vector<BranchPoint> continue_branch(const HarmonicBalance& hb, double omega_from, double omega_to,
                                         const ContinuationOptions& options = ContinuationOptions(),
                                         const ProgressCallback& progress = ProgressCallback(),
                                         const Solution* start = nullptr);

/// The first point of a branch that crosses the branch of `base` at a bifurcation: Keller's corrector
/// (Omega free) from `base` along the gap direction `direction` (same layout as the gaps), at the point
/// whose gaps have moved by `step` [m] along the unit direction. For a period doubling, `hb` is the
/// nu = 2 solver, `base` the period-one solution near the doubling written in its harmonics and
/// `direction` the critical mode on the odd ones (period_doubled_guess): the period-one branch has no
/// odd part, so the constraint keeps the corrector off it. Throws SolverError when the corrector does
/// not converge within the solver's max_iterations.
Solution branch_off(const HarmonicBalance& hb, const Solution& base, const VectorX& direction, double step,
                    const ContinuationOptions& options = ContinuationOptions());

}  // namespace crackle::sweep
