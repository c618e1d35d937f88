// Gmsh MSH 4.1 meshes against the built-in box generator (issue 7): the same K, M and frequencies
// for structured hexahedra of order 1 and 2 (ASCII and binary files), and the same crack pairs and
// open-crack frequencies for a crack given as a physical surface (split by crackle) or already split
// by Gmsh's Crack plugin.
#include <gtest/gtest.h>

#include <algorithm>
#include <fstream>
#include <sstream>

#include "fem/loads.hpp"
#include "gmsh_testing.hpp"
#include "mesh/box.hpp"
#include "mesh/gmsh.hpp"

namespace crackle::mesh {
namespace {

using testing::match_nodes;
using testing::mesh_file;
using testing::steel;

BoxSpec test_box(int order, std::array<int, 3> cells) {
  BoxSpec box;
  box.size = Vec3(0.2, 0.05, 0.04);
  box.cells = cells;
  box.order = order;
  return box;
}

CrackSpec test_crack() {
  CrackSpec crack;
  crack.normal = kZ;
  crack.at = 0.02;
  crack.region[kX] = {0.05, 0.1};
  crack.region[kY] = {0.0, 0.05};
  return crack;
}

/// K and M of a Gmsh mesh and of a box mesh of the same body agree after matching nodes.
void expect_same_matrices(const Mesh& gmsh, const Mesh& box, Variant variant) {
  const std::vector<Index> nodes = match_nodes(gmsh, box);
  ASSERT_EQ(gmsh.n_nodes(), box.n_nodes());
  // Coincident crack copies: match each Gmsh node to the box node on the same side (same DOF
  // node in the variant) by the elements that use it, through the DOF maps below.
  const DofMap gmsh_dofs = make_dof_map(gmsh, variant), box_dofs = make_dof_map(box, variant);
  ASSERT_EQ(gmsh_dofs.n_dofs(), box_dofs.n_dofs());
  const fem::Materials materials = steel();
  std::vector<Index> match(gmsh_dofs.n_dofs(), -1);
  // Element-wise: elements match by centroid, then local nodes by position.
  const std::vector<Index> elements = [&] {
    Mesh gmsh_centroids, box_centroids;
    for (const Mesh* source : {&gmsh, &box}) {
      Mesh& target = source == &gmsh ? gmsh_centroids : box_centroids;
      for (Index e = 0; e < source->n_elements(); ++e) {
        Vec3 c = Vec3::Zero();
        for (int a = 0; a < source->nodes_per_element(); ++a) c += source->nodes[source->element_nodes(e)[a]];
        target.nodes.push_back(c / source->nodes_per_element());
      }
    }
    return match_nodes(gmsh_centroids, box_centroids);
  }();
  for (Index e = 0; e < gmsh.n_elements(); ++e) {
    ASSERT_GE(elements[e], 0);
    const Index* g = gmsh.element_nodes(e);
    const Index* b = box.element_nodes(elements[e]);
    for (int a = 0; a < gmsh.nodes_per_element(); ++a) {
      ASSERT_EQ(nodes[g[a]] >= 0, true);
      int local = -1;
      for (int c = 0; c < box.nodes_per_element(); ++c) {
        if ((box.nodes[b[c]] - gmsh.nodes[g[a]]).norm() < 1e-12) local = c;
      }
      ASSERT_GE(local, 0);
      for (int c = 0; c < 3; ++c) match[gmsh_dofs.dof(g[a], c)] = box_dofs.dof(b[local], c);
    }
  }
  const double stiffness = testing::permuted_difference(fem::assemble_stiffness(gmsh, gmsh_dofs, materials),
                                                        fem::assemble_stiffness(box, box_dofs, materials), match);
  const double mass = testing::permuted_difference(fem::assemble_consistent_mass(gmsh, gmsh_dofs, materials),
                                                   fem::assemble_consistent_mass(box, box_dofs, materials), match);
  EXPECT_LT(stiffness, 1e-10);
  EXPECT_LT(mass, 1e-10);
  const VectorX gmsh_lumped = fem::assemble_lumped_mass(gmsh, gmsh_dofs, materials);
  const VectorX box_lumped = fem::assemble_lumped_mass(box, box_dofs, materials);
  double lumped = 0.0;
  for (Index i = 0; i < gmsh_lumped.size(); ++i) lumped = std::max(lumped, std::abs(gmsh_lumped[i] - box_lumped[match[i]]));
  EXPECT_LT(lumped, 1e-10 * box_lumped.maxCoeff());
}

TEST(GmshBox, HexahedraOfOrderOneAndTwoGiveTheGeneratorsMatricesAndFrequencies) {
  for (const auto& [file, order] : {std::pair<std::string, int>{"box-hex8.msh", 1}, {"box-hex27.msh", 2},
                                    {"box-hex27-binary.msh", 2}}) {
    SCOPED_TRACE(file);
    const Mesh gmsh = read_gmsh(mesh_file(file));
    const Mesh box = build_box_mesh(test_box(order, {4, 2, 2}));
    EXPECT_EQ(gmsh.shape, ElementShape::hexahedron);
    EXPECT_EQ(gmsh.order, order);
    EXPECT_EQ(gmsh.n_elements(), 16);
    EXPECT_FALSE(gmsh.has_crack());
    EXPECT_NEAR(gmsh.volume(), 0.2 * 0.05 * 0.04, 1e-15);
    expect_same_matrices(gmsh, box, Variant::open);

    // Lowest frequencies of the cantilever clamped at x = 0 (group "clamp", box face "x-").
    const VectorX f_gmsh = testing::lowest_frequencies(gmsh, Variant::open, steel(),
                                                       {testing::clamp(gmsh.node_sets.at("clamp"))}, 6);
    const VectorX f_box = testing::lowest_frequencies(box, Variant::open, steel(),
                                                      {testing::clamp(box.node_sets.at("x-"))}, 6);
    ASSERT_EQ(f_gmsh.size(), 6);
    for (int i = 0; i < 6; ++i) EXPECT_NEAR(f_gmsh[i], f_box[i], 1e-10 * f_box[i]) << "mode " << i;
  }
}

TEST(GmshBox, PhysicalGroupsBecomeNamedSets) {
  const Mesh mesh = read_gmsh(mesh_file("box-hex27.msh"));
  const Mesh box = build_box_mesh(test_box(2, {4, 2, 2}));
  const std::vector<Index> nodes = match_nodes(mesh, box);
  // Node sets: the nodes of the group's elements, in mesh numbering.
  for (const auto& [group, face] : {std::pair<std::string, std::string>{"clamp", "x-"}, {"load", "x+"}, {"bottom", "z-"}}) {
    std::vector<Index> mapped;
    for (Index n : mesh.node_sets.at(group)) mapped.push_back(nodes[n]);
    std::sort(mapped.begin(), mapped.end());
    std::vector<Index> expected = box.node_sets.at(face);
    std::sort(expected.begin(), expected.end());
    EXPECT_EQ(mapped, expected) << group;
    EXPECT_NEAR(fem::face_area(mesh, mesh.face_sets.at(group)), fem::face_area(box, box.face_sets.at(face)), 1e-15)
        << group;
  }
  ASSERT_EQ(mesh.node_sets.at("corner").size(), 1u);
  EXPECT_TRUE(mesh.nodes[mesh.node_sets.at("corner")[0]].isApprox(Vec3(0.2, 0.05, 0.04)));
  EXPECT_EQ(mesh.element_sets.at("body").size(), 16u);
  EXPECT_EQ(group_names(mesh), "body, bottom, clamp, corner, load");
  // A traction on a face group loads exactly the face's area.
  const DofMap dofs = make_dof_map(mesh, Variant::open);
  VectorX force;
  fem::add_face_traction(mesh, dofs, mesh.face_sets.at("load"), Vec3(0, 0, 1e6), force);
  EXPECT_NEAR(force.sum(), 1e6 * 0.05 * 0.04, 1e-6);
}

TEST(GmshBox, BinaryAndAsciiFilesGiveTheSameMesh) {
  const Mesh ascii = read_gmsh(mesh_file("box-hex27.msh"));
  const Mesh binary = read_gmsh(mesh_file("box-hex27-binary.msh"));
  // ASCII files hold 16 significant digits: equal to rounding.
  ASSERT_EQ(ascii.nodes.size(), binary.nodes.size());
  for (std::size_t n = 0; n < ascii.nodes.size(); ++n) EXPECT_LT((ascii.nodes[n] - binary.nodes[n]).norm(), 1e-16);
  EXPECT_EQ(ascii.connectivity, binary.connectivity);
  EXPECT_EQ(ascii.node_sets, binary.node_sets);
  EXPECT_EQ(ascii.element_sets, binary.element_sets);
}

/// Pairs of two cracked meshes agree: count, front, areas and normals (matched by place).
void expect_same_pairs(const Mesh& gmsh, const Mesh& box) {
  ASSERT_EQ(gmsh.crack_pairs.size(), box.crack_pairs.size());
  EXPECT_EQ(gmsh.n_original_nodes, box.n_original_nodes);
  EXPECT_EQ(gmsh.n_nodes(), box.n_nodes());
  EXPECT_NEAR(gmsh.crack_area, box.crack_area, 1e-15);
  const std::vector<Index> nodes = match_nodes(gmsh, box);
  std::map<Index, const CrackPair*> box_pairs;
  for (const CrackPair& pair : box.crack_pairs) box_pairs[pair.plus] = &pair;
  double total = 0.0;
  for (const CrackPair& pair : gmsh.crack_pairs) {
    ASSERT_TRUE(box_pairs.count(nodes[pair.plus]));
    const CrackPair& expected = *box_pairs.at(nodes[pair.plus]);
    EXPECT_EQ(pair.on_front(), expected.on_front());
    EXPECT_NEAR(pair.area, expected.area, 1e-12 * box.crack_area);
    EXPECT_LT((pair.normal - expected.normal).norm(), 1e-12);
    // The plus node is on the lower side: its elements lie below the plane.
    EXPECT_LT(pair.plus, gmsh.n_original_nodes);
    if (!pair.on_front()) EXPECT_GE(pair.minus, gmsh.n_original_nodes);
    total += pair.area;
  }
  EXPECT_NEAR(total, 0.05 * 0.05, 1e-15);
}

/// The cracked Gmsh mesh `file` (crack group "crack") against the built-in cracked box of the same
/// order: same pairs, K and M of both variants, and the 4 lowest frequencies of `variants` to 1e-10.
void expect_same_as_box_crack(const std::string& file, int order, std::initializer_list<Variant> variants) {
  GmshOptions options;
  options.crack_group = "crack";
  const Mesh gmsh = read_gmsh(mesh_file(file), options);
  const Mesh box = build_box_mesh(test_box(order, {8, 2, 2}), test_crack());
  expect_same_pairs(gmsh, box);
  expect_same_matrices(gmsh, box, Variant::open);
  expect_same_matrices(gmsh, box, Variant::uncracked);
  for (Variant variant : variants) {
    const VectorX f_gmsh = testing::lowest_frequencies(gmsh, variant, steel(), {testing::clamp(gmsh.node_sets.at("clamp"))}, 4);
    const VectorX f_box = testing::lowest_frequencies(box, variant, steel(), {testing::clamp(box.node_sets.at("x-"))}, 4);
    for (int i = 0; i < 4; ++i) EXPECT_NEAR(f_gmsh[i], f_box[i], 1e-10 * f_box[i]) << variant_name(variant) << " mode " << i;
  }
}

TEST(GmshCrack, PhysicalSurfaceGivesTheBoxCrack) {
  expect_same_as_box_crack("cracked-box-hex27.msh", 2, {Variant::uncracked, Variant::open});
}

TEST(GmshCrack, MeshSplitByGmshsCrackPluginIsRecognised) {
  expect_same_as_box_crack("cracked-box-split.msh", 1, {Variant::open});
}

TEST(GmshCrack, TetrahedralCrackSplitsOffTheFront) {
  for (const std::string file : {"cracked-box-tet4.msh", "cracked-box-tet10.msh"}) {
    SCOPED_TRACE(file);
    GmshOptions options;
    options.crack_group = "crack";
    const Mesh mesh = read_gmsh(mesh_file(file), options);
    EXPECT_EQ(mesh.shape, ElementShape::tetrahedron);
    ASSERT_TRUE(mesh.has_crack());
    double total = 0.0;
    int split = 0;
    for (const CrackPair& pair : mesh.crack_pairs) {
      const Vec3& x = mesh.nodes[pair.plus];
      EXPECT_NEAR(x.z(), 0.02, 1e-12);
      EXPECT_GT(pair.area, 0.0);
      EXPECT_LT((pair.normal - Vec3(0, 0, 1)).norm(), 1e-12);
      // Front: the crack's edges inside the body, x = 0.05 and x = 0.1; its edges on y = 0, 0.05 open.
      const bool front = std::abs(x.x() - 0.05) < 1e-9 || std::abs(x.x() - 0.1) < 1e-9;
      EXPECT_EQ(pair.on_front(), front) << x.transpose();
      if (!pair.on_front()) {
        ++split;
        EXPECT_EQ(mesh.nodes[pair.minus], x);
        EXPECT_GE(pair.minus, mesh.n_original_nodes);
      }
      total += pair.area;
    }
    EXPECT_NEAR(total, 0.05 * 0.05, 1e-15);
    EXPECT_NEAR(mesh.crack_area, 0.05 * 0.05, 1e-15);
    EXPECT_EQ(mesh.n_nodes() - mesh.n_original_nodes, split);
    // Every element above the crack uses the copies of split nodes, every element below the originals
    // (also those that touch the crack at an edge or a vertex only).
    std::set<Index> originals, copies;
    for (const CrackPair& pair : mesh.crack_pairs) {
      if (pair.on_front()) continue;
      originals.insert(pair.plus);
      copies.insert(pair.minus);
    }
    int touching = 0;
    for (Index e = 0; e < mesh.n_elements(); ++e) {
      Vec3 centroid = Vec3::Zero();
      for (int a = 0; a < mesh.nodes_per_element(); ++a) centroid += mesh.nodes[mesh.element_nodes(e)[a]];
      const bool above = centroid.z() / mesh.nodes_per_element() > 0.02;
      for (int a = 0; a < mesh.nodes_per_element(); ++a) {
        const Index node = mesh.element_nodes(e)[a];
        EXPECT_FALSE(above ? originals.count(node) : copies.count(node)) << "element " << e << " node " << node;
        touching += copies.count(node) > 0;
      }
    }
    EXPECT_GT(touching, 0);
    // Open-crack frequencies lie below the uncracked ones, mode by mode.
    const std::vector<fem::DirichletCondition> clamp = {testing::clamp(mesh.node_sets.at("clamp"))};
    const VectorX uncracked = testing::lowest_frequencies(mesh, Variant::uncracked, steel(), clamp, 4);
    const VectorX open = testing::lowest_frequencies(mesh, Variant::open, steel(), clamp, 4);
    for (int i = 0; i < 4; ++i) EXPECT_LE(open[i], uncracked[i] * (1 + 1e-12)) << "mode " << i;
    EXPECT_LT(open[0], 0.999 * uncracked[0]);
  }
}

TEST(GmshCrack, TenNodeTetrahedraApproachTheHexahedralFrequencies) {
  // Same cracked cantilever: 10-node tetrahedra (h = 20 mm) against 27-node hexahedra, within 1 %
  // for both limits (the crack lowers the third mode by 6 %).
  GmshOptions options;
  options.crack_group = "crack";
  const Mesh tet = read_gmsh(mesh_file("cracked-box-tet10.msh"), options);
  const Mesh hex = read_gmsh(mesh_file("cracked-box-hex27.msh"), options);
  for (Variant variant : {Variant::uncracked, Variant::open}) {
    const VectorX f_tet = testing::lowest_frequencies(tet, variant, steel(), {testing::clamp(tet.node_sets.at("clamp"))}, 3);
    const VectorX f_hex = testing::lowest_frequencies(hex, variant, steel(), {testing::clamp(hex.node_sets.at("clamp"))}, 3);
    for (int i = 0; i < 3; ++i) EXPECT_NEAR(f_tet[i], f_hex[i], 0.01 * f_hex[i]) << variant_name(variant) << " mode " << i;
  }
}

}  // namespace
}  // namespace crackle::mesh
