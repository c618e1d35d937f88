#include "model.hpp"

#include "core/errors.hpp"
#include "fem/material.hpp"
#include "mesh/box.hpp"

namespace crackle::app {

Model build_model(const scene::Scene& scene) {
  Model model;
  model.mesh = mesh::build_box_mesh(scene.box, scene.crack);
  if (model.mesh.n_elements() == 0) {
    throw InputError(scene.file + ": mesh: a body left with no elements");
  }
  model.materials.push_back(
      fem::isotropic(scene.material.young, scene.material.poisson, scene.material.density, "material"));
  for (std::size_t b = 0; b < scene.boundary.size(); ++b) {
    const scene::BoundarySection& section = scene.boundary[b];
    fem::DirichletCondition condition;
    condition.nodes = model.mesh.node_sets.at(section.face);
    condition.components = section.components;
    condition.values = section.values;
    condition.source = scene.file + ":" + std::to_string(section.line) + ": boundary[" + std::to_string(b) +
                       "] (face " + section.face + ")";
    model.dirichlet.push_back(std::move(condition));
  }
  return model;
}

}  // namespace crackle::app
