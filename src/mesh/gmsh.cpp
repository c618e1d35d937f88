#include "mesh/gmsh.hpp"

#include <Eigen/LU>
#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <map>
#include <set>
#include <sstream>
#include <unordered_map>

#include "core/errors.hpp"
#include "mesh/surface_crack.hpp"
#include "mesh/topology.hpp"

namespace crackle::mesh {
namespace {

// ---- element types

struct ElementType {
  int nodes;
  const char* name;
};

/// Gmsh element types by number (those a mesh file is likely to hold).
const std::map<int, ElementType>& element_types() {
  static const std::map<int, ElementType> types = {
      {1, {2, "2-node line"}},           {2, {3, "3-node triangle"}},       {3, {4, "4-node quadrangle"}},
      {4, {4, "4-node tetrahedron"}},    {5, {8, "8-node hexahedron"}},     {6, {6, "6-node prism"}},
      {7, {5, "5-node pyramid"}},        {8, {3, "3-node line"}},           {9, {6, "6-node triangle"}},
      {10, {9, "9-node quadrangle"}},    {11, {10, "10-node tetrahedron"}}, {12, {27, "27-node hexahedron"}},
      {13, {18, "18-node prism"}},       {14, {14, "14-node pyramid"}},     {15, {1, "1-node point"}},
      {16, {8, "8-node quadrangle"}},    {17, {20, "20-node hexahedron"}},  {18, {15, "15-node prism"}},
      {19, {13, "13-node pyramid"}},     {20, {9, "9-node triangle"}},      {21, {10, "10-node triangle"}},
      {22, {12, "12-node triangle"}},    {23, {15, "15-node triangle"}},    {24, {15, "15-node triangle"}},
      {25, {21, "21-node triangle"}},    {26, {4, "4-node line"}},          {27, {5, "5-node line"}},
      {28, {6, "6-node line"}},          {29, {20, "20-node tetrahedron"}}, {30, {35, "35-node tetrahedron"}},
      {31, {56, "56-node tetrahedron"}}, {36, {16, "16-node quadrangle"}},  {37, {25, "25-node quadrangle"}},
      {92, {64, "64-node hexahedron"}},  {93, {125, "125-node hexahedron"}},
  };
  return types;
}

bool supported_volume(int type) { return type == 4 || type == 11 || type == 5 || type == 12; }

const char* kSupported = "crackle reads 4- and 10-node tetrahedra and 8- and 27-node hexahedra";

/// Lexicographic GLL node a of crackle's hexahedron -> node of Gmsh's hexahedron.
const std::vector<int>& hexahedron_order(int order) {
  static const std::vector<int> linear = {0, 1, 3, 2, 4, 5, 7, 6};
  static const std::vector<int> quadratic = [] {
    // Reference coordinates (-1, 0, 1) of Gmsh's 27 nodes: vertices, edge midpoints (edges 01, 03,
    // 04, 12, 15, 23, 26, 37, 45, 47, 56, 67), face centres (z-, y-, x-, x+, y+, z+), centre.
    static const int reference[27][3] = {
        {-1, -1, -1}, {1, -1, -1}, {1, 1, -1}, {-1, 1, -1}, {-1, -1, 1}, {1, -1, 1}, {1, 1, 1},
        {-1, 1, 1},   {0, -1, -1}, {-1, 0, -1}, {-1, -1, 0}, {1, 0, -1},  {1, -1, 0}, {0, 1, -1},
        {1, 1, 0},    {-1, 1, 0},  {0, -1, 1},  {-1, 0, 1},  {1, 0, 1},   {0, 1, 1},  {0, 0, -1},
        {0, -1, 0},   {-1, 0, 0},  {1, 0, 0},   {0, 1, 0},   {0, 0, 1},   {0, 0, 0}};
    std::vector<int> order(27);
    for (int g = 0; g < 27; ++g) {
      const int* r = reference[g];
      order[(r[0] + 1) + 3 * ((r[1] + 1) + 3 * (r[2] + 1))] = g;
    }
    return order;
  }();
  return order == 1 ? linear : quadratic;
}

// ---- reading

/// Cursor over the file contents: ASCII tokens or binary values, with the section for messages.
class Reader {
 public:
  Reader(const std::string& data, std::string name) : data_(data), name_(std::move(name)) {}

  [[noreturn]] void fail(const std::string& message) const { throw InputError(name_ + ": " + message); }
  [[noreturn]] void truncated(const std::string& expected) const {
    fail("truncated file: " + section_ + " ends before " + expected);
  }

  /// The section being read, for messages ("$Nodes", or "the file" between sections).
  void set_section(const std::string& section) { section_ = section; }
  void set_binary(bool binary) { binary_ = binary; }
  bool binary() const { return binary_; }

  void skip_space() {
    while (pos_ < data_.size() && std::isspace(static_cast<unsigned char>(data_[pos_]))) ++pos_;
  }
  bool at_end() {
    skip_space();
    return pos_ >= data_.size();
  }
  /// The rest of the current line (without '\r').
  std::string line() {
    const std::size_t end = data_.find('\n', pos_);
    std::string text = data_.substr(pos_, end == std::string::npos ? std::string::npos : end - pos_);
    pos_ = end == std::string::npos ? data_.size() : end + 1;
    if (!text.empty() && text.back() == '\r') text.pop_back();
    return text;
  }
  std::string token(const std::string& expected) {
    skip_space();
    if (pos_ >= data_.size()) truncated(expected);
    const std::size_t start = pos_;
    while (pos_ < data_.size() && !std::isspace(static_cast<unsigned char>(data_[pos_]))) ++pos_;
    return data_.substr(start, pos_ - start);
  }
  /// An `int` (4 bytes in binary files).
  long long integer(const std::string& expected) {
    if (binary_) {
      std::int32_t value;
      raw(&value, sizeof value, expected);
      return value;
    }
    return parse_integer(token(expected), expected);
  }
  /// A `size_t` (8 bytes in binary files).
  long long size(const std::string& expected) {
    if (binary_) {
      std::uint64_t value;
      raw(&value, sizeof value, expected);
      if (value > static_cast<std::uint64_t>(1) << 40) fail(section_ + ": expected " + expected + ", got " + std::to_string(value));
      return static_cast<long long>(value);
    }
    const long long value = parse_integer(token(expected), expected);
    if (value < 0) fail(section_ + ": expected " + expected + ", got " + std::to_string(value));
    return value;
  }
  double real(const std::string& expected) {
    if (binary_) {
      double value;
      raw(&value, sizeof value, expected);
      return value;
    }
    const std::string text = token(expected);
    char* end = nullptr;
    errno = 0;
    const double value = std::strtod(text.c_str(), &end);
    if (end != text.c_str() + text.size() || errno != 0) fail(section_ + ": expected " + expected + ", got '" + text + "'");
    return value;
  }
  /// Reads `$End<section>` after the section's data.
  void end_section(const std::string& section) {
    skip_space();
    const std::string marker = "$End" + section;
    if (data_.compare(pos_, marker.size(), marker) != 0) {
      if (pos_ >= data_.size()) truncated(marker);
      fail(section_ + ": expected " + marker + ", got '" + data_.substr(pos_, std::min<std::size_t>(20, line_length())) + "'");
    }
    pos_ += marker.size();
  }
  /// Skips an unknown section up to its end marker.
  void skip_section(const std::string& section) {
    const std::string marker = "\n$End" + section;
    const std::size_t found = data_.find(marker, pos_ > 0 ? pos_ - 1 : 0);
    if (found == std::string::npos) truncated("$End" + section);
    pos_ = found + marker.size();
  }
  /// A count of items that take at least `bytes_each` bytes each in the file: a count the rest
  /// of the file cannot hold means a truncated (or corrupt) file, not a huge allocation.
  long long count(const std::string& expected, const std::string& items, std::size_t bytes_each) {
    const long long value = size(expected);
    if (static_cast<unsigned long long>(value) > (data_.size() - std::min(pos_, data_.size())) / bytes_each) {
      truncated("its " + std::to_string(value) + " " + items);
    }
    return value;
  }

 private:
  std::size_t line_length() const {
    const std::size_t end = data_.find('\n', pos_);
    return (end == std::string::npos ? data_.size() : end) - pos_;
  }
  long long parse_integer(const std::string& text, const std::string& expected) const {
    char* end = nullptr;
    errno = 0;
    const long long value = std::strtoll(text.c_str(), &end, 10);
    if (end != text.c_str() + text.size() || errno != 0) fail(section_ + ": expected " + expected + ", got '" + text + "'");
    return value;
  }
  void raw(void* target, std::size_t bytes, const std::string& expected) {
    if (pos_ + bytes > data_.size()) truncated(expected);
    std::memcpy(target, data_.data() + pos_, bytes);
    pos_ += bytes;
  }

  const std::string& data_;
  std::string name_;
  std::string section_ = "the file";
  std::size_t pos_ = 0;
  bool binary_ = false;
};

struct ElementBlock {
  int dimension = 0;
  int entity = 0;
  int type = 0;
  std::vector<long long> tags;   ///< element tags
  std::vector<long long> nodes;  ///< node tags, nodes-per-type per element
};

/// Everything the reader keeps from a file.
struct GmshFile {
  std::map<std::pair<int, int>, std::string> physical_names;  ///< (dimension, tag) -> name
  std::map<std::pair<int, int>, std::vector<int>> physicals;  ///< (dimension, entity) -> physical tags
  std::unordered_map<long long, Vec3> nodes;                  ///< node tag -> coordinates
  std::vector<ElementBlock> blocks;
  bool has_nodes = false, has_elements = false;
};

void read_format(Reader& reader) {
  const std::string version = reader.token("the version");
  const long long file_type = reader.integer("the file type (0 ASCII, 1 binary)");
  const long long data_size = reader.integer("the data size");
  if (version != "4.1") {
    reader.fail("expected a Gmsh MSH 4.1 file, got version " + version +
                " (save it with gmsh -format msh41, or Mesh.MshFileVersion = 4.1)");
  }
  if (file_type != 0 && file_type != 1) reader.fail("$MeshFormat: expected file type 0 or 1, got " + std::to_string(file_type));
  if (data_size != 8) reader.fail("$MeshFormat: expected a data size of 8 (64-bit size_t), got " + std::to_string(data_size));
  if (file_type == 1) {
    reader.line();  // the end of the format line
    reader.set_binary(true);
    const long long one = reader.integer("the byte-order mark");
    if (one != 1) reader.fail("$MeshFormat: the binary file has the other byte order (big-endian); write it on this machine");
  }
}

void read_physical_names(Reader& reader, GmshFile& file) {
  // Always ASCII: count, then lines `dimension tag "name"`.
  const bool binary = reader.binary();
  reader.set_binary(false);
  const long long count = reader.count("the number of physical names", "physical names", 6);
  for (long long i = 0; i < count; ++i) {
    const int dimension = static_cast<int>(reader.integer("a physical dimension"));
    const int tag = static_cast<int>(reader.integer("a physical tag"));
    reader.skip_space();
    std::string name = reader.line();
    if (name.size() >= 2 && name.front() == '"' && name.back() == '"') name = name.substr(1, name.size() - 2);
    file.physical_names[{dimension, tag}] = name;
  }
  reader.set_binary(binary);
}

void read_entities(Reader& reader, GmshFile& file) {
  long long counts[4];
  for (int d = 0; d < 4; ++d) counts[d] = reader.count("the number of entities", "entities", 8);
  for (int dimension = 0; dimension < 4; ++dimension) {
    for (long long i = 0; i < counts[dimension]; ++i) {
      const int tag = static_cast<int>(reader.integer("an entity tag"));
      for (int c = 0; c < (dimension == 0 ? 3 : 6); ++c) reader.real("an entity coordinate");
      const long long n_physicals = reader.count("the number of physical tags", "physical tags", 2);
      std::vector<int>& physicals = file.physicals[{dimension, tag}];
      for (long long k = 0; k < n_physicals; ++k) physicals.push_back(static_cast<int>(reader.integer("a physical tag")));
      if (dimension > 0) {
        const long long n_bounding = reader.count("the number of bounding entities", "bounding entities", 2);
        for (long long k = 0; k < n_bounding; ++k) reader.integer("a bounding entity tag");
      }
    }
  }
}

void read_nodes(Reader& reader, GmshFile& file) {
  const long long n_blocks = reader.count("the number of node blocks", "node blocks", 8);
  const long long n_nodes = reader.count("the number of nodes", "nodes", 8);
  reader.size("the smallest node tag");
  reader.size("the largest node tag");
  file.nodes.reserve(static_cast<std::size_t>(n_nodes));
  std::vector<long long> tags;
  for (long long b = 0; b < n_blocks; ++b) {
    const int dimension = static_cast<int>(reader.integer("an entity dimension"));
    reader.integer("an entity tag");
    const long long parametric = reader.integer("the parametric flag");
    const long long count = reader.count("the number of nodes in a block", "nodes", 8);
    tags.resize(static_cast<std::size_t>(count));
    for (long long& tag : tags) tag = reader.size("a node tag");
    for (long long tag : tags) {
      Vec3 x;
      for (int c = 0; c < 3; ++c) x[c] = reader.real("a node coordinate");
      if (parametric) {
        for (int c = 0; c < dimension; ++c) reader.real("a parametric coordinate");
      }
      file.nodes[tag] = x;
    }
  }
  file.has_nodes = true;
}

void read_elements(Reader& reader, GmshFile& file) {
  const long long n_blocks = reader.count("the number of element blocks", "element blocks", 8);
  reader.size("the number of elements");
  reader.size("the smallest element tag");
  reader.size("the largest element tag");
  for (long long b = 0; b < n_blocks; ++b) {
    ElementBlock block;
    block.dimension = static_cast<int>(reader.integer("an entity dimension"));
    block.entity = static_cast<int>(reader.integer("an entity tag"));
    block.type = static_cast<int>(reader.integer("an element type"));
    const long long count = reader.count("the number of elements in a block", "elements", 4);
    const auto type = element_types().find(block.type);
    if (type == element_types().end()) {
      reader.fail("unsupported element type " + std::to_string(block.type) + " (unknown to crackle) in entity " +
                  std::to_string(block.entity) + " of dimension " + std::to_string(block.dimension) + "; " + kSupported);
    }
    if (block.dimension == 3 && !supported_volume(block.type)) {
      reader.fail("unsupported element type " + std::to_string(block.type) + " (" + type->second.name + ") in volume " +
                  std::to_string(block.entity) + "; " + kSupported);
    }
    const int per_element = type->second.nodes;
    block.tags.resize(static_cast<std::size_t>(count));
    block.nodes.resize(static_cast<std::size_t>(count) * per_element);
    for (long long e = 0; e < count; ++e) {
      block.tags[e] = reader.size("an element tag");
      for (int a = 0; a < per_element; ++a) block.nodes[e * per_element + a] = reader.size("a node tag of an element");
    }
    file.blocks.push_back(std::move(block));
  }
  file.has_elements = true;
}

GmshFile read_file(const std::string& contents, const std::string& name) {
  Reader reader(contents, name);
  GmshFile file;
  bool first = true;
  while (!reader.at_end()) {
    const std::string header = reader.line();
    if (header.empty() || header[0] != '$') {
      reader.fail(first ? "expected a Gmsh MSH 4.1 file (starting with $MeshFormat), got '" + header.substr(0, 40) + "'"
                        : "expected a section such as $Nodes, got '" + header.substr(0, 40) + "'");
    }
    const std::string section = header.substr(1);
    if (first && section != "MeshFormat") {
      reader.fail("expected a Gmsh MSH 4.1 file (starting with $MeshFormat), got '" + header.substr(0, 40) + "'");
    }
    first = false;
    reader.set_section("$" + section);
    if (section == "MeshFormat") {
      read_format(reader);  // switches the reader to binary for a binary file
    } else if (section == "PhysicalNames") {
      read_physical_names(reader, file);
    } else if (section == "Entities") {
      read_entities(reader, file);
    } else if (section == "PartitionedEntities") {
      reader.fail("partitioned meshes are not supported (save the mesh without partitions)");
    } else if (section == "Nodes") {
      read_nodes(reader, file);
    } else if (section == "Elements") {
      read_elements(reader, file);
    } else {
      reader.skip_section(section);
      continue;
    }
    reader.end_section(section);
  }
  if (first) reader.fail("expected a Gmsh MSH 4.1 file, got an empty file");
  reader.set_section("the file");
  if (!file.has_nodes) reader.truncated("a $Nodes section");
  if (!file.has_elements) reader.truncated("an $Elements section");
  return file;
}

// ---- building the mesh

/// The name of a physical group: its name, or its number when it has none.
std::string group_name(const GmshFile& file, int dimension, int tag) {
  const auto found = file.physical_names.find({dimension, tag});
  return found == file.physical_names.end() ? std::to_string(tag) : found->second;
}

const char* dimension_noun(int dimension) {
  static const char* nouns[4] = {"point", "curve", "surface", "volume"};
  return nouns[dimension];
}

/// Determinant of the element map at the element's corners (hexahedra: trilinear map of the 8
/// corners; tetrahedra: the affine map of the vertices), the smallest one relative to h^3.
double smallest_corner_jacobian(const Mesh& mesh, Index e) {
  const Index* nodes = mesh.element_nodes(e);
  if (mesh.shape == ElementShape::tetrahedron) {
    Eigen::Matrix3d edges;
    for (int c = 0; c < 3; ++c) edges.col(c) = mesh.nodes[nodes[c + 1]] - mesh.nodes[nodes[0]];
    const double h = std::max({edges.col(0).norm(), edges.col(1).norm(), edges.col(2).norm()});
    return edges.determinant() / (h * h * h);
  }
  const int n = mesh.order + 1;
  Vec3 x[2][2][2];
  for (int k = 0; k < 2; ++k)
    for (int j = 0; j < 2; ++j)
      for (int i = 0; i < 2; ++i) x[k][j][i] = mesh.nodes[nodes[i * mesh.order + n * (j * mesh.order + n * k * mesh.order)]];
  double smallest = std::numeric_limits<double>::infinity();
  for (int k = 0; k < 2; ++k)
    for (int j = 0; j < 2; ++j)
      for (int i = 0; i < 2; ++i) {
        Eigen::Matrix3d jacobian;
        jacobian.col(0) = (x[k][j][1] - x[k][j][0]);
        jacobian.col(1) = (x[k][1][i] - x[k][0][i]);
        jacobian.col(2) = (x[1][j][i] - x[0][j][i]);
        const double h = std::max({jacobian.col(0).norm(), jacobian.col(1).norm(), jacobian.col(2).norm()});
        smallest = std::min(smallest, jacobian.determinant() / (h * h * h));
      }
  return smallest;
}

/// The mesh of the volume elements; `index_of` maps node tags to mesh nodes.
Mesh build_mesh(const GmshFile& file, const std::string& name, std::unordered_map<long long, Index>& index_of) {
  auto fail = [&](const std::string& message) -> void { throw InputError(name + ": " + message); };
  // The volume elements: one supported type.
  int volume_type = 0;
  for (const ElementBlock& block : file.blocks) {
    if (block.dimension != 3 || block.tags.empty()) continue;
    if (volume_type != 0 && block.type != volume_type) {
      fail(std::string("the mesh mixes ") + element_types().at(volume_type).name + "s and " +
           element_types().at(block.type).name + "s; crackle needs one element type per mesh");
    }
    volume_type = block.type;
  }
  if (volume_type == 0) {
    fail("no volume elements (a 2D mesh? with physical groups Gmsh saves only their elements: give the volume "
         "a physical group or save with -save_all)");
  }
  Mesh mesh;
  mesh.shape = volume_type == 4 || volume_type == 11 ? ElementShape::tetrahedron : ElementShape::hexahedron;
  mesh.order = volume_type == 11 || volume_type == 12 ? 2 : 1;
  const int per_element = element_types().at(volume_type).nodes;

  // Nodes used by the volume elements, numbered by increasing tag.
  std::vector<long long> used;
  for (const ElementBlock& block : file.blocks) {
    if (block.dimension == 3) used.insert(used.end(), block.nodes.begin(), block.nodes.end());
  }
  std::sort(used.begin(), used.end());
  used.erase(std::unique(used.begin(), used.end()), used.end());
  index_of.reserve(used.size());
  for (long long tag : used) {
    const auto found = file.nodes.find(tag);
    if (found == file.nodes.end()) fail("an element refers to node " + std::to_string(tag) + ", which $Nodes does not define");
    index_of[tag] = static_cast<Index>(mesh.nodes.size());
    mesh.nodes.push_back(found->second);
  }
  mesh.n_original_nodes = mesh.n_nodes();

  // Connectivity in crackle's local order; element sets of the physical volumes.
  const std::vector<int>* order = mesh.shape == ElementShape::hexahedron ? &hexahedron_order(mesh.order) : nullptr;
  std::vector<long long> element_tags;
  for (const ElementBlock& block : file.blocks) {
    if (block.dimension != 3) continue;
    std::vector<std::string> groups;
    const auto physicals = file.physicals.find({3, block.entity});
    if (physicals != file.physicals.end()) {
      for (int tag : physicals->second) groups.push_back(group_name(file, 3, tag));
    }
    for (std::size_t e = 0; e < block.tags.size(); ++e) {
      const long long* nodes = &block.nodes[e * per_element];
      const Index element = static_cast<Index>(element_tags.size());
      for (int a = 0; a < per_element; ++a) mesh.connectivity.push_back(index_of.at(nodes[order ? (*order)[a] : a]));
      element_tags.push_back(block.tags[e]);
      for (const std::string& group : groups) mesh.element_sets[group].push_back(element);
    }
  }
  mesh.element_region.assign(mesh.n_elements(), 0);
  for (Index e = 0; e < mesh.n_elements(); ++e) {
    const double jacobian = smallest_corner_jacobian(mesh, e);
    if (!(jacobian > 1e-12)) {
      fail("element " + std::to_string(element_tags[e]) + " (" + element_types().at(volume_type).name +
           ") is inverted or degenerate: scaled Jacobian " + format_number(jacobian) +
           " at a corner (its nodes must follow Gmsh's order with a positive volume)");
    }
  }

  // Node sets of every group, face sets of the surface groups.
  const FaceTable table = face_table(mesh);
  for (const ElementBlock& block : file.blocks) {
    const auto physicals = file.physicals.find({block.dimension, block.entity});
    if (physicals == file.physicals.end() || physicals->second.empty()) continue;
    const int per = element_types().at(block.type).nodes;
    std::vector<Index> nodes;
    for (long long tag : block.nodes) {
      const auto found = index_of.find(tag);
      if (found != index_of.end()) nodes.push_back(found->second);
    }
    std::vector<FaceRef> faces;
    if (block.dimension == 2) {
      const int corners = block.type == 2 || block.type == 9 ? 3 : 4;
      for (std::size_t e = 0; e < block.tags.size(); ++e) {
        Index ids[4];
        bool inside = true;
        for (int c = 0; c < corners; ++c) {
          const auto found = index_of.find(block.nodes[e * per + c]);
          inside = inside && found != index_of.end();
          if (inside) ids[c] = found->second;
        }
        if (!inside) continue;
        const auto face = table.find(face_key(ids, corners));
        if (face != table.end()) faces.push_back(face->second[0]);
      }
    }
    for (int tag : physicals->second) {
      const std::string group = group_name(file, block.dimension, tag);
      std::vector<Index>& set = mesh.node_sets[group];
      set.insert(set.end(), nodes.begin(), nodes.end());
      if (block.dimension == 2) {
        std::vector<FaceRef>& face_set = mesh.face_sets[group];
        face_set.insert(face_set.end(), faces.begin(), faces.end());
      }
    }
  }
  for (auto& [group, set] : mesh.node_sets) {
    std::sort(set.begin(), set.end());
    set.erase(std::unique(set.begin(), set.end()), set.end());
  }
  return mesh;
}

void make_crack(const GmshFile& file, const std::string& name, const std::string& group,
                const std::unordered_map<long long, Index>& index_of, Mesh& mesh) {
  // The group's dimensions, and the faces of its surface elements (corners in mesh numbering).
  std::set<int> dimensions;
  for (const auto& [key, physical_name] : file.physical_names) {
    if (physical_name == group) dimensions.insert(key.first);
  }
  std::vector<std::vector<Index>> faces;
  for (const ElementBlock& block : file.blocks) {
    if (block.dimension != 2) continue;
    const auto physicals = file.physicals.find({2, block.entity});
    if (physicals == file.physicals.end()) continue;
    bool in_group = false;
    for (int tag : physicals->second) in_group = in_group || group_name(file, 2, tag) == group;
    if (!in_group) continue;
    dimensions.insert(2);
    const int per = element_types().at(block.type).nodes;
    const int corners = block.type == 2 || block.type == 9 ? 3 : block.type == 3 || block.type == 10 ? 4 : 0;
    if (corners == 0) {
      throw InputError(name + ": crack group '" + group + "' has " + element_types().at(block.type).name +
                       "s; a crack surface needs triangles or quadrangles of the volume elements' faces");
    }
    for (std::size_t e = 0; e < block.tags.size(); ++e) {
      std::vector<Index> ids;
      for (int c = 0; c < corners; ++c) {
        const auto found = index_of.find(block.nodes[e * per + c]);
        if (found == index_of.end()) {
          throw InputError(name + ": crack group '" + group + "' is not a surface of the mesh: its element " +
                           std::to_string(block.tags[e]) + " has a node outside the volume elements");
        }
        ids.push_back(found->second);
      }
      faces.push_back(ids);
    }
  }
  if (dimensions.empty()) {
    throw InputError(name + ": crack: no physical group '" + group + "' (the file has: " + group_names(mesh) + ")");
  }
  if (!dimensions.count(2)) {
    throw InputError(name + ": crack group '" + group + "' is a physical " + dimension_noun(*dimensions.begin()) +
                     ", not a surface of the mesh");
  }
  split_surface_crack(mesh, faces, name + ": crack group '" + group + "'");
}

}  // namespace

std::string group_names(const Mesh& mesh) {
  std::string text;
  for (const auto& [group, nodes] : mesh.node_sets) text += (text.empty() ? "" : ", ") + group;
  return text.empty() ? "no groups" : text;
}

Mesh parse_gmsh(const std::string& contents, const std::string& name, const GmshOptions& options) {
  const GmshFile file = read_file(contents, name);
  std::unordered_map<long long, Index> index_of;
  Mesh mesh = build_mesh(file, name, index_of);
  if (!options.crack_group.empty()) make_crack(file, name, options.crack_group, index_of, mesh);
  return mesh;
}

Mesh read_gmsh(const std::string& path, const GmshOptions& options) {
  std::ifstream stream(path, std::ios::binary);
  if (!stream) throw InputError(path + ": expected a readable Gmsh mesh file, got " + std::strerror(errno));
  std::ostringstream contents;
  contents << stream.rdbuf();
  return parse_gmsh(contents.str(), path, options);
}

}  // namespace crackle::mesh
