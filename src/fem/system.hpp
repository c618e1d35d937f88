#pragma once
/// \file The linear part of the semi-discrete system of one variant of the body, MODEL.md eq. (26):
/// its DOF map (uncracked: faces tied; open: faces split), Dirichlet constraints, mass, stiffness
/// (as an operator, and assembled on request) and load shapes. Built once per variant and shared
/// by every solver (modal, the full transient, the reduced model); each piece is made on first use,
/// so a run computes only what its stages need.
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "core/types.hpp"
#include "fem/assembly.hpp"
#include "fem/constraints.hpp"
#include "fem/elastic_operator.hpp"
#include "mesh/mesh.hpp"

namespace crackle::fem {

/// A force of `total` [N] on a node set (spread evenly over its DOF nodes, add_point_force) or, if
/// `faces` is not empty, on a face set as a uniform traction of that total (add_face_traction).
struct LoadPlacement {
  std::string name;                  ///< for messages (a scene key)
  std::vector<Index> nodes;          ///< node set (used when `faces` is empty)
  std::vector<mesh::FaceRef> faces;  ///< face set
  Vec3 total = Vec3::Zero();         ///< total force [N]
};

/// A load's nodal forces [N] at its nonzero free DOFs (held DOFs dropped).
struct LoadShape {
  std::string name;
  std::vector<Index> dofs;
  std::vector<double> values;
  double dot(const VectorX& x) const {
    double sum = 0.0;
    for (std::size_t k = 0; k < dofs.size(); ++k) sum += values[k] * x[dofs[k]];
    return sum;
  }
  /// The shape as a vector over all DOFs of `n_dofs`.
  VectorX dense(Index n_dofs) const;
};

/// One variant of the body. `mesh` and `materials` are borrowed and must outlive it.
class System {
 public:
  /// `element_shares`: the mesh is one rank's share of a distributed mesh (transient::Distribution),
  /// whose lumped mass is completed by the halo; a node may lie outside its elements.
  System(const mesh::Mesh& mesh, const Materials& materials, const std::vector<DirichletCondition>& dirichlet,
         mesh::Variant variant, const ElasticOperatorOptions& elastic_options = {}, bool element_shares = false);
  ~System();
  System(System&&) noexcept;

  const mesh::Mesh& mesh() const { return *mesh_; }
  const Materials& materials() const { return *materials_; }
  mesh::Variant variant() const { return variant_; }
  const mesh::DofMap& dofs() const { return dofs_; }
  const Constraints& constraints() const { return constraints_; }
  Index n_dofs() const { return dofs_.n_dofs(); }

  /// A 64-bit fingerprint of everything K, M and the constraints are made from: the mesh (nodes,
  /// elements, regions), the materials, the variant's DOF map, the constraints, and the hash of the
  /// code that assembles them (CRACKLE_FORMULATION_HASH). Equal fingerprints give equal K, M and
  /// free DOFs, so the file caches of modes and reduced models are keyed by it without assembling K.
  std::uint64_t fingerprint() const;

  /// Lumped mass per DOF (eq. 27), all DOFs.
  const VectorX& lumped_mass() const;
  /// K as an operator over all DOFs (matrix-free on hexahedra, eq. 25a), made once.
  const ElasticOperator& stiffness() const;
  /// K assembled over all DOFs, for a factorisation (not kept: the caller owns it).
  SparseMatrix assemble_stiffness() const;
  /// Consistent mass (eq. 25c) over all DOFs (not kept).
  SparseMatrix assemble_consistent_mass() const;

  /// The nodal forces of a load. InputError naming `placement.name` for an empty set, a face set
  /// of zero area or a non-finite force.
  LoadShape load_shape(const LoadPlacement& placement) const;

 private:
  const mesh::Mesh* mesh_;
  const Materials* materials_;
  mesh::Variant variant_;
  ElasticOperatorOptions elastic_options_;
  bool element_shares_ = false;
  mesh::DofMap dofs_;
  Constraints constraints_;
  struct Lazy;
  std::unique_ptr<Lazy> lazy_;
};

}  // namespace crackle::fem
