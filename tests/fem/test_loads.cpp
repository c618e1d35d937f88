// External loads, MODEL.md eq. (25b).
#include <gtest/gtest.h>

#include <Eigen/Dense>

#include "core/errors.hpp"
#include "fem/loads.hpp"
#include "fem_meshes.hpp"

namespace crackle::fem {
namespace {

using testing::grid_mesh;
using testing::GridMesh;
using testing::identity_dofs;
using testing::skew_map;

class LoadOrder : public ::testing::TestWithParam<int> {};

TEST_P(LoadOrder, TractionOnFacesSumsToTractionTimesArea) {
  const GridMesh grid = grid_mesh(GetParam(), {2, 3, 2}, Vec3(1.0, 0.6, 0.8), 0.15, skew_map());
  const mesh::DofMap dofs = identity_dofs(grid.mesh);
  const Eigen::Matrix3d& g = grid.affine;
  // box face x+ is the parallelogram spanned by G (0, Ly, 0) and G (0, 0, Lz)
  const double area = (g.col(1) * 0.6).cross(g.col(2) * 0.8).norm();
  const std::vector<mesh::FaceRef> faces = grid.box_faces(1);
  EXPECT_NEAR(face_area(grid.mesh, faces), area, 1e-13 * area);
  const Vec3 traction(1e6, -2e5, 3e5);
  VectorX force;  // empty: the load starts it at zero
  add_face_traction(grid.mesh, dofs, faces, traction, force);
  ASSERT_EQ(force.size(), dofs.n_dofs());
  for (int c = 0; c < 3; ++c) {
    double sum = 0.0;
    for (Index r = 0; r < dofs.n_dof_nodes; ++r) sum += force[3 * r + c];
    EXPECT_NEAR(sum, traction[c] * area, 1e-12 * traction.norm() * area) << "component " << c;
  }
  // only nodes on the face are loaded
  for (Index node = 0; node < grid.mesh.n_nodes(); ++node) {
    const Vec3 reference = g.inverse() * grid.mesh.nodes[node];
    if (reference.x() < 1.0 - 1e-9) {
      EXPECT_EQ(force.segment<3>(3 * node).norm(), 0.0) << "node " << node;
    }
  }
}

TEST_P(LoadOrder, ConsistentFaceForcesAreGllWeightsOnAFlatFace) {
  // \int N_a dGamma = w_s w_t A / 4 on an affine face: the GLL rule integrates the degree-p basis
  // exactly (degree 2p-1 >= p). Corners get less than the mean for p >= 2 (not lumped evenly).
  const int order = GetParam();
  const GridMesh grid = grid_mesh(order, {1, 1, 1}, Vec3(0.5, 2.0, 3.0), 0.0);
  const mesh::DofMap dofs = identity_dofs(grid.mesh);
  VectorX force = VectorX::Zero(dofs.n_dofs());
  add_face_traction(grid.mesh, dofs, {{0, 0}}, Vec3(0.0, 0.0, 1.0), force);
  const Rule1D gll = gauss_lobatto(order + 1);
  const std::vector<int> local = mesh::face_local_nodes(order, 0);
  for (int t = 0; t <= order; ++t) {
    for (int s = 0; s <= order; ++s) {
      const Index node = grid.mesh.element_nodes(0)[local[s + (order + 1) * t]];
      EXPECT_NEAR(force[3 * node + 2], gll.weights[s] * gll.weights[t] * 6.0 / 4.0, 1e-14) << s << "," << t;
      EXPECT_EQ(force[3 * node], 0.0);
    }
  }
}

TEST_P(LoadOrder, BodyForceIsConsistentMassTimesAcceleration) {
  const GridMesh grid = grid_mesh(GetParam(), {2, 1, 2}, Vec3(1.0, 0.5, 0.7), 0.15, skew_map());
  const mesh::DofMap dofs = identity_dofs(grid.mesh);
  const Materials materials{isotropic(200e9, 0.3, 7800.0)};
  const Vec3 gravity(0.0, -9.81, 1.5);
  VectorX force = VectorX::Zero(dofs.n_dofs());
  add_body_force(grid.mesh, dofs, materials, gravity, force);
  VectorX uniform(dofs.n_dofs());
  for (Index r = 0; r < dofs.n_dof_nodes; ++r) uniform.segment<3>(3 * r) = gravity;
  // partition of unity: \int N_a rho b = sum_b M_ab b
  const VectorX expected = assemble_consistent_mass(grid.mesh, dofs, materials) * uniform;
  EXPECT_LE((force - expected).norm(), 1e-12 * expected.norm());
  const double mass = 7800.0 * grid.volume();
  for (int c = 0; c < 3; ++c) {
    double sum = 0.0;
    for (Index r = 0; r < dofs.n_dof_nodes; ++r) sum += force[3 * r + c];
    EXPECT_NEAR(sum, mass * gravity[c], 1e-12 * mass * gravity.norm());
  }
}

INSTANTIATE_TEST_SUITE_P(Orders, LoadOrder, ::testing::Values(1, 2, 3, 4));

TEST(Loads, PointForceIsSpreadOverDistinctDofNodes) {
  const GridMesh grid = grid_mesh(1, {1, 1, 1}, Vec3::Ones(), 0.0);
  mesh::DofMap dofs = identity_dofs(grid.mesh);
  dofs.dof_node[7] = 0;  // node 7 tied to node 0 (as a crack pair in the uncracked variant)
  VectorX force = VectorX::Zero(dofs.n_dofs());
  const Vec3 total(3.0, -6.0, 9.0);
  add_point_force(dofs, {0, 5, 5, 7}, total, force);  // distinct DOF nodes: 0 and 5
  EXPECT_EQ(Vec3(force.segment<3>(0)), Vec3(total / 2.0));
  EXPECT_EQ(Vec3(force.segment<3>(15)), Vec3(total / 2.0));
  EXPECT_EQ(force.sum(), total.sum());
  EXPECT_THROW(add_point_force(dofs, {}, total, force), InputError);
  EXPECT_THROW(add_point_force(dofs, {8}, total, force), InputError);
}

TEST(Loads, BadFaceThrowsInputError) {
  const GridMesh grid = grid_mesh(1, {1, 1, 1}, Vec3::Ones(), 0.0);
  const mesh::DofMap dofs = identity_dofs(grid.mesh);
  VectorX force;
  EXPECT_THROW(add_face_traction(grid.mesh, dofs, {{1, 0}}, Vec3::Ones(), force), InputError);
  EXPECT_THROW(face_area(grid.mesh, {{0, 6}}), InputError);
}

}  // namespace
}  // namespace crackle::fem
