#pragma once
/// \file One-dimensional quadrature rules and Lagrange bases on [-1, 1].
#include <vector>

namespace crackle {

/// Points and weights of a 1D rule on [-1, 1].
struct Rule1D {
  std::vector<double> points;
  std::vector<double> weights;
  int size() const { return static_cast<int>(points.size()); }
};

/// Gauss–Legendre rule with n points: exact for polynomials of degree 2n-1.
Rule1D gauss_legendre(int n);

/// Gauss–Lobatto–Legendre rule with n >= 2 points (end points included): exact to degree 2n-3.
/// The nodes of a GLL Lagrange element of order p are gauss_lobatto(p + 1).points.
Rule1D gauss_lobatto(int n);

/// Lagrange basis on the given nodes, evaluated at x: values[a] = l_a(x), derivatives[a] = l_a'(x).
void lagrange_basis(const std::vector<double>& nodes, double x, double* values, double* derivatives);

}  // namespace crackle
