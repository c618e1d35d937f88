// Dirichlet constraints, MODEL.md eq. (5).
#include <gtest/gtest.h>

#include <Eigen/SparseCholesky>
#include <set>

#include "core/errors.hpp"
#include "fem/assembly.hpp"
#include "fem/constraints.hpp"
#include "fem_meshes.hpp"

namespace crackle::fem {
namespace {

using testing::grid_mesh;
using testing::GridMesh;
using testing::identity_dofs;
using testing::skew_map;

TEST(Constraints, ContradictionNamesBothSourcesAndValues) {
  const GridMesh grid = grid_mesh(1, {1, 1, 1}, Vec3::Ones(), 0.0);
  const mesh::DofMap dofs = identity_dofs(grid.mesh);
  const std::vector<DirichletCondition> conditions = {
      {{0, 2, 4, 6}, {0, 1}, {0.0, 0.0}, "boundary[0] (face x-)"},
      {{0, 1, 4, 5}, {1}, {0.0}, "boundary[1] (face y-)"},              // same value: fine
      {{4, 5, 6, 7}, {2, 0}, {1e-3, 2.5e-4}, "boundary[2] (face z+)"},  // x of 4, 6: 0 vs 2.5e-4
  };
  try {
    make_constraints(dofs, conditions);
    FAIL() << "no exception";
  } catch (const InputError& error) {
    const std::string message = error.what();
    EXPECT_NE(message.find("boundary[0] (face x-)"), std::string::npos) << message;
    EXPECT_NE(message.find("boundary[2] (face z+)"), std::string::npos) << message;
    EXPECT_NE(message.find("0.00025"), std::string::npos) << message;
    EXPECT_NE(message.find("node 4"), std::string::npos) << message;
  }
  // without the contradiction it goes through
  const Constraints constraints = make_constraints(dofs, {conditions[0], conditions[1]});
  EXPECT_EQ(constraints.n_free(), dofs.n_dofs() - 8 - 2);  // 4 nodes x 2 components + y of nodes 1, 5
  EXPECT_TRUE(constraints.fixed[dofs.dof(0, 1)]);
  EXPECT_FALSE(constraints.fixed[dofs.dof(0, 2)]);
  EXPECT_EQ(constraints.free_index[dofs.dof(0, 2)], 0);
  for (Index i = 0; i < constraints.n_free(); ++i)
    EXPECT_EQ(constraints.free_index[constraints.free_dofs[i]], i);
}

TEST(Constraints, BadInputThrowsWithSource) {
  const GridMesh grid = grid_mesh(1, {1, 1, 1}, Vec3::Ones(), 0.0);
  const mesh::DofMap dofs = identity_dofs(grid.mesh);
  for (const DirichletCondition& bad :
       {DirichletCondition{{0}, {3}, {0.0}, "clamp"}, DirichletCondition{{0}, {0, 1}, {0.0}, "clamp"},
        DirichletCondition{{8}, {0}, {0.0}, "clamp"}}) {
    try {
      make_constraints(dofs, {bad});
      FAIL() << "no exception";
    } catch (const InputError& error) {
      EXPECT_NE(std::string(error.what()).find("clamp"), std::string::npos) << error.what();
    }
  }
}

TEST(Constraints, DisplacementPatchTestReproducesLinearFieldInside) {
  // Prescribe u = A x + c on the whole boundary; the solution of K_ff u_f = -K_fc u_c is the same
  // linear field at every interior node (eqs. 5, 25a), on distorted elements.
  const GridMesh grid = grid_mesh(2, {2, 2, 2}, Vec3(1.0, 0.8, 1.2), 0.12, skew_map());
  const mesh::Mesh& mesh = grid.mesh;
  const mesh::DofMap dofs = identity_dofs(mesh);
  const SparseMatrix stiffness = assemble_stiffness(mesh, dofs, {testing::anisotropic_material()});
  Eigen::Matrix3d gradient;
  gradient << 1.0, -0.4, 0.3, 0.2, -0.6, 0.5, 0.7, 0.1, 0.9;
  gradient *= 1e-3;
  const Vec3 shift(1e-4, 2e-4, -3e-4);
  std::vector<DirichletCondition> conditions;
  for (int f = 0; f < 6; ++f) {
    std::set<Index> nodes;
    for (const mesh::FaceRef& face : grid.box_faces(f)) {
      for (int a : mesh::face_local_nodes(2, face.local_face))
        nodes.insert(mesh.element_nodes(face.element)[a]);
    }
    for (Index node : nodes) {
      const Vec3 u = gradient * mesh.nodes[node] + shift;
      conditions.push_back({{node}, {0, 1, 2}, {u[0], u[1], u[2]}, "face " + std::to_string(f)});
    }
  }
  const Constraints constraints = make_constraints(dofs, conditions);
  ASSERT_EQ(constraints.n_free(), 3 * 27);  // interior nodes of the 5x5x5 grid
  const SparseMatrix reduced = restrict_to_free(stiffness, constraints);
  ASSERT_TRUE(reduced.isCompressed());
  const VectorX rhs = free_right_hand_side(stiffness, VectorX::Zero(dofs.n_dofs()), constraints);
  const Eigen::SparseMatrix<double> column_major = reduced;
  Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>> solver(column_major);
  ASSERT_EQ(solver.info(), Eigen::Success);
  const VectorX u = expand_from_free(solver.solve(rhs), constraints, true);
  double error = 0.0;
  for (Index node = 0; node < mesh.n_nodes(); ++node) {
    error = std::max(error, (u.segment<3>(3 * node) - gradient * mesh.nodes[node] - shift).norm());
  }
  EXPECT_LE(error, 1e-10 * gradient.norm());
}

TEST(Constraints, RestrictAndExpand) {
  const GridMesh grid = grid_mesh(1, {2, 1, 1}, Vec3::Ones(), 0.0);
  const mesh::DofMap dofs = identity_dofs(grid.mesh);
  const SparseMatrix stiffness = assemble_stiffness(grid.mesh, dofs, {isotropic(1.0, 0.3, 1.0)});
  const Constraints constraints = make_constraints(dofs, {{{0, 3}, {0, 2}, {0.5, -0.25}, "a"}});
  const SparseMatrix reduced = restrict_to_free(stiffness, constraints);
  ASSERT_EQ(reduced.rows(), constraints.n_free());
  for (Index i = 0; i < constraints.n_free(); ++i) {
    for (Index j = 0; j < constraints.n_free(); ++j) {
      ASSERT_EQ(reduced.coeff(i, j), stiffness.coeff(constraints.free_dofs[i], constraints.free_dofs[j]));
    }
  }
  VectorX full = VectorX::LinSpaced(dofs.n_dofs(), 1.0, double(dofs.n_dofs()));
  const VectorX free = restrict_to_free(full, constraints);
  const VectorX back = expand_from_free(free, constraints, true);
  const VectorX zeros = expand_from_free(free, constraints, false);
  for (Index dof = 0; dof < dofs.n_dofs(); ++dof) {
    EXPECT_EQ(back[dof], constraints.fixed[dof] ? constraints.values[dof] : full[dof]);
    EXPECT_EQ(zeros[dof], constraints.fixed[dof] ? 0.0 : full[dof]);
  }
  EXPECT_EQ(back[dofs.dof(3, 2)], -0.25);
}

TEST(Constraints, RestrictingAnAssembledMatrixInPlaceGivesTheCopysEntries) {
  // The first node fixed (its rows and columns), a middle node's one component, and the last node.
  const GridMesh grid = grid_mesh(2, {3, 2, 1}, Vec3(3.0, 2.0, 1.0), 0.0);
  const mesh::DofMap dofs = identity_dofs(grid.mesh);
  const SparseMatrix stiffness = assemble_stiffness(grid.mesh, dofs, {isotropic(1.0, 0.3, 1.0)});
  const Index last = grid.mesh.n_nodes() - 1;
  const Constraints constraints =
      make_constraints(dofs, {{{0, 7, last}, {0, 1, 2}, {0.0, 0.0, 0.0}, "a"}, {{20}, {1}, {0.0}, "b"}});
  const SparseMatrix copied = restrict_to_free(stiffness, constraints);
  SparseMatrix handed = stiffness;
  const double* storage = handed.valuePtr();
  const SparseMatrix in_place = restrict_to_free(std::move(handed), constraints);
  EXPECT_EQ(in_place.valuePtr(), storage) << "the entries were copied, not compacted in place";
  ASSERT_EQ(in_place.rows(), constraints.n_free());
  ASSERT_EQ(in_place.cols(), constraints.n_free());
  ASSERT_TRUE(in_place.isCompressed());
  ASSERT_EQ(in_place.nonZeros(), copied.nonZeros());
  for (Index i = 0; i <= constraints.n_free(); ++i) ASSERT_EQ(in_place.outerIndexPtr()[i], copied.outerIndexPtr()[i]) << i;
  for (Index k = 0; k < copied.nonZeros(); ++k) {
    ASSERT_EQ(in_place.innerIndexPtr()[k], copied.innerIndexPtr()[k]) << k;
    ASSERT_EQ(in_place.valuePtr()[k], copied.valuePtr()[k]) << k;
  }
  // Nothing fixed: the matrix as it was.
  SparseMatrix whole = stiffness;
  const SparseMatrix unchanged = restrict_to_free(std::move(whole), make_constraints(dofs, {}));
  EXPECT_EQ((MatrixX(unchanged) - MatrixX(stiffness)).norm(), 0.0);
}

}  // namespace
}  // namespace crackle::fem
