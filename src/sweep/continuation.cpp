#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <memory>
#include <utility>
#include <vector>

#include "core/errors.hpp"
#include "core/interrupt.hpp"
#include "sweep/harmonic_balance.hpp"

namespace crackle::sweep {

namespace {

/// Scaled state y = (G / s, Omega / Omega_ref): the residual and the linearisation of its extended
/// Jacobian [dr/dx, dr/dw] (dense or matrix-free, HarmonicBalance::linearize).
struct Extended {
  std::unique_ptr<Linearization> linear;
  VectorX column;    ///< dr/dw = dr/dOmega Omega_ref, n
  VectorX residual;  ///< n
  /// Solves [dr/dx dr/dw; row^T] x = b.
  VectorX solve_bordered(const VectorX& row, const VectorX& b, double tolerance) const {
    return linear->solve_bordered(column, row, b, tolerance);
  }
};

Extended evaluate(const HarmonicBalance& hb, const VectorX& y, double omega_ref) {
  const Index n = hb.n_unknowns();
  const double omega = y[n] * omega_ref;
  const VectorX gaps = y.head(n) * hb.gap_scale();
  Extended e;
  e.linear = hb.linearize(omega, gaps, true);
  e.column = e.linear->d_omega() * omega_ref;
  e.residual = hb.residual(omega, gaps);
  return e;
}

/// Relative tolerance of the tangent's solves.
constexpr double kTangentTolerance = 1e-10;

double extended_merit(const HarmonicBalance& hb, const VectorX& y, double omega_ref, const VectorX& t,
                      const VectorX& y_prev, double ds) {
  const Index n = hb.n_unknowns();
  const double constraint = t.dot(y - y_prev) - ds;
  return hb.residual(y[n] * omega_ref, y.head(n) * hb.gap_scale()).squaredNorm() + constraint * constraint;
}

/// The same numbers of unstable multipliers of each kind.
bool same_counts(const Stability& a, const Stability& b) {
  return a.unstable_positive == b.unstable_positive && a.unstable_negative == b.unstable_negative &&
         a.unstable_complex == b.unstable_complex;
}

/// Unit tangent: null vector of the n x (n+1) Jacobian, oriented along `previous`.
VectorX tangent(const Extended& e, const VectorX& previous) {
  const Index n = e.residual.size();
  VectorX t = e.solve_bordered(previous, VectorX::Unit(n + 1, n), kTangentTolerance);
  t.normalize();
  if (t.dot(previous) < 0.0) t = -t;
  return t;
}

/// A corrected point: the state, the corrector's iterations and final residual, and the linearisation
/// of its last iteration (the bordered matrix [dr/dy; t^T] is solved through it).
struct Corrected {
  VectorX y;
  int iterations = 0;
  double residual = 0.0;
  Extended bordered;
};

/// Keller's corrector from the predictor y_base + ds t: Newton on [r(y); t^T (y - y_base) - ds], full
/// steps first, then backtracking on the extended residual (piecewise-linear contact can make plain
/// Newton cycle between two active-sample patterns near a kink). False when it does not converge
/// within `max_iterations`.
bool correct(const HarmonicBalance& hb, double omega_ref, const VectorX& y_base, const VectorX& t, double ds,
             int target_iterations, int max_iterations, Corrected& c) {
  const Index n = hb.n_unknowns();
  const double tolerance = hb.options().tolerance;
  c.y = y_base + ds * t;
  for (c.iterations = 1; c.iterations <= max_iterations; ++c.iterations) {
    c.bordered = evaluate(hb, c.y, omega_ref);
    VectorX rhs(n + 1);
    rhs.head(n) = -c.bordered.residual;
    rhs[n] = -(t.dot(c.y - y_base) - ds);
    const VectorX delta = c.bordered.solve_bordered(t, rhs, inexact_forcing(rhs.norm(), tolerance));
    const double merit = rhs.squaredNorm();
    double alpha = 1.0;
    VectorX trial = c.y + delta;
    while (c.iterations > target_iterations && alpha > 1.0 / 256.0) {
      if (extended_merit(hb, trial, omega_ref, t, y_base, ds) < merit) break;
      alpha *= 0.5;
      trial = c.y + alpha * delta;
    }
    c.y = trial;
    if (!c.y.allFinite()) return false;
    c.residual = hb.residual(c.y[n] * omega_ref, c.y.head(n) * hb.gap_scale()).lpNorm<Eigen::Infinity>();
    if (c.residual <= tolerance && delta.lpNorm<Eigen::Infinity>() <= 1e3 * tolerance + 1e-8) return true;
  }
  return false;
}

/// The points of options.solve_at strictly between two consecutive points (scaled states y0 and y1,
/// no fold between them) of a branch, in the branch's order: Newton at each fixed Omega from the
/// chord; a point that fails or lands farther from the chord than |y1 - y0| is left out.
std::vector<std::pair<Solution, double>> landed_points(const HarmonicBalance& hb, const ContinuationOptions& options,
                                                       double omega_ref, const VectorX& y0, const VectorX& y1) {
  const Index n = hb.n_unknowns();
  std::vector<std::pair<double, double>> crossings;  // (fraction along the chord, Omega)
  for (const double omega : options.solve_at) {
    const double w = omega / omega_ref;
    if ((w - y0[n]) * (w - y1[n]) < 0.0) crossings.emplace_back((w - y0[n]) / (y1[n] - y0[n]), omega);
  }
  std::sort(crossings.begin(), crossings.end());
  std::vector<std::pair<Solution, double>> points;
  for (const auto& [fraction, omega] : crossings) {
    const VectorX chord = (1.0 - fraction) * y0.head(n) + fraction * y1.head(n);
    try {
      Solution solution = hb.solve(omega, chord * hb.gap_scale());
      if ((solution.gaps / hb.gap_scale() - chord).norm() <= (y1 - y0).norm()) points.emplace_back(std::move(solution), fraction);
    } catch (const SolverError&) {
      // not solved there: the branch keeps its continued points only
    }
  }
  return points;
}

}  // namespace

std::vector<BranchPoint> continue_branch(const HarmonicBalance& hb, double omega_from, double omega_to,
                                         const ContinuationOptions& options, const ProgressCallback& progress,
                                         const Solution* start) {
  if (!(omega_from > 0.0) || !(omega_to > 0.0) || omega_from == omega_to)
    throw InputError("continuation: need two distinct positive frequencies, got " + format_number(omega_from) +
                     " and " + format_number(omega_to) + " rad/s");
  const Index n = hb.n_unknowns();
  const double omega_ref = omega_from;
  const double w_low = std::min(omega_from, omega_to) / omega_ref;
  const double w_high = std::max(omega_from, omega_to) / omega_ref;
  const double direction = omega_to > omega_from ? 1.0 : -1.0;

  std::vector<BranchPoint> branch;
  auto add_point = [&](Solution&& sol, double tangent_omega) {
    poll_interrupt();
    BranchPoint point;
    point.solution = std::move(sol);
    point.tangent_omega = tangent_omega;
    if (options.stability)
      point.stability = options.hill_everywhere ? hb.hill_stability(point.solution) : hb.floquet_stability(point.solution);
    if (!branch.empty()) {
      const BranchPoint& last = branch.back();
      point.fold = (last.tangent_omega > 0.0) != (point.tangent_omega > 0.0);
      if (options.stability) {
        const Stability& a = last.stability;
        const Stability& b = point.stability;
        point.period_doubling = a.unstable_negative != b.unstable_negative;
        point.stability_change = (a.unstable_positive + a.unstable_negative + a.unstable_complex) !=
                                 (b.unstable_positive + b.unstable_negative + b.unstable_complex);
        if (!same_counts(a, b) && options.hill_at_events && !options.hill_everywhere)
          point.hill_check = same_counts(hb.hill_stability(last.solution), a) &&
                             same_counts(hb.hill_stability(point.solution), b);
      }
    }
    branch.push_back(std::move(point));
    return progress ? progress(branch.back()) : true;
  };

  Solution first = start ? *start : hb.solve(omega_from);
  VectorX y(n + 1);
  y.head(n) = first.gaps / hb.gap_scale();
  y[n] = first.omega / omega_ref;
  VectorX t_prev = VectorX::Zero(n + 1);
  t_prev[n] = direction;
  Extended e = evaluate(hb, y, omega_ref);
  VectorX t = tangent(e, t_prev);
  if (!add_point(std::move(first), t[n])) return branch;

  double ds = options.initial_step;
  const int max_corrector = std::max(8, 3 * options.target_iterations);
  while (static_cast<int>(branch.size()) < options.max_points) {
    Corrected c;
    while (!correct(hb, omega_ref, y, t, ds, options.target_iterations, max_corrector, c)) {
      ds *= 0.5;
      if (ds < options.min_step) return branch;  // cannot go on: the branch so far
    }
    // The new tangent from the last corrector matrix: its Jacobian is that of a point within the
    // corrector's last step (<= 1e3 tolerance) of y_new, its last row the tangent it is oriented along
    // (the same bordered system tangent() solves; one factorisation per point saved).
    VectorX t_new = c.bordered.solve_bordered(t, VectorX::Unit(n + 1, n), kTangentTolerance);
    t_new.normalize();
    if (t_new.dot(t) < 0.0) t_new = -t_new;
    if (!options.solve_at.empty() && (t[n] > 0.0) == (t_new[n] > 0.0))
      for (auto& [landed, fraction] : landed_points(hb, options, omega_ref, y, c.y))
        if (!add_point(std::move(landed), (1.0 - fraction) * t[n] + fraction * t_new[n])) return branch;
    y = c.y;
    t = t_new;
    Solution sol;
    sol.omega = y[n] * omega_ref;
    sol.gaps = y.head(n) * hb.gap_scale();
    sol.iterations = c.iterations;
    sol.residual = c.residual;
    sol.converged = true;
    hb.complete(sol);
    if (!add_point(std::move(sol), t[n])) return branch;
    if (y[n] > w_high || y[n] < w_low) break;
    const double factor = std::clamp(static_cast<double>(options.target_iterations) / std::max(c.iterations, 1), 0.5, 2.0);
    ds = std::clamp(ds * factor, options.min_step, options.max_step);
  }
  return branch;
}

Solution branch_off(const HarmonicBalance& hb, const Solution& base, const VectorX& direction, double step,
                    const ContinuationOptions& options) {
  const Index n = hb.n_unknowns();
  if (base.gaps.size() != n || direction.size() != n || !(direction.norm() > 0.0) || !(step > 0.0))
    throw InputError("branch_off: need a base solution and a nonzero direction of " + std::to_string(n) +
                     " gap harmonics and a positive step, got " + std::to_string(base.gaps.size()) + ", " +
                     std::to_string(direction.size()) + " and " + format_number(step) + " m");
  const double omega_ref = base.omega;
  VectorX y(n + 1), t = VectorX::Zero(n + 1);
  y.head(n) = base.gaps / hb.gap_scale();
  y[n] = 1.0;
  t.head(n) = direction.normalized();
  Corrected c;
  if (!correct(hb, omega_ref, y, t, step / hb.gap_scale(), options.target_iterations, hb.options().max_iterations, c))
    throw SolverError("branch_off: the corrector did not converge from Omega = " + format_number(base.omega) +
                      " rad/s at a step of " + format_number(step) + " m (residual " + format_number(c.residual) + ")");
  Solution sol;
  sol.omega = c.y[n] * omega_ref;
  sol.gaps = c.y.head(n) * hb.gap_scale();
  sol.iterations = c.iterations;
  sol.residual = c.residual;
  sol.converged = true;
  hb.complete(sol);
  return sol;
}

}  // namespace crackle::sweep
