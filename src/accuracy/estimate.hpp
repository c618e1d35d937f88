#pragma once
/// \file Error estimates of computed quantities by refinement (DETECTION.md sec. 1): Richardson
/// extrapolation with the observed order over three levels (eqs. 1-3), a one-refinement estimate
/// with a known order (time step, penalty) or none (modal truncation), and the sum of the
/// components. Pure numerics on numbers: which runs make the levels is the caller's business.
#include <string>
#include <vector>

namespace crackle::accuracy {

/// Safety factors of the grid convergence index (Roache; Celik et al. 2008): three levels with a
/// sane observed order, and everything else (two levels, an order out of range).
inline constexpr double kSafetyFactor = 1.25;
inline constexpr double kCautiousSafetyFactor = 3.0;

/// Element-order levels read geometrically (the order raised by one per level, the ratio e): the
/// observed "order" is the rate ln((Q1 - Q2)/(Q2 - Q3)) per order, sane when the error at least
/// halves per order (rate ln 2 up to 20). The signatures' mesh part and identify's model error.
inline constexpr double kOrderLevelRatio = 2.718281828459045;
inline constexpr double kOrderRateMin = 0.6931471805599453, kOrderRateMax = 20.0;

/// One error component of one quantity: the estimated error of the value that was run.
struct Component {
  std::string name;           ///< "mesh", "modes", "steps", "penalty", "window"
  double value = 0.0;         ///< the quantity as run
  double refined = 0.0;       ///< the quantity at the (finest) refinement
  double delta = 0.0;         ///< signed relative error estimate of `value`: (Q_true - value) / |value|, times Fs
  double safety_factor = kSafetyFactor;
  double observed_order = 0.0;  ///< 0: not observed (two levels)
  double ratio = 0.0;         ///< (Q1 - Q2) / (Q2 - Q3) of three levels (0: two levels)
  bool asymptotic = true;     ///< the levels look asymptotic (three levels: order in range)
  bool verified = true;       ///< false: the estimate cannot be trusted (see reason)
  std::string reason;         ///< why not verified or not asymptotic
  std::string check;          ///< an independent discretisation it was checked against (checked_against); empty: none
  double check_delta = 0.0;   ///< (Q_check - value) / |value|
  double levels_delta = 0.0;  ///< delta before the check (the levels' own estimate)
  double bound_ratio = 0.0;   ///< window_tail: the slowest decay's ratio per window (0: none given)
};

/// Three levels of a refinement with constant ratio r (coarse Q1, Q2, fine Q3 = the value that was
/// run): observed order (eq. 1), extrapolated value (eq. 2) and the GCI (eq. 3) as a signed error of
/// Q3. `order_range` is the sane range of the observed order; outside it, or for a non-monotone
/// sequence ((Q1 - Q2)/(Q2 - Q3) <= 0), the component is not verified and Fs = 3 is used with the
/// change between the two finest levels.
Component three_level(const std::string& name, double q1, double q2, double q3, double ratio,
                      double order_min, double order_max);

/// Three levels as three_level, but the error of the level that was run, `run` = 1, 2 or 3 (Q1, Q2
/// or Q3 = three_level): Fs (Q_ext - Q_run) / |Q_run|, where the finer levels are refinements of the
/// setting that was run (a modal solve estimated by the next element orders). In the cautious cases
/// Fs = 3 times the change to the next level (for Q3, the change from Q2).
Component three_level_at(const std::string& name, double q1, double q2, double q3, int run, double ratio,
                         double order_min, double order_max);

/// Three levels whose refinement ratio is not constant (Celik et al. 2008): representative cell
/// sizes h1 > h2 > h3 (for example DOFs^-1/3 of p-levels), Q_k = Q* + C h_k^p with p solved from
/// (Q1 - Q2)/(Q2 - Q3) = r32^p (r21^p - 1)/(r32^p - 1) (eq. 1 with non-uniform ratios), Q_ext =
/// Q3 + (Q3 - Q2)/(r32^p - 1) (eq. 2), and the error of level `run` (1, 2 or 3) as three_level_at.
/// Equal ratios give three_level_at exactly. `safety_factor`: Fs with an order in range (3 where the
/// levels are not geometrically similar grids, as p-levels on one grid: Roache's value for a study
/// whose asymptotic range the levels cannot show).
Component three_level_sizes(const std::string& name, double q1, double q2, double q3, double h1, double h2,
                            double h3, int run, double order_min, double order_max,
                            double safety_factor = kSafetyFactor);

/// Ratio of the difference to an independent discretisation over the levels' estimate above which
/// the levels' asymptotic claim is refuted (checked_against).
inline constexpr double kCheckRefutes = 2.0;

/// A component checked against an independent discretisation of the same quantity, of another family
/// of refinements than the levels' (order 2 on cells x 2 beside p-levels on one grid). p-levels on a
/// coarse grid can look asymptotic while the crack front is under-resolved (docs/benchmarks.md 11.9:
/// effectivity 0.23 on 25 mm cells); the other family tells. The estimate then covers the difference
/// to `check_value` (it never claims the run closer to the truth than to an independent solution; the
/// sign stays the levels'), and a difference above kCheckRefutes times the levels' estimate refutes
/// their asymptotic claim: not verified. A check without a finite value changes nothing.
Component checked_against(Component component, const std::string& check, double check_value);

/// One refinement from the setting that was run (value) to a finer one (refined) whose error is
/// expected to fall as refinement^-order: the error of `value` is (refined - value) r^p / (r^p - 1).
/// order <= 0: the convergence order is unknown (modal truncation): the change itself, times Fs = 3.
Component one_refinement(const std::string& name, double value, double refined, double refinement, double order);

/// A component given directly as a relative residue (the steady-state window change).
Component residue(const std::string& name, double value, double relative);

/// The start transient left in the last analysis window (value) of a harmonic run, from the two
/// windows before it (before, previous; NaN where the run had fewer): the transient decays by a
/// constant ratio per window, so the changes between windows fall geometrically and what is left is
/// Fs (Q3 - Q2)/(r - 1) (eq. 2 with r^p the ratio of successive changes). A linear damped transient
/// cannot decay faster than its slowest mode, `slowest_ratio` = exp(sigma_min T_window) per window
/// (sigma_min the least modal decay rate of the damping); a faster observed ratio comes from content
/// of an earlier window that is not the tail (the start ramp) and would understate what is left
/// (docs/benchmarks.md 11.11: a 45x ratio against 12.4 allowed, the estimate 0.35 of the error), so
/// the ratio used is the smaller of the two, and the component then says it is not asymptotic.
/// Non-monotone windows (beats) or two windows only: the larger of three times the last change and
/// Fs/(slowest_ratio - 1) times it, not asymptotic. slowest_ratio <= 1 (no damping): not verified;
/// NaN: no bound known (the observed ratio alone).
Component window_tail(const std::string& name, double before, double previous, double value, double slowest_ratio);

/// The components of one quantity, combined.
struct Estimate {
  std::string quantity;  ///< "A2/A1", "f_b", ...
  double value = 0.0;
  std::vector<Component> components;
  /// The estimate reported (combine): the signed sum of the components' corrections delta/Fs whose
  /// sign is trusted (Fs below kCautiousSafetyFactor), in modulus, plus each one's margin (Fs - 1)
  /// |delta/Fs|, plus |delta| of every cautious component. It equals `sum` when the components
  /// share a sign and is smaller where they cancel in the true error.
  double error = 0.0;
  double sum = 0.0;         ///< sum of |delta| (the conservative bound)
  double signed_sum = 0.0;  ///< sum of delta
  double rss = 0.0;         ///< root-sum-square of delta
  bool asymptotic = true;
  bool verified = true;
  std::vector<std::string> reasons;  ///< why not verified (the components that are not)
};

/// The estimate (Estimate::error), sum, signed sum and root-sum-square of the components; verified and
/// asymptotic only when every component is.
Estimate combine(const std::string& quantity, double value, std::vector<Component> components);

/// One line: `A2/A1 = 0.1547 ± 0.6 % (mesh +0.5, modes -0.2, steps +0.1, penalty +0.1)` (each
/// component's signed delta in %), with
/// `not verified: reason` appended when it is not.
std::string estimate_line(const Estimate& estimate);

}  // namespace crackle::accuracy
