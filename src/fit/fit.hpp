#pragma once
/// \file Bounded nonlinear least squares and its uncertainty (DETECTION.md sec. 2), as plain
/// numerics over a residual function that evaluates a batch of parameter vectors at once (so that
/// the forward runs of a Jacobian can run in parallel).
///
/// - fit_bounded(): Levenberg-Marquardt with bounds (Ceres), Jacobians by one-sided finite
///   differences that stay inside the bounds, evaluated as one batch per Jacobian;
/// - bounded_linear_step(): the Gauss-Newton step of a bounded fit (the linearised misfit's minimum
///   over the box);
/// - uncertainty(): the Gauss-Newton covariance C = s^2 (J^T J)^-1 through a QR of J (eq. 8), the
///   95 % intervals with Student's t (eq. 9), the correlation matrix, the rank;
/// - student_t_quantile(): the quantile of Student's t distribution;
/// - TensorSpline: natural cubic splines over a tensor grid (the misfit map's interpolant);
/// - grid_minima(): the local minima of values on a tensor grid;
/// - profile(): the 2D profile of a misfit over two unknowns (the least over the others).
#include <array>
#include <functional>
#include <string>
#include <vector>

#include "core/types.hpp"

namespace crackle::fit {

/// Residual vectors r(theta) (each the same length) of a batch of parameter vectors.
using BatchResiduals = std::function<std::vector<VectorX>(const std::vector<VectorX>& thetas)>;

struct Bounds {
  VectorX lower;
  VectorX upper;
};

struct FitOptions {
  int max_iterations = 30;
  /// Relative finite-difference step per unknown, as a fraction of its bound width (one-sided,
  /// towards the inside at a bound).
  VectorX steps;
  double function_tolerance = 1e-10;  ///< relative change of the cost that stops the fit
  double parameter_tolerance = 1e-8;  ///< relative step that stops the fit
  double gradient_tolerance = 1e-12;
};

struct FitResult {
  VectorX theta;
  VectorX residuals;
  MatrixX jacobian;    ///< of the residuals at theta (the last one computed)
  double chi2 = 0.0;   ///< sum of squared residuals
  int iterations = 0;
  int evaluations = 0;  ///< residual evaluations (each a forward run per parameter vector)
  bool converged = false;
  std::string message;  ///< the solver's own summary line
  std::vector<bool> at_bound;  ///< per unknown: within 1e-6 of its width of a bound (at_bounds)
};

/// Per unknown: theta within 1e-6 of its width of a bound.
std::vector<bool> at_bounds(const VectorX& theta, const Bounds& bounds);

/// The k points of a finite-difference Jacobian at theta: theta + h_j e_j, h_j = steps_j (upper_j -
/// lower_j), negated where that would leave the bounds (so a caller can evaluate them ahead).
std::vector<VectorX> jacobian_points(const VectorX& theta, const Bounds& bounds, const VectorX& steps);

/// Central or one-sided finite-difference Jacobian of the residuals at theta (residuals r0 there),
/// one batch of k evaluations: theta + h_j e_j, h_j = steps_j (upper_j - lower_j), negated where
/// that would leave the bounds.
MatrixX jacobian(const BatchResiduals& residuals, const VectorX& theta, const VectorX& r0, const Bounds& bounds,
                 const VectorX& steps, int* evaluations = nullptr);

/// The step d that minimises |r + J d|^2 over lower <= d <= upper (lower <= 0 <= upper): the
/// Gauss-Newton step of a fit at theta kept inside its bounds (lower = bounds.lower - theta, upper =
/// bounds.upper - theta). Unlike the unconstrained step clipped to the box, it is the minimum of the
/// linearised misfit over the box, so its predicted decrease is zero exactly where theta is a
/// stationary point of the bounded fit (a clipped step can predict a rise while the misfit still
/// falls along a bound). Exact by active sets (each unknown free, at its lower or at its upper
/// bound) for up to 8 unknowns; beyond, projected gradient iterations.
VectorX bounded_linear_step(const MatrixX& jacobian, const VectorX& r, const VectorX& lower, const VectorX& upper);

/// Minimises sum r_i(theta)^2 over lower <= theta <= upper from `start` (clamped into the bounds).
FitResult fit_bounded(const BatchResiduals& residuals, const VectorX& start, const Bounds& bounds,
                      const FitOptions& options);

struct Uncertainty {
  MatrixX covariance;   ///< k x k
  MatrixX correlation;  ///< k x k (NaN on an unidentified unknown)
  VectorX sd;
  std::vector<std::array<double, 2>> interval_95;
  int rank = 0;            ///< numerical rank of J (relative tolerance 1e-8 on the R diagonal)
  bool rank_deficient = false;
  double s2 = 1.0;         ///< the variance factor used
  double t = 0.0;          ///< the quantile used
  int dof = 0;             ///< n - k
  bool scaled = false;     ///< s2 = chi2 / (n - k) (else 1, with the normal quantile)
};

/// The Gauss-Newton covariance at a minimum (eqs. 8-9), from a column-pivoted QR of J (never J^T J).
/// scale_by_fit: s^2 = chi2/(n - k) with Student's t of n - k degrees of freedom (eq. 8, 9); without
/// (or when n <= k) s^2 = 1 with the normal quantile 1.96 (sigmas trusted). On a rank-deficient J the
/// unidentified directions get infinite variance.
Uncertainty uncertainty(const MatrixX& jacobian, const VectorX& theta, double chi2, bool scale_by_fit);

/// Quantile of Student's t distribution with `dof` degrees of freedom (dof >= 1), p in (0, 1).
double student_t_quantile(double p, int dof);

/// Natural cubic splines through values on a tensor grid: axes[d] ascending (at least 2 points;
/// 2 points: linear), values in row-major order (the last axis fastest), each a vector (one per
/// quantity). Evaluation outside the grid clamps to it. A missing value (NaN: a forward run without
/// that quantity there) stays local: the splines are built with it replaced by the nearest grid
/// point's value of that quantity, and a quantity is NaN in every grid cell with a corner where it
/// is missing (a natural spline is global along each grid line, so one NaN would spread along them).
class TensorSpline {
 public:
  TensorSpline() = default;
  TensorSpline(std::vector<std::vector<double>> axes, std::vector<VectorX> values);
  VectorX operator()(const VectorX& theta) const;
  const std::vector<std::vector<double>>& axes() const { return axes_; }

 private:
  VectorX evaluate(int axis, std::size_t offset, const VectorX& theta) const;
  std::vector<std::vector<double>> axes_;
  std::vector<VectorX> values_;
  std::vector<std::size_t> strides_;
  std::vector<VectorX> missing_;  ///< per grid point, 1 where a quantity is missing (empty: none is)
};

/// Flat indices (row-major, last axis fastest) of the grid points whose value is no larger than any
/// neighbour's (the 3^d - 1 neighbours), lowest first; NaN points are never minima; a plateau
/// keeps its first point.
std::vector<std::size_t> grid_minima(const std::vector<std::vector<double>>& axes, const std::vector<double>& values);

/// The 2D profile of a misfit over the unknowns `first` < `second`: on each node (a, b) of
/// axes[first] x axes[second], the least sum of squared residuals over the other unknowns within
/// their bounds (the profile likelihood's -2 log). Each node's fit starts from the grid point of least
/// `values` (the misfit on the whole grid, row-major, last axis fastest; NaN allowed) in that slice;
/// the profile is never above that point's value. With two unknowns the profile is `values` itself
/// (nothing is fitted). `options.steps` holds every unknown's step; only the others' are used.
struct Profile {
  std::size_t first = 0, second = 0;
  std::vector<double> chi2;  ///< axes[first].size() x axes[second].size(), row-major (NaN: no finite misfit)
  std::vector<VectorX> at;   ///< where each least misfit lies (every unknown)
  int evaluations = 0;       ///< residual evaluations of the fits
};
Profile profile(const BatchResiduals& residuals, const std::vector<std::vector<double>>& axes,
                const std::vector<double>& values, const Bounds& bounds, std::size_t first, std::size_t second,
                const FitOptions& options);

}  // namespace crackle::fit
