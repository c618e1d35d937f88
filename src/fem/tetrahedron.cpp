#include "fem/tetrahedron.hpp"

#include "core/errors.hpp"
#include "core/quadrature.hpp"

namespace crackle::fem {
namespace {

/// Gauss–Legendre rule mapped to [0, 1].
Rule1D unit_gauss(int n) {
  Rule1D rule = gauss_legendre(n);
  for (int i = 0; i < n; ++i) {
    rule.points[i] = 0.5 * (rule.points[i] + 1.0);
    rule.weights[i] *= 0.5;
  }
  return rule;
}

void check_order(int order) {
  if (order != 1 && order != 2) {
    throw InputError("tetrahedron order must be 1 or 2, got " + std::to_string(order));
  }
}

}  // namespace

void tetrahedron_shape(int order, const double xi[3], double* values, double* gradients) {
  const double lambda[4] = {1.0 - xi[0] - xi[1] - xi[2], xi[0], xi[1], xi[2]};
  static const double dlambda[4][3] = {{-1, -1, -1}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
  if (order == 1) {
    for (int a = 0; a < 4; ++a) {
      values[a] = lambda[a];
      for (int j = 0; j < 3; ++j) gradients[3 * a + j] = dlambda[a][j];
    }
    return;
  }
  // Vertices lambda_a (2 lambda_a - 1); edge nodes 4 lambda_i lambda_j (Gmsh's edge order).
  static const int edges[6][2] = {{0, 1}, {1, 2}, {2, 0}, {3, 0}, {3, 2}, {3, 1}};
  for (int a = 0; a < 4; ++a) {
    values[a] = lambda[a] * (2.0 * lambda[a] - 1.0);
    for (int j = 0; j < 3; ++j) gradients[3 * a + j] = (4.0 * lambda[a] - 1.0) * dlambda[a][j];
  }
  for (int k = 0; k < 6; ++k) {
    const int i = edges[k][0], l = edges[k][1];
    values[4 + k] = 4.0 * lambda[i] * lambda[l];
    for (int j = 0; j < 3; ++j) gradients[3 * (4 + k) + j] = 4.0 * (dlambda[i][j] * lambda[l] + lambda[i] * dlambda[l][j]);
  }
}


TriangleRule triangle_rule(int n) {
  // (s, t) = (u, (1 - u) v) on the unit square, dA = (1 - u) du dv.
  const Rule1D g = unit_gauss(n);
  TriangleRule rule;
  for (int i = 0; i < n; ++i) {
    for (int j = 0; j < n; ++j) {
      const double u = g.points[i], v = g.points[j];
      rule.s.push_back(u);
      rule.t.push_back((1.0 - u) * v);
      rule.weights.push_back(g.weights[i] * g.weights[j] * (1.0 - u));
    }
  }
  return rule;
}

TetBasis::TetBasis(int order_) : order(order_), n_nodes(order_ == 2 ? 10 : 4), n_points(0) {
  check_order(order);
  // Stroud conical product: xi = u, eta = (1 - u) v, zeta = (1 - u)(1 - v) w on the unit cube,
  // dV = (1 - u)^2 (1 - v) du dv dw; with p + 2 Gauss points per direction.
  const int m = order + 2;
  const Rule1D g = unit_gauss(m);
  n_points = m * m * m;
  points.resize(3 * n_points);
  weights.resize(n_points);
  values.resize(static_cast<std::size_t>(n_points) * n_nodes);
  gradients.resize(static_cast<std::size_t>(n_points) * n_nodes * 3);
  int q = 0;
  for (int i = 0; i < m; ++i) {
    for (int j = 0; j < m; ++j) {
      for (int k = 0; k < m; ++k, ++q) {
        const double u = g.points[i], v = g.points[j], w = g.points[k];
        double* x = &points[3 * q];
        x[0] = u;
        x[1] = (1.0 - u) * v;
        x[2] = (1.0 - u) * (1.0 - v) * w;
        weights[q] = g.weights[i] * g.weights[j] * g.weights[k] * (1.0 - u) * (1.0 - u) * (1.0 - v);
        tetrahedron_shape(order, x, &values[static_cast<std::size_t>(q) * n_nodes],
                          &gradients[static_cast<std::size_t>(q) * n_nodes * 3]);
      }
    }
  }
}

void element_stiffness(const TetBasis& basis, const double* coords, const Material& material,
                       MatrixX& stiffness) {
  tabulated_stiffness(basis.view(), coords, material, stiffness);
}

void element_mass_scalar(const TetBasis& basis, const double* coords, MatrixX& mass) {
  tabulated_mass_scalar(basis.view(), coords, mass);
}

void element_lumped_mass_scalar(const TetBasis& basis, const double* coords, double* mass) {
  // HRZ: m_a = M_aa V / sum_b M_bb, with M the consistent scalar mass (eq. 25c).
  MatrixX consistent;
  tabulated_mass_scalar(basis.view(), coords, consistent);
  double volume = 0.0;
  for (int q = 0; q < basis.n_points; ++q) volume += basis.weights[q] * tabulated_determinant(basis.view(), coords, q);
  const double scale = volume / consistent.diagonal().sum();
  for (int a = 0; a < basis.n_nodes; ++a) mass[a] = scale * consistent(a, a);
}

void element_shape_integrals(const TetBasis& basis, const double* coords, double* integrals) {
  tabulated_shape_integrals(basis.view(), coords, integrals);
}

}  // namespace crackle::fem
