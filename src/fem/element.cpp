#include "fem/element.hpp"

#include <Eigen/LU>

#include "core/errors.hpp"
#include "fem/tabulated.hpp"

namespace crackle::fem {
namespace {

/// Jacobian J_ij = dx_i/dxi_j = sum_a x_a,i dN_a/dxi_j at one point; `dshape` is n x 3.
Eigen::Matrix3d jacobian(int n_nodes, const double* coords, const double* dshape) {
  Eigen::Matrix3d jac = Eigen::Matrix3d::Zero();
  for (int a = 0; a < n_nodes; ++a) {
    const double* x = coords + 3 * a;
    const double* g = dshape + 3 * a;
    for (int i = 0; i < 3; ++i) {
      for (int j = 0; j < 3; ++j) jac(i, j) += x[i] * g[j];
    }
  }
  return jac;
}

/// det J, throwing InputError for an inverted or degenerate element.
double checked_determinant(const Eigen::Matrix3d& jac) {
  const double det = jac.determinant();
  if (!(det > 0.0)) {
    throw InputError("element Jacobian determinant " + format_number(det) +
                     " <= 0 (inverted or degenerate element)");
  }
  return det;
}

}  // namespace

HexBasis::HexBasis(int order_)
    : order(order_),
      n_nodes((order_ + 1) * (order_ + 1) * (order_ + 1)),
      gll(gauss_lobatto(order_ + 1 >= 2 ? order_ + 1 : 2)),
      gauss(gauss_legendre(order_ + 1 >= 1 ? order_ + 1 : 1)),
      n_points(n_nodes) {
  if (order < 1 || order > 4) {
    throw InputError("element order must be 1..4, got " + std::to_string(order));
  }
  const int m = order + 1;
  // 1D basis on the GLL nodes, tabulated at the Gauss points.
  std::vector<double> v1(m * m), d1(m * m);
  for (int q = 0; q < m; ++q) lagrange_basis(gll.points, gauss.points[q], &v1[q * m], &d1[q * m]);
  gll_derivatives.resize(m * m);
  std::vector<double> unused(m);
  for (int i = 0; i < m; ++i)
    lagrange_basis(gll.points, gll.points[i], unused.data(), &gll_derivatives[i * m]);

  weights.resize(n_points);
  values.resize(static_cast<std::size_t>(n_points) * n_nodes);
  gradients.resize(static_cast<std::size_t>(n_points) * n_nodes * 3);
  for (int qk = 0; qk < m; ++qk) {
    for (int qj = 0; qj < m; ++qj) {
      for (int qi = 0; qi < m; ++qi) {
        const int q = qi + m * (qj + m * qk);
        weights[q] = gauss.weights[qi] * gauss.weights[qj] * gauss.weights[qk];
        for (int k = 0; k < m; ++k) {
          for (int j = 0; j < m; ++j) {
            for (int i = 0; i < m; ++i) {
              const int a = i + m * (j + m * k);
              const double vi = v1[qi * m + i], vj = v1[qj * m + j], vk = v1[qk * m + k];
              const std::size_t index = static_cast<std::size_t>(q) * n_nodes + a;
              values[index] = vi * vj * vk;
              gradients[3 * index + 0] = d1[qi * m + i] * vj * vk;
              gradients[3 * index + 1] = vi * d1[qj * m + j] * vk;
              gradients[3 * index + 2] = vi * vj * d1[qk * m + k];
            }
          }
        }
      }
    }
  }
}

namespace {

TabulatedBasis view(const HexBasis& basis) {
  return {basis.n_nodes, basis.n_points, basis.weights.data(), basis.values.data(), basis.gradients.data()};
}

}  // namespace

double tabulated_determinant(const TabulatedBasis& basis, const double* coords, int q) {
  const double* dshape = basis.gradients + static_cast<std::size_t>(q) * basis.n_nodes * 3;
  return checked_determinant(jacobian(basis.n_nodes, coords, dshape));
}

void tabulated_stiffness(const TabulatedBasis& basis, const double* coords, const Material& material,
                         MatrixX& stiffness) {
  // K_ab = sum_q w_q det J_q B_a^T D B_b (eq. 25a), B_a the 6x3 strain-displacement block of node a
  // (Voigt xx, yy, zz, yz, xz, xy). B_a has 9 nonzeros out of 18; both products below use that.
  const int n = basis.n_nodes;
  const VoigtMatrix& d = material.stiffness;
  stiffness.setZero(3 * n, 3 * n);
  std::vector<double> grad(3 * n);  // physical gradients dN_a/dx_j
  std::vector<double> d_b(18 * n);  // (w det J) D B_b, 6x3 row-major per node
  for (int q = 0; q < basis.n_points; ++q) {
    const double* dshape = &basis.gradients[static_cast<std::size_t>(q) * n * 3];
    const Eigen::Matrix3d jac = jacobian(n, coords, dshape);
    const double det = checked_determinant(jac);
    const Eigen::Matrix3d inv = jac.inverse();
    const double scale = basis.weights[q] * det;
    for (int a = 0; a < n; ++a) {
      const double* g = dshape + 3 * a;
      for (int j = 0; j < 3; ++j) grad[3 * a + j] = g[0] * inv(0, j) + g[1] * inv(1, j) + g[2] * inv(2, j);
    }
    for (int b = 0; b < n; ++b) {
      const double gx = scale * grad[3 * b], gy = scale * grad[3 * b + 1], gz = scale * grad[3 * b + 2];
      double* x = &d_b[18 * b];
      for (int r = 0; r < 6; ++r) {
        // Columns of B_b: u_x -> (xx: gx, xz: gz, xy: gy), u_y -> (yy: gy, yz: gz, xy: gx),
        // u_z -> (zz: gz, yz: gy, xz: gx).
        x[3 * r + 0] = d(r, 0) * gx + d(r, 4) * gz + d(r, 5) * gy;
        x[3 * r + 1] = d(r, 1) * gy + d(r, 3) * gz + d(r, 5) * gx;
        x[3 * r + 2] = d(r, 2) * gz + d(r, 3) * gy + d(r, 4) * gx;
      }
    }
    // Upper block triangle a <= b; the lower one is mirrored at the end (exact symmetry).
    for (int b = 0; b < n; ++b) {
      const double* x = &d_b[18 * b];
      for (int a = 0; a <= b; ++a) {
        const double gx = grad[3 * a], gy = grad[3 * a + 1], gz = grad[3 * a + 2];
        for (int col = 0; col < 3; ++col) {
          double* k = &stiffness(3 * a, 3 * b + col);
          k[0] += gx * x[col] + gz * x[12 + col] + gy * x[15 + col];
          k[1] += gy * x[3 + col] + gz * x[9 + col] + gx * x[15 + col];
          k[2] += gz * x[6 + col] + gy * x[9 + col] + gx * x[12 + col];
        }
      }
    }
  }
  for (int b = 0; b < n; ++b) {
    for (int a = 0; a <= b; ++a) {
      for (int r = 0; r < 3; ++r) {
        for (int c = (a == b ? r + 1 : 0); c < 3; ++c) {
          stiffness(3 * b + c, 3 * a + r) = stiffness(3 * a + r, 3 * b + c);
        }
      }
    }
  }
}

void tabulated_mass_scalar(const TabulatedBasis& basis, const double* coords, MatrixX& mass) {
  // M_ab = sum_q w_q det J_q N_a N_b (eq. 25c without rho).
  const int n = basis.n_nodes;
  mass.setZero(n, n);
  for (int q = 0; q < basis.n_points; ++q) {
    const double* dshape = &basis.gradients[static_cast<std::size_t>(q) * n * 3];
    const double scale = basis.weights[q] * checked_determinant(jacobian(n, coords, dshape));
    const double* shape = &basis.values[static_cast<std::size_t>(q) * n];
    for (int b = 0; b < n; ++b) {
      const double sb = scale * shape[b];
      for (int a = 0; a <= b; ++a) mass(a, b) += shape[a] * sb;
    }
  }
  for (int b = 0; b < n; ++b) {
    for (int a = 0; a < b; ++a) mass(b, a) = mass(a, b);
  }
}

void element_stiffness(const HexBasis& basis, const double* coords, const Material& material,
                       MatrixX& stiffness) {
  tabulated_stiffness(view(basis), coords, material, stiffness);
}

void element_mass_scalar(const HexBasis& basis, const double* coords, MatrixX& mass) {
  tabulated_mass_scalar(view(basis), coords, mass);
}

void element_lumped_mass_scalar(const HexBasis& basis, const double* coords, double* mass) {
  // GLL nodal quadrature of eq. (25c): N_a(xi_b) = delta_ab, so m_a = w_i w_j w_k det J(xi_a).
  const int m = basis.order + 1;
  const double* dmat = basis.gll_derivatives.data();
  for (int k = 0; k < m; ++k) {
    for (int j = 0; j < m; ++j) {
      for (int i = 0; i < m; ++i) {
        Eigen::Matrix3d jac = Eigen::Matrix3d::Zero();
        for (int l = 0; l < m; ++l) {
          const double* xi = coords + 3 * (l + m * (j + m * k));
          const double* xj = coords + 3 * (i + m * (l + m * k));
          const double* xk = coords + 3 * (i + m * (j + m * l));
          for (int c = 0; c < 3; ++c) {
            jac(c, 0) += dmat[i * m + l] * xi[c];
            jac(c, 1) += dmat[j * m + l] * xj[c];
            jac(c, 2) += dmat[k * m + l] * xk[c];
          }
        }
        const double weight = basis.gll.weights[i] * basis.gll.weights[j] * basis.gll.weights[k];
        mass[i + m * (j + m * k)] = weight * checked_determinant(jac);
      }
    }
  }
  // The GLL rule integrates det J exactly on affine elements only (degree 2p-1 per direction); scale
  // to the Gauss-exact element volume so that the masses always sum to rho V (factor 1 on affine).
  double gll_volume = 0.0, volume = 0.0;
  for (int a = 0; a < basis.n_nodes; ++a) gll_volume += mass[a];
  for (int q = 0; q < basis.n_points; ++q) {
    const double* dshape = &basis.gradients[static_cast<std::size_t>(q) * basis.n_nodes * 3];
    volume += basis.weights[q] * checked_determinant(jacobian(basis.n_nodes, coords, dshape));
  }
  const double scale = volume / gll_volume;
  for (int a = 0; a < basis.n_nodes; ++a) mass[a] *= scale;
}

void tabulated_shape_integrals(const TabulatedBasis& basis, const double* coords, double* integrals) {
  const int n = basis.n_nodes;
  for (int a = 0; a < n; ++a) integrals[a] = 0.0;
  for (int q = 0; q < basis.n_points; ++q) {
    const double* dshape = &basis.gradients[static_cast<std::size_t>(q) * n * 3];
    const double scale = basis.weights[q] * checked_determinant(jacobian(n, coords, dshape));
    const double* shape = &basis.values[static_cast<std::size_t>(q) * n];
    for (int a = 0; a < n; ++a) integrals[a] += scale * shape[a];
  }
}

void element_shape_integrals(const HexBasis& basis, const double* coords, double* integrals) {
  tabulated_shape_integrals(view(basis), coords, integrals);
}

void brick_coordinates(const HexBasis& basis, double hx, double hy, double hz, double* coords) {
  const int m = basis.order + 1;
  for (int k = 0; k < m; ++k) {
    for (int j = 0; j < m; ++j) {
      for (int i = 0; i < m; ++i) {
        double* x = coords + 3 * (i + m * (j + m * k));
        x[0] = 0.5 * (basis.gll.points[i] + 1.0) * hx;
        x[1] = 0.5 * (basis.gll.points[j] + 1.0) * hy;
        x[2] = 0.5 * (basis.gll.points[k] + 1.0) * hz;
      }
    }
  }
}

}  // namespace crackle::fem
