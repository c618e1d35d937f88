#include "fit/fit.hpp"

#include <ceres/ceres.h>
#include <Eigen/QR>
#include <Eigen/SVD>

#include <algorithm>
#include <cmath>
#include <limits>
#include <memory>
#include <numeric>

#include "core/errors.hpp"

namespace crackle::fit {
namespace {

VectorX clamp_into(const VectorX& theta, const Bounds& bounds) {
  return theta.cwiseMax(bounds.lower).cwiseMin(bounds.upper);
}

/// The residual function as one Ceres cost with a k-vector parameter block; a Jacobian is one batch
/// of k forward runs (plus r(theta) unless the last evaluation was at the same theta).
class BatchCost final : public ceres::CostFunction {
 public:
  BatchCost(const BatchResiduals& residuals, const Bounds& bounds, const VectorX& steps, int n, int k,
            int* evaluations)
      : residuals_(residuals), bounds_(bounds), steps_(steps), evaluations_(evaluations) {
    set_num_residuals(n);
    mutable_parameter_block_sizes()->push_back(k);
  }

  bool Evaluate(double const* const* parameters, double* residuals, double** jacobians) const override {
    const Eigen::Index k = bounds_.lower.size();
    const VectorX theta = Eigen::Map<const VectorX>(parameters[0], k);
    if (last_theta_.size() != k || last_theta_ != theta) {
      last_r_ = residuals_({theta}).at(0);
      last_theta_ = theta;
      ++*evaluations_;
    }
    if (!last_r_.allFinite()) return false;  // Ceres shortens the step
    Eigen::Map<VectorX>(residuals, last_r_.size()) = last_r_;
    if (jacobians && jacobians[0]) {
      last_jacobian_ = jacobian(residuals_, theta, last_r_, bounds_, steps_, evaluations_);
      if (!last_jacobian_.allFinite()) return false;
      Eigen::Map<Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>>(jacobians[0], last_r_.size(),
                                                                                         k) = last_jacobian_;
    }
    return true;
  }

  const MatrixX& last_jacobian() const { return last_jacobian_; }

 private:
  const BatchResiduals& residuals_;
  const Bounds& bounds_;
  const VectorX& steps_;
  int* evaluations_;
  mutable VectorX last_theta_, last_r_;
  mutable MatrixX last_jacobian_;
};

/// Regularized incomplete beta I_x(a, b) by its continued fraction (modified Lentz).
double incomplete_beta(double x, double a, double b) {
  if (x <= 0.0) return 0.0;
  if (x >= 1.0) return 1.0;
  if (x > (a + 1.0) / (a + b + 2.0)) return 1.0 - incomplete_beta(1.0 - x, b, a);
  const double front =
      std::exp(std::lgamma(a + b) - std::lgamma(a) - std::lgamma(b) + a * std::log(x) + b * std::log1p(-x)) / a;
  constexpr double tiny = 1e-300;
  double f = 1.0, c = 1.0, d = 0.0;
  for (int i = 0; i <= 400; ++i) {
    const int m = i / 2;
    double numerator;
    if (i == 0)
      numerator = 1.0;
    else if (i % 2 == 0)
      numerator = (m * (b - m) * x) / ((a + 2.0 * m - 1.0) * (a + 2.0 * m));
    else
      numerator = -((a + m) * (a + b + m) * x) / ((a + 2.0 * m) * (a + 2.0 * m + 1.0));
    d = 1.0 + numerator * d;
    if (std::abs(d) < tiny) d = tiny;
    d = 1.0 / d;
    c = 1.0 + numerator / c;
    if (std::abs(c) < tiny) c = tiny;
    const double cd = c * d;
    f *= cd;
    if (std::abs(1.0 - cd) < 1e-15) return front * (f - 1.0);
  }
  return front * (f - 1.0);
}

/// P(T <= t) of Student's t with nu degrees of freedom.
double student_t_cdf(double t, double nu) {
  const double tail = 0.5 * incomplete_beta(nu / (nu + t * t), 0.5 * nu, 0.5);
  return t >= 0.0 ? 1.0 - tail : tail;
}

/// Second derivatives of the natural cubic spline through (x_i, y_i) (rows of y: points).
MatrixX natural_second_derivatives(const std::vector<double>& x, const MatrixX& y) {
  const std::size_t n = x.size();
  MatrixX m = MatrixX::Zero(static_cast<Eigen::Index>(n), y.cols());
  if (n < 3) return m;
  // Thomas algorithm on the interior equations, m_0 = m_{n-1} = 0.
  std::vector<double> c_prime(n, 0.0);
  MatrixX d_prime = MatrixX::Zero(static_cast<Eigen::Index>(n), y.cols());
  for (std::size_t i = 1; i + 1 < n; ++i) {
    const double h0 = x[i] - x[i - 1], h1 = x[i + 1] - x[i];
    const double a = h0 / 6.0, b = (h0 + h1) / 3.0, c = h1 / 6.0;
    const Eigen::RowVectorXd rhs = (y.row(i + 1) - y.row(i)) / h1 - (y.row(i) - y.row(i - 1)) / h0;
    const double denominator = b - a * c_prime[i - 1];
    c_prime[i] = c / denominator;
    d_prime.row(i) = (rhs - a * d_prime.row(i - 1)) / denominator;
  }
  for (std::size_t i = n - 2; i >= 1; --i) {
    m.row(i) = d_prime.row(i) - c_prime[i] * m.row(i + 1);
    if (i == 1) break;
  }
  return m;
}

Eigen::RowVectorXd spline_at(const std::vector<double>& x, const MatrixX& y, double at) {
  at = std::clamp(at, x.front(), x.back());
  const MatrixX m = natural_second_derivatives(x, y);
  std::size_t i = std::upper_bound(x.begin(), x.end(), at) - x.begin();
  i = std::clamp<std::size_t>(i, 1, x.size() - 1) - 1;
  const double h = x[i + 1] - x[i];
  const double a = (x[i + 1] - at) / h, b = (at - x[i]) / h;
  return a * y.row(i) + b * y.row(i + 1) +
         ((a * a * a - a) * m.row(i) + (b * b * b - b) * m.row(i + 1)) * (h * h) / 6.0;
}

}  // namespace

VectorX bounded_linear_step(const MatrixX& jacobian, const VectorX& r, const VectorX& lower, const VectorX& upper) {
  const Eigen::Index k = jacobian.cols();
  const auto misfit = [&](const VectorX& d) { return (r + jacobian * d).squaredNorm(); };
  VectorX best = VectorX::Zero(k);  // feasible: lower <= 0 <= upper
  double best_misfit = misfit(best);
  if (k <= 8) {
    // The minimum of a convex quadratic over a box has some active set (each unknown free, at its
    // lower or at its upper bound) with the free unknowns at their reduced least-squares solution:
    // every feasible such candidate bounds the minimum from above, and the least of them is it.
    Eigen::Index patterns = 1;
    for (Eigen::Index j = 0; j < k; ++j) patterns *= 3;
    for (Eigen::Index pattern = 0; pattern < patterns; ++pattern) {
      VectorX d = VectorX::Zero(k);
      std::vector<Eigen::Index> free;
      Eigen::Index rest = pattern;
      for (Eigen::Index j = 0; j < k; ++j, rest /= 3) {
        if (rest % 3 == 0) free.push_back(j);
        else d[j] = rest % 3 == 1 ? lower[j] : upper[j];
      }
      if (!free.empty()) {
        MatrixX reduced(jacobian.rows(), static_cast<Eigen::Index>(free.size()));
        for (std::size_t c = 0; c < free.size(); ++c) reduced.col(static_cast<Eigen::Index>(c)) = jacobian.col(free[c]);
        const VectorX solved = reduced.colPivHouseholderQr().solve(-(r + jacobian * d));
        for (std::size_t c = 0; c < free.size(); ++c) d[free[c]] = solved[static_cast<Eigen::Index>(c)];
      }
      bool feasible = d.allFinite();
      for (Eigen::Index j = 0; j < k && feasible; ++j) {
        const double slack = 1e-12 * std::max(upper[j] - lower[j], 1e-300);
        feasible = d[j] >= lower[j] - slack && d[j] <= upper[j] + slack;
      }
      if (!feasible) continue;
      d = d.cwiseMax(lower).cwiseMin(upper);
      const double value = misfit(d);
      if (value < best_misfit) {
        best_misfit = value;
        best = d;
      }
    }
    return best;
  }
  // Projected gradient on the quadratic with the step 1/|J|_2^2 (monotone).
  const Eigen::JacobiSVD<MatrixX> svd(jacobian);
  const double lipschitz = std::max(svd.singularValues()[0] * svd.singularValues()[0], 1e-300);
  VectorX d = best;
  for (int iteration = 0; iteration < 100000; ++iteration) {
    const VectorX next = (d - jacobian.transpose() * (r + jacobian * d) / lipschitz).cwiseMax(lower).cwiseMin(upper);
    if ((next - d).norm() <= 1e-14 * (1.0 + d.norm())) break;
    d = next;
  }
  return d;
}

std::vector<bool> at_bounds(const VectorX& theta, const Bounds& bounds) {
  std::vector<bool> at;
  for (Eigen::Index j = 0; j < theta.size(); ++j) {
    const double margin = 1e-6 * (bounds.upper[j] - bounds.lower[j]);
    at.push_back(theta[j] <= bounds.lower[j] + margin || theta[j] >= bounds.upper[j] - margin);
  }
  return at;
}

std::vector<VectorX> jacobian_points(const VectorX& theta, const Bounds& bounds, const VectorX& steps) {
  std::vector<VectorX> points;
  for (Eigen::Index j = 0; j < theta.size(); ++j) {
    double h = steps[j] * (bounds.upper[j] - bounds.lower[j]);
    if (theta[j] + h > bounds.upper[j]) h = -h;  // one-sided, towards the inside
    VectorX point = theta;
    point[j] += h;
    points.push_back(point);
  }
  return points;
}

MatrixX jacobian(const BatchResiduals& residuals, const VectorX& theta, const VectorX& r0, const Bounds& bounds,
                 const VectorX& steps, int* evaluations) {
  const Eigen::Index k = theta.size();
  const std::vector<VectorX> points = jacobian_points(theta, bounds, steps);
  const std::vector<VectorX> values = residuals(points);
  if (evaluations) *evaluations += static_cast<int>(k);
  MatrixX result(r0.size(), k);
  for (Eigen::Index j = 0; j < k; ++j) result.col(j) = (values.at(j) - r0) / (points[j][j] - theta[j]);
  return result;
}

FitResult fit_bounded(const BatchResiduals& residuals, const VectorX& start, const Bounds& bounds,
                      const FitOptions& options) {
  // Ceres reports a residual it could not evaluate (a forward run without a value there) through
  // glog's ERROR channel, on stderr, even with logging_type SILENT; the fit's result says it
  // (converged, message), so glog keeps to fatal messages.
  static const bool quiet = [] {
    FLAGS_minloglevel = google::GLOG_FATAL;
    return true;
  }();
  (void)quiet;
  const Eigen::Index k = start.size();
  FitResult result;
  VectorX theta = clamp_into(start, bounds);
  const VectorX r_start = residuals({theta}).at(0);
  result.evaluations = 1;
  VectorX steps = options.steps.size() == k ? options.steps : VectorX::Constant(k, 1e-4);

  auto* cost = new BatchCost(residuals, bounds, steps, static_cast<int>(r_start.size()), static_cast<int>(k),
                             &result.evaluations);
  ceres::Problem problem;
  problem.AddResidualBlock(cost, nullptr, theta.data());
  for (Eigen::Index j = 0; j < k; ++j) {
    problem.SetParameterLowerBound(theta.data(), static_cast<int>(j), bounds.lower[j]);
    problem.SetParameterUpperBound(theta.data(), static_cast<int>(j), bounds.upper[j]);
  }
  ceres::Solver::Options solver;
  solver.minimizer_type = ceres::TRUST_REGION;
  solver.trust_region_strategy_type = ceres::LEVENBERG_MARQUARDT;
  solver.linear_solver_type = ceres::DENSE_QR;
  solver.logging_type = ceres::SILENT;
  solver.minimizer_progress_to_stdout = false;
  solver.max_num_iterations = options.max_iterations;
  solver.function_tolerance = options.function_tolerance;
  solver.parameter_tolerance = options.parameter_tolerance;
  solver.gradient_tolerance = options.gradient_tolerance;
  solver.num_threads = 1;
  ceres::Solver::Summary summary;
  ceres::Solve(solver, &problem, &summary);

  result.theta = theta;
  result.residuals = residuals({theta}).at(0);
  ++result.evaluations;
  result.jacobian = jacobian(residuals, theta, result.residuals, bounds, steps, &result.evaluations);
  result.chi2 = result.residuals.squaredNorm();
  result.iterations = static_cast<int>(summary.iterations.size());
  result.converged = summary.termination_type == ceres::CONVERGENCE;
  result.message = summary.message;
  result.at_bound = at_bounds(theta, bounds);
  return result;
}

Uncertainty uncertainty(const MatrixX& jacobian, const VectorX& theta, double chi2, bool scale_by_fit) {
  const Eigen::Index n = jacobian.rows(), k = jacobian.cols();
  Uncertainty u;
  u.dof = static_cast<int>(n - k);
  Eigen::ColPivHouseholderQR<MatrixX> qr(jacobian);
  qr.setThreshold(1e-8);
  u.rank = static_cast<int>(qr.rank());
  u.rank_deficient = u.rank < k;
  u.scaled = scale_by_fit && n > k;
  u.s2 = u.scaled ? chi2 / static_cast<double>(n - k) : 1.0;
  u.t = u.scaled ? student_t_quantile(0.975, u.dof) : student_t_quantile(0.975, 1000000);
  u.covariance = MatrixX::Constant(k, k, std::numeric_limits<double>::quiet_NaN());
  if (!u.rank_deficient) {
    // (J^T J)^-1 = P R^-1 R^-T P^T.
    const MatrixX r = qr.matrixR().topLeftCorner(k, k).template triangularView<Eigen::Upper>();
    const MatrixX r_inverse = r.triangularView<Eigen::Upper>().solve(MatrixX::Identity(k, k));
    const MatrixX inner = r_inverse * r_inverse.transpose();
    const auto& p = qr.colsPermutation();
    u.covariance = u.s2 * (p * inner * p.transpose());
  } else {
    for (Eigen::Index j = 0; j < k; ++j) u.covariance(j, j) = std::numeric_limits<double>::infinity();
  }
  u.sd = u.covariance.diagonal().cwiseSqrt();
  u.correlation = MatrixX::Constant(k, k, std::numeric_limits<double>::quiet_NaN());
  for (Eigen::Index a = 0; a < k; ++a)
    for (Eigen::Index b = 0; b < k; ++b)
      if (std::isfinite(u.sd[a]) && std::isfinite(u.sd[b]) && u.sd[a] > 0 && u.sd[b] > 0)
        u.correlation(a, b) = u.covariance(a, b) / (u.sd[a] * u.sd[b]);
  for (Eigen::Index j = 0; j < k; ++j) u.interval_95.push_back({theta[j] - u.t * u.sd[j], theta[j] + u.t * u.sd[j]});
  return u;
}

double student_t_quantile(double p, int dof) {
  if (!(p > 0.0 && p < 1.0) || dof < 1) throw SolverError("student_t_quantile: p in (0, 1) and dof >= 1 expected");
  if (p < 0.5) return -student_t_quantile(1.0 - p, dof);
  double low = 0.0, high = 1.0;
  while (student_t_cdf(high, dof) < p) high *= 2.0;
  for (int i = 0; i < 200 && high - low > 1e-13 * high; ++i) {
    const double mid = 0.5 * (low + high);
    (student_t_cdf(mid, dof) < p ? low : high) = mid;
  }
  return 0.5 * (low + high);
}

TensorSpline::TensorSpline(std::vector<std::vector<double>> axes, std::vector<VectorX> values)
    : axes_(std::move(axes)), values_(std::move(values)) {
  std::size_t total = 1;
  strides_.assign(axes_.size(), 1);
  for (std::size_t d = axes_.size(); d-- > 0;) {
    if (axes_[d].size() < 2) throw SolverError("TensorSpline: every axis needs at least 2 points");
    strides_[d] = total;
    total *= axes_[d].size();
  }
  if (values_.size() != total) throw SolverError("TensorSpline: one value per grid point expected");
  bool any_missing = false;
  for (const VectorX& v : values_) any_missing = any_missing || !v.allFinite();
  if (!any_missing) return;
  // Each missing value takes the nearest grid point's (in grid steps) that has the quantity.
  const std::size_t d = axes_.size();
  const auto distance = [&](std::size_t a, std::size_t b) {
    double sum = 0.0;
    for (std::size_t axis = 0; axis < d; ++axis) {
      const double step = static_cast<double>((a / strides_[axis]) % axes_[axis].size()) -
                          static_cast<double>((b / strides_[axis]) % axes_[axis].size());
      sum += step * step;
    }
    return sum;
  };
  std::vector<VectorX> filled = values_;
  missing_.assign(total, VectorX::Zero(values_.front().size()));
  for (std::size_t flat = 0; flat < total; ++flat) {
    for (Eigen::Index q = 0; q < values_[flat].size(); ++q) {
      if (std::isfinite(values_[flat][q])) continue;
      missing_[flat][q] = 1.0;
      double nearest = HUGE_VAL;
      for (std::size_t other = 0; other < total; ++other) {
        if (!std::isfinite(values_[other][q]) || distance(flat, other) >= nearest) continue;
        nearest = distance(flat, other);
        filled[flat][q] = values_[other][q];
      }
    }
  }
  values_ = std::move(filled);
}

VectorX TensorSpline::evaluate(int axis, std::size_t offset, const VectorX& theta) const {
  const std::vector<double>& x = axes_[axis];
  const Eigen::Index q = values_.front().size();
  MatrixX y(static_cast<Eigen::Index>(x.size()), q);
  for (std::size_t i = 0; i < x.size(); ++i) {
    const std::size_t at = offset + i * strides_[axis];
    if (axis + 1 == static_cast<int>(axes_.size()))
      y.row(static_cast<Eigen::Index>(i)) = values_[at].transpose();
    else
      y.row(static_cast<Eigen::Index>(i)) = evaluate(axis + 1, at, theta).transpose();
  }
  return spline_at(x, y, theta[axis]).transpose();
}

VectorX TensorSpline::operator()(const VectorX& theta) const {
  VectorX result = evaluate(0, 0, theta);
  if (missing_.empty()) return result;
  // The cell around theta (as spline_at picks it), and a quantity missing at any of its corners.
  const std::size_t d = axes_.size();
  std::vector<std::size_t> low(d);
  for (std::size_t axis = 0; axis < d; ++axis) {
    const std::vector<double>& x = axes_[axis];
    const double at = std::clamp(theta[static_cast<Eigen::Index>(axis)], x.front(), x.back());
    const std::size_t i = static_cast<std::size_t>(std::upper_bound(x.begin(), x.end(), at) - x.begin());
    low[axis] = std::clamp<std::size_t>(i, 1, x.size() - 1) - 1;
  }
  for (std::size_t corner = 0; corner < (std::size_t{1} << d); ++corner) {
    std::size_t flat = 0;
    for (std::size_t axis = 0; axis < d; ++axis) flat += (low[axis] + ((corner >> axis) & 1)) * strides_[axis];
    for (Eigen::Index q = 0; q < result.size(); ++q)
      if (missing_[flat][q] != 0.0) result[q] = std::numeric_limits<double>::quiet_NaN();
  }
  return result;
}

std::vector<std::size_t> grid_minima(const std::vector<std::vector<double>>& axes, const std::vector<double>& values) {
  const std::size_t d = axes.size();
  std::vector<std::size_t> sizes(d), strides(d, 1);
  for (std::size_t a = d; a-- > 0;) {
    sizes[a] = axes[a].size();
    if (a + 1 < d) strides[a] = strides[a + 1] * sizes[a + 1];
  }
  std::vector<std::size_t> minima;
  for (std::size_t flat = 0; flat < values.size(); ++flat) {
    if (!std::isfinite(values[flat])) continue;
    std::vector<long> index(d);
    for (std::size_t a = 0; a < d; ++a) index[a] = static_cast<long>((flat / strides[a]) % sizes[a]);
    bool minimum = true;
    std::vector<int> offset(d, -1);
    while (minimum) {
      bool centre = true;
      long neighbour = 0;
      bool inside = true;
      for (std::size_t a = 0; a < d; ++a) {
        const long i = index[a] + offset[a];
        if (offset[a] != 0) centre = false;
        if (i < 0 || i >= static_cast<long>(sizes[a])) inside = false;
        neighbour += i * static_cast<long>(strides[a]);
      }
      if (!centre && inside) {
        const double other = values[static_cast<std::size_t>(neighbour)];
        // Strictly lower neighbours, or an equal one earlier in the grid (one point per plateau).
        if (other < values[flat] || (other == values[flat] && static_cast<std::size_t>(neighbour) < flat))
          minimum = false;
      }
      std::size_t a = 0;
      for (; a < d; ++a) {
        if (++offset[a] <= 1) break;
        offset[a] = -1;
      }
      if (a == d) break;
    }
    if (minimum) minima.push_back(flat);
  }
  std::sort(minima.begin(), minima.end(), [&](std::size_t a, std::size_t b) { return values[a] < values[b]; });
  return minima;
}

Profile profile(const BatchResiduals& residuals, const std::vector<std::vector<double>>& axes,
                const std::vector<double>& values, const Bounds& bounds, std::size_t first, std::size_t second,
                const FitOptions& options) {
  const std::size_t d = axes.size();
  if (!(first < second && second < d)) throw SolverError("profile: two distinct unknowns of the grid expected");
  std::vector<std::size_t> sizes(d), strides(d, 1);
  for (std::size_t a = d; a-- > 0;) {
    sizes[a] = axes[a].size();
    if (a + 1 < d) strides[a] = strides[a + 1] * sizes[a + 1];
  }
  if (values.size() != strides[0] * sizes[0]) throw SolverError("profile: one value per grid point expected");
  std::vector<std::size_t> others;
  for (std::size_t a = 0; a < d; ++a)
    if (a != first && a != second) others.push_back(a);
  const Eigen::Index m = static_cast<Eigen::Index>(others.size());
  Profile result;
  result.first = first;
  result.second = second;
  Bounds reduced{VectorX(m), VectorX(m)};
  FitOptions reduced_options = options;
  reduced_options.steps = VectorX(m);
  for (Eigen::Index o = 0; o < m; ++o) {
    const Eigen::Index a = static_cast<Eigen::Index>(others[static_cast<std::size_t>(o)]);
    reduced.lower[o] = bounds.lower[a];
    reduced.upper[o] = bounds.upper[a];
    reduced_options.steps[o] = options.steps.size() == static_cast<Eigen::Index>(d) ? options.steps[a] : 1e-6;
  }
  for (std::size_t a = 0; a < sizes[first]; ++a) {
    for (std::size_t b = 0; b < sizes[second]; ++b) {
      // The slice's least grid point.
      std::size_t best = values.size();
      for (std::size_t flat = 0; flat < values.size(); ++flat) {
        if ((flat / strides[first]) % sizes[first] != a || (flat / strides[second]) % sizes[second] != b) continue;
        if (std::isfinite(values[flat]) && (best == values.size() || values[flat] < values[best])) best = flat;
      }
      VectorX theta(static_cast<Eigen::Index>(d));
      for (std::size_t c = 0; c < d; ++c)
        theta[static_cast<Eigen::Index>(c)] = axes[c][(best == values.size() ? 0 : best / strides[c]) % sizes[c]];
      if (best == values.size()) {
        result.chi2.push_back(std::numeric_limits<double>::quiet_NaN());
        result.at.push_back(theta);
        continue;
      }
      if (m == 0) {
        result.chi2.push_back(values[best]);
        result.at.push_back(theta);
        continue;
      }
      const BatchResiduals on_others = [&](const std::vector<VectorX>& parts) {
        std::vector<VectorX> full;
        for (const VectorX& part : parts) {
          VectorX point = theta;
          for (Eigen::Index o = 0; o < m; ++o) point[static_cast<Eigen::Index>(others[static_cast<std::size_t>(o)])] = part[o];
          full.push_back(point);
        }
        return residuals(full);
      };
      VectorX start(m);
      for (Eigen::Index o = 0; o < m; ++o) start[o] = theta[static_cast<Eigen::Index>(others[static_cast<std::size_t>(o)])];
      const FitResult fitted = fit_bounded(on_others, start, reduced, reduced_options);
      result.evaluations += fitted.evaluations;
      // A fit that ends above its start (it cannot, but a non-finite residual on the way can stop
      // it early) keeps the grid point.
      const bool better = std::isfinite(fitted.chi2) && fitted.chi2 < values[best];
      if (better)
        for (Eigen::Index o = 0; o < m; ++o) theta[static_cast<Eigen::Index>(others[static_cast<std::size_t>(o)])] = fitted.theta[o];
      result.chi2.push_back(better ? fitted.chi2 : values[best]);
      result.at.push_back(theta);
    }
  }
  return result;
}

}  // namespace crackle::fit
