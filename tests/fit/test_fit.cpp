// Bounded least squares, its covariance and intervals, Student's t, the tensor spline and the
// minima of a grid and the 2D profile of a misfit, the bounded Gauss-Newton step: each against an
// exact answer or its optimality conditions.
#include <gtest/gtest.h>

#include <Eigen/LU>
#include <Eigen/QR>

#include <cmath>
#include <random>
#include <stdexcept>

#include "core/errors.hpp"
#include "fit/fit.hpp"

namespace crackle::fit {
namespace {

/// y = a exp(-b x) sampled at 8 points: a smooth two-parameter model.
struct Exponential {
  std::vector<double> x{0.0, 0.3, 0.6, 1.0, 1.5, 2.0, 2.5, 3.0};
  std::vector<double> y;
  double sigma = 1.0;
  VectorX model(const VectorX& theta) const {
    VectorX m(x.size());
    for (std::size_t i = 0; i < x.size(); ++i) m[i] = theta[0] * std::exp(-theta[1] * x[i]);
    return m;
  }
  BatchResiduals residuals(int* calls = nullptr) const {
    return [this, calls](const std::vector<VectorX>& thetas) {
      std::vector<VectorX> out;
      for (const VectorX& theta : thetas) {
        VectorX r = model(theta);
        for (std::size_t i = 0; i < x.size(); ++i) r[i] = (r[i] - y[i]) / sigma;
        out.push_back(r);
        if (calls) ++*calls;
      }
      return out;
    };
  }
};

Bounds box(std::initializer_list<double> low, std::initializer_list<double> high) {
  Bounds b{VectorX(low.size()), VectorX(high.size())};
  int i = 0;
  for (double v : low) b.lower[i++] = v;
  i = 0;
  for (double v : high) b.upper[i++] = v;
  return b;
}

TEST(StudentT, QuantilesMatchTheTables) {
  // Two-sided 95 % values of the standard tables.
  EXPECT_NEAR(student_t_quantile(0.975, 1), 12.7062, 1e-4);
  EXPECT_NEAR(student_t_quantile(0.975, 2), 4.3027, 1e-4);
  EXPECT_NEAR(student_t_quantile(0.975, 5), 2.5706, 1e-4);
  EXPECT_NEAR(student_t_quantile(0.975, 10), 2.2281, 1e-4);
  EXPECT_NEAR(student_t_quantile(0.975, 30), 2.0423, 1e-4);
  EXPECT_NEAR(student_t_quantile(0.975, 1000000), 1.95996, 1e-4);
  EXPECT_NEAR(student_t_quantile(0.995, 4), 4.6041, 1e-4);
  EXPECT_NEAR(student_t_quantile(0.025, 5), -2.5706, 1e-4);
}

TEST(FitBounded, RecoversExactParametersWithFewForwardRuns) {
  Exponential problem;
  const VectorX truth = (VectorX(2) << 2.0, 0.7).finished();
  const VectorX m = problem.model(truth);
  problem.y.assign(m.data(), m.data() + m.size());
  int calls = 0;
  FitOptions options;
  options.steps = VectorX::Constant(2, 1e-6);
  const FitResult result = fit_bounded(problem.residuals(&calls), (VectorX(2) << 1.0, 0.2).finished(),
                                       box({0.1, 0.01}, {5.0, 3.0}), options);
  EXPECT_TRUE(result.converged) << result.message;
  EXPECT_NEAR(result.theta[0], 2.0, 1e-6);
  EXPECT_NEAR(result.theta[1], 0.7, 1e-6);
  EXPECT_LT(result.chi2, 1e-12);
  EXPECT_EQ(result.evaluations, calls);
  EXPECT_LT(calls, 100);
  EXPECT_FALSE(result.at_bound[0] || result.at_bound[1]);
}

TEST(FitBounded, StopsAtAnActiveBoundAndSaysSo) {
  Exponential problem;
  const VectorX m = problem.model((VectorX(2) << 2.0, 0.7).finished());
  problem.y.assign(m.data(), m.data() + m.size());
  FitOptions options;
  options.steps = VectorX::Constant(2, 1e-6);
  // The decay rate may not exceed 0.5: the best fit sits on that bound.
  const FitResult result = fit_bounded(problem.residuals(), (VectorX(2) << 1.0, 0.2).finished(),
                                       box({0.1, 0.01}, {5.0, 0.5}), options);
  EXPECT_NEAR(result.theta[1], 0.5, 1e-9);
  EXPECT_TRUE(result.at_bound[1]);
  EXPECT_FALSE(result.at_bound[0]);
  // The Jacobian at the upper bound is one-sided from inside.
  EXPECT_TRUE(result.jacobian.allFinite());
}

/// The bounded step's optimality (KKT) conditions: feasible, the gradient of |r + J d|^2 zero on a
/// free unknown, pointing out of the box on one at a bound. Returns the largest violation, relative
/// to the gradient at d = 0.
double kkt_violation(const MatrixX& j, const VectorX& r, const VectorX& lower, const VectorX& upper, const VectorX& d) {
  const VectorX g = 2.0 * j.transpose() * (r + j * d);
  const double scale = (2.0 * j.transpose() * r).norm() + 1e-300;
  double worst = 0.0;
  for (Eigen::Index i = 0; i < d.size(); ++i) {
    const double width = upper[i] - lower[i];
    worst = std::max(worst, std::max(lower[i] - d[i], d[i] - upper[i]) / width);
    const bool at_lower = d[i] <= lower[i] + 1e-9 * width, at_upper = d[i] >= upper[i] - 1e-9 * width;
    if (at_lower) worst = std::max(worst, -g[i] / scale);      // the misfit must rise inwards
    else if (at_upper) worst = std::max(worst, g[i] / scale);
    else worst = std::max(worst, std::abs(g[i]) / scale);
  }
  return worst;
}

TEST(BoundedLinearStep, FindsTheDecreaseThatTheClippedGaussNewtonStepMisses) {
  // Nearly parallel columns: the free step (11, -10) lies far outside the box |d| <= 0.2. Clipped
  // to it, (0.2, -0.2) predicts a rise (misfit 1.0004 from 1), which a fit reads as "no step left";
  // the minimum over the box is the corner (0.2, 0.2) with misfit 0.6^2 + 0.42^2 = 0.5364.
  const MatrixX j = (MatrixX(2, 2) << 1.0, 1.0, 1.0, 1.1).finished();
  const VectorX r = (VectorX(2) << -1.0, 0.0).finished();
  const VectorX lower = VectorX::Constant(2, -0.2), upper = VectorX::Constant(2, 0.2);
  const VectorX clipped = j.colPivHouseholderQr().solve(-r).cwiseMax(lower).cwiseMin(upper);
  EXPECT_GT((r + j * clipped).squaredNorm(), r.squaredNorm());
  const VectorX d = bounded_linear_step(j, r, lower, upper);
  EXPECT_NEAR(d[0], 0.2, 1e-12);
  EXPECT_NEAR(d[1], 0.2, 1e-12);
  EXPECT_NEAR((r + j * d).squaredNorm(), 0.5364, 1e-12);
  EXPECT_LT(kkt_violation(j, r, lower, upper, d), 1e-12);
}

TEST(BoundedLinearStep, IsTheFreeStepInsideTheBoxAndOptimalOnRandomBoxes) {
  std::mt19937 random(29);
  std::uniform_real_distribution<double> uniform(-1.0, 1.0);
  for (int k : {1, 2, 3, 5, 10}) {  // 10: the projected-gradient route
    for (int trial = 0; trial < 20; ++trial) {
      const Eigen::Index n = k + 4;
      MatrixX j(n, k);
      VectorX r(n), lower(k), upper(k);
      for (Eigen::Index a = 0; a < n; ++a) {
        r[a] = uniform(random);
        for (Eigen::Index b = 0; b < k; ++b) j(a, b) = uniform(random);
      }
      for (Eigen::Index b = 0; b < k; ++b) {
        lower[b] = -0.05 - 0.5 * std::abs(uniform(random));
        upper[b] = 0.05 + 0.5 * std::abs(uniform(random));
      }
      const VectorX d = bounded_linear_step(j, r, lower, upper);
      EXPECT_LT(kkt_violation(j, r, lower, upper, d), k <= 8 ? 1e-10 : 1e-6) << "k " << k << ", trial " << trial;
      // A box wide enough to hold the free step gives the free step.
      const VectorX free = j.colPivHouseholderQr().solve(-r);
      const VectorX wide = VectorX::Constant(k, 2.0 * free.cwiseAbs().maxCoeff() + 1.0);
      EXPECT_LT((bounded_linear_step(j, r, -wide, wide) - free).norm(), 1e-6 * (1.0 + free.norm())) << "k " << k;
    }
  }
}

TEST(FitBounded, AResidualWithoutAValueStopsTheFitQuietly) {
  // Residuals that cannot be evaluated (NaN) at the start (a map point whose forward run has no value):
  // the fit stops there and says so in its result, and nothing reaches stderr (Ceres logs such a
  // failure through glog by default, "Terminating: Residual and Jacobian evaluation failed").
  const BatchResiduals residuals = [](const std::vector<VectorX>& thetas) {
    std::vector<VectorX> out;
    for (const VectorX& theta : thetas)
      out.push_back(theta[0] > 1.0 ? VectorX::Constant(2, std::nan("")) : (VectorX(2) << theta[0] - 3.0, 0.0).finished());
    return out;
  };
  FitOptions options;
  options.steps = VectorX::Constant(1, 1e-6);
  testing::internal::CaptureStderr();
  const FitResult result = fit_bounded(residuals, VectorX::Constant(1, 2.0), box({0.0}, {5.0}), options);
  const std::string logged = testing::internal::GetCapturedStderr();
  EXPECT_EQ(logged, "");
  EXPECT_FALSE(result.converged);
  EXPECT_FALSE(std::isfinite(result.chi2));
  EXPECT_NE(result.message.find("evaluation failed"), std::string::npos) << result.message;
}

TEST(Uncertainty, LinearModelCovarianceIsExactAndIntervalsCoverAtTheNominalRate) {
  // y = a + b x with sigma = 1: C = (X^T X)^-1 exactly, and over many noisy replicas the 95 %
  // intervals (Student t, s^2 from the fit) cover the truth in about 95 % of them.
  const std::vector<double> x{0.0, 1.0, 2.0, 3.0, 4.0, 5.0};
  MatrixX design(6, 2);
  for (int i = 0; i < 6; ++i) design.row(i) << 1.0, x[i];
  const MatrixX exact = (design.transpose() * design).inverse();
  const Uncertainty trusted = uncertainty(design, VectorX::Zero(2), 4.0, false);
  EXPECT_NEAR((trusted.covariance - exact).norm(), 0.0, 1e-12);
  EXPECT_NEAR(trusted.correlation(0, 1), exact(0, 1) / std::sqrt(exact(0, 0) * exact(1, 1)), 1e-12);
  const Uncertainty scaled = uncertainty(design, VectorX::Zero(2), 8.0, true);
  EXPECT_NEAR(scaled.s2, 2.0, 1e-12);
  EXPECT_NEAR(scaled.t, student_t_quantile(0.975, 4), 1e-12);

  std::mt19937 generator(7);
  std::normal_distribution<double> noise(0.0, 0.3);
  int covered = 0;
  const int replicas = 2000;
  for (int rep = 0; rep < replicas; ++rep) {
    VectorX y(6);
    for (int i = 0; i < 6; ++i) y[i] = 1.0 + 0.5 * x[i] + noise(generator);
    const VectorX theta = design.colPivHouseholderQr().solve(y);
    const double chi2 = (design * theta - y).squaredNorm();
    const Uncertainty u = uncertainty(design, theta, chi2, true);
    if (u.interval_95[1][0] <= 0.5 && 0.5 <= u.interval_95[1][1]) ++covered;
  }
  EXPECT_NEAR(static_cast<double>(covered) / replicas, 0.95, 0.015);
}

TEST(Uncertainty, RankDeficientJacobianIsFlagged) {
  MatrixX j(4, 2);
  j << 1, 2, 2, 4, 3, 6, 4, 8;  // the second column is twice the first: only a + 2b is seen
  const Uncertainty u = uncertainty(j, VectorX::Zero(2), 1.0, false);
  EXPECT_TRUE(u.rank_deficient);
  EXPECT_EQ(u.rank, 1);
  EXPECT_FALSE(std::isfinite(u.sd[0]));
}

TEST(TensorSpline, ReproducesCubicsAlongOneAxisAndLinearFunctionsEverywhere) {
  // A natural spline reproduces linear functions exactly; on a fine grid a smooth function to O(h^4).
  std::vector<double> a{0.0, 0.5, 1.0, 1.5, 2.0}, b{-1.0, 0.0, 1.0, 2.0};
  std::vector<VectorX> values, smooth;
  for (double u : a)
    for (double v : b) {
      values.push_back((VectorX(2) << 1.0 + 2.0 * u - 3.0 * v, u - v).finished());
      smooth.push_back((VectorX(1) << std::sin(u) * std::cos(0.5 * v)).finished());
    }
  const TensorSpline linear({a, b}, values);
  const VectorX at = (VectorX(2) << 0.73, 1.31).finished();
  EXPECT_NEAR(linear(at)[0], 1.0 + 2.0 * 0.73 - 3.0 * 1.31, 1e-12);
  EXPECT_NEAR(linear(at)[1], 0.73 - 1.31, 1e-12);
  // Grid values are hit exactly.
  EXPECT_NEAR(TensorSpline({a, b}, smooth)((VectorX(2) << 1.5, 0.0).finished())[0], std::sin(1.5), 1e-12);
  // Halving the spacing shrinks the interior error by about 16 (fourth order away from the ends).
  auto error = [](int n) {
    std::vector<double> axis;
    for (int i = 0; i <= n; ++i) axis.push_back(-1.0 + 4.0 * i / n);
    std::vector<VectorX> v;
    for (double u : axis)
      for (double w : axis) v.push_back((VectorX(1) << std::sin(u) * std::cos(0.5 * w)).finished());
    const TensorSpline spline({axis, axis}, v);
    return std::abs(spline((VectorX(2) << 1.05, 0.9).finished())[0] - std::sin(1.05) * std::cos(0.45));
  };
  const double ratio = error(16) / error(32);
  EXPECT_GT(ratio, 8.0);
}

TEST(TensorSpline, AMissingValueStaysInTheCellsAroundIt) {
  // A linear function on a 5 x 5 grid with quantity 0 missing at one inner point: quantity 0 is NaN
  // in the four cells around it and finite in the others, where the splines (built with the nearest
  // value in its place) stay near the function; quantity 1, present everywhere, is exact everywhere.
  // Before, the one NaN made quantity 0 NaN along its grid lines and beyond.
  const std::vector<double> a{0.0, 1.0, 2.0, 3.0, 4.0}, b{0.0, 1.0, 2.0, 3.0, 4.0};
  std::vector<VectorX> values;
  for (double u : a)
    for (double v : b) values.push_back((VectorX(2) << u + 2.0 * v, u - v).finished());
  values[1 * 5 + 2][0] = std::nan("");  // at (1, 2)
  const TensorSpline spline({a, b}, values);
  for (double u = 0.25; u < 4.0; u += 0.5)
    for (double v = 0.25; v < 4.0; v += 0.5) {
      const VectorX at = spline((VectorX(2) << u, v).finished());
      const bool around = u < 2.0 && v > 1.0 && v < 3.0;
      EXPECT_EQ(std::isnan(at[0]), around) << u << ", " << v;
      if (!around) EXPECT_NEAR(at[0], u + 2.0 * v, 0.35) << u << ", " << v;
      EXPECT_NEAR(at[1], u - v, 1e-12);
    }
  // A grid point next to the missing one is still hit exactly.
  EXPECT_NEAR(spline((VectorX(2) << 3.0, 2.0).finished())[0], 7.0, 1e-12);
}

TEST(GridMinima, FindsEveryLocalMinimumLowestFirst) {
  // Two wells of a symmetric function on a 9 x 5 grid: both reported, the deeper first.
  std::vector<double> u, v{0, 1, 2, 3, 4};
  for (int i = 0; i < 9; ++i) u.push_back(i);
  std::vector<double> values;
  for (double a : u)
    for (double b : v) values.push_back(std::min(std::pow(a - 2, 2), std::pow(a - 6, 2) + 0.5) + std::pow(b - 2, 2));
  const std::vector<std::size_t> minima = grid_minima({u, v}, values);
  ASSERT_EQ(minima.size(), 2u);
  EXPECT_EQ(minima[0], 2u * 5 + 2);
  EXPECT_EQ(minima[1], 6u * 5 + 2);
}

TEST(Profile, OfAQuadraticMisfitIsItsMarginalQuadraticForm) {
  // Linear residuals r = A theta - y in 3 and 4 unknowns: the least misfit over the others at fixed
  // (theta_i, theta_j) is chi2_min + d^T C_ij^-1 d, d = (theta_i, theta_j) - their estimate, C = (A^T
  // A)^-1 (the marginal covariance of the pair). The others' bounds are wide enough to hold their
  // conditional minimisers, so the formula is exact; every node is also at most its slice's least
  // grid value, and with two unknowns the profile is the grid itself.
  std::mt19937 generator(3);
  std::normal_distribution<double> gauss(0.0, 1.0);
  for (const int k : {3, 4}) {
    const int n = 7;
    MatrixX a(n, k);
    for (int i = 0; i < n; ++i)
      for (int j = 0; j < k; ++j) a(i, j) = gauss(generator) + (i % k == j ? 2.0 : 0.0);
    const VectorX y = VectorX::NullaryExpr(n, [&](Eigen::Index) { return gauss(generator); });
    const BatchResiduals residuals = [&](const std::vector<VectorX>& thetas) {
      std::vector<VectorX> out;
      for (const VectorX& theta : thetas) out.push_back(a * theta - y);
      return out;
    };
    const VectorX estimate = a.colPivHouseholderQr().solve(y);
    const double least = (a * estimate - y).squaredNorm();
    const MatrixX covariance = (a.transpose() * a).inverse();
    std::vector<std::vector<double>> axes(static_cast<std::size_t>(k));
    Bounds bounds{VectorX(k), VectorX(k)};
    for (int j = 0; j < k; ++j) {
      const double half = j < 2 ? 3.0 * std::sqrt(covariance(j, j)) : 30.0;  // the pair's grid about the estimate
      bounds.lower[j] = estimate[j] - half;
      bounds.upper[j] = estimate[j] + half;
      for (int i = 0; i < 5; ++i) axes[static_cast<std::size_t>(j)].push_back(bounds.lower[j] + 2.0 * half * i / 4.0);
    }
    std::vector<double> values;
    std::size_t total = 1;
    for (const auto& axis : axes) total *= axis.size();
    for (std::size_t flat = 0; flat < total; ++flat) {
      VectorX theta(k);
      std::size_t rest = flat;
      for (int j = k; j-- > 0;) {
        theta[j] = axes[static_cast<std::size_t>(j)][rest % 5];
        rest /= 5;
      }
      values.push_back((a * theta - y).squaredNorm());
    }
    FitOptions options;
    options.steps = VectorX::Constant(k, 1e-6);
    const Profile p = profile(residuals, axes, values, bounds, 0, 1, options);
    ASSERT_EQ(p.chi2.size(), 25u);
    const Eigen::Matrix2d inverse = covariance.topLeftCorner(2, 2).inverse();
    for (std::size_t node = 0; node < 25; ++node) {
      const Eigen::Vector2d d(axes[0][node / 5] - estimate[0], axes[1][node % 5] - estimate[1]);
      const double exact = least + d.dot(inverse * d);
      EXPECT_NEAR(p.chi2[node], exact, 1e-6 * exact) << "k = " << k << ", node " << node;
      EXPECT_NEAR((a * p.at[node] - y).squaredNorm(), p.chi2[node], 1e-9 * exact);
      double slice = HUGE_VAL;
      for (std::size_t flat = 0; flat < total; ++flat)
        if (flat / (total / 5) == node / 5 && (flat / (total / 25)) % 5 == node % 5) slice = std::min(slice, values[flat]);
      EXPECT_LE(p.chi2[node], slice * (1.0 + 1e-12));
    }
    EXPECT_GT(p.evaluations, 25);
  }
  // Two unknowns: the grid's own values, no fit.
  const std::vector<std::vector<double>> axes{{0.0, 1.0, 2.0}, {0.0, 1.0}};
  const std::vector<double> values{5.0, 4.0, 3.0, 2.0, 1.0, std::nan("")};
  const Bounds bounds = box({0.0, 0.0}, {2.0, 1.0});
  const BatchResiduals unused = [](const std::vector<VectorX>&) -> std::vector<VectorX> {
    throw std::logic_error("no fit with two unknowns");
  };
  const Profile two = profile(unused, axes, values, bounds, 0, 1, FitOptions{});
  EXPECT_EQ(two.chi2.front(), 5.0);
  EXPECT_TRUE(std::isnan(two.chi2.back()));
  EXPECT_EQ(two.evaluations, 0);
  EXPECT_THROW(profile(unused, axes, values, bounds, 1, 1, FitOptions{}), SolverError);
}

}  // namespace
}  // namespace crackle::fit
