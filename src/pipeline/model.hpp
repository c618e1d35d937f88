#pragma once
/// \file The wiring from a validated scene to the objects the solvers take: the mesh, its
/// materials, the Dirichlet conditions and the linear system of each variant (fem::System),
/// shared by every stage of a run.
#include <array>
#include <map>
#include <memory>
#include <vector>

#include "contact/contact.hpp"
#include "fem/assembly.hpp"
#include "fem/constraints.hpp"
#include "fem/system.hpp"
#include "mesh/mesh.hpp"
#include "scene/scene.hpp"

namespace crackle::modal {
class StiffnessFactors;
}

namespace crackle::pipeline {

/// Everything a scene describes about the body, built once and shared by every stage of a run.
struct Model {
  mesh::Mesh mesh;
  fem::Materials materials;
  std::vector<fem::DirichletCondition> dirichlet;

  Model() = default;
  /// A moved model starts without systems (they borrow the mesh and materials of their model).
  Model(Model&& other) noexcept
      : mesh(std::move(other.mesh)), materials(std::move(other.materials)), dirichlet(std::move(other.dirichlet)) {}
  Model(const Model&) = delete;
  Model& operator=(const Model&) = delete;
  Model& operator=(Model&&) = delete;

  /// The linear system of a variant (DOF map, constraints, lumped mass, K), made on first use and
  /// shared by the modal and transient stages. Valid while this model lives.
  std::shared_ptr<const fem::System> system(mesh::Variant variant) const {
    std::shared_ptr<const fem::System>& entry = systems_[variant];
    if (!entry) entry = std::make_shared<const fem::System>(mesh, materials, dirichlet, variant);
    return entry;
  }

  /// The factors of K that one stage leaves to the next (the modal stage's to the reduced model's
  /// eigen-solves and static images, and to the runs that share this model), made at the first
  /// call. Only a run whose later stages solve with K asks for it: a full explicit run must not hold
  /// a factor through its transient.
  modal::StiffnessFactors& factors() const;

 private:
  mutable std::map<mesh::Variant, std::shared_ptr<const fem::System>> systems_;
  mutable std::shared_ptr<modal::StiffnessFactors> factors_;
};

/// The crack contact of the scene's `crack.contact` (and the crack's gap g0).
contact::ContactOptions scene_contact_options(const scene::Scene& scene);

/// The variant the transient (and the reduced model built for it) runs on: open where
/// transient.variant says so and the mesh has a crack, else uncracked.
mesh::Variant transient_variant(const scene::Scene& scene, const Model& model);

/// What a model is built for: `mesh.box.grading: auto` grades the box mesh towards the crack front
/// for modal analysis and leaves it uniform for `crackle run` and `crackle sweep`: the full
/// explicit transient's stable step would pay the smallest cell, and the reduced transient and the
/// sweep keep the full run's mesh, so that switching transient.model changes the cost, not the
/// answer (docs/architecture.md, "Which analysis grades").
enum class MeshUse { modal, transient };

/// The grading of the box mesh for this use (layers = 0: none).
mesh::Grading box_grading(const scene::Scene& scene, MeshUse use);

/// Meshes the body, makes its materials and turns `boundary:` into Dirichlet conditions.
/// Throws InputError (naming the scene file) for problems only visible once meshed.
Model build_model(const scene::Scene& scene, MeshUse use = MeshUse::transient);

/// The grid lines of a box scene for this use (grading, crack edges, material regions).
std::array<std::vector<double>, 3> box_lines(const scene::Scene& scene, MeshUse use);

}  // namespace crackle::pipeline
