#pragma once
/// \file The mesh: GLL hexahedra of order p, named node and face sets, and the crack-face pairs.
///
/// The crack lives only in the element-to-node map (STYLE.md): the nodes of the crack faces are
/// duplicated, the elements on one side refer to the copies, and the mesh emits the list of
/// face pairs {minus, plus, normal n+, tributary area}. Element kernels never see the crack.
#include <map>
#include <string>
#include <vector>

#include "core/types.hpp"

namespace crackle::mesh {

/// One node pair of the crack faces (MODEL.md eq. 9): g_N = g0 + (u_minus - u_plus) . normal.
/// `plus` lies on the face whose outward normal is `normal` (n+); `minus` on the opposite face.
/// On the crack front the faces share their node: there `minus == plus` and the pair only carries
/// its share of the face quadrature, so that the pair areas integrate over the whole crack.
struct CrackPair {
  Index minus = 0;
  Index plus = 0;
  Vec3 normal = Vec3::Zero();
  double area = 0.0;  ///< tributary area from GLL nodal quadrature of the crack face [m^2]
  bool on_front() const { return minus == plus; }
};

/// A face of an element: element index and local face 0..5 = x-, x+, y-, y+, z-, z+ of the
/// reference cube.
struct FaceRef {
  Index element = 0;
  int local_face = 0;
};

/// Hexahedral mesh of Lagrange elements of order p on Gauss–Lobatto–Legendre nodes.
///
/// Nodes of an element are stored lexicographically: local node a = i + (p+1) (j + (p+1) k) sits
/// at reference point (xi_i, xi_j, xi_k), the GLL points. Duplicated crack nodes are appended after
/// all original nodes, so dropping them (tying each to its original) gives the numbering of the
/// same mesh built without a crack.
struct Mesh {
  int order = 1;                          ///< p = 1..4
  std::vector<Vec3> nodes;                ///< coordinates [m], including duplicated crack nodes
  std::vector<Index> connectivity;        ///< n_elements() x nodes_per_element()
  std::vector<int> element_region;        ///< region (material) index of each element
  Index n_original_nodes = 0;             ///< nodes before crack duplication
  std::map<std::string, std::vector<Index>> node_sets;  ///< e.g. "x-": all nodes on that face
  std::map<std::string, std::vector<FaceRef>> face_sets;  ///< e.g. "x+": element faces on it
  std::vector<CrackPair> crack_pairs;     ///< empty without a crack
  double crack_area = 0.0;                ///< exact area of the crack rectangle(s) [m^2]
  /// True when every element is an axis-aligned brick with GLL nodes at their affine positions
  /// (box generator): element matrices then depend only on the brick's size and material.
  bool axis_aligned_bricks = false;

  int nodes_per_edge() const { return order + 1; }
  int nodes_per_element() const { return (order + 1) * (order + 1) * (order + 1); }
  Index n_nodes() const { return static_cast<Index>(nodes.size()); }
  Index n_elements() const {
    return static_cast<Index>(connectivity.size() / nodes_per_element());
  }
  const Index* element_nodes(Index element) const {
    return connectivity.data() + static_cast<std::size_t>(element) * nodes_per_element();
  }
  bool has_crack() const { return !crack_pairs.empty(); }
  /// Total volume of the elements [m^3] (from the corner nodes; exact for bricks).
  double volume() const;
};

/// Local node indices of local face f (0..5 = x-, x+, y-, y+, z-, z+) of a hexahedron of order p,
/// ordered lexicographically in the face's two tangential directions.
std::vector<int> face_local_nodes(int order, int local_face);

/// The two linear variants of a cracked mesh (MODEL.md sec. 5).
enum class Variant {
  uncracked,  ///< each crack pair tied into one set of DOFs
  open,       ///< crack faces free
};
const char* variant_name(Variant variant);

/// Map from mesh nodes to DOF nodes (3 DOFs each, interleaved x, y, z) for one variant.
/// For `open` it is the identity; for `uncracked` each duplicated crack node maps to its original,
/// which gives exactly the numbering of the mesh without a crack.
struct DofMap {
  std::vector<Index> dof_node;  ///< DOF node of each mesh node
  Index n_dof_nodes = 0;
  Index n_dofs() const { return 3 * n_dof_nodes; }
  Index dof(Index node, int component) const { return 3 * dof_node[node] + component; }
};

DofMap make_dof_map(const Mesh& mesh, Variant variant);

}  // namespace crackle::mesh
