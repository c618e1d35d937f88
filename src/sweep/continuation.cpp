#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <memory>

#include "core/errors.hpp"
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

}  // namespace

std::vector<BranchPoint> continue_branch(const HarmonicBalance& hb, double omega_from, double omega_to,
                                         const ContinuationOptions& options, const ProgressCallback& progress,
                                         const Solution* start) {
  if (!(omega_from > 0.0) || !(omega_to > 0.0) || omega_from == omega_to)
    throw InputError("continuation: need two distinct positive frequencies, got " + format_number(omega_from) +
                     " and " + format_number(omega_to) + " rad/s");
  const Index n = hb.n_unknowns();
  const double omega_ref = omega_from;
  const double tolerance = hb.options().tolerance;
  const double w_low = std::min(omega_from, omega_to) / omega_ref;
  const double w_high = std::max(omega_from, omega_to) / omega_ref;
  const double direction = omega_to > omega_from ? 1.0 : -1.0;

  std::vector<BranchPoint> branch;
  auto add_point = [&](Solution&& sol, double tangent_omega) {
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
    bool accepted = false;
    VectorX y_new;
    int iterations = 0;
    double residual = 0.0;
    Extended bordered;  // the linearisation [dr/dy; t^T] of the last corrector iteration
    while (!accepted) {
      y_new = y + ds * t;
      for (iterations = 1; iterations <= max_corrector; ++iterations) {
        bordered = evaluate(hb, y_new, omega_ref);
        VectorX rhs(n + 1);
        rhs.head(n) = -bordered.residual;
        rhs[n] = -(t.dot(y_new - y) - ds);
        const VectorX delta = bordered.solve_bordered(t, rhs, inexact_forcing(rhs.norm(), tolerance));
        // full steps first, then backtracking on the extended residual: piecewise-linear contact can
        // make plain Newton cycle between two active-sample patterns near a kink
        const double merit = rhs.squaredNorm();
        double alpha = 1.0;
        VectorX trial = y_new + delta;
        while (iterations > options.target_iterations && alpha > 1.0 / 256.0) {
          const double m_trial = extended_merit(hb, trial, omega_ref, t, y, ds);
          if (m_trial < merit) break;
          alpha *= 0.5;
          trial = y_new + alpha * delta;
        }
        y_new = trial;
        if (!y_new.allFinite()) break;
        residual = hb.residual(y_new[n] * omega_ref, y_new.head(n) * hb.gap_scale()).lpNorm<Eigen::Infinity>();
        if (residual <= tolerance && delta.lpNorm<Eigen::Infinity>() <= 1e3 * tolerance + 1e-8) {
          accepted = true;
          break;
        }
      }
      if (!accepted) {
        ds *= 0.5;
        if (ds < options.min_step) return branch;  // cannot go on: the branch so far
      }
    }
    // The new tangent from the last corrector matrix: its Jacobian is that of a point within the
    // corrector's last step (<= 1e3 tolerance) of y_new, its last row the tangent it is oriented along
    // (the same bordered system tangent() solves; one factorisation per point saved).
    VectorX t_new = bordered.solve_bordered(t, VectorX::Unit(n + 1, n), kTangentTolerance);
    t_new.normalize();
    if (t_new.dot(t) < 0.0) t_new = -t_new;
    y = y_new;
    t = t_new;
    Solution sol;
    sol.omega = y[n] * omega_ref;
    sol.gaps = y.head(n) * hb.gap_scale();
    sol.iterations = iterations;
    sol.residual = residual;
    sol.converged = true;
    hb.complete(sol);
    if (!add_point(std::move(sol), t[n])) return branch;
    if (y[n] > w_high || y[n] < w_low) break;
    const double factor = std::clamp(static_cast<double>(options.target_iterations) / std::max(iterations, 1), 0.5, 2.0);
    ds = std::clamp(ds * factor, options.min_step, options.max_step);
  }
  return branch;
}

}  // namespace crackle::sweep
