// Lagrange tetrahedra of order 1 and 2 (issue 7): basis, patch test, rigid-body modes, mass
// conservation, HRZ lumping, and convergence towards the hexahedral frequencies.
#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "core/errors.hpp"
#include "fem/element_basis.hpp"
#include "fem/loads.hpp"
#include "fem/tetrahedron.hpp"
#include "io/vtu.hpp"
#include "gmsh_testing.hpp"
#include "mesh/box.hpp"
#include "mesh/gmsh.hpp"

namespace crackle::fem {
namespace {

using testing::mesh_file;
using testing::steel;

TEST(Tetrahedron, BasisIsNodalAndAPartitionOfUnity) {
  // Reference nodes of Gmsh's tetrahedra: vertices, then midpoints of edges 01, 12, 20, 30, 32, 31.
  const double nodes[10][3] = {{0, 0, 0},     {1, 0, 0},     {0, 1, 0},     {0, 0, 1},     {0.5, 0, 0},
                               {0.5, 0.5, 0}, {0, 0.5, 0},   {0, 0, 0.5},   {0, 0.5, 0.5}, {0.5, 0, 0.5}};
  for (int order : {1, 2}) {
    const int n = order == 1 ? 4 : 10;
    double values[10], gradients[30];
    for (int b = 0; b < n; ++b) {
      tetrahedron_shape(order, nodes[b], values, gradients);
      for (int a = 0; a < n; ++a) EXPECT_NEAR(values[a], a == b ? 1.0 : 0.0, 1e-15) << order << " " << a << " " << b;
    }
    const double point[3] = {0.2, 0.3, 0.15};
    tetrahedron_shape(order, point, values, gradients);
    double sum = 0.0;
    Vec3 gradient_sum = Vec3::Zero();
    for (int a = 0; a < n; ++a) {
      sum += values[a];
      gradient_sum += Vec3(gradients[3 * a], gradients[3 * a + 1], gradients[3 * a + 2]);
    }
    EXPECT_NEAR(sum, 1.0, 1e-15);
    EXPECT_LT(gradient_sum.norm(), 1e-14);
    // The mesh's edge-node table agrees with the basis.
    if (order == 2) EXPECT_EQ(mesh::tetrahedron_edge_node(2, 3), 8);
  }
  const TetBasis basis(2);
  double volume = 0.0;
  for (double w : basis.weights) {
    EXPECT_GT(w, 0.0);
    volume += w;
  }
  EXPECT_NEAR(volume, 1.0 / 6.0, 1e-15);
}

TEST(Tetrahedron, GmshEdgeNodesAreTheEdgeMidpoints) {
  const mesh::Mesh mesh = mesh::read_gmsh(mesh_file("box-tet10.msh"));
  ASSERT_EQ(mesh.shape, mesh::ElementShape::tetrahedron);
  ASSERT_EQ(mesh.order, 2);
  const int edges[6][2] = {{0, 1}, {1, 2}, {2, 0}, {3, 0}, {3, 2}, {3, 1}};
  for (Index e = 0; e < mesh.n_elements(); ++e) {
    const Index* nodes = mesh.element_nodes(e);
    for (int k = 0; k < 6; ++k) {
      const Vec3 midpoint = 0.5 * (mesh.nodes[nodes[edges[k][0]]] + mesh.nodes[nodes[edges[k][1]]]);
      ASSERT_LT((mesh.nodes[nodes[4 + k]] - midpoint).norm(), 1e-12) << "element " << e << " edge " << k;
    }
  }
}

TEST(Tetrahedron, PatchTestRigidModesAndMass) {
  // A linear displacement field is reproduced exactly: K u has no force on interior nodes; the six
  // rigid-body modes carry no force at all; masses sum to rho V; HRZ masses are positive.
  for (const std::string file : {"box-tet4.msh", "box-tet10.msh"}) {
    SCOPED_TRACE(file);
    const mesh::Mesh mesh = mesh::read_gmsh(mesh_file(file));
    const mesh::DofMap dofs = mesh::make_dof_map(mesh, mesh::Variant::open);
    const Materials materials = {testing::steel()[0]};
    const SparseMatrix k = assemble_stiffness(mesh, dofs, materials);
    EXPECT_LT((MatrixX(k) - MatrixX(k).transpose()).cwiseAbs().maxCoeff(), 1e-6);
    EXPECT_NEAR(mesh.volume(), 4e-4, 1e-15);

    Eigen::Matrix3d gradient;
    gradient << 1e-3, 2e-4, -3e-4,  //
        5e-4, -2e-3, 1e-4,          //
        -1e-4, 3e-4, 1.5e-3;
    VectorX linear(dofs.n_dofs()), rigid(dofs.n_dofs());
    const Vec3 rotation(0.3, -0.2, 0.5), translation(1e-3, -2e-3, 5e-4);
    for (Index n = 0; n < mesh.n_nodes(); ++n) {
      const Vec3 u = gradient * mesh.nodes[n] + translation;
      const Vec3 r = rotation.cross(mesh.nodes[n]) + translation;
      for (int c = 0; c < 3; ++c) {
        linear[dofs.dof(n, c)] = u[c];
        rigid[dofs.dof(n, c)] = r[c];
      }
    }
    const double scale = k.coeffs().cwiseAbs().maxCoeff() * 1e-3;
    EXPECT_LT((k * rigid).cwiseAbs().maxCoeff(), 1e-12 * scale);
    const VectorX force = k * linear;
    std::vector<char> on_boundary(mesh.n_nodes(), 0);
    const double eps = 1e-9;
    for (Index n = 0; n < mesh.n_nodes(); ++n) {
      const Vec3& x = mesh.nodes[n];
      on_boundary[n] = x.x() < eps || x.x() > 0.2 - eps || x.y() < eps || x.y() > 0.05 - eps || x.z() < eps ||
                       x.z() > 0.04 - eps;
    }
    for (Index n = 0; n < mesh.n_nodes(); ++n) {
      if (on_boundary[n]) continue;
      for (int c = 0; c < 3; ++c) ASSERT_LT(std::abs(force[dofs.dof(n, c)]), 1e-9 * scale) << "node " << n;
    }

    const SparseMatrix m = assemble_consistent_mass(mesh, dofs, materials);
    VectorX ones = VectorX::Zero(dofs.n_dofs());
    for (Index n = 0; n < mesh.n_nodes(); ++n) ones[dofs.dof(n, 0)] = 1.0;
    EXPECT_NEAR(ones.dot(m * ones), 7850.0 * 4e-4, 1e-12);
    const VectorX lumped = assemble_lumped_mass(mesh, dofs, materials);
    EXPECT_GT(lumped.minCoeff(), 0.0);
    EXPECT_NEAR(lumped.sum(), 3 * 7850.0 * 4e-4, 1e-12);
    VectorX body;
    add_body_force(mesh, dofs, materials, Vec3(0, 0, -9.81), body);
    EXPECT_NEAR(body.sum(), -9.81 * 7850.0 * 4e-4, 1e-12);
    VectorX traction;
    add_face_traction(mesh, dofs, mesh.face_sets.at("load"), Vec3(1e6, 0, 0), traction);
    EXPECT_NEAR(traction.sum(), 1e6 * 0.05 * 0.04, 1e-6);
    EXPECT_NEAR(face_area(mesh, mesh.face_sets.at("clamp")), 0.05 * 0.04, 1e-15);
  }
}

TEST(Tetrahedron, HrzLumpingOfTheTenNodeTetrahedron) {
  // Vertices get 1/36 and edge nodes 4/27 of the element mass (nodal quadrature would give the
  // vertices nothing).
  const ElementBasis basis(mesh::ElementShape::tetrahedron, 2);
  std::vector<double> coords = {0, 0, 0, 2, 0, 0, 0, 3, 0, 0, 0, 1};
  const int edges[6][2] = {{0, 1}, {1, 2}, {2, 0}, {3, 0}, {3, 2}, {3, 1}};
  for (const auto& edge : edges) {
    for (int c = 0; c < 3; ++c) coords.push_back(0.5 * (coords[3 * edge[0] + c] + coords[3 * edge[1] + c]));
  }
  double mass[10];
  basis.lumped_mass_scalar(coords.data(), mass);
  const double volume = 1.0;  // 2 * 3 * 1 / 6
  for (int a = 0; a < 4; ++a) EXPECT_NEAR(mass[a], volume / 36.0, 1e-15);
  for (int a = 4; a < 10; ++a) EXPECT_NEAR(mass[a], 4.0 * volume / 27.0, 1e-15);
  // Inverted element: a clear error.
  std::swap(coords[3], coords[6]);
  std::swap(coords[4], coords[7]);
  MatrixX k;
  EXPECT_THROW(basis.stiffness(coords.data(), testing::steel()[0], k), InputError);
}

TEST(Tetrahedron, FrequenciesConvergeToTheHexahedralOnes) {
  // The clamped box: 10-node tetrahedra within 2 %, 4-node tetrahedra stiffer.
  const mesh::Mesh hex = mesh::read_gmsh(mesh_file("box-hex27.msh"));
  const mesh::Mesh tet10 = mesh::read_gmsh(mesh_file("box-tet10.msh"));
  const mesh::Mesh tet4 = mesh::read_gmsh(mesh_file("box-tet4.msh"));
  auto frequencies = [](const mesh::Mesh& mesh) {
    return testing::lowest_frequencies(mesh, mesh::Variant::open, steel(), {testing::clamp(mesh.node_sets.at("clamp"))}, 3);
  };
  const VectorX f_hex = frequencies(hex), f_tet10 = frequencies(tet10), f_tet4 = frequencies(tet4);
  for (int i = 0; i < 3; ++i) {
    EXPECT_NEAR(f_tet10[i], f_hex[i], 0.02 * f_hex[i]) << "mode " << i;
    EXPECT_GT(f_tet4[i], f_tet10[i]) << "mode " << i;
  }
}

TEST(Tetrahedron, VtuFilesHoldQuadraticTetrahedra) {
  // One VTK cell per element: VTK_QUADRATIC_TETRA (24) with VTK's edge order (13 before 23).
  const mesh::Mesh mesh = mesh::read_gmsh(mesh_file("box-tet10.msh"));
  const std::filesystem::path path = std::filesystem::path(::testing::TempDir()) / "tet10.vtu";
  io::write_vtu(path, mesh, {});
  std::ifstream stream(path, std::ios::binary);
  std::ostringstream contents;
  contents << stream.rdbuf();
  const std::string text = contents.str();
  EXPECT_NE(text.find("NumberOfCells=\"" + std::to_string(mesh.n_elements()) + "\""), std::string::npos);
  // The appended blocks: 8-byte size, then the data; read the connectivity and the types.
  auto block = [&](const std::string& name) {
    const std::size_t at = text.find("Name=\"" + name + "\"");
    const std::size_t offset = std::stoul(text.substr(text.find("offset=\"", at) + 8));
    const std::size_t data = text.find("<AppendedData encoding=\"raw\">") + std::strlen("<AppendedData encoding=\"raw\">");
    const std::size_t start = text.find('_', data) + 1 + offset;
    std::uint64_t bytes;
    std::memcpy(&bytes, text.data() + start, sizeof bytes);
    return text.substr(start + 8, bytes);
  };
  const std::string types = block("types");
  ASSERT_EQ(types.size(), static_cast<std::size_t>(mesh.n_elements()));
  for (char type : types) EXPECT_EQ(static_cast<int>(type), 24);
  const std::string connectivity = block("connectivity");
  ASSERT_EQ(connectivity.size(), 10 * 8 * static_cast<std::size_t>(mesh.n_elements()));
  std::int64_t first[10];
  std::memcpy(first, connectivity.data(), sizeof first);
  const Index* nodes = mesh.element_nodes(0);
  const int vtk[10] = {0, 1, 2, 3, 4, 5, 6, 7, 9, 8};
  for (int a = 0; a < 10; ++a) EXPECT_EQ(first[a], nodes[vtk[a]]);
  // VTK node 8 is the midpoint of vertices 1 and 3.
  EXPECT_LT((mesh.nodes[first[8]] - 0.5 * (mesh.nodes[first[1]] + mesh.nodes[first[3]])).norm(), 1e-12);
}

}  // namespace
}  // namespace crackle::fem
