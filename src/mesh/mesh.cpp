#include "mesh/mesh.hpp"

#include <cassert>
#include <cmath>

#include <Eigen/LU>

namespace crackle::mesh {

const char* shape_name(ElementShape shape) {
  return shape == ElementShape::tetrahedron ? "tetrahedron" : "hexahedron";
}

double Mesh::volume() const {
  if (shape == ElementShape::tetrahedron) {
    // Straight-sided tetrahedra: det[x1 - x0, x2 - x0, x3 - x0] / 6 from the vertices.
    double total = 0.0;
    for (Index e = 0; e < n_elements(); ++e) {
      const Index* element = element_nodes(e);
      Eigen::Matrix3d edges;
      for (int c = 0; c < 3; ++c) edges.col(c) = nodes[element[c + 1]] - nodes[element[0]];
      total += edges.determinant() / 6.0;
    }
    return total;
  }
  // Volume from the eight corners by the 2x2x2 Gauss rule on the trilinear map (exact for bricks
  // and for any trilinear hexahedron).
  const int n = nodes_per_edge();
  const int corner[8] = {0, n - 1, n * (n - 1), n * n - 1, n * n * (n - 1), n * n * (n - 1) + n - 1,
                         n * n * n - n, n * n * n - 1};
  const double g = 1.0 / std::sqrt(3.0);
  double total = 0.0;
  for (Index e = 0; e < n_elements(); ++e) {
    const Index* element = element_nodes(e);
    Vec3 x[8];
    for (int c = 0; c < 8; ++c) x[c] = nodes[element[corner[c]]];
    for (int q = 0; q < 8; ++q) {
      const double xi[3] = {(q & 1) ? g : -g, (q & 2) ? g : -g, (q & 4) ? g : -g};
      Eigen::Matrix3d jacobian = Eigen::Matrix3d::Zero();
      for (int c = 0; c < 8; ++c) {
        const double s[3] = {(c & 1) ? 1.0 : -1.0, (c & 2) ? 1.0 : -1.0, (c & 4) ? 1.0 : -1.0};
        for (int d = 0; d < 3; ++d) {
          double derivative = s[d] / 8.0;
          for (int o = 0; o < 3; ++o) {
            if (o != d) derivative *= 1.0 + s[o] * xi[o];
          }
          jacobian.col(d) += derivative * x[c];
        }
      }
      total += jacobian.determinant();
    }
  }
  return total;
}

std::vector<int> face_local_nodes(int order, int local_face) {
  assert(local_face >= 0 && local_face < 6);
  const int n = order + 1;
  const int axis = local_face / 2;
  const int fixed = (local_face % 2 == 0) ? 0 : order;
  std::vector<int> result;
  result.reserve(n * n);
  for (int t2 = 0; t2 < n; ++t2) {
    for (int t1 = 0; t1 < n; ++t1) {
      int ijk[3];
      ijk[axis] = fixed;
      // tangential axes in increasing order
      const int first = axis == 0 ? 1 : 0;
      const int second = axis == 2 ? 1 : 2;
      ijk[first] = t1;
      ijk[second] = t2;
      result.push_back(ijk[0] + n * (ijk[1] + n * ijk[2]));
    }
  }
  return result;
}

const std::array<int, 3>& tetrahedron_face_vertices(int local_face) {
  assert(local_face >= 0 && local_face < 4);
  static const std::array<int, 3> faces[4] = {{1, 2, 3}, {0, 3, 2}, {0, 1, 3}, {0, 2, 1}};
  return faces[local_face];
}

int tetrahedron_edge_node(int a, int b) {
  // Gmsh's 10-node tetrahedron: node 4 + k on edge k of 01, 12, 20, 30, 32, 31.
  static const int edges[6][2] = {{0, 1}, {1, 2}, {2, 0}, {3, 0}, {3, 2}, {3, 1}};
  for (int k = 0; k < 6; ++k) {
    if ((edges[k][0] == a && edges[k][1] == b) || (edges[k][0] == b && edges[k][1] == a)) return 4 + k;
  }
  assert(false && "not an edge of a tetrahedron");
  return -1;
}

std::vector<int> face_local_nodes(ElementShape shape, int order, int local_face) {
  if (shape == ElementShape::hexahedron) return face_local_nodes(order, local_face);
  const std::array<int, 3>& v = tetrahedron_face_vertices(local_face);
  std::vector<int> result(v.begin(), v.end());
  if (order == 2) {
    for (int k = 0; k < 3; ++k) result.push_back(tetrahedron_edge_node(v[k], v[(k + 1) % 3]));
  }
  return result;
}

DofMap make_dof_map(const Mesh& mesh, Variant variant) {
  DofMap map;
  map.dof_node.resize(mesh.nodes.size());
  for (Index i = 0; i < mesh.n_nodes(); ++i) map.dof_node[i] = i;
  map.n_dof_nodes = mesh.n_nodes();
  if (variant == Variant::uncracked) {
    // Duplicates were appended after the originals: tying each to its original gives exactly the
    // numbering of the mesh without the crack.
    for (const CrackPair& pair : mesh.crack_pairs) map.dof_node[pair.minus] = map.dof_node[pair.plus];
    map.n_dof_nodes = mesh.n_original_nodes;
  }
  return map;
}

}  // namespace crackle::mesh
