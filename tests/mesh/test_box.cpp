#include <gtest/gtest.h>

#include <algorithm>
#include <numeric>
#include <set>

#include "core/errors.hpp"
#include "mesh/box.hpp"

using namespace crackle;
using namespace crackle::mesh;

namespace {

BoxSpec beam_box(int order) {
  BoxSpec box;
  box.size = Vec3(0.2, 0.02, 0.01);
  box.cells = {40, 4, 2};
  box.order = order;
  return box;
}

CrackSpec edge_crack() {
  CrackSpec crack;
  crack.normal = kX;
  crack.at = 0.05;
  crack.region[kY] = {0.0, 0.02};
  crack.region[kZ] = {0.007, 0.01};
  return crack;
}

/// Number of connected pieces of the element graph (elements sharing a node are connected).
int count_pieces(const Mesh& mesh) {
  std::vector<Index> parent(mesh.n_nodes());
  std::iota(parent.begin(), parent.end(), 0);
  auto find = [&](Index i) {
    while (parent[i] != i) i = parent[i] = parent[parent[i]];
    return i;
  };
  for (Index e = 0; e < mesh.n_elements(); ++e) {
    const Index* nodes = mesh.element_nodes(e);
    for (int a = 1; a < mesh.nodes_per_element(); ++a) parent[find(nodes[a])] = find(nodes[0]);
  }
  std::set<Index> roots;
  for (Index e = 0; e < mesh.n_elements(); ++e) roots.insert(find(mesh.element_nodes(e)[0]));
  return static_cast<int>(roots.size());
}

double total_pair_area(const Mesh& mesh) {
  double sum = 0.0;
  for (const CrackPair& pair : mesh.crack_pairs) sum += pair.area;
  return sum;
}

}  // namespace

TEST(BoxMesh, CountsAndVolumeWithoutCrack) {
  for (int p = 1; p <= 4; ++p) {
    Mesh mesh = build_box_mesh(beam_box(p));
    EXPECT_EQ(mesh.n_elements(), 40 * 4 * 2);
    EXPECT_EQ(mesh.n_nodes(), (40 * p + 1) * (4 * p + 1) * (2 * p + 1));
    EXPECT_NEAR(mesh.volume(), 0.2 * 0.02 * 0.01, 1e-18);
    EXPECT_FALSE(mesh.has_crack());
    EXPECT_EQ(mesh.node_sets.at("x-").size(), static_cast<std::size_t>((4 * p + 1) * (2 * p + 1)));
    EXPECT_EQ(mesh.face_sets.at("z+").size(), 40u * 4u);
  }
}

TEST(BoxMesh, NodesSitAtGllPointsOfEachCell) {
  Mesh mesh = build_box_mesh(beam_box(3));
  // Element 0 spans [0, 0.005] in x; its nodes along x are the 4 GLL points mapped there.
  const std::vector<double> gll = {-1.0, -std::sqrt(0.2), std::sqrt(0.2), 1.0};
  for (int a = 0; a < 4; ++a) {
    EXPECT_NEAR(mesh.nodes[mesh.element_nodes(0)[a]].x(), 0.0025 * (gll[a] + 1.0), 1e-16);
  }
}

TEST(BoxMesh, GridLinesAreInsertedAtCrackEdges) {
  auto lines = grid_lines(beam_box(2), edge_crack());
  EXPECT_EQ(lines[kX].size(), 41u);
  EXPECT_EQ(lines[kY].size(), 5u);
  ASSERT_EQ(lines[kZ].size(), 4u);  // 0, 0.005, 0.007, 0.01
  EXPECT_DOUBLE_EQ(lines[kZ][2], 0.007);
}

TEST(BoxMesh, EdgeCrackPairsAreaAndFront) {
  for (int p = 1; p <= 4; ++p) {
    Mesh mesh = build_box_mesh(beam_box(p), edge_crack());
    // Crack face: 4 cells across y, 1 cell (0.007..0.01) in z.
    const int along_y = 4 * p + 1, along_z = p + 1;
    ASSERT_EQ(mesh.crack_pairs.size(), static_cast<std::size_t>(along_y * along_z));
    EXPECT_NEAR(mesh.crack_area, 0.02 * 0.003, 1e-18);
    EXPECT_NEAR(total_pair_area(mesh), mesh.crack_area, 1e-15 * mesh.crack_area);
    int front = 0;
    for (const CrackPair& pair : mesh.crack_pairs) {
      EXPECT_GT(pair.area, 0.0);
      EXPECT_EQ(pair.normal, Vec3(1, 0, 0));
      EXPECT_DOUBLE_EQ(mesh.nodes[pair.plus].x(), 0.05);
      EXPECT_EQ(mesh.nodes[pair.minus], mesh.nodes[pair.plus]);
      const bool at_front_line = std::abs(mesh.nodes[pair.plus].z() - 0.007) < 1e-12;
      EXPECT_EQ(pair.on_front(), at_front_line) << "node at z = " << mesh.nodes[pair.plus].z();
      front += pair.on_front();
      if (!pair.on_front()) {
        EXPECT_GE(pair.minus, mesh.n_original_nodes);
        EXPECT_LT(pair.plus, mesh.n_original_nodes);
      }
    }
    EXPECT_EQ(front, along_y);
    EXPECT_EQ(mesh.n_nodes(), mesh.n_original_nodes + along_y * along_z - along_y);
    EXPECT_EQ(count_pieces(mesh), 1);
  }
}

TEST(BoxMesh, ElementsOnEachSideUseTheirOwnCopy) {
  Mesh mesh = build_box_mesh(beam_box(2), edge_crack());
  std::vector<int> side(mesh.n_nodes(), 0);  // +1 used by an element below the plane, +2 above
  for (Index e = 0; e < mesh.n_elements(); ++e) {
    const Index* nodes = mesh.element_nodes(e);
    Vec3 centre = Vec3::Zero();
    for (int a = 0; a < mesh.nodes_per_element(); ++a) centre += mesh.nodes[nodes[a]];
    centre /= mesh.nodes_per_element();
    for (int a = 0; a < mesh.nodes_per_element(); ++a) side[nodes[a]] |= centre.x() < 0.05 ? 1 : 2;
  }
  for (const CrackPair& pair : mesh.crack_pairs) {
    if (pair.on_front()) {
      EXPECT_EQ(side[pair.plus], 3);
    } else {
      EXPECT_EQ(side[pair.plus], 1);
      EXPECT_EQ(side[pair.minus], 2);
    }
  }
}

TEST(BoxMesh, EmbeddedCrackHasFrontAllRound) {
  BoxSpec box;
  box.size = Vec3(1, 1, 1);
  box.cells = {4, 4, 4};
  box.order = 2;
  CrackSpec crack;
  crack.normal = kZ;
  crack.at = 0.5;
  crack.region[kX] = {0.25, 0.75};
  crack.region[kY] = {0.25, 0.5};
  Mesh mesh = build_box_mesh(box, crack);
  EXPECT_EQ(mesh.crack_pairs.size(), 5u * 3u);
  int split = 0;
  for (const CrackPair& pair : mesh.crack_pairs) split += !pair.on_front();
  EXPECT_EQ(split, 3);  // the interior row of the 5 x 3 face nodes
  EXPECT_NEAR(total_pair_area(mesh), 0.125, 1e-15);
  EXPECT_EQ(mesh.crack_pairs[0].normal, Vec3(0, 0, 1));
}

TEST(BoxMesh, ThroughCrackCutsTheBodyInTwo) {
  BoxSpec box = beam_box(1);
  CrackSpec crack = edge_crack();
  crack.region[kZ] = {0.0, 0.01};
  Mesh mesh = build_box_mesh(box, crack);
  for (const CrackPair& pair : mesh.crack_pairs) EXPECT_FALSE(pair.on_front());
  EXPECT_EQ(count_pieces(mesh), 2);
  EXPECT_NEAR(total_pair_area(mesh), 0.0002, 1e-18);
}

TEST(BoxMesh, UncrackedDofMapIsTheMeshWithoutCrack) {
  const BoxSpec box = beam_box(2);
  const auto lines = grid_lines(box, edge_crack());
  Mesh cracked = build_box_mesh(box, lines, edge_crack());
  Mesh plain = build_box_mesh(box, lines, std::nullopt);
  DofMap tied = make_dof_map(cracked, Variant::uncracked);
  DofMap open = make_dof_map(cracked, Variant::open);
  EXPECT_EQ(tied.n_dof_nodes, plain.n_nodes());
  EXPECT_EQ(open.n_dof_nodes, cracked.n_nodes());
  ASSERT_EQ(cracked.connectivity.size(), plain.connectivity.size());
  for (std::size_t k = 0; k < plain.connectivity.size(); ++k) {
    ASSERT_EQ(tied.dof_node[cracked.connectivity[k]], plain.connectivity[k]);
  }
}

TEST(BoxMesh, FaceLocalNodesLieOnTheFace) {
  for (int p = 1; p <= 4; ++p) {
    const int n = p + 1;
    for (int face = 0; face < 6; ++face) {
      std::vector<int> nodes = face_local_nodes(p, face);
      ASSERT_EQ(nodes.size(), static_cast<std::size_t>(n * n));
      std::set<int> distinct(nodes.begin(), nodes.end());
      EXPECT_EQ(distinct.size(), nodes.size());
      const int axis = face / 2, fixed = face % 2 ? p : 0;
      for (int a : nodes) {
        const int ijk[3] = {a % n, (a / n) % n, a / (n * n)};
        EXPECT_EQ(ijk[axis], fixed);
      }
    }
  }
}

TEST(BoxMesh, CrackChecks) {
  const BoxSpec box = beam_box(2);
  CrackSpec crack = edge_crack();
  EXPECT_EQ(check_crack(box, crack), "");
  crack.at = 0.051;
  EXPECT_EQ(check_crack(box, crack),
            "plane.at: expected a grid plane of the mesh, x = 0 + k*0.005 (nearest 0.05 or 0.055), got 0.051");
  crack.at = 0.2;
  EXPECT_EQ(check_crack(box, crack), "plane.at: expected a position strictly inside the body, x in (0, 0.2), got 0.2");
  crack = edge_crack();
  crack.region[kZ] = {0.007, 0.007};
  EXPECT_EQ(check_crack(box, crack),
            "region.z: expected [low, high] with low < high (a crack of nonzero area), got [0.007, 0.007]");
  crack.region[kZ] = {0.007, 0.012};
  EXPECT_EQ(check_crack(box, crack), "region.z: expected a range inside the body, z in [0, 0.01], got [0.007, 0.012]");
  EXPECT_THROW(build_box_mesh(box, crack), InputError);
}

TEST(BoxMesh, CrackChecksOnAHugeGridBuildNoLines) {
  // 1e9 cells along the normal: the grid plane is found without the 8 GB of lines (the scene is
  // refused later, by the memory estimate).
  BoxSpec box = beam_box(1);
  box.cells = {1000000000, 1, 1};
  CrackSpec crack = edge_crack();
  EXPECT_EQ(check_crack(box, crack), "");
  box.cells = {1000000, 1, 1};
  crack.at = 0.05 + 1e-7;  // half-way between two planes 2e-7 apart
  const std::string message = check_crack(box, crack);
  EXPECT_NE(message.find("plane.at: expected a grid plane of the mesh, x = 0 + k*2e-7 (nearest 0.05 or 0.0500002)"),
            std::string::npos)
      << message;
}

TEST(BoxMesh, ExtraLinesAreMergedWithCrackEdges) {
  BoxSpec box = beam_box(1);
  box.extra_lines[kZ] = {0.007, 0.008, 0.01, 0.02, 0.008};  // repeat, boundary, outside: ignored
  auto lines = grid_lines(box, edge_crack());
  EXPECT_EQ(lines[kZ], (std::vector<double>{0.0, 0.005, 0.007, 0.008, 0.01}));
  // The crack's own mesh and the uncracked mesh with the same extra lines have the same elements.
  Mesh cracked = build_box_mesh(box, edge_crack());
  box.extra_lines[kZ].push_back(0.007);
  Mesh plain = build_box_mesh(box);
  EXPECT_EQ(cracked.n_elements(), plain.n_elements());
  EXPECT_EQ(cracked.n_original_nodes, plain.n_nodes());
}

TEST(MorphLines, MovesTheCrackLinesOntoTheCrackAndKeepsTheTopology) {
  BoxSpec box = beam_box(2);
  box.grading.layers = 2;
  const CrackSpec reference = edge_crack();
  const auto lines = grid_lines(box, reference);
  // The same crack: nothing moves.
  const auto same = morph_lines(box, lines, reference, reference, {});
  for (int axis = 0; axis < 3; ++axis) {
    ASSERT_EQ(same[axis].size(), lines[axis].size());
    for (std::size_t i = 0; i < lines[axis].size(); ++i) EXPECT_NEAR(same[axis][i], lines[axis][i], 1e-15);
  }
  // Another crack (off the uniform grid, deeper): same number of lines, the crack's plane and edge on them,
  // the ends and the fixed line x = 0.15 where they were, lines still ascending.
  CrackSpec moved = reference;
  moved.at = 0.0613;
  moved.region[kZ] = {0.0061, 0.01};
  const auto result = morph_lines(box, lines, reference, moved, {{{0.15}, {}, {}}});
  for (int axis = 0; axis < 3; ++axis) {
    ASSERT_EQ(result[axis].size(), lines[axis].size());
    EXPECT_TRUE(std::is_sorted(result[axis].begin(), result[axis].end()));
    EXPECT_DOUBLE_EQ(result[axis].front(), lines[axis].front());
    EXPECT_DOUBLE_EQ(result[axis].back(), lines[axis].back());
  }
  EXPECT_NE(std::find(result[kX].begin(), result[kX].end(), 0.0613), result[kX].end());
  EXPECT_NE(std::find(result[kX].begin(), result[kX].end(), 0.15), result[kX].end());
  EXPECT_NE(std::find(result[kZ].begin(), result[kZ].end(), 0.0061), result[kZ].end());
  // The mesh on the moved lines has the moved crack, with the same pairs and the moved area.
  const Mesh base = build_box_mesh(box, lines, reference);
  const Mesh mesh = build_box_mesh(box, result, moved);
  EXPECT_EQ(mesh.n_nodes(), base.n_nodes());
  EXPECT_EQ(mesh.crack_pairs.size(), base.crack_pairs.size());
  EXPECT_NEAR(total_pair_area(mesh), 0.02 * (0.01 - 0.0061), 1e-15);
}

TEST(MorphLines, RefusesACrackThatWouldPassAFixedLine) {
  const BoxSpec box = beam_box(1);
  const CrackSpec reference = edge_crack();
  CrackSpec moved = reference;
  moved.at = 0.17;
  try {
    morph_lines(box, grid_lines(box, reference), reference, moved, {{{0.15}, {}, {}}});
    FAIL() << "expected InputError";
  } catch (const InputError& error) {
    EXPECT_NE(std::string(error.what()).find("crack.reference.at: moving the grid"), std::string::npos) << error.what();
  }
  // Without a reference the plane must be a uniform grid plane; with one it may lie anywhere.
  moved.at = 0.0613;
  EXPECT_NE(check_crack(box, moved), "");
  EXPECT_EQ(check_crack(box, moved, false), "");
}
