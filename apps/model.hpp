#pragma once
/// \file The wiring from a validated scene to the objects the solvers take: the mesh, its
/// materials and the Dirichlet conditions. Only apps/ knows both sides.
#include <vector>

#include "fem/assembly.hpp"
#include "fem/constraints.hpp"
#include "mesh/mesh.hpp"
#include "scene/scene.hpp"

namespace crackle::app {

/// Everything a scene describes about the body, built once and shared by every stage of a run.
struct Model {
  mesh::Mesh mesh;
  fem::Materials materials;
  std::vector<fem::DirichletCondition> dirichlet;
};

/// Meshes the body, makes its materials and turns `boundary:` into Dirichlet conditions.
/// Throws InputError (naming the scene file) for problems only visible once meshed.
Model build_model(const scene::Scene& scene);

}  // namespace crackle::app
