#pragma once
/// \file VTK unstructured-grid (.vtu) files that open in ParaView. Each GLL hexahedron of order
/// p is written as p^3 linear hexahedra over its nodes, so any order renders everywhere; tetrahedra
/// as VTK (quadratic) tetrahedra.
#include <filesystem>
#include <string>
#include <vector>

#include "mesh/mesh.hpp"

namespace crackle::io {

/// Nodal data: `components` values per mesh node (1 = scalar, 3 = vector), node-major.
struct PointField {
  std::string name;
  int components = 1;
  std::vector<double> values;
};

/// Per-element data (written for each of the element's sub-cells).
struct CellField {
  std::string name;
  std::vector<double> values;  ///< one per element
};

/// Writes the mesh with its fields, atomically (binary appended data, base64-free raw encoding).
void write_vtu(const std::filesystem::path& path, const mesh::Mesh& mesh,
               const std::vector<PointField>& point_fields, const std::vector<CellField>& cell_fields = {});

}  // namespace crackle::io
