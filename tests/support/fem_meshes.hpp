#pragma once
/// \file Small hand-built meshes for the fem tests (independent of the mesh generator; compiled once
/// in crackle_test_support).
#include <array>
#include <cmath>
#include <vector>

#include "core/quadrature.hpp"
#include "core/types.hpp"
#include "fem/material.hpp"
#include "mesh/mesh.hpp"

namespace crackle::fem::testing {

/// A grid of n[0] x n[1] x n[2] elements of order p on the box [0, L]: the element vertices are moved
/// by up to `distortion` times the cell size (interior vertices in all directions, boundary
/// vertices only within their box face or edge, corners fixed), so that the elements are trilinear
/// but the box faces stay planar; then everything is mapped by x -> affine x + offset.
/// The element geometry is exactly the trilinear map of its vertices (GLL nodes placed on it).
struct GridMesh {
  mesh::Mesh mesh;
  std::array<int, 3> cells{};
  Eigen::Matrix3d affine = Eigen::Matrix3d::Identity();
  Vec3 lengths = Vec3::Ones();
  /// Volume of the mapped box.
  double volume() const;
  /// Element faces on box face f (0..5 = x-, x+, y-, y+, z-, z+).
  std::vector<mesh::FaceRef> box_faces(int f) const;
  /// Outward unit normal of box face f after the affine map.
  Vec3 box_normal(int f) const;
};

/// A linear congruential generator's next value in [-1, 1).
double pseudo_random(unsigned& state);

GridMesh grid_mesh(int order, std::array<int, 3> cells, Vec3 lengths, double distortion,
                   const Eigen::Matrix3d& affine = Eigen::Matrix3d::Identity(), const Vec3& offset = Vec3::Zero(),
                   unsigned seed = 1);

/// The identity DOF map (every mesh node its own DOF node).
mesh::DofMap identity_dofs(const mesh::Mesh& mesh);

/// A symmetric positive definite, fully anisotropic Voigt stiffness (no zero entries).
Material anisotropic_material(double density = 7800.0);

/// A mild shear + rotation + stretch (det > 0).
Eigen::Matrix3d skew_map();

}  // namespace crackle::fem::testing
