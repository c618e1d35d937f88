#pragma once
/// \file Time integration of the reduced model (HYBRID.md §3): average-acceleration Newmark per mode,
/// the massless crack boundary (residual flexibility) instantaneous, the penalty contact law and
/// Coulomb's return mapping closed per step through the step compliance W.
///
/// **Scheme.** Per mode r (unit modal mass, d_r = 2 zeta_r omega_r = alpha + beta omega_r^2, which is
/// alpha alone for a rigid mode):
/// \f[ \ddot q_{n+1} + d\,\dot q_{n+1} + \omega^2 q_{n+1} = \phi^T(\hat f\,a(t_{n+1}) + B^T p_{n+1}),\quad
///     q_{n+1} = q_n + h\dot q_n + \tfrac{h^2}{4}(\ddot q_n + \ddot q_{n+1}),\quad
///     \dot q_{n+1} = \dot q_n + \tfrac{h}{2}(\ddot q_n + \ddot q_{n+1}). \f]
/// The end-of-step modal state is affine in the end-of-step pair forces,
/// \f$q_{n+1} = \tilde q + S\,(B\Phi)^T p_{n+1}\f$ with \f$S_r = h^2 / (4 + 2 d_r h + \omega_r^2 h^2)\f$, so
/// the gaps are \f$g_{n+1} = \tilde g + W p_{n+1}\f$, \f$W = B\Phi\,S\,(B\Phi)^T + R\f$ (formed once per step
/// size). The contact law closes a small piecewise-linear problem on W (see ReducedIntegrator::step).
///
/// **Switching steps.** With the massless boundary the pair forces are a function p(q) of the modal
/// state, the gradient of a convex, piecewise-quadratic potential V(q) (penalty + residual strain).
/// While the closed set holds over a step, V is one quadratic along it and the trapezoidal rule
/// conserves energy exactly; in a step where a pair closes or opens it does not, and when the
/// closed system's stiffest frequency (reduced_closed_max_frequency, the penalty in series with the
/// small residual flexibility) is far above the highest retained mode the step resolves, those
/// errors are O(1) per closure and can pump energy without bound (measured: a 9-pair delamination
/// with a 20 x stiffer closed system grew to 5e5 m; docs/benchmarks.md section 8.5). A switching
/// step therefore conserves energy: its velocity gets the jump lambda (B Phi)^T (p_{n+1} - p_n)
/// along the contact-force change that zeroes the step's energy error (a quadratic in lambda; the
/// position, the forces and the gaps are untouched, in the spirit of the velocity update of
/// energy-conserving impact schemes). A gain that no such jump removes is rare: the step is then
/// redone with the end-of-step force p_{n+1} in place of the trapezoidal mean, which cannot gain
/// energy (convexity of V: V(q_n) >= V(q_{n+1}) + grad V(q_{n+1}) . (q_n - q_{n+1})), and corrected
/// the same way. Counted: switching_steps(), implicit_switching_steps(), unconserved_switching_steps().
///
/// **Energy balance** (exact to round-off for the linear part, see ReducedEnergy): the displacement is
/// \f$u = \Phi q + G_{res}(B^T p + \hat f a)\f$ and \f$\Phi^T K G_{res} = 0\f$, so the strain energy splits into
/// the modal part \f$\tfrac12\sum\omega_r^2 q_r^2\f$ and the residual part
/// \f$\tfrac12 (B^Tp + \hat f a)^T G_{res} (B^Tp + \hat f a)\f$. Its load-only term
/// \f$\tfrac12 a^2 \hat f^T G_{res}\hat f\f$ equals the external work done through it (massless, so it is
/// stored and returned instantly) and is left out of both sides.
#include <functional>
#include <vector>

#include <Eigen/Cholesky>
#include <Eigen/Core>

#include "core/types.hpp"
#include "reduced/system.hpp"

namespace crackle::reduced {

/// Energy account of the reduced model since the initial state [J]. Conserved quantity:
/// `total()` = stored + dissipated - external work, constant in exact arithmetic.
struct ReducedEnergy {
  double kinetic = 0.0;          ///< \f$\tfrac12 \dot q^T\dot q\f$ (modal masses are 1)
  double modal_strain = 0.0;     ///< \f$\tfrac12 \sum_r \omega_r^2 q_r^2\f$
  double residual_strain = 0.0;  ///< \f$\tfrac12 p^T R p + a\, p^T r_f\f$ (the load-only term cancels, see file doc)
  double penalty = 0.0;          ///< normal \f$\tfrac12 \varepsilon_N A g_N^2\f$ (closed) + tangential \f$A|t_T|^2/(2\varepsilon_T)\f$
  double external_work = 0.0;    ///< trapezoidal: \f$\sum \bar a\,(\phi^T\hat f\cdot\Delta q + r_f\cdot\Delta p)\f$
  double damping_dissipation = 0.0;   ///< \f$\sum_n h \sum_r d_r \bar{\dot q}_r^2\f$ (exact for the scheme)
  double friction_dissipation = 0.0;  ///< Coulomb slip dissipation (contact::coulomb_return_mapping)

  double stored() const { return kinetic + modal_strain + residual_strain + penalty; }
  double total() const { return stored() + damping_dissipation + friction_dissipation - external_work; }
};

/// Options of the per-step contact solve.
struct ReducedIntegratorOptions {
  int max_contact_iterations = 100;  ///< frictionless: active-set iterations per step before SolverError
  /// Friction: converged when \f$|p - P(z(p))|_\infty \le\f$ force_tolerance \f$\max(|p|_\infty, |P|_\infty)\f$.
  double force_tolerance = 1e-9;
  double min_line_search_step = 1.0 / 1024.0;  ///< friction Newton: smallest damping factor tried
  int newton_iterations = 8;     ///< friction: Newton solves before (and after each) Gauss-Seidel round
  int gauss_seidel_sweeps = 20;  ///< friction: projected Gauss-Seidel sweeps per round
  int max_gauss_seidel_rounds = 100;  ///< friction: rounds before SolverError
  /// Switching steps (a pair closes or opens) conserve energy by a velocity jump along the
  /// contact-force change (see ReducedIntegrator::step); false keeps the plain trapezoidal contact
  /// force, which gains energy without bound when the closed system's stiffest frequencies are not
  /// resolved by the step (kept to show exactly that in the tests).
  bool conserve_switching_energy = true;
  /// Relative energy-balance error (energy_error()) above which step() throws SolverError instead of
  /// going on with a wrong state: the full model's guard (transient::TransientOptions::energy_tolerance).
  /// 0 turns the check off.
  double energy_tolerance = 0.05;
};

/// Time integrator of a ReducedSystem. Borrows the system: it must outlive the integrator.
///
/// **Contact solve per step.** Unknowns: the forces of the closed pairs' rows. Frictionless: the
/// linear complementarity problem \f$p \ge 0,\ K^{-1}p + g \ge 0,\ p^T(K^{-1}p + g) = 0\f$ with
/// \f$g = \tilde g + W p\f$ (K = eps_N A, the penalty of eq. 25d), one solution (H = K^{-1} + W is
/// symmetric positive definite). A primal-dual active set, warm-started from the previous step's
/// closed rows: each iteration solves \f$H_{AA}\,p_A = -\tilde g_A\f$, releases the rows with p <= 0 and
/// activates the open rows with g < 0, in stages for the first iterations (only the rows penetrated
/// at least half as deep as the deepest; the forces of those lift the others or leave them to the
/// next iteration). The Cholesky factor of \f$H_{AA}\f$ is kept from step to step and follows the set:
/// a set change cuts it before the first released row (the rows before keep their factor) and
/// appends the kept rows after it with the entering ones as one block (a triangular solve and the
/// factor of the Schur complement), instead of refactorising the whole set. With friction: the
/// condensed pair equations \f$F(p) = p - P(z(p)) = 0\f$,
/// z the trial forces (normal \f$-\varepsilon_N A g_N\f$, tangential the elastic predictor of the step's
/// tangential increment) and P the penalty (eq. 25d) with Coulomb's return mapping (eq. 15,
/// contact::coulomb_return_mapping). A semi-smooth Newton with its generalized Jacobian (Cholesky on
/// the stick-only block, cached; LU while a pair slips) and an Armijo line search, warm-started from
/// the previous step; where it stalls at the kinks of P (states changing on many coupled pairs) it
/// restarts as rounds of projected Gauss-Seidel sweeps over the pairs on \f$K^{-1} + W\f$ (robust,
/// linear), each round followed by a Newton finish kept only if it converges.
///
/// **Cost.** Setup: W in O(c^2 m). Per step: O(c m) for the free gaps, O(c |A|) per iteration for
/// the gaps and O(|A|^2) for the solve. Frictionless factor work per set change: appending b rows
/// after the first k kept ones costs \f$k^2 b + k b^2 + b^3/3\f$ (total_factor_work()), so a step whose
/// set only grows or loses its last rows pays for the new rows only, and one that releases an early
/// row refactorises what follows it. The sets are genuinely large at impacts: with long steps (few
/// modes) the whole crack can close for a step (bench_reduced, 1081 pairs, 10 modes: final sets of
/// 400-560 rows a few times per period, a mean of 20). Measured against the former dense
/// refactorisation of every new set: 0.5-0.7 of its factorisation work on the tests' cases, 1.5-2x
/// less CPU per step at 300-1081 pairs and 10 modes, no change at 40 modes (docs/benchmarks.md 8.3).
/// With friction: an O((3|A|)^3) LU per Newton solve while any pair slips (a Cholesky factor,
/// cached, while all stick), and O(c^2) per Gauss-Seidel sweep.
class ReducedIntegrator {
 public:
  using LoadFunction = std::function<double(double)>;

  /// \param system the reduced model (borrowed)  \param time_step h > 0 [s]
  /// \param load a(t), the time function of the load shape. Throws InputError on inconsistent sizes.
  ReducedIntegrator(const ReducedSystem& system, double time_step, LoadFunction load,
                    ReducedIntegratorOptions options = {});

  /// Sets the modal state at `time`, solves the (massless, static) contact problem there for
  /// consistent pair forces (tangential forces start at 0, the current slip as reference), the
  /// initial acceleration, and resets the energy account. The default state is rest at t = 0.
  void set_initial_state(const VectorX& modal_displacement, const VectorX& modal_velocity, double time = 0.0);

  /// Advances one step h. Throws SolverError (naming step and time) if the contact solve does not
  /// converge, the state is not finite or the energy balance fails (options' energy_tolerance).
  void step();
  /// Advances `n_steps` steps.
  void advance(Index n_steps);

  double time() const { return time_; }
  double time_step() const { return time_step_; }
  Index n_steps_taken() const { return step_count_; }

  const VectorX& modal_displacement() const { return q_; }
  const VectorX& modal_velocity() const { return v_; }
  const VectorX& modal_acceleration() const { return acc_; }
  /// Pair-row forces p (c entries, on the minus node, see system.hpp) [N].
  const VectorX& pair_forces() const { return p_; }
  /// Pair-row gaps g = g0 + B Phi q + R p + r_f a (c entries; g0 on normal rows only) [m].
  const VectorX& gaps() const { return g_; }

  /// Probe outputs y = C Phi q + C G_res B^T p + C G_res f_hat a(t) [m].
  VectorX outputs() const;
  /// One output row of outputs().
  double output(Index row) const;

  Index n_closed() const;    ///< pairs with a positive normal force
  Index n_slipping() const;  ///< closed pairs slipping in the last step
  /// Contact state of `pair` after the last step, as contact::PenaltyContact::pair_state: 0 open (no
  /// normal force), 1 closed and sticking (the solve's return mapping), 2 closed and slipping (always
  /// without friction: the faces slide freely).
  int pair_state(Index pair) const;
  double closed_fraction() const;  ///< n_closed / n_pairs (0 without pairs)

  const ReducedEnergy& energy() const { return energy_; }
  /// |total() - total at the initial state| relative to the largest energy magnitude seen so far
  /// (stored, external work or dissipated).
  double energy_error() const;

  /// Contact iterations of the last step (1 = the warm-started guess was right).
  int last_iterations() const { return last_iterations_; }
  /// Contact iterations and Cholesky/LU factorisations (from scratch) summed over all steps.
  long total_iterations() const { return total_iterations_; }
  long total_factorizations() const { return total_factorizations_; }
  /// Steps in which a pair closed or opened, and of them the ones whose energy could not be
  /// conserved exactly (see step()); the energy the switching corrections removed or added [J].
  long switching_steps() const { return switching_steps_; }
  long implicit_switching_steps() const { return implicit_switching_steps_; }
  long unconserved_switching_steps() const { return unconserved_switching_steps_; }
  double switching_correction() const { return switching_correction_; }
  /// Frictionless: rows appended to or cut from the cached Cholesky factor (not from scratch), summed
  /// over all steps.
  long total_factor_updates() const { return total_factor_updates_; }
  /// Frictionless: floating-point operations of the factorisations and factor updates, summed over all steps
  /// (counted from the block sizes: |A|^2 b + |A| b^2 + b^3/3 to append b rows to |A|, so |A|^3/3 for
  /// a factorisation from scratch): the load-independent share of the cost.
  double total_factor_work() const { return total_factor_work_; }
  /// Friction: rounds of projected Gauss-Seidel sweeps the Newton solve needed, summed over all steps.
  long total_gauss_seidel_rounds() const { return total_gauss_seidel_rounds_; }
  /// Rows of the factorised blocks summed over all factorisations (their mean size: divide by
  /// total_factorizations()).
  long total_factorized_rows() const { return total_factorized_rows_; }
  /// Rows of the largest factorised block so far (frictionless: the largest set the updated factor held).
  long largest_factorized_rows() const { return largest_factorized_rows_; }
  /// The step compliance W = B Phi S (B Phi)^T + R (c x c) [m/N].
  const MatrixX& step_compliance() const { return w_; }

 private:
  enum class PairState { kOpen, kStick, kSlip };

  /// One pair's block of dP/dz (see friction_newton_direction): open, stick (identity), or slip along
  /// `direction` (unit, in the tangent rows) with `radial_ratio` = mu z_N / |z_T|.
  struct FrictionJacobian {
    PairState state = PairState::kOpen;
    Eigen::Vector2d direction = Eigen::Vector2d::Zero();
    double radial_ratio = 0.0;
  };

  /// A friction iterate: forces p, their gaps, the projection P(z(p)), its Jacobian, |p - P|_inf.
  struct FrictionIterate {
    VectorX force, gap, projected;
    std::vector<FrictionJacobian> jacobians;
    double residual = 0.0;
  };

  /// A step's end state and energy terms before it is committed (see trial_step).
  struct StepTrial {
    VectorX q, v, acc;
    double external = 0.0, friction = 0.0;                       ///< the step's works [J]
    double modal_strain = 0.0, residual_strain = 0.0, penalty = 0.0;  ///< end-state energies [J]
  };

  /// Cholesky factor \f$L L^T = H_{AA}\f$ of the frictionless step matrix \f$H = K^{-1} + W\f$ over an
  /// ordered row set A, grown by appending blocks of rows and shrunk by cutting its tail.
  class ActiveSetFactor {
   public:
    Index size() const { return static_cast<Index>(rows_.size()); }
    const std::vector<Index>& rows() const { return rows_; }
    void clear() { rows_.clear(); }
    /// Appends `rows`: `coupling` = H over (rows(), rows), `block` = H over (rows, rows): a triangular
    /// solve and the Cholesky factor of the Schur complement, O(|A|^2 b + b^3/3) for b rows. False
    /// (factor unchanged) if the block would not be positive definite.
    bool append(const std::vector<Index>& rows, const MatrixX& coupling, const MatrixX& block);
    /// Keeps the first `size` rows (their factor does not depend on the rows after them).
    void truncate(Index size) { rows_.resize(static_cast<std::size_t>(size)); }
    /// Solves \f$H_{AA} x = b\f$.
    VectorX solve(const VectorX& rhs) const;

   private:
    std::vector<Index> rows_;
    MatrixX lower_;  ///< capacity x capacity; the leading size() x size() block holds L
  };

  struct CachedFactor {
    std::vector<Index> rows;
    Eigen::LLT<MatrixX> factor;
    bool valid = false;
  };

  bool friction_active() const;
  void solve_normal(const MatrixX& w, const VectorX& free_gap, ActiveSetFactor& factor);
  /// The step's contact solve on w_ from the free gaps (friction or frictionless, warm-started from p_).
  void solve_contact(const VectorX& free_gap);
  /// Swaps w_ and its factors with the end-of-step-force step's (switching_w_ and its factors).
  void swap_switching_compliance();
  void solve_with_friction(const VectorX& free_gap);
  /// Gaps g(p), the projection P(z(p)) of the trial forces (penalty and return mapping) and its
  /// Jacobian blocks; returns |p - P|_inf [N].
  double friction_map(const VectorX& p, const VectorX& free_gap, VectorX& gap, VectorX& projected,
                      std::vector<FrictionJacobian>& jacobians) const;
  void evaluate(const VectorX& free_gap, FrictionIterate& iterate) const;
  bool friction_converged(const FrictionIterate& iterate) const;
  /// At most `budget` damped Newton steps; true once converged. Counts the linear solves.
  bool friction_newton(const VectorX& free_gap, int budget, FrictionIterate& iterate, int& solves);
  /// `sweeps` projected Gauss-Seidel sweeps over the pairs, then re-evaluates the iterate.
  void friction_gauss_seidel(const VectorX& free_gap, int sweeps, FrictionIterate& iterate);
  /// The semi-smooth Newton direction for F = p - P at p (residual F).
  VectorX friction_newton_direction(const VectorX& p, const VectorX& residual,
                                    const std::vector<FrictionJacobian>& jacobians);
  /// (B Phi)^T p: the modal force of the pair forces p (over their nonzero rows).
  VectorX modal_pair_force(const VectorX& p) const;
  /// Whether a pair closed or opened in the step (its normal force changed sign).
  bool closed_set_changed() const;
  /// The end-of-step state of one step from the current one, before it is committed: `p_`, `g_` are
  /// set (from the warm start p_old_), the energies of the end state and the step's work returned.
  /// `end_of_step_force`: the step's contact force is p_{n+1} instead of (p_n + p_{n+1}) / 2.
  void trial_step(double a1, bool end_of_step_force, StepTrial& trial);
  /// Switching step: the velocity jump along the contact-force change that makes the trial step
  /// conserve energy; false if there is none (with `best_effort`, the jump that comes closest is
  /// applied).
  bool conserve_switching_energy(StepTrial& trial, bool best_effort);
  double penalty_energy() const;
  double residual_strain(const VectorX& p, double a) const;
  void update_energy_scale();
  [[noreturn]] void fail(const char* what) const;

  const ReducedSystem& system_;
  double time_step_;
  LoadFunction load_;
  ReducedIntegratorOptions options_;

  VectorX omega2_;       ///< omega_r^2
  MatrixX pair_modes_transposed_;  ///< (B Phi)^T, m x c: a pair row's modal force is a contiguous column
  VectorX damping_;      ///< d_r = alpha + beta omega_r^2
  VectorX denominator_;  ///< 1 + d_r h/2 + omega_r^2 h^2/4
  VectorX normal_stiffness_, tangential_stiffness_;  ///< eps A per pair [N/m]
  VectorX row_compliance_;  ///< friction: 1 / (eps A) per row (the Newton merit's scaling)
  MatrixX w_;
  MatrixX switching_w_;             ///< W + B Phi S (B Phi)^T, formed at the first end-of-step-force step
  CachedFactor switching_factor_;   ///< its friction factor
  ActiveSetFactor switching_normal_factor_;  ///< its frictionless factor
  long switching_steps_ = 0;
  long implicit_switching_steps_ = 0;
  long unconserved_switching_steps_ = 0;
  double switching_correction_ = 0.0;

  double time_ = 0.0;
  double load_value_ = 0.0;
  Index step_count_ = 0;
  VectorX q_, v_, acc_;
  VectorX p_, g_;  ///< current pair forces and gaps (also the friction history of the next step)
  VectorX p_old_, g_old_;
  std::vector<PairState> state_;
  CachedFactor step_factor_;   ///< friction: the stick-only Newton block
  ActiveSetFactor normal_factor_;  ///< frictionless: H_AA of the step's active set

  ReducedEnergy energy_;
  double initial_total_ = 0.0;
  double energy_scale_ = 0.0;
  int last_iterations_ = 0;
  long total_iterations_ = 0;
  long total_factorizations_ = 0;
  long total_factor_updates_ = 0;
  double total_factor_work_ = 0.0;
  long total_gauss_seidel_rounds_ = 0;
  long total_factorized_rows_ = 0;
  long largest_factorized_rows_ = 0;
};

/// Default steps per period of the highest frequency to resolve, from the receptance test: at 40
/// the average-acceleration scheme's frequency error is (omega h)^2/12 = 2e-3 (see tests).
inline constexpr int kDefaultStepsPerPeriod = 40;

/// Recommended step h = 1 / (steps_per_period * f), f the larger of `max_frequency_hz` (the highest
/// harmonic wanted) and the highest retained mode's frequency [s]. The scheme is unconditionally
/// stable: this is an accuracy choice. Throws InputError if steps_per_period < 1 or f is not positive.
double reduced_time_step(const ReducedSystem& system, double max_frequency_hz,
                         int steps_per_period = kDefaultStepsPerPeriod);

/// Highest natural frequency [Hz] of the reduced model's all-closed linear limit: every pair row with
/// a penalty (normal eps_N A; tangential eps_T A with friction, stuck) in series with the residual
/// flexibility, \f$K_c = \Omega^2 + (B\Phi)^T (R + K_p^{-1})^{-1} B\Phi\f$. Cost O(c^3/3 + m^3) once.
/// Note: the energy error of an impact is O(h^2) with a scale set by the pair's local stiffness
/// against the mass near it, which the few retained modes do not see: it can be far above this
/// frequency (tests: resolving the full model's closed frequency with 80 steps keeps the chattering
/// energy error < 1e-3 over 1000 periods; resolving this one leaves 1e-2).
double reduced_closed_max_frequency(const ReducedSystem& system);

}  // namespace crackle::reduced
