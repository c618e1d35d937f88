#include "fem/element_basis.hpp"

namespace crackle::fem {

ElementBasis::ElementBasis(mesh::ElementShape shape, int order) : shape_(shape) {
  if (shape == mesh::ElementShape::tetrahedron) {
    tetrahedron_.emplace(order);
    n_nodes_ = tetrahedron_->n_nodes;
  } else {
    hexahedron_.emplace(order);
    n_nodes_ = hexahedron_->n_nodes;
  }
}

void ElementBasis::stiffness(const double* coords, const Material& material, MatrixX& matrix) const {
  if (hexahedron_) {
    element_stiffness(*hexahedron_, coords, material, matrix);
  } else {
    element_stiffness(*tetrahedron_, coords, material, matrix);
  }
}

void ElementBasis::mass_scalar(const double* coords, MatrixX& matrix) const {
  if (hexahedron_) {
    element_mass_scalar(*hexahedron_, coords, matrix);
  } else {
    element_mass_scalar(*tetrahedron_, coords, matrix);
  }
}

void ElementBasis::lumped_mass_scalar(const double* coords, double* mass) const {
  if (hexahedron_) {
    element_lumped_mass_scalar(*hexahedron_, coords, mass);
  } else {
    element_lumped_mass_scalar(*tetrahedron_, coords, mass);
  }
}

void ElementBasis::shape_integrals(const double* coords, double* integrals) const {
  if (hexahedron_) {
    element_shape_integrals(*hexahedron_, coords, integrals);
  } else {
    element_shape_integrals(*tetrahedron_, coords, integrals);
  }
}

}  // namespace crackle::fem
