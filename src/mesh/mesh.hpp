#pragma once
/// \file The mesh: GLL hexahedra or Lagrange tetrahedra of order p, named node, face and element
/// sets, and the crack-face pairs.
///
/// The crack lives only in the element-to-node map (STYLE.md): the nodes of the crack faces are
/// duplicated, the elements on one side refer to the copies, and the mesh emits the list of
/// face pairs {minus, plus, normal n+, tributary area}. Element kernels never see the crack.
#include <array>
#include <map>
#include <string>
#include <vector>

#include "core/types.hpp"
#include "core/words.hpp"

namespace crackle::mesh {

/// One node pair of the crack faces (MODEL.md eq. 9): g_N = g0 + (u_minus - u_plus) . normal.
/// `plus` lies on the face whose outward normal is `normal` (n+); `minus` on the opposite face.
/// On the crack front the faces share their node: there `minus == plus` and the pair only carries
/// its share of the face quadrature, so that the pair areas integrate over the whole crack.
struct CrackPair {
  Index minus = 0;
  Index plus = 0;
  Vec3 normal = Vec3::Zero();
  double area = 0.0;  ///< tributary area: nodal quadrature of the crack faces (HRZ on 6-node triangles) [m^2]
  bool on_front() const { return minus == plus; }
};

/// A face of an element: element index and local face. Hexahedra: 0..5 = x-, x+, y-, y+, z-, z+ of
/// the reference cube; tetrahedra: 0..3, face f opposite vertex f (tetrahedron_face_vertices()).
struct FaceRef {
  Index element = 0;
  int local_face = 0;
};

/// Shape of the elements of a mesh (one shape and one order per mesh).
enum class ElementShape {
  hexahedron,   ///< GLL Lagrange hexahedra of order 1..4, lexicographic local nodes
  tetrahedron,  ///< Lagrange tetrahedra of order 1 (4 nodes) or 2 (10 nodes), Gmsh local order
};
const char* shape_name(ElementShape shape);

/// Mesh of Lagrange elements of order p: hexahedra on Gauss–Lobatto–Legendre nodes (the default) or
/// tetrahedra.
///
/// Hexahedra store their nodes lexicographically: local node a = i + (p+1) (j + (p+1) k) sits at
/// reference point (xi_i, xi_j, xi_k), the GLL points. Tetrahedra use Gmsh's order: vertices 0..3 at
/// reference (0,0,0), (1,0,0), (0,1,0), (0,0,1), then for p = 2 the edge midpoints of the edges
/// 01, 12, 20, 30, 32, 31. Duplicated crack nodes are appended after all original nodes, so dropping
/// them (tying each to its original) gives the numbering of the same mesh built without a crack.
struct Mesh {
  ElementShape shape = ElementShape::hexahedron;
  int order = 1;                          ///< p = 1..4 (hexahedra), 1..2 (tetrahedra)
  std::vector<Vec3> nodes;                ///< coordinates [m], including duplicated crack nodes
  std::vector<Index> connectivity;        ///< n_elements() x nodes_per_element()
  std::vector<int> element_region;        ///< region (material) index of each element
  Index n_original_nodes = 0;             ///< nodes before crack duplication
  std::map<std::string, std::vector<Index>> node_sets;  ///< e.g. "x-": all nodes on that face
  std::map<std::string, std::vector<FaceRef>> face_sets;  ///< e.g. "x+": element faces on it
  /// Named element sets, e.g. the physical volume groups of a Gmsh file (material regions).
  std::map<std::string, std::vector<Index>> element_sets;
  std::vector<CrackPair> crack_pairs;     ///< empty without a crack
  double crack_area = 0.0;                ///< area of the crack rectangle or surface [m^2]
  /// True when every element is an axis-aligned brick with GLL nodes at their affine positions
  /// (box generator): element matrices then depend only on the brick's size and material.
  bool axis_aligned_bricks = false;

  int nodes_per_edge() const { return order + 1; }
  int nodes_per_element() const {
    if (shape == ElementShape::tetrahedron) return (order + 1) * (order + 2) * (order + 3) / 6;
    return (order + 1) * (order + 1) * (order + 1);
  }
  /// Local faces of one element: 6 (hexahedra) or 4 (tetrahedra).
  int faces_per_element() const { return shape == ElementShape::tetrahedron ? 4 : 6; }
  Index n_nodes() const { return static_cast<Index>(nodes.size()); }
  Index n_elements() const {
    return static_cast<Index>(connectivity.size() / nodes_per_element());
  }
  const Index* element_nodes(Index element) const {
    return connectivity.data() + static_cast<std::size_t>(element) * nodes_per_element();
  }
  bool has_crack() const { return !crack_pairs.empty(); }
  /// Total volume of the elements [m^3] (from the corner nodes; exact for bricks and straight-sided
  /// tetrahedra).
  double volume() const;
};

/// Local node indices of local face f (0..5 = x-, x+, y-, y+, z-, z+) of a hexahedron of order p,
/// ordered lexicographically in the face's two tangential directions.
std::vector<int> face_local_nodes(int order, int local_face);

/// Local node indices of local face f of an element of the given shape. Hexahedra: as above.
/// Tetrahedra: the three vertices (counter-clockwise seen from outside), then for p = 2 the
/// midpoints of the edges v0v1, v1v2, v2v0 of that triangle.
std::vector<int> face_local_nodes(ElementShape shape, int order, int local_face);

/// The vertices of face f of a tetrahedron (f opposite vertex f), counter-clockwise seen from outside.
const std::array<int, 3>& tetrahedron_face_vertices(int local_face);

/// The local node on edge (a, b) of a 10-node tetrahedron (a != b vertices 0..3).
int tetrahedron_edge_node(int a, int b);

/// The two linear variants of a cracked mesh (MODEL.md sec. 5).
enum class Variant {
  uncracked,  ///< each crack pair tied into one set of DOFs
  open,       ///< crack faces free
};
/// The scene's words for the variants (modal.variants, transient.variant, a release's mode).
inline constexpr Words<Variant, 2> kVariantWords{{{"uncracked", Variant::uncracked}, {"open", Variant::open}}};
inline const char* variant_name(Variant variant) { return text_of(kVariantWords, variant); }

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
