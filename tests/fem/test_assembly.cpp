// Global assembly (MODEL.md eqs. 25a, 25c): patch tests, rigid modes, masses, cache, threads.
#include <gtest/gtest.h>
#include <omp.h>

#include <Eigen/Dense>
#include <algorithm>
#include <atomic>
#include <cmath>
#include <set>

#include "core/errors.hpp"
#include "core/interrupt.hpp"
#include "fem/assembly.hpp"
#include "fem/kernels.hpp"
#include "fem/loads.hpp"
#include "fem/system.hpp"
#include "fem_meshes.hpp"
#include "mesh/box.hpp"

namespace crackle::fem {
namespace {

using testing::anisotropic_material;
using testing::grid_mesh;
using testing::GridMesh;
using testing::identity_dofs;
using testing::skew_map;

/// CSR invariants: compressed, strictly increasing columns in each row.
void expect_clean_csr(const SparseMatrix& matrix) {
  ASSERT_TRUE(matrix.isCompressed());
  for (Index row = 0; row < matrix.rows(); ++row) {
    for (Index k = matrix.outerIndexPtr()[row] + 1; k < matrix.outerIndexPtr()[row + 1]; ++k) {
      ASSERT_LT(matrix.innerIndexPtr()[k - 1], matrix.innerIndexPtr()[k]) << "row " << row;
    }
  }
}

double max_abs(const SparseMatrix& matrix) { return matrix.coeffs().cwiseAbs().maxCoeff(); }

/// u = A x + c at every node.
VectorX linear_field(const mesh::Mesh& mesh, const Eigen::Matrix3d& gradient, const Vec3& shift) {
  VectorX u(3 * mesh.n_nodes());
  for (Index i = 0; i < mesh.n_nodes(); ++i) u.segment<3>(3 * i) = gradient * mesh.nodes[i] + shift;
  return u;
}

Eigen::Matrix3d some_gradient() {
  Eigen::Matrix3d gradient;
  gradient << 1.0, -0.4, 0.3, 0.2, -0.6, 0.5, 0.7, 0.1, 0.9;
  return 1e-3 * gradient;
}

class AssemblyOrder : public ::testing::TestWithParam<int> {};

TEST_P(AssemblyOrder, PatchTestLinearFieldGivesExactBoundaryForces) {
  // u = A x + c has constant strain eps and stress sigma = D eps (eqs. 2, 3); then K u (eq. 25a)
  // equals the consistent nodal forces \int N_a sigma n dGamma of the boundary (eq. 25b) and vanishes
  // at interior nodes. Distorted trilinear elements, sheared box, fully anisotropic D.
  const int order = GetParam();
  const GridMesh grid = grid_mesh(order, {2, 2, 2}, Vec3(1.0, 0.8, 1.2), 0.12, skew_map(), Vec3(0.5, -1, 2));
  const mesh::Mesh& mesh = grid.mesh;
  ASSERT_FALSE(mesh.axis_aligned_bricks);
  const mesh::DofMap dofs = identity_dofs(mesh);
  const Material material = anisotropic_material();
  const SparseMatrix stiffness = assemble_stiffness(mesh, dofs, {material});
  expect_clean_csr(stiffness);

  const Eigen::Matrix3d gradient = some_gradient();
  const VectorX u = linear_field(mesh, gradient, Vec3(0.1, -0.2, 0.3));
  const double grad[3][3] = {{gradient(0, 0), gradient(0, 1), gradient(0, 2)},
                             {gradient(1, 0), gradient(1, 1), gradient(1, 2)},
                             {gradient(2, 0), gradient(2, 1), gradient(2, 2)}};
  const Voigt strain = strain_from_gradient(grad);
  Voigt voigt_stress;
  stress_from_strain(material, 1, strain.data(), voigt_stress.data());
  Eigen::Matrix3d sigma;
  sigma << voigt_stress[0], voigt_stress[5], voigt_stress[4],  //
      voigt_stress[5], voigt_stress[1], voigt_stress[3],       //
      voigt_stress[4], voigt_stress[3], voigt_stress[2];
  VectorX expected = VectorX::Zero(dofs.n_dofs());
  std::set<Index> boundary;
  for (int f = 0; f < 6; ++f) {
    add_face_traction(mesh, dofs, grid.box_faces(f), sigma * grid.box_normal(f), expected);
    for (const mesh::FaceRef& face : grid.box_faces(f)) {
      for (int a : mesh::face_local_nodes(order, face.local_face))
        boundary.insert(mesh.element_nodes(face.element)[a]);
    }
  }
  const VectorX force = stiffness * u;
  EXPECT_LE((force - expected).norm(), 1e-10 * expected.norm());
  double interior = 0.0;
  int n_interior = 0;
  for (Index node = 0; node < mesh.n_nodes(); ++node) {
    if (boundary.count(node)) continue;
    ++n_interior;
    interior = std::max(interior, force.segment<3>(3 * node).cwiseAbs().maxCoeff());
  }
  EXPECT_GT(n_interior, 0);
  EXPECT_LE(interior, 1e-10 * expected.cwiseAbs().maxCoeff());
}

TEST_P(AssemblyOrder, RigidBodyModesGiveZeroForceAndMatrixIsSymmetric) {
  const int order = GetParam();
  const GridMesh grid = grid_mesh(order, {2, 1, 2}, Vec3(2.0, 1.0, 1.0), 0.15, skew_map());
  const mesh::Mesh& mesh = grid.mesh;
  const mesh::DofMap dofs = identity_dofs(mesh);
  const SparseMatrix stiffness = assemble_stiffness(mesh, dofs, {anisotropic_material()});
  const SparseMatrix transpose = stiffness.transpose();
  EXPECT_EQ((stiffness - transpose).norm(), 0.0);
  const double norm = stiffness.norm();
  for (int mode = 0; mode < 6; ++mode) {
    VectorX r(dofs.n_dofs());
    for (Index i = 0; i < mesh.n_nodes(); ++i) {
      Vec3 axis = Vec3::Zero();
      axis[mode % 3] = 1.0;
      r.segment<3>(3 * i) = mode < 3 ? axis : Vec3(axis.cross(mesh.nodes[i] - Vec3(0.3, 0.2, 0.1)));
    }
    EXPECT_LE((stiffness * r).norm(), 1e-10 * norm * r.norm()) << "mode " << mode;
  }
  // and a non-rigid field does give forces
  const VectorX u = linear_field(mesh, some_gradient(), Vec3::Zero());
  EXPECT_GT((stiffness * u).norm(), 1e-6 * norm * u.norm());
}

TEST_P(AssemblyOrder, LumpedAndConsistentMassSumToDensityTimesVolume) {
  const int order = GetParam();
  const double density = 2700.0;
  const GridMesh grid = grid_mesh(order, {2, 2, 1}, Vec3(1.0, 0.5, 0.25), 0.15, skew_map());
  const mesh::Mesh& mesh = grid.mesh;
  const mesh::DofMap dofs = identity_dofs(mesh);
  const Materials materials{isotropic(70e9, 0.33, density)};
  const double expected = density * grid.volume();
  const VectorX lumped = assemble_lumped_mass(mesh, dofs, materials);
  ASSERT_EQ(lumped.size(), dofs.n_dofs());
  EXPECT_GT(lumped.minCoeff(), 0.0);
  for (int c = 0; c < 3; ++c) {
    double sum = 0.0;
    for (Index r = 0; r < dofs.n_dof_nodes; ++r) sum += lumped[3 * r + c];
    EXPECT_NEAR(sum, expected, 1e-12 * expected) << "component " << c;
  }
  const SparseMatrix mass = assemble_consistent_mass(mesh, dofs, materials);
  expect_clean_csr(mass);
  EXPECT_EQ((mass - SparseMatrix(mass.transpose())).norm(), 0.0);
  for (int c = 0; c < 3; ++c) {
    VectorX translation = VectorX::Zero(dofs.n_dofs());
    for (Index r = 0; r < dofs.n_dof_nodes; ++r) translation[3 * r + c] = 1.0;
    EXPECT_NEAR(translation.dot(mass * translation), expected, 1e-12 * expected) << "component " << c;
    // no coupling between components: M e_c has nothing in the other components
    const VectorX product = mass * translation;
    for (Index r = 0; r < dofs.n_dof_nodes; ++r) EXPECT_EQ(product[3 * r + (c + 1) % 3], 0.0);
  }
}

INSTANTIATE_TEST_SUITE_P(Orders, AssemblyOrder, ::testing::Values(1, 2, 3, 4));

TEST(Assembly, StiffnessIsPositiveSemidefiniteWithExactlySixZeroModes) {
  struct Case {
    int order;
    std::array<int, 3> cells;
  };
  for (const Case& test : {Case{1, {2, 2, 2}}, Case{2, {2, 1, 1}}, Case{3, {1, 1, 1}}, Case{4, {1, 1, 1}}}) {
    const GridMesh grid = grid_mesh(test.order, test.cells, Vec3(1.0, 0.7, 0.9), 0.1, skew_map());
    const mesh::DofMap dofs = identity_dofs(grid.mesh);
    const MatrixX dense = MatrixX(assemble_stiffness(grid.mesh, dofs, {anisotropic_material()}));
    Eigen::SelfAdjointEigenSolver<MatrixX> solver(dense, Eigen::EigenvaluesOnly);
    const VectorX& lambda = solver.eigenvalues();
    const double largest = lambda.maxCoeff();
    int n_zero = 0;
    for (Index i = 0; i < lambda.size(); ++i) {
      EXPECT_GT(lambda[i], -1e-11 * largest) << "order " << test.order;
      if (std::abs(lambda[i]) <= 1e-11 * largest) ++n_zero;
    }
    EXPECT_EQ(n_zero, 6) << "order " << test.order;
    EXPECT_GT(lambda[6], 1e-7 * largest) << "order " << test.order;
  }
}

TEST(Assembly, PatternHoldsEveryNodeNeighbourBlock) {
  // Row of node r holds exactly the 3x3 blocks of the nodes sharing an element with r.
  const GridMesh grid = grid_mesh(2, {2, 2, 1}, Vec3::Ones(), 0.0);
  const mesh::Mesh& mesh = grid.mesh;
  const mesh::DofMap dofs = identity_dofs(mesh);
  const SparseMatrix stiffness = assemble_stiffness(mesh, dofs, {isotropic(1.0, 0.25, 1.0)});
  const SparseMatrix mass = assemble_consistent_mass(mesh, dofs, {isotropic(1.0, 0.25, 1.0)});
  std::vector<std::set<Index>> neighbours(mesh.n_nodes());
  for (Index e = 0; e < mesh.n_elements(); ++e) {
    for (int a = 0; a < mesh.nodes_per_element(); ++a) {
      for (int b = 0; b < mesh.nodes_per_element(); ++b) {
        neighbours[mesh.element_nodes(e)[a]].insert(mesh.element_nodes(e)[b]);
      }
    }
  }
  for (Index r = 0; r < mesh.n_nodes(); ++r) {
    for (int c = 0; c < 3; ++c) {
      std::vector<Index> expected_stiffness, expected_mass, got_stiffness, got_mass;
      for (Index s : neighbours[r]) {
        for (int d = 0; d < 3; ++d) expected_stiffness.push_back(3 * s + d);
        expected_mass.push_back(3 * s + c);
      }
      for (SparseMatrix::InnerIterator it(stiffness, 3 * r + c); it; ++it) got_stiffness.push_back(it.col());
      for (SparseMatrix::InnerIterator it(mass, 3 * r + c); it; ++it) got_mass.push_back(it.col());
      ASSERT_EQ(got_stiffness, expected_stiffness) << "row " << 3 * r + c;
      ASSERT_EQ(got_mass, expected_mass) << "row " << 3 * r + c;
    }
  }
}

TEST(Assembly, BrickCacheEqualsGeneralPath) {
  // Graded bricks (several sizes) and two regions: cached element matrices = computed ones.
  // Exactly representable sizes, so that equal bricks have equal bits.
  mesh::Mesh mesh = grid_mesh(2, {4, 3, 2}, Vec3(1.0, 0.75, 0.5), 0.0,
                              Eigen::Vector3d(1.0, 1.5, 0.5).asDiagonal(), Vec3(-0.25, 0.5, 4.0))
                        .mesh;
  for (Vec3& x : mesh.nodes) {
    if (x.x() > 0.25) x.x() = 0.25 + 2.0 * (x.x() - 0.25);  // the two cells right of x = 0.25 twice as long
  }
  for (Index e = 0; e < mesh.n_elements(); ++e) mesh.element_region[e] = e % 3 == 0 ? 1 : 0;
  ASSERT_TRUE(mesh.axis_aligned_bricks);
  const mesh::DofMap dofs = identity_dofs(mesh);
  const Materials materials{anisotropic_material(7800.0), isotropic(70e9, 0.33, 2700.0)};
  AssemblyReport cached_report, general_report;
  const SparseMatrix cached = assemble_stiffness(mesh, dofs, materials, AssemblyOptions{}, &cached_report);
  const SparseMatrix general =
      assemble_stiffness(mesh, dofs, materials, AssemblyOptions{false}, &general_report);
  EXPECT_EQ(cached_report.n_element_matrices, 4);  // 2 brick sizes x 2 regions
  EXPECT_EQ(general_report.n_element_matrices, mesh.n_elements());
  EXPECT_EQ(cached_report.n_nonzeros, general_report.n_nonzeros);
  EXPECT_GT(cached_report.n_colours, 1);
  EXPECT_LE(max_abs(cached - general), 1e-12 * max_abs(general));
  const SparseMatrix cached_mass = assemble_consistent_mass(mesh, dofs, materials);
  const SparseMatrix general_mass =
      assemble_consistent_mass(mesh, dofs, materials, AssemblyOptions{false}, nullptr);
  EXPECT_LE(max_abs(cached_mass - general_mass), 1e-12 * max_abs(general_mass));
}

std::atomic<int> checks_asked{0};
int stop_after = -1;  ///< the check asks to stop from this call on (-1: never)
bool counting_check() { return ++checks_asked > stop_after && stop_after >= 0; }

// A host's stop (core/interrupt.hpp) is asked between element matrices, not only between the phases
// and the colour classes: a graded order-4 mesh has hundreds of distinct bricks of tens of ms each, and
// a class hundreds of elements (seconds with no poll under load: python.test_interrupt's modal stage).
TEST(Assembly, AHostsStopIsAskedBetweenElementMatricesAndStopsTheAssembly) {
  mesh::Mesh mesh = grid_mesh(2, {6, 4, 3}, Vec3::Ones(), 0.0).mesh;
  // graded in each direction: every brick has its own size (72 element matrices)
  for (Vec3& x : mesh.nodes) x = Vec3(x.x() * (1.0 + x.x()), x.y() * (2.0 + x.y()), std::exp(x.z()));
  ASSERT_TRUE(mesh.axis_aligned_bricks);
  const mesh::DofMap dofs = identity_dofs(mesh);
  const Materials materials{isotropic(70e9, 0.33, 2700.0)};
  const int threads = omp_get_max_threads();
  omp_set_num_threads(1);  // the calling thread does every element: it asks before each
  const InterruptCheck previous = set_interrupt_check(&counting_check);
  checks_asked = 0;
  stop_after = -1;
  AssemblyReport report;
  assemble_stiffness(mesh, dofs, materials, AssemblyOptions{}, &report);
  const int asked = checks_asked;
  EXPECT_EQ(report.n_element_matrices, mesh.n_elements());
  EXPECT_GE(asked, report.n_element_matrices + mesh.n_elements()) << report.n_colours << " colour classes";
  checks_asked = 0;
  stop_after = 10;  // a stop asked for during the element matrices
  EXPECT_THROW(assemble_stiffness(mesh, dofs, materials, AssemblyOptions{}, nullptr), Interrupted);
  checks_asked = 0;
  stop_after = report.n_element_matrices + 10;  // during the scatter
  EXPECT_THROW(assemble_stiffness(mesh, dofs, materials, AssemblyOptions{}, nullptr), Interrupted);
  set_interrupt_check(previous);
  omp_set_num_threads(threads);
}

TEST(Assembly, ThreadCountDoesNotChangeTheMatrix) {
  const GridMesh grid = grid_mesh(2, {3, 3, 2}, Vec3::Ones(), 0.1, skew_map());
  const mesh::DofMap dofs = identity_dofs(grid.mesh);
  const Materials materials{anisotropic_material()};
  const int threads = omp_get_max_threads();
  omp_set_num_threads(1);
  AssemblyReport one_report, two_report;
  const SparseMatrix one = assemble_stiffness(grid.mesh, dofs, materials, AssemblyOptions{}, &one_report);
  const SparseMatrix one_mass = assemble_consistent_mass(grid.mesh, dofs, materials);
  omp_set_num_threads(2);
  const SparseMatrix two = assemble_stiffness(grid.mesh, dofs, materials, AssemblyOptions{}, &two_report);
  const SparseMatrix two_mass = assemble_consistent_mass(grid.mesh, dofs, materials);
  omp_set_num_threads(threads);
  EXPECT_EQ(one_report.n_threads, 1);
  EXPECT_EQ(two_report.n_threads, 2);
  ASSERT_EQ(one.nonZeros(), two.nonZeros());
  EXPECT_TRUE(std::equal(one.valuePtr(), one.valuePtr() + one.nonZeros(), two.valuePtr()));
  EXPECT_TRUE(std::equal(one.innerIndexPtr(), one.innerIndexPtr() + one.nonZeros(), two.innerIndexPtr()));
  EXPECT_TRUE(
      std::equal(one_mass.valuePtr(), one_mass.valuePtr() + one_mass.nonZeros(), two_mass.valuePtr()));
}

TEST(Assembly, ColourClassesShareNoNode) {
  const GridMesh grid = grid_mesh(1, {4, 3, 3}, Vec3::Ones(), 0.0);
  const mesh::DofMap dofs = identity_dofs(grid.mesh);
  const auto classes = colour_elements(grid.mesh, dofs);
  std::vector<int> seen(grid.mesh.n_elements(), 0);
  for (const auto& members : classes) {
    std::set<Index> used;
    for (Index e : members) {
      ++seen[e];
      for (int a = 0; a < 8; ++a)
        EXPECT_TRUE(used.insert(grid.mesh.element_nodes(e)[a]).second) << "element " << e;
    }
  }
  for (int count : seen) EXPECT_EQ(count, 1);
  EXPECT_EQ(classes.size(), 8u);  // greedy on a structured hex grid: 2 x 2 x 2 pattern
}

TEST(Assembly, MergedDuplicateNodesGiveTheConformingMatrix) {
  // Duplicate the nodes of the interface between two elements (a "crack" through the mesh): with a
  // DOF map that ties each copy to its original (uncracked variant), K is that of the intact mesh;
  // with the identity map (open variant) the two elements are free bodies: 12 zero modes.
  const GridMesh grid = grid_mesh(2, {2, 1, 1}, Vec3(2.0, 1.0, 1.0), 0.0);
  const mesh::Mesh& intact = grid.mesh;
  mesh::Mesh split = intact;
  mesh::DofMap tied = identity_dofs(intact);
  Index* second = split.connectivity.data() + split.nodes_per_element();
  for (int a : mesh::face_local_nodes(2, 0)) {
    const Index original = second[a];
    second[a] = split.n_nodes();
    split.nodes.push_back(intact.nodes[original]);
    tied.dof_node.push_back(original);
  }
  const Materials materials{isotropic(1.0, 0.3, 1.0)};
  const SparseMatrix expected = assemble_stiffness(intact, identity_dofs(intact), materials);
  const SparseMatrix merged = assemble_stiffness(split, tied, materials);
  EXPECT_EQ((merged - expected).norm(), 0.0);
  const VectorX lumped = assemble_lumped_mass(split, tied, materials);
  EXPECT_LT((lumped - assemble_lumped_mass(intact, identity_dofs(intact), materials)).norm(), 1e-15);

  const MatrixX open = MatrixX(assemble_stiffness(split, identity_dofs(split), materials));
  Eigen::SelfAdjointEigenSolver<MatrixX> solver(open, Eigen::EigenvaluesOnly);
  const VectorX& lambda = solver.eigenvalues();
  EXPECT_LT(std::abs(lambda[11]), 1e-11 * lambda.maxCoeff());
  EXPECT_GT(lambda[12], 1e-6 * lambda.maxCoeff());
}

TEST(Assembly, BoxMeshWithCrackUncrackedVariantIsTheIntactBody) {
  // Box generator integration: the brick cache path equals the general path, and the uncracked
  // DOF map of a cracked box gives exactly the matrices of the box without a crack.
  mesh::BoxSpec box;
  box.size = Vec3(1.0, 0.5, 0.5);
  box.cells = {4, 2, 2};
  box.order = 2;
  mesh::CrackSpec crack;
  crack.normal = kX;
  crack.at = 0.5;
  crack.region[kY] = {0.0, 0.25};
  crack.region[kZ] = {0.0, 0.5};
  const mesh::Mesh intact = mesh::build_box_mesh(box);
  const mesh::Mesh cracked = mesh::build_box_mesh(box, crack);
  ASSERT_TRUE(cracked.has_crack());
  ASSERT_TRUE(cracked.axis_aligned_bricks);
  const Materials materials{anisotropic_material()};
  const mesh::DofMap intact_dofs = mesh::make_dof_map(intact, mesh::Variant::open);
  const SparseMatrix expected = assemble_stiffness(intact, intact_dofs, materials);
  const SparseMatrix general =
      assemble_stiffness(intact, intact_dofs, materials, AssemblyOptions{false}, nullptr);
  EXPECT_LE(max_abs(expected - general), 1e-12 * max_abs(general));
  const mesh::DofMap tied = mesh::make_dof_map(cracked, mesh::Variant::uncracked);
  ASSERT_EQ(tied.n_dofs(), intact_dofs.n_dofs());
  EXPECT_LE(max_abs(assemble_stiffness(cracked, tied, materials) - expected), 1e-12 * max_abs(expected));
  EXPECT_LE(
      (assemble_lumped_mass(cracked, tied, materials) - assemble_lumped_mass(intact, intact_dofs, materials))
          .norm(),
      1e-12 * assemble_lumped_mass(intact, intact_dofs, materials).norm());
  // open crack: larger, still 6 rigid modes only (the crack does not cut the body in two)
  const mesh::DofMap open = mesh::make_dof_map(cracked, mesh::Variant::open);
  const SparseMatrix open_stiffness = assemble_stiffness(cracked, open, materials);
  EXPECT_GT(open_stiffness.rows(), expected.rows());
  EXPECT_EQ((open_stiffness - SparseMatrix(open_stiffness.transpose())).norm(), 0.0);
}

TEST(Assembly, BadRegionAndInvertedElementThrowInputError) {
  GridMesh grid = grid_mesh(1, {2, 1, 1}, Vec3::Ones(), 0.0);
  const mesh::DofMap dofs = identity_dofs(grid.mesh);
  grid.mesh.element_region[1] = 3;
  EXPECT_THROW(assemble_stiffness(grid.mesh, dofs, {isotropic(1.0, 0.3, 1.0)}), InputError);
  grid.mesh.element_region[1] = 0;
  for (Index node = 0; node < grid.mesh.n_nodes(); ++node) {
    if (grid.mesh.nodes[node].x() > 0.75) grid.mesh.nodes[node].x() = 0.0;  // fold element 1 over
  }
  grid.mesh.axis_aligned_bricks = false;
  try {
    assemble_stiffness(grid.mesh, dofs, {isotropic(1.0, 0.3, 1.0)});
    FAIL() << "no exception";
  } catch (const InputError& error) {
    EXPECT_NE(std::string(error.what()).find("element 1"), std::string::npos) << error.what();
  }
  EXPECT_THROW(assemble_lumped_mass(grid.mesh, dofs, {isotropic(1.0, 0.3, 1.0)}), InputError);
}

TEST(SystemFingerprint, FollowsWhatKAndMAreMadeOfAndNotTheCrackOfTheUncrackedVariant) {
  // The caches of modes and reduced models are keyed by System::fingerprint instead of K and M:
  // equal fingerprints must mean equal matrices, and every input of them must change it.
  mesh::BoxSpec box;
  box.size = Vec3(1.0, 0.5, 0.5);
  box.cells = {4, 2, 2};
  box.order = 2;
  mesh::CrackSpec shallow;
  shallow.normal = kX;
  shallow.at = 0.5;
  shallow.region[kY] = {0.0, 0.5};
  shallow.region[kZ] = {0.25, 0.5};
  mesh::CrackSpec deep = shallow;
  deep.region[kZ] = {0.0, 0.5};
  const mesh::Mesh a = mesh::build_box_mesh(box, shallow), b = mesh::build_box_mesh(box, deep);
  const mesh::Mesh a_again = mesh::build_box_mesh(box, shallow);
  ASSERT_NE(a.n_nodes(), b.n_nodes());  // the deeper crack splits more nodes
  const Materials steel{isotropic(210e9, 0.3, 7850.0)};
  DirichletCondition clamp;
  for (Index node : a.node_sets.at("x-")) clamp.nodes.push_back(node);
  clamp.components = {0, 1, 2};
  clamp.values = {0.0, 0.0, 0.0};
  clamp.source = "clamp";
  const std::vector<DirichletCondition> held{clamp};
  const auto fingerprint = [&](const mesh::Mesh& mesh, const Materials& materials, mesh::Variant variant,
                               const std::vector<DirichletCondition>& conditions) {
    return System(mesh, materials, conditions, variant).fingerprint();
  };
  const auto uncracked = mesh::Variant::uncracked, open = mesh::Variant::open;
  EXPECT_EQ(fingerprint(a, steel, open, held), fingerprint(a_again, steel, open, held));
  // The uncracked variant ties the crack faces: the same K and the same fingerprint for any crack.
  EXPECT_EQ(fingerprint(a, steel, uncracked, held), fingerprint(b, steel, uncracked, held));
  const System tied_a(a, steel, held, uncracked), tied_b(b, steel, held, uncracked);
  EXPECT_EQ(max_abs(tied_a.assemble_stiffness() - tied_b.assemble_stiffness()), 0.0);
  // What changes K, M or the free DOFs changes it.
  EXPECT_NE(fingerprint(a, steel, open, held), fingerprint(b, steel, open, held));
  EXPECT_NE(fingerprint(a, steel, uncracked, held), fingerprint(a, steel, open, held));
  EXPECT_NE(fingerprint(a, steel, open, held), fingerprint(a, steel, open, {}));
  EXPECT_NE(fingerprint(a, steel, open, held), fingerprint(a, {isotropic(210e9, 0.3, 7851.0)}, open, held));
  EXPECT_NE(fingerprint(a, steel, open, held), fingerprint(a, {isotropic(210e9, 0.29, 7850.0)}, open, held));
  mesh::BoxSpec longer = box;
  longer.size[0] = 1.0 + 1e-12;
  EXPECT_NE(fingerprint(a, steel, open, held), fingerprint(mesh::build_box_mesh(longer, shallow), steel, open, held));
  mesh::BoxSpec higher = box;
  higher.order = 3;
  const mesh::Mesh p3 = mesh::build_box_mesh(higher, shallow);
  DirichletCondition clamp3 = clamp;
  clamp3.nodes = p3.node_sets.at("x-");
  EXPECT_NE(fingerprint(a, steel, open, held), fingerprint(p3, steel, open, {clamp3}));
}

}  // namespace
}  // namespace crackle::fem
