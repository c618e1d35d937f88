#include "delaminated_plate.hpp"

#include <vector>

#include "fem/material.hpp"
#include "fem/system.hpp"
#include "mesh/box.hpp"

namespace crackle::reduced::testing {

DelaminatedPlate delaminated_plate(int cells, int modes, const contact::ContactOptions& contact) {
  mesh::BoxSpec box;
  box.size = Vec3(0.2, 0.2, 0.01);
  box.cells = {cells, cells, 2};
  mesh::CrackSpec crack;
  crack.normal = kZ;
  crack.at = 0.005;
  crack.region = {{{0.1, 0.2}, {0.0, 0.2}, {0.0, 0.0}}};
  const mesh::Mesh mesh = mesh::build_box_mesh(box, crack);
  const fem::Materials materials = {fem::isotropic(210e9, 0.3, 7850.0)};
  const std::vector<fem::DirichletCondition> clamp = {{mesh.node_sets.at("x-"), {0, 1, 2}, {0.0, 0.0, 0.0}, "x-"}};
  const fem::System system(mesh, materials, clamp, mesh::Variant::open);
  std::vector<Index> tip_top;
  for (Index node = 0; node < mesh.n_nodes(); ++node)
    if (mesh.nodes[node].x() > 0.2 - 1e-9 && mesh.nodes[node].z() > 0.01 - 1e-9) tip_top.push_back(node);
  const fem::LoadShape load = system.load_shape({"tip", tip_top, {}, Vec3(0.0, 0.0, 1.0)});
  ReductionOptions options;
  options.modes = modes;
  options.friction = contact.friction_coefficient > 0.0;
  return {compute_reduction(system, options, {}, load), contact::choose_penalty(mesh, materials, contact)};
}

}  // namespace crackle::reduced::testing
