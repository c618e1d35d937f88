#include <gtest/gtest.h>
#include <omp.h>

#include <array>

#include "core/errors.hpp"
#include "fem/assembly.hpp"
#include "fem/material.hpp"
#include "mesh/box.hpp"
#include "fem/elastic_operator.hpp"

namespace crackle::fem {
namespace {

mesh::Mesh small_box(int order, bool crack) {
  mesh::BoxSpec box;
  box.size = Vec3(0.4, 0.2, 0.1);
  box.cells = {4, 3, 2};
  box.order = order;
  std::optional<mesh::CrackSpec> spec;
  if (crack) {
    mesh::CrackSpec c;
    c.normal = kX;
    c.at = 0.2;
    c.region = {{{0, 0}, {0.0, 0.1333333333333333}, {0.0, 0.1}}};
    spec = c;
  }
  return mesh::build_box_mesh(box, spec);
}

/// Moves every node by a smooth map, which keeps the elements valid but not bricks.
void distort(mesh::Mesh& mesh) {
  for (Vec3& x : mesh.nodes) {
    const Vec3 y = x;
    x[0] += 0.03 * std::sin(7.0 * y[1]) + 0.02 * y[2] * y[0];
    x[1] += 0.02 * std::sin(5.0 * y[0] + 3.0 * y[2]);
    x[2] += 0.01 * std::cos(4.0 * y[0]) * y[1];
  }
  mesh.axis_aligned_bricks = false;
}

void expect_matches_assembled(const mesh::Mesh& mesh, const fem::Materials& materials, bool brick, const char* kernel) {
  const mesh::DofMap dofs = mesh::make_dof_map(mesh, mesh::Variant::open);
  const SparseMatrix k = fem::assemble_stiffness(mesh, dofs, materials);
  ElasticOperatorOptions options;
  options.brick_kernel = brick;
  options.chunk_elements = 8;
  const ElasticOperator op(mesh, dofs, materials, options);
  EXPECT_EQ(op.info().kernel, kernel);
  VectorX x = VectorX::Random(dofs.n_dofs());
  const VectorX expected = k * x;
  for (int threads : {1, 2}) {
    omp_set_num_threads(threads);
    VectorX y;
    op.apply(x, y);
    EXPECT_LE((y - expected).norm(), 1e-12 * expected.norm()) << "threads " << threads << " order " << mesh.order;
  }
}

TEST(ElasticOperator, BrickKernelEqualsAssembledStiffness) {
  const fem::Materials materials = {fem::isotropic(2e11, 0.3, 7800.0)};
  for (int order = 1; order <= 4; ++order) {
    expect_matches_assembled(small_box(order, true), materials, true, "brick-blocked");
  }
}

TEST(ElasticOperator, LatticeBatchesOfOrderOneEqualAssembledStiffness) {
  // Rows of 19 elements: most batches of 8 consecutive elements are gathered with vector moves;
  // those across a row end, near the split crack nodes, or partial are not.
  mesh::BoxSpec box;
  box.size = Vec3(1.9, 0.2, 0.3);
  box.cells = {19, 2, 3};
  mesh::CrackSpec crack;
  crack.normal = kZ;
  crack.at = 0.1;
  crack.region = {{{0.5, 1.2}, {0.0, 0.2}, {0.0, 0.0}}};
  const mesh::Mesh mesh = mesh::build_box_mesh(box, crack);
  const fem::Materials materials = {fem::isotropic(2e11, 0.3, 7800.0)};
  const mesh::DofMap dofs = mesh::make_dof_map(mesh, mesh::Variant::open);
  const ElasticOperator op(mesh, dofs, materials);
  EXPECT_GT(op.info().n_lattice_batches, 0);
  EXPECT_LT(op.info().n_lattice_batches, op.info().n_batches);
  EXPECT_EQ(op.info().n_element_matrices, 1);  // sizes equal up to rounding share one matrix
  const VectorX x = VectorX::Random(dofs.n_dofs());
  const VectorX expected = fem::assemble_stiffness(mesh, dofs, materials) * x;
  VectorX y;
  op.apply(x, y);
  EXPECT_LE((y - expected).norm(), 1e-12 * expected.norm());
}

TEST(ElasticOperator, FixedOrderKernelGivesTheGeneralBrickKernelsResultsToTheBit) {
  // Orders 1 and 2: a graded mesh with a crack (several bricks, lattice and scalar batches, partial
  // batches) applied by the kernel compiled for the order's layout and by the one that reads the
  // layout at run time: the same operations in the same order, so the same bits.
  const fem::Materials materials = {fem::isotropic(2e11, 0.3, 7800.0)};
  for (int order : {1, 2}) {
    mesh::BoxSpec box;
    box.size = Vec3(1.9, 0.2, 0.3);
    box.cells = {19, 2, 3};
    box.order = order;
    box.extra_lines[0] = {0.05, 0.15, 1.25};  // three brick sizes along x
    mesh::CrackSpec crack;
    crack.normal = kZ;
    crack.at = 0.1;
    crack.region = {{{0.5, 1.2}, {0.0, 0.2}, {0.0, 0.0}}};
    const mesh::Mesh mesh = mesh::build_box_mesh(box, crack);
    const mesh::DofMap dofs = mesh::make_dof_map(mesh, mesh::Variant::open);
    ElasticOperatorOptions fixed_options, general_options;
    general_options.fixed_order_kernel = false;
    const ElasticOperator fixed(mesh, dofs, materials, fixed_options);
    const ElasticOperator general(mesh, dofs, materials, general_options);
    EXPECT_GT(fixed.info().n_element_matrices, 1);
    EXPECT_EQ(fixed.info().n_fixed_order_batches, fixed.info().n_batches) << "order " << order;
    EXPECT_EQ(general.info().n_fixed_order_batches, 0);
    if (order == 1) {
      EXPECT_GT(fixed.info().n_lattice_batches, 0);
      EXPECT_LT(fixed.info().n_lattice_batches, fixed.info().n_batches);
    }
    omp_set_num_threads(1);
    const VectorX x = VectorX::Random(dofs.n_dofs());
    VectorX y_fixed = VectorX::Random(dofs.n_dofs()), y_general = y_fixed;
    fixed.apply_add(-0.7, x, y_fixed);
    general.apply_add(-0.7, x, y_general);
    EXPECT_EQ((y_fixed - y_general).cwiseAbs().maxCoeff(), 0.0) << "order " << order;
    const VectorX expected = fem::assemble_stiffness(mesh, dofs, materials) * x;
    VectorX y;
    fixed.apply(x, y);
    EXPECT_LE((y - expected).norm(), 1e-12 * expected.norm()) << "order " << order;
  }
}

TEST(ElasticOperator, ElementRangesBetweenCutsSumToTheWholeProduct) {
  // Chunks of 8 cut at elements 5 and 13 (a distributed run's boundary and interior halves): the
  // three ranges applied in turn give the whole product, on one thread to the last bit.
  const fem::Materials materials = {fem::isotropic(2e11, 0.3, 7800.0)};
  for (bool brick : {true, false}) {
    for (int order : {1, 2}) {
      const mesh::Mesh mesh = small_box(order, true);  // 24 elements
      const mesh::DofMap dofs = mesh::make_dof_map(mesh, mesh::Variant::open);
      ElasticOperatorOptions options;
      options.brick_kernel = brick;
      options.chunk_elements = 8;
      options.element_cuts = {5, 13};
      const ElasticOperator op(mesh, dofs, materials, options);
      EXPECT_EQ(op.info().n_chunks, 4);  // 0-5, 5-13, 13-21, 21-24
      EXPECT_TRUE(op.can_apply_elements(0, 5));
      EXPECT_TRUE(op.can_apply_elements(5, 13));
      EXPECT_TRUE(op.can_apply_elements(13, 24));
      EXPECT_FALSE(op.can_apply_elements(0, 4));
      EXPECT_FALSE(op.can_apply_elements(5, 12));
      VectorX scratch = VectorX::Zero(dofs.n_dofs());
      EXPECT_THROW(op.apply_add_elements(1.0, scratch, scratch, 0, 4), InputError);
      omp_set_num_threads(1);
      const VectorX x = VectorX::Random(dofs.n_dofs());
      VectorX whole, in_turn = VectorX::Zero(dofs.n_dofs());
      op.apply(x, whole);
      const Index ranges[3][2] = {{0, 5}, {5, 13}, {13, 24}};
      for (const auto& range : ranges) {
        VectorX part = VectorX::Zero(dofs.n_dofs());
        op.apply_add_elements(2.0, x, part, range[0], range[1]);
        EXPECT_GT(part.norm(), 0.05 * whole.norm());  // each range does its share
        op.apply_add_elements(1.0, x, in_turn, range[0], range[1]);
      }
      EXPECT_EQ((in_turn - whole).cwiseAbs().maxCoeff(), 0.0) << "brick " << brick << " order " << order;
    }
  }
  // Above 20000 DOFs on 2 threads: each range runs colour by colour over its own chunks.
  mesh::BoxSpec box;
  box.cells = {30, 30, 10};
  const mesh::Mesh mesh = mesh::build_box_mesh(box);
  const mesh::DofMap dofs = mesh::make_dof_map(mesh, mesh::Variant::open);
  ElasticOperatorOptions options;
  options.chunk_elements = 256;
  options.element_cuts = {1000, 5000};
  const ElasticOperator op(mesh, dofs, materials, options);
  ASSERT_GE(dofs.n_dofs(), 20000);
  EXPECT_GT(op.info().n_colours, 1);
  omp_set_num_threads(2);
  const VectorX x = VectorX::Random(dofs.n_dofs());
  VectorX whole, in_turn = VectorX::Zero(dofs.n_dofs());
  op.apply(x, whole);
  for (const auto& range : {std::array<Index, 2>{0, 1000}, {1000, 5000}, {5000, 9000}})
    op.apply_add_elements(1.0, x, in_turn, range[0], range[1]);
  EXPECT_LE((in_turn - whole).cwiseAbs().maxCoeff(), 1e-13 * whole.cwiseAbs().maxCoeff());
  omp_set_num_threads(1);
}

TEST(ElasticOperator, GeneralKernelEqualsAssembledStiffness) {
  const fem::Materials materials = {fem::isotropic(7e10, 0.33, 2700.0)};
  for (int order = 1; order <= 4; ++order) {
    mesh::Mesh mesh = small_box(order, true);
    distort(mesh);
    expect_matches_assembled(mesh, materials, true, "general");
  }
}

TEST(ElasticOperator, AnisotropicBricksUseDenseMatrices) {
  fem::Material material = fem::isotropic(1e10, 0.25, 1500.0);
  material.stiffness(0, 5) = material.stiffness(5, 0) = 2e9;  // couples xx and xy: no reflection symmetry
  for (int order = 1; order <= 2; ++order) expect_matches_assembled(small_box(order, false), {material}, true, "brick-dense");
  expect_matches_assembled(small_box(2, false), {material}, false, "general");
}

}  // namespace
}  // namespace crackle::fem
