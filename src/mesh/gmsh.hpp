#pragma once
/// \file Reader of Gmsh MSH 4.1 files (ASCII and binary), written for crackle (no Gmsh library).
///
/// Volume elements: 4- and 10-node tetrahedra (Gmsh types 4, 11) and 8- and 27-node hexahedra
/// (types 5, 12), one type per mesh. The 27-node hexahedron's nodes (edge midpoints, face and cell
/// centres) are exactly the GLL nodes of order 2, so both hexahedra map to crackle's GLL hexahedra
/// with their nodes reordered lexicographically; tetrahedra keep Gmsh's node order.
///
/// Physical groups become named sets: every group a node set (the nodes of its elements), surface
/// groups also a face set (the element faces its triangles or quadrangles cover) and volume groups an
/// element set (material regions). An unnamed group is named by its number.
#include <string>

#include "mesh/mesh.hpp"

namespace crackle::mesh {

struct GmshOptions {
  /// Physical surface group to make a crack (split_surface_crack()); empty: no crack.
  std::string crack_group;
};

/// Reads a mesh file. Throws InputError naming the file for: a file that is not MSH 4.1 or is
/// truncated, unsupported element types (named), inverted elements, a crack group that does not
/// exist (listing those that do) or is not a surface inside the mesh.
Mesh read_gmsh(const std::string& path, const GmshOptions& options = {});

/// Same, from the contents of a file; `name` stands for the file in messages.
Mesh parse_gmsh(const std::string& contents, const std::string& name, const GmshOptions& options = {});

/// "clamp, crack, load": the names of the mesh's node sets (its groups), for messages.
std::string group_names(const Mesh& mesh);

}  // namespace crackle::mesh
