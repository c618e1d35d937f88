#include <gtest/gtest.h>

#include <cmath>

#include "core/quadrature.hpp"

using namespace crackle;

namespace {
double integrate(const Rule1D& rule, int degree) {
  double sum = 0.0;
  for (int q = 0; q < rule.size(); ++q) sum += rule.weights[q] * std::pow(rule.points[q], degree);
  return sum;
}
double exact_monomial(int degree) { return degree % 2 ? 0.0 : 2.0 / (degree + 1); }
}  // namespace

TEST(Quadrature, GaussLegendreIsExactToDegree2nMinus1) {
  for (int n = 1; n <= 8; ++n) {
    Rule1D rule = gauss_legendre(n);
    for (int degree = 0; degree <= 2 * n - 1; ++degree) {
      EXPECT_NEAR(integrate(rule, degree), exact_monomial(degree), 1e-14) << "n=" << n << " degree=" << degree;
    }
    EXPECT_GT(std::abs(integrate(rule, 2 * n) - exact_monomial(2 * n)), 1e-6) << "n=" << n;
  }
}

TEST(Quadrature, GaussLobattoIsExactToDegree2nMinus3AndIncludesEnds) {
  for (int n = 2; n <= 9; ++n) {
    Rule1D rule = gauss_lobatto(n);
    EXPECT_EQ(rule.points.front(), -1.0);
    EXPECT_EQ(rule.points.back(), 1.0);
    for (int q = 1; q < n; ++q) EXPECT_GT(rule.points[q], rule.points[q - 1]);
    for (int q = 0; q < n; ++q) EXPECT_GT(rule.weights[q], 0.0);
    for (int degree = 0; degree <= 2 * n - 3; ++degree) {
      EXPECT_NEAR(integrate(rule, degree), exact_monomial(degree), 1e-14) << "n=" << n << " degree=" << degree;
    }
  }
  // Known values: 4 points are -1, -1/sqrt(5), 1/sqrt(5), 1 with weights 1/6, 5/6.
  Rule1D rule = gauss_lobatto(4);
  EXPECT_NEAR(rule.points[1], -1.0 / std::sqrt(5.0), 1e-15);
  EXPECT_NEAR(rule.weights[0], 1.0 / 6.0, 1e-15);
  EXPECT_NEAR(rule.weights[1], 5.0 / 6.0, 1e-15);
}

TEST(Quadrature, LagrangeBasisIsNodalAndReproducesPolynomials) {
  for (int p = 1; p <= 4; ++p) {
    const std::vector<double> nodes = gauss_lobatto(p + 1).points;
    std::vector<double> values(p + 1), derivatives(p + 1);
    for (int a = 0; a <= p; ++a) {
      lagrange_basis(nodes, nodes[a], values.data(), derivatives.data());
      for (int b = 0; b <= p; ++b) EXPECT_NEAR(values[b], a == b ? 1.0 : 0.0, 1e-14);
    }
    // Interpolating x^p reproduces it and its derivative anywhere.
    for (double x : {-0.93, -0.2, 0.37, 0.8}) {
      lagrange_basis(nodes, x, values.data(), derivatives.data());
      double value = 0.0, derivative = 0.0, sum = 0.0, derivative_sum = 0.0;
      for (int a = 0; a <= p; ++a) {
        value += values[a] * std::pow(nodes[a], p);
        derivative += derivatives[a] * std::pow(nodes[a], p);
        sum += values[a];
        derivative_sum += derivatives[a];
      }
      EXPECT_NEAR(value, std::pow(x, p), 1e-13);
      EXPECT_NEAR(derivative, p * std::pow(x, p - 1), 1e-12);
      EXPECT_NEAR(sum, 1.0, 1e-14);
      EXPECT_NEAR(derivative_sum, 0.0, 1e-12);
    }
  }
}
