#pragma once
/// \file Faces of a mesh: keys by corner nodes, the table of element faces, face corners and edges.
/// Used to match surface elements of a mesh file to element faces and to split a crack surface.
#include <array>
#include <unordered_map>
#include <vector>

#include "mesh/mesh.hpp"

namespace crackle::mesh {

/// Shape functions of the triangle of order 1 or 2 (vertices (0,0), (1,0), (0,1), then the
/// midpoints of edges 01, 12, 20) at (s, t): values[a], gradients[2a + j] = dN_a/ds_j.
void triangle_shape(int order, double s, double t, double* values, double* gradients);

/// A face by its corner nodes, sorted ascending; -1 pads the fourth entry of a triangle.
using FaceKey = std::array<Index, 4>;

struct FaceKeyHash {
  std::size_t operator()(const FaceKey& key) const;
};

/// Every element face of a mesh by its key: one FaceRef for a boundary face, two for an interior one.
using FaceTable = std::unordered_map<FaceKey, std::vector<FaceRef>, FaceKeyHash>;

FaceKey face_key(const Index* corners, int n_corners);

/// Positions of the corners in the face node list (face_local_nodes), in cyclic order:
/// counter-clockwise in the face's own parameters, so that the face normal x_s x x_t points the
/// way the cycle turns (right-hand rule).
std::vector<int> face_corner_positions(ElementShape shape, int order);

/// For each edge k of a face (from corner k to corner k+1 of the cycle): the positions in the face
/// node list of the nodes on it, both corners included, in order.
std::vector<std::vector<int>> face_edge_positions(ElementShape shape, int order);

/// The mesh nodes of an element face, in face_local_nodes() order.
std::vector<Index> face_nodes(const Mesh& mesh, const FaceRef& face);

/// The key of an element face.
FaceKey face_key(const Mesh& mesh, const FaceRef& face);

FaceTable face_table(const Mesh& mesh);

/// Nodal quadrature of a face with nodes `x` (face_local_nodes() order) of a mesh with this shape and
/// order: tributary area and unit normal (x_s x x_t, the cycle's orientation) of each node.
/// Quadrilaterals: GLL nodal quadrature (positive). Triangles: p = 1 one third of the area each;
/// p = 2 HRZ areas, the diagonal of the face "mass" \f$\int N_a^2\f$ scaled to the face area (nodal
/// quadrature would give the vertices zero area).
void face_nodal_areas(ElementShape shape, int order, const std::vector<Vec3>& x, std::vector<double>& areas,
                      std::vector<Vec3>& normals);

}  // namespace crackle::mesh
