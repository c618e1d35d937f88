#pragma once
/// \file Lagrange tetrahedra of order 1 (4 nodes) and 2 (10 nodes) in Gmsh's node order
/// (mesh.hpp), their triangular faces, and element matrices.
///
/// Stiffness and consistent mass use a collapsed (Stroud conical-product) Gauss rule with
/// (p+2)^3 positive-weight points, exact to degree 2p+1 on straight-sided elements: enough for
/// both matrices of eq. (25a) and (25c). The lumped mass is HRZ lumping (Hinton–Rock–Zienkiewicz):
/// the diagonal of the consistent mass scaled to the element mass. Nodal quadrature is no option
/// for the 10-node tetrahedron: it gives its vertices zero (or, by other rules, negative) mass;
/// HRZ gives every node a positive share (vertices 1/36, edge nodes 4/27 of rho V).
#include <vector>

#include "core/types.hpp"
#include "fem/material.hpp"
#include "fem/tabulated.hpp"
#include "mesh/topology.hpp"

namespace crackle::fem {

/// Shape functions of the tetrahedron of order 1 or 2 at reference point xi (reference vertices
/// (0,0,0), (1,0,0), (0,1,0), (0,0,1)): values[a], gradients[3a + j] = dN_a/dxi_j.
void tetrahedron_shape(int order, const double xi[3], double* values, double* gradients);

/// Shape functions of the triangle of order 1 or 2 (faces of tetrahedra): the mesh layer's.
using mesh::triangle_shape;

/// A quadrature rule on the reference triangle (weights sum to 1/2).
struct TriangleRule {
  std::vector<double> s, t, weights;
  int size() const { return static_cast<int>(weights.size()); }
};

/// Collapsed Gauss rule with n x n positive-weight points, exact to degree 2n - 2.
TriangleRule triangle_rule(int n);

/// Tabulated basis of the tetrahedron of order p = 1 or 2.
struct TetBasis {
  explicit TetBasis(int order);
  int order;
  int n_nodes;                    ///< 4 or 10
  int n_points;                   ///< (p+2)^3 collapsed Gauss points
  std::vector<double> points;     ///< n_points x 3 reference coordinates
  std::vector<double> weights;    ///< n_points, sum 1/6
  std::vector<double> values;     ///< n_points x n_nodes
  std::vector<double> gradients;  ///< n_points x n_nodes x 3
  TabulatedBasis view() const {
    return {n_nodes, n_points, weights.data(), values.data(), gradients.data()};
  }
};

/// Element stiffness (3n x 3n, DOFs interleaved per node) of eq. (25a); `coords` is n x 3.
void element_stiffness(const TetBasis& basis, const double* coords, const Material& material,
                       MatrixX& stiffness);

/// Consistent element mass per component (n x n) of eq. (25c), without density.
void element_mass_scalar(const TetBasis& basis, const double* coords, MatrixX& mass);

/// HRZ-lumped element mass per node (n, scalar), without density: the diagonal of the consistent
/// mass scaled to sum to the element volume. Strictly positive.
void element_lumped_mass_scalar(const TetBasis& basis, const double* coords, double* mass);

/// \f$\int_{\Omega_e} N_a\, d\Omega\f$ (n values): the load of a unit body force density, eq. (25b).
void element_shape_integrals(const TetBasis& basis, const double* coords, double* integrals);

}  // namespace crackle::fem
