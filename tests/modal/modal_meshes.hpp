#pragma once
// Meshes, supports and materials shared by the modal tests.
#include <string>
#include <vector>

#include "fem/constraints.hpp"
#include "fem/material.hpp"
#include "mesh/box.hpp"

namespace crackle::modal::testing {

constexpr double kSteelYoung = 2.1e11;
constexpr double kSteelDensity = 7800.0;

inline fem::Materials steel(double poisson) { return {fem::isotropic(kSteelYoung, poisson, kSteelDensity, "steel")}; }

inline mesh::Mesh box_mesh(const Vec3& size, std::array<int, 3> cells, int order,
                           const std::optional<mesh::CrackSpec>& crack = std::nullopt) {
  mesh::BoxSpec box;
  box.size = size;
  box.cells = cells;
  box.order = order;
  return mesh::build_box_mesh(box, crack);
}

/// Fixes `components` of every node of box face `face` to zero.
inline fem::DirichletCondition fix(const mesh::Mesh& mesh, const std::string& face, std::vector<int> components) {
  fem::DirichletCondition condition;
  condition.nodes = mesh.node_sets.at(face);
  condition.values.assign(components.size(), 0.0);
  condition.components = std::move(components);
  condition.source = "face " + face;
  return condition;
}

/// For a cantilever 1 x 0.1 x 0.2: an edge crack from the bottom (z = 0) to mid-depth at x = 0.3.
inline mesh::CrackSpec edge_crack() {
  mesh::CrackSpec crack;
  crack.normal = kX;
  crack.at = 0.3;
  crack.region[kY] = {0.0, 0.1};
  crack.region[kZ] = {0.0, 0.1};
  return crack;
}

}  // namespace crackle::modal::testing
