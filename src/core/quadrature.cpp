#include "core/quadrature.hpp"

#include <cassert>
#include <cmath>

namespace crackle {
namespace {

/// Legendre polynomial P_n(x) and its derivative by the three-term recurrence.
void legendre(int n, double x, double& value, double& derivative) {
  double p0 = 1.0, p1 = x;
  if (n == 0) {
    value = 1.0;
    derivative = 0.0;
    return;
  }
  for (int k = 2; k <= n; ++k) {
    double p2 = ((2 * k - 1) * x * p1 - (k - 1) * p0) / k;
    p0 = p1;
    p1 = p2;
  }
  value = p1;
  // P_n'(x) = n (x P_n - P_{n-1}) / (x^2 - 1), valid away from the end points.
  derivative = n * (x * p1 - p0) / (x * x - 1.0);
}

}  // namespace

Rule1D gauss_legendre(int n) {
  assert(n >= 1);
  Rule1D rule;
  rule.points.resize(n);
  rule.weights.resize(n);
  for (int i = 0; i < n; ++i) {
    double x = std::cos(M_PI * (i + 0.75) / (n + 0.5));  // Newton start near the i-th root
    double value = 0, derivative = 1;
    for (int iteration = 0; iteration < 100; ++iteration) {
      legendre(n, x, value, derivative);
      double step = value / derivative;
      x -= step;
      if (std::abs(step) < 1e-16) break;
    }
    legendre(n, x, value, derivative);
    rule.points[n - 1 - i] = x;
    rule.weights[n - 1 - i] = 2.0 / ((1.0 - x * x) * derivative * derivative);
  }
  return rule;
}

Rule1D gauss_lobatto(int n) {
  assert(n >= 2);
  const int p = n - 1;
  Rule1D rule;
  rule.points.resize(n);
  rule.weights.resize(n);
  rule.points[0] = -1.0;
  rule.points[p] = 1.0;
  // Interior points are the roots of P_p'(x); Newton on P_p' with P_p'' from the Legendre ODE:
  // (1 - x^2) P'' = 2 x P' - p (p + 1) P.
  for (int i = 1; i < p; ++i) {
    double x = -std::cos(M_PI * i / p);  // Chebyshev–Gauss–Lobatto start
    for (int iteration = 0; iteration < 100; ++iteration) {
      double value, derivative;
      legendre(p, x, value, derivative);
      double second = (2.0 * x * derivative - p * (p + 1.0) * value) / (1.0 - x * x);
      double step = derivative / second;
      x -= step;
      if (std::abs(step) < 1e-16) break;
    }
    rule.points[i] = x;
  }
  for (int i = 0; i < n; ++i) {
    double value, derivative;
    double x = rule.points[i];
    if (i == 0 || i == p) {
      value = (i == 0 && p % 2 == 1) ? -1.0 : 1.0;
    } else {
      legendre(p, x, value, derivative);
    }
    rule.weights[i] = 2.0 / (p * (p + 1.0) * value * value);
  }
  return rule;
}

void lagrange_basis(const std::vector<double>& nodes, double x, double* values, double* derivatives) {
  const int n = static_cast<int>(nodes.size());
  for (int a = 0; a < n; ++a) {
    double value = 1.0, derivative = 0.0;
    for (int b = 0; b < n; ++b) {
      if (b == a) continue;
      double factor = 1.0 / (nodes[a] - nodes[b]);
      // product rule: d/dx [value * (x - x_b) f] = derivative * (x - x_b) f + value * f
      derivative = derivative * (x - nodes[b]) * factor + value * factor;
      value *= (x - nodes[b]) * factor;
    }
    values[a] = value;
    if (derivatives) derivatives[a] = derivative;
  }
}

}  // namespace crackle
