#pragma once
/// \file Element matrices from a basis tabulated at quadrature points, whatever the element shape:
/// the hexahedron (element.hpp) and the tetrahedron (tetrahedron.hpp) share these kernels.
#include "core/types.hpp"
#include "fem/material.hpp"

namespace crackle::fem {

/// A borrowed view of a basis tabulated at quadrature points on the reference element.
struct TabulatedBasis {
  int n_nodes = 0;
  int n_points = 0;
  const double* weights = nullptr;    ///< n_points reference weights
  const double* values = nullptr;     ///< n_points x n_nodes: N_a(xi_q)
  const double* gradients = nullptr;  ///< n_points x n_nodes x 3: dN_a/dxi_j (xi_q)
};

/// Jacobian determinant of the element map at point q; InputError if it is not positive
/// (inverted or degenerate element).
double tabulated_determinant(const TabulatedBasis& basis, const double* coords, int q);

/// K_e = sum_q w_q det J_q B^T D B (MODEL.md eq. 25a), 3n x 3n, DOFs interleaved per node.
void tabulated_stiffness(const TabulatedBasis& basis, const double* coords, const Material& material,
                         MatrixX& stiffness);

/// Consistent scalar mass sum_q w_q det J_q N_a N_b (eq. 25c without rho), n x n.
void tabulated_mass_scalar(const TabulatedBasis& basis, const double* coords, MatrixX& mass);

/// \f$\int_{\Omega_e} N_a\, d\Omega\f$ by the tabulated rule (n values).
void tabulated_shape_integrals(const TabulatedBasis& basis, const double* coords, double* integrals);

}  // namespace crackle::fem
