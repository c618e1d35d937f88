#pragma once
/// \file Reference hexahedron of order p with GLL nodes, and element matrices.
#include <vector>

#include "core/quadrature.hpp"
#include "core/types.hpp"
#include "fem/material.hpp"

namespace crackle::fem {

/// Tabulated basis of the GLL Lagrange hexahedron of order p.
/// Stiffness and consistent mass use (p+1)^3 Gauss points: exact on affine elements.
/// The lumped mass uses the GLL nodes themselves as quadrature points (diagonal, positive).
struct HexBasis {
  explicit HexBasis(int order);
  int order;
  int n_nodes;                  ///< (p+1)^3
  Rule1D gll;                   ///< nodes and weights of the GLL rule with p+1 points
  Rule1D gauss;                 ///< Gauss rule with p+1 points
  int n_points;                 ///< (p+1)^3 Gauss points
  std::vector<double> weights;  ///< n_points tensor weights
  std::vector<double> values;   ///< n_points x n_nodes: N_a(xi_q)
  std::vector<double> gradients;  ///< n_points x n_nodes x 3: dN_a/dxi_j (xi_q)
  /// (p+1) x (p+1) derivative matrix of the 1D GLL basis at its own nodes: [i][l] = l_l'(xi_i).
  std::vector<double> gll_derivatives;
};

/// Element stiffness K_e (3n x 3n, DOFs interleaved per node) of MODEL.md eq. (25a).
/// `coords` is n_nodes x 3 (node coordinates of the element).
void element_stiffness(const HexBasis& basis, const double* coords, const Material& material,
                       MatrixX& stiffness);

/// Consistent element mass per component (n x n, scalar) of eq. (25c), without density.
void element_mass_scalar(const HexBasis& basis, const double* coords, MatrixX& mass);

/// Lumped element mass per node (n, scalar) by GLL nodal quadrature, without density: diagonal of
/// eq. (25c), positive. Scaled to sum to the element volume, which changes it only on non-affine
/// elements (where the GLL rule does not integrate det J exactly).
void element_lumped_mass_scalar(const HexBasis& basis, const double* coords, double* mass);

/// Integrals of the shape functions \f$\int_{\Omega_e} N_a\, d\Omega\f$ (n values) with the
/// Gauss rule: the load vector of a unit body force density, eq. (25b).
void element_shape_integrals(const HexBasis& basis, const double* coords, double* integrals);

/// Node coordinates (n x 3) of the axis-aligned brick [0,hx] x [0,hy] x [0,hz] of order p.
void brick_coordinates(const HexBasis& basis, double hx, double hy, double hz, double* coords);

}  // namespace crackle::fem
