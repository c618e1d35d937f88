#pragma once
/// \file A crack along a surface of element faces in an unstructured mesh (e.g. a physical surface
/// group of a Gmsh file), split exactly like the box generator's cracks.
#include <string>
#include <vector>

#include "mesh/mesh.hpp"

namespace crackle::mesh {

/// Makes the faces `crack_faces` (each given by its corner nodes, 3 or 4) a crack of `mesh`:
///
/// - **Faces inside the body** (each shared by two elements): the nodes of the surface are
///   duplicated except on the crack front. Front rule (as for box cracks): the nodes of the
///   surface's boundary edges stay shared unless the edge lies on the body's outer surface (an edge
///   crack opens at the surface); a node around which the surface does not separate the elements
///   stays shared too. Elements on the minus side refer to the copies, appended after all nodes.
/// - **Faces already split** (Gmsh's Crack plugin: two coincident boundary faces on different nodes):
///   the coincident nodes become the pairs and nodes shared by both faces the front; the copies on
///   the minus side are renumbered to come after all other nodes.
///
/// n+ is the face normal oriented consistently over each connected piece of the surface, with its
/// largest component positive on the piece's first face (a crack normal to z gets n+ = +z); the plus
/// side is the side n+ points away from. Pair areas are the nodal quadrature of the crack faces
/// (face_nodal_areas()), the pair normal the area-weighted mean of the nodal normals. Face node sets
/// get both copies of a split node. `what` names the surface in messages ("crack group 'crack'").
/// Throws InputError if a face is not a face of the mesh, lies on the outer boundary without a
/// coincident twin, or the surface cannot be oriented.
void split_surface_crack(Mesh& mesh, const std::vector<std::vector<Index>>& crack_faces, const std::string& what);

}  // namespace crackle::mesh
