#pragma once
/// \file The element basis of a mesh, whatever its element shape: one object that dispatches the
/// element matrices to the GLL hexahedron (element.hpp) or the Lagrange tetrahedron
/// (tetrahedron.hpp). Assembly, loads and lumped masses go through it.
#include <optional>

#include "core/types.hpp"
#include "fem/element.hpp"
#include "fem/material.hpp"
#include "fem/tetrahedron.hpp"
#include "mesh/mesh.hpp"

namespace crackle::fem {

class ElementBasis {
 public:
  /// InputError for an order the shape does not have (hexahedra 1..4, tetrahedra 1..2).
  ElementBasis(mesh::ElementShape shape, int order);
  explicit ElementBasis(const mesh::Mesh& mesh) : ElementBasis(mesh.shape, mesh.order) {}

  mesh::ElementShape shape() const { return shape_; }
  int n_nodes() const { return n_nodes_; }
  /// The hexahedral basis, or nullptr for tetrahedra.
  const HexBasis* hexahedron() const { return hexahedron_ ? &*hexahedron_ : nullptr; }
  /// The tetrahedral basis, or nullptr for hexahedra.
  const TetBasis* tetrahedron() const { return tetrahedron_ ? &*tetrahedron_ : nullptr; }

  /// Element stiffness of eq. (25a), 3n x 3n; `coords` is n x 3.
  void stiffness(const double* coords, const Material& material, MatrixX& matrix) const;
  /// Consistent scalar mass of eq. (25c) without density, n x n.
  void mass_scalar(const double* coords, MatrixX& matrix) const;
  /// Lumped scalar mass without density (n): GLL nodal quadrature for hexahedra, HRZ for
  /// tetrahedra. Strictly positive, sums to the element volume.
  void lumped_mass_scalar(const double* coords, double* mass) const;
  /// \f$\int N_a\, d\Omega\f$ (n values).
  void shape_integrals(const double* coords, double* integrals) const;

 private:
  mesh::ElementShape shape_;
  int n_nodes_ = 0;
  std::optional<HexBasis> hexahedron_;
  std::optional<TetBasis> tetrahedron_;
};

}  // namespace crackle::fem
