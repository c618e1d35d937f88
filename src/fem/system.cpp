#include "fem/system.hpp"

#include <cmath>

#include "core/errors.hpp"
#include "fem/loads.hpp"

namespace crackle::fem {

/// The pieces made on first use.
struct System::Lazy {
  std::unique_ptr<VectorX> lumped_mass;
  std::unique_ptr<ElasticOperator> stiffness;
};

VectorX LoadShape::dense(Index n_dofs) const {
  VectorX vector = VectorX::Zero(n_dofs);
  for (std::size_t k = 0; k < dofs.size(); ++k) vector[dofs[k]] = values[k];
  return vector;
}

System::System(const mesh::Mesh& mesh, const Materials& materials, const std::vector<DirichletCondition>& dirichlet,
               mesh::Variant variant, const ElasticOperatorOptions& elastic_options, bool element_shares)
    : mesh_(&mesh),
      materials_(&materials),
      variant_(variant),
      elastic_options_(elastic_options),
      element_shares_(element_shares),
      dofs_(mesh::make_dof_map(mesh, variant)),
      constraints_(make_constraints(dofs_, dirichlet)),
      lazy_(std::make_unique<Lazy>()) {}

System::~System() = default;
System::System(System&&) noexcept = default;

const VectorX& System::lumped_mass() const {
  if (!lazy_->lumped_mass) lazy_->lumped_mass = std::make_unique<VectorX>(assemble_lumped_mass(*mesh_, dofs_, *materials_, element_shares_));
  return *lazy_->lumped_mass;
}

SparseMatrix System::assemble_consistent_mass() const { return fem::assemble_consistent_mass(*mesh_, dofs_, *materials_); }

const ElasticOperator& System::stiffness() const {
  if (!lazy_->stiffness) lazy_->stiffness = std::make_unique<ElasticOperator>(*mesh_, dofs_, *materials_, elastic_options_);
  return *lazy_->stiffness;
}

SparseMatrix System::assemble_stiffness() const { return fem::assemble_stiffness(*mesh_, dofs_, *materials_); }

LoadShape System::load_shape(const LoadPlacement& placement) const {
  const std::string& where = placement.name;
  if (!placement.total.allFinite()) throw InputError(where + ": expected a finite force, got a non-finite one");
  VectorX pattern = VectorX::Zero(n_dofs());
  if (!placement.faces.empty()) {
    const double area = face_area(*mesh_, placement.faces);
    if (!(area > 0.0)) throw InputError(where + ": the face set has zero area");
    add_face_traction(*mesh_, dofs_, placement.faces, placement.total / area, pattern);
  } else {
    if (placement.nodes.empty()) throw InputError(where + ": empty node set and no faces");
    add_point_force(dofs_, placement.nodes, placement.total, pattern);
  }
  LoadShape shape;
  shape.name = placement.name;
  for (Index d = 0; d < n_dofs(); ++d) {
    if (pattern[d] != 0.0 && !constraints_.fixed[d]) {
      shape.dofs.push_back(d);
      shape.values.push_back(pattern[d]);
    }
  }
  return shape;
}

}  // namespace crackle::fem
