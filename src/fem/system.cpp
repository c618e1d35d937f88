#include "fem/system.hpp"

#include <cmath>
#include <optional>

#include "core/errors.hpp"
#include "core/fingerprint.hpp"
#include "fem/loads.hpp"
#include "fem/formulation_hash.hpp"

namespace crackle::fem {

/// The pieces made on first use.
struct System::Lazy {
  std::unique_ptr<VectorX> lumped_mass;
  std::unique_ptr<ElasticOperator> stiffness;
  std::optional<std::uint64_t> fingerprint;  ///< the caches ask for it per stage and per refinement run
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

std::uint64_t System::fingerprint() const {
  if (lazy_->fingerprint) return *lazy_->fingerprint;
  std::uint64_t hash = kFingerprintSeed;
  const auto mix = [&hash](const void* data, std::size_t bytes) { fingerprint_mix(hash, data, bytes); };
  const std::uint64_t formulation = CRACKLE_FORMULATION_HASH;
  mix(&formulation, sizeof formulation);
  const mesh::Mesh& mesh = *mesh_;
  const std::int64_t shape[4] = {static_cast<std::int64_t>(mesh.shape), mesh.order,
                                 static_cast<std::int64_t>(mesh.connectivity.size()), mesh.axis_aligned_bricks ? 1 : 0};
  mix(shape, sizeof shape);
  // The body as the variant's DOF map sees it: the coordinates of each DOF node and the DOF nodes of
  // each element. The uncracked variant ties the crack's node copies, so its fingerprint does not
  // depend on the crack (a study over crack sizes shares its uncracked solve), as its K does not.
  std::vector<Vec3> coordinates(static_cast<std::size_t>(dofs_.n_dof_nodes), Vec3::Zero());
  for (Index node = 0; node < mesh.n_nodes(); ++node) coordinates[dofs_.dof_node[node]] = mesh.nodes[node];
  mix(coordinates.data(), sizeof(Vec3) * coordinates.size());
  std::vector<Index> element_dof_nodes(mesh.connectivity.size());
  for (std::size_t k = 0; k < element_dof_nodes.size(); ++k) element_dof_nodes[k] = dofs_.dof_node[mesh.connectivity[k]];
  mix(element_dof_nodes.data(), sizeof(Index) * element_dof_nodes.size());
  mix(mesh.element_region.data(), sizeof(int) * mesh.element_region.size());
  for (const Material& material : *materials_) {
    mix(&material.density, sizeof material.density);
    mix(material.stiffness.data(), sizeof(double) * material.stiffness.size());
  }
  const std::int64_t layout[3] = {static_cast<std::int64_t>(variant_), dofs_.n_dof_nodes, element_shares_ ? 1 : 0};
  mix(layout, sizeof layout);
  mix(constraints_.fixed.data(), constraints_.fixed.size());
  mix(constraints_.values.data(), sizeof(double) * constraints_.values.size());
  lazy_->fingerprint = hash;
  return hash;
}

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
