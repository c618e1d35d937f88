#include "io/vtu.hpp"

#include <cstdint>
#include <cstring>
#include <string>

#include "core/errors.hpp"
#include "io/files.hpp"

namespace crackle::io {
namespace {

/// Appends the raw bytes of an array, preceded by its size as a 64-bit header (VTK "raw").
template <typename T>
void append_block(std::string& data, const std::vector<T>& values) {
  const std::uint64_t bytes = values.size() * sizeof(T);
  data.append(reinterpret_cast<const char*>(&bytes), sizeof bytes);
  data.append(reinterpret_cast<const char*>(values.data()), bytes);
}

}  // namespace

void write_vtu(const std::filesystem::path& path, const mesh::Mesh& mesh,
               const std::vector<PointField>& point_fields, const std::vector<CellField>& cell_fields) {
  const int p = mesh.order, n = p + 1;
  const bool tetrahedra = mesh.shape == mesh::ElementShape::tetrahedron;
  const Index n_cells = tetrahedra ? mesh.n_elements() : mesh.n_elements() * p * p * p;
  for (const PointField& field : point_fields) {
    if (field.values.size() != static_cast<std::size_t>(mesh.n_nodes()) * field.components) {
      throw IoError(path.string() + ": point field '" + field.name + "' has " +
                    std::to_string(field.values.size()) + " values for " + std::to_string(mesh.n_nodes()) +
                    " nodes x " + std::to_string(field.components) + " components");
    }
  }
  for (const CellField& field : cell_fields) {
    if (field.values.size() != static_cast<std::size_t>(mesh.n_elements())) {
      throw IoError(path.string() + ": cell field '" + field.name + "' has the wrong length");
    }
  }

  std::vector<double> points(3 * static_cast<std::size_t>(mesh.n_nodes()));
  for (Index i = 0; i < mesh.n_nodes(); ++i) {
    for (int d = 0; d < 3; ++d) points[3 * i + d] = mesh.nodes[i][d];
  }
  // Each element of order p becomes p^3 linear hexahedra over consecutive GLL nodes.
  std::vector<std::int64_t> connectivity;
  connectivity.reserve(8 * static_cast<std::size_t>(n_cells));
  std::vector<std::int64_t> offsets(n_cells);
  // VTK_HEXAHEDRON; tetrahedra: VTK_TETRA or VTK_QUADRATIC_TETRA
  std::vector<std::uint8_t> types(n_cells, tetrahedra ? (p == 2 ? 24 : 10) : 12);
  std::vector<std::int32_t> element_of_cell(n_cells);
  Index cell = 0;
  for (Index e = 0; tetrahedra && e < mesh.n_elements(); ++e) {
    // VTK orders the last two edge nodes 13, 23; Gmsh (and crackle) 32, 31.
    static const int vtk_order[10] = {0, 1, 2, 3, 4, 5, 6, 7, 9, 8};
    const Index* nodes = mesh.element_nodes(e);
    for (int a = 0; a < mesh.nodes_per_element(); ++a) connectivity.push_back(nodes[vtk_order[a]]);
    offsets[cell] = static_cast<std::int64_t>(connectivity.size());
    element_of_cell[cell] = e;
    ++cell;
  }
  for (Index e = 0; !tetrahedra && e < mesh.n_elements(); ++e) {
    const Index* nodes = mesh.element_nodes(e);
    for (int k = 0; k < p; ++k)
      for (int j = 0; j < p; ++j)
        for (int i = 0; i < p; ++i) {
          auto local = [&](int a, int b, int c) { return nodes[(i + a) + n * ((j + b) + n * (k + c))]; };
          for (auto v : {local(0, 0, 0), local(1, 0, 0), local(1, 1, 0), local(0, 1, 0), local(0, 0, 1),
                         local(1, 0, 1), local(1, 1, 1), local(0, 1, 1)}) {
            connectivity.push_back(v);
          }
          offsets[cell] = static_cast<std::int64_t>(connectivity.size());
          element_of_cell[cell] = e;
          ++cell;
        }
  }

  std::string header, data;
  std::size_t offset = 0;
  auto array = [&](const std::string& type, const std::string& name, int components, auto&& values) {
    header += "        <DataArray type=\"" + type + "\" Name=\"" + name + "\" NumberOfComponents=\"" +
              std::to_string(components) + "\" format=\"appended\" offset=\"" + std::to_string(offset) + "\"/>\n";
    const std::size_t before = data.size();
    append_block(data, values);
    offset += data.size() - before;
  };

  header += "<?xml version=\"1.0\"?>\n";
  header += "<VTKFile type=\"UnstructuredGrid\" version=\"1.0\" byte_order=\"LittleEndian\" header_type=\"UInt64\">\n";
  header += "  <UnstructuredGrid>\n";
  header += "    <Piece NumberOfPoints=\"" + std::to_string(mesh.n_nodes()) + "\" NumberOfCells=\"" +
            std::to_string(n_cells) + "\">\n";
  header += "      <PointData>\n";
  for (const PointField& field : point_fields) array("Float64", field.name, field.components, field.values);
  header += "      </PointData>\n      <CellData>\n";
  array("Int32", "element", 1, element_of_cell);
  std::vector<std::int32_t> region(n_cells);
  for (Index c = 0; c < n_cells; ++c) region[c] = mesh.element_region[element_of_cell[c]];
  array("Int32", "region", 1, region);
  for (const CellField& field : cell_fields) {
    std::vector<double> expanded(n_cells);
    for (Index c = 0; c < n_cells; ++c) expanded[c] = field.values[element_of_cell[c]];
    array("Float64", field.name, 1, expanded);
  }
  header += "      </CellData>\n      <Points>\n";
  array("Float64", "Points", 3, points);
  header += "      </Points>\n      <Cells>\n";
  array("Int64", "connectivity", 1, connectivity);
  array("Int64", "offsets", 1, offsets);
  array("UInt8", "types", 1, types);
  header += "      </Cells>\n    </Piece>\n  </UnstructuredGrid>\n  <AppendedData encoding=\"raw\">\n   _";
  write_file_atomic(path, header + data + "\n  </AppendedData>\n</VTKFile>\n");
}

}  // namespace crackle::io
