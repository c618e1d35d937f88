#include "mesh/surface_crack.hpp"

#include <Eigen/Geometry>
#include <algorithm>
#include <map>
#include <numeric>
#include <set>
#include <unordered_set>

#include "core/errors.hpp"
#include "mesh/topology.hpp"

namespace crackle::mesh {
namespace {

/// One geometric face of the crack surface with the element faces on its two sides.
struct CrackFace {
  FaceRef first, second;            ///< element faces on the two sides
  std::vector<Index> first_nodes;   ///< nodes of `first`, face_local_nodes() order
  std::vector<Index> second_nodes;  ///< coincident nodes of `second` at the same positions (split meshes)
  std::vector<Index> corners;       ///< canonical corner ids in `first`'s cycle
  int orientation = 0;              ///< +1: n+ = x_s x x_t of `first`'s cycle; -1: opposite
  Vec3 normal = Vec3::Zero();       ///< n+ (unit), once oriented
  bool first_is_plus = true;
};

std::string point_text(const Vec3& x) {
  return "(" + format_number(x[0]) + ", " + format_number(x[1]) + ", " + format_number(x[2]) + ")";
}

Vec3 centroid(const Mesh& mesh, Index element) {
  Vec3 sum = Vec3::Zero();
  const Index* nodes = mesh.element_nodes(element);
  for (int a = 0; a < mesh.nodes_per_element(); ++a) sum += mesh.nodes[nodes[a]];
  return sum / mesh.nodes_per_element();
}

/// Newell normal (twice the vector area) of a polygon.
Vec3 polygon_normal(const std::vector<Vec3>& corners) {
  Vec3 normal = Vec3::Zero();
  for (std::size_t k = 0; k < corners.size(); ++k) normal += corners[k].cross(corners[(k + 1) % corners.size()]);
  return normal;
}

using EdgeKey = std::pair<Index, Index>;
EdgeKey edge_key(Index a, Index b) { return a < b ? EdgeKey{a, b} : EdgeKey{b, a}; }

/// Orients the faces consistently over each connected piece (edge-adjacent in canonical corner
/// ids) and decides the plus side of each face.
void orient(const Mesh& mesh, std::vector<CrackFace>& faces, const std::string& what) {
  std::map<EdgeKey, std::vector<std::pair<int, int>>> edges;  // edge -> (face, +1 if traversed low -> high)
  for (int f = 0; f < static_cast<int>(faces.size()); ++f) {
    const std::vector<Index>& c = faces[f].corners;
    for (std::size_t k = 0; k < c.size(); ++k) {
      const Index a = c[k], b = c[(k + 1) % c.size()];
      edges[edge_key(a, b)].push_back({f, a < b ? 1 : -1});
    }
  }
  std::vector<std::vector<std::pair<int, int>>> neighbours(faces.size());  // (face, relative sign)
  for (const auto& [edge, users] : edges) {
    if (users.size() > 2) {
      throw InputError(what + " branches: the edge between " + point_text(mesh.nodes[edge.first]) + " and " +
                       point_text(mesh.nodes[edge.second]) + " belongs to " + std::to_string(users.size()) +
                       " of its faces; crackle splits surfaces that do not branch");
    }
    if (users.size() == 2) {
      // Consistent orientations traverse a shared edge in opposite directions.
      const int relative = -users[0].second * users[1].second;
      neighbours[users[0].first].push_back({users[1].first, relative});
      neighbours[users[1].first].push_back({users[0].first, relative});
    }
  }
  for (int seed = 0; seed < static_cast<int>(faces.size()); ++seed) {
    if (faces[seed].orientation != 0) continue;
    std::vector<Vec3> x;
    for (Index c : faces[seed].corners) x.push_back(mesh.nodes[c]);
    const Vec3 normal = polygon_normal(x);
    int axis = 0;
    normal.cwiseAbs().maxCoeff(&axis);
    faces[seed].orientation = normal[axis] >= 0.0 ? 1 : -1;
    std::vector<int> stack{seed};
    while (!stack.empty()) {
      const int f = stack.back();
      stack.pop_back();
      for (const auto& [g, relative] : neighbours[f]) {
        const int wanted = relative * faces[f].orientation;
        if (faces[g].orientation == 0) {
          faces[g].orientation = wanted;
          stack.push_back(g);
        } else if (faces[g].orientation != wanted) {
          throw InputError(what + " cannot be oriented (a one-sided surface such as a Moebius strip)");
        }
      }
    }
  }
  for (CrackFace& face : faces) {
    std::vector<Vec3> x;
    for (Index c : face.corners) x.push_back(mesh.nodes[c]);
    face.normal = (face.orientation * polygon_normal(x)).normalized();
    Vec3 center = Vec3::Zero();
    for (const Vec3& p : x) center += p;
    center /= static_cast<double>(x.size());
    // n+ points from the plus side into the crack: the plus element lies behind the face.
    face.first_is_plus = (centroid(mesh, face.first.element) - center).dot(face.normal) < 0.0;
  }
}

/// Union-find over a few local indices.
struct Components {
  explicit Components(int n) : parent(n) { std::iota(parent.begin(), parent.end(), 0); }
  int find(int i) { return parent[i] == i ? i : parent[i] = find(parent[i]); }
  void unite(int a, int b) { parent[find(a)] = find(b); }
  std::vector<int> parent;
};

/// Faces inside the body: duplicate the crack nodes off the front. Returns the minus node of each
/// crack node (itself on the front).
std::map<Index, Index> split_interior(Mesh& mesh, const FaceTable& table, std::vector<CrackFace>& faces) {
  const std::vector<std::vector<int>> edge_positions = face_edge_positions(mesh.shape, mesh.order);
  std::unordered_set<FaceKey, FaceKeyHash> crack_keys;
  for (const CrackFace& face : faces) crack_keys.insert(face_key(mesh, face.first));

  // Boundary edges of the crack surface, and the edges of the body's outer surface.
  std::map<EdgeKey, std::vector<std::pair<int, int>>> surface_edges;  // edge -> (face, edge index)
  for (int f = 0; f < static_cast<int>(faces.size()); ++f) {
    const std::vector<Index>& c = faces[f].corners;
    for (int k = 0; k < static_cast<int>(c.size()); ++k) surface_edges[edge_key(c[k], c[(k + 1) % c.size()])].push_back({f, k});
  }
  std::set<EdgeKey> outer_edges;
  const std::vector<int> corner_positions = face_corner_positions(mesh.shape, mesh.order);
  for (const auto& [key, refs] : table) {
    if (refs.size() != 1) continue;
    const std::vector<Index> nodes = face_nodes(mesh, refs[0]);
    for (std::size_t k = 0; k < corner_positions.size(); ++k) {
      outer_edges.insert(edge_key(nodes[corner_positions[k]], nodes[corner_positions[(k + 1) % corner_positions.size()]]));
    }
  }
  std::set<Index> front;
  for (const auto& [edge, users] : surface_edges) {
    if (users.size() != 1 || outer_edges.count(edge)) continue;
    const auto [f, k] = users[0];
    for (int position : edge_positions[k]) front.insert(faces[f].first_nodes[position]);
  }

  // Elements around each node, and the crack faces (with their sides) at each crack node.
  std::vector<std::vector<Index>> node_elements(mesh.n_nodes());
  for (Index e = 0; e < mesh.n_elements(); ++e) {
    const Index* nodes = mesh.element_nodes(e);
    for (int a = 0; a < mesh.nodes_per_element(); ++a) {
      auto& list = node_elements[nodes[a]];
      if (list.empty() || list.back() != e) list.push_back(e);
    }
  }
  std::map<Index, std::vector<int>> node_faces;
  for (int f = 0; f < static_cast<int>(faces.size()); ++f) {
    for (Index n : faces[f].first_nodes) node_faces[n].push_back(f);
  }
  std::vector<std::vector<int>> local_faces(mesh.faces_per_element());
  for (int f = 0; f < mesh.faces_per_element(); ++f) local_faces[f] = face_local_nodes(mesh.shape, mesh.order, f);

  std::map<Index, Index> minus_of;
  std::vector<std::pair<Index, Index>> switches;  // (element, node): the element takes the node's copy
  mesh.n_original_nodes = mesh.n_nodes();  // the copies are appended after every node
  for (const auto& [node, crack_faces] : node_faces) {
    minus_of[node] = node;
    if (front.count(node)) continue;
    // Components of the elements around the node, connected through faces that hold the node and
    // are not crack faces.
    const std::vector<Index>& around = node_elements[node];
    const int count = static_cast<int>(around.size());
    auto local_index = [&](Index e) {
      return static_cast<int>(std::lower_bound(around.begin(), around.end(), e) - around.begin());
    };
    Components components(count);
    for (int i = 0; i < count; ++i) {
      const Index* nodes = mesh.element_nodes(around[i]);
      for (int f = 0; f < mesh.faces_per_element(); ++f) {
        bool holds = false;
        for (int a : local_faces[f]) holds = holds || nodes[a] == node;
        if (!holds) continue;
        const FaceKey key = face_key(mesh, {around[i], f});
        if (crack_keys.count(key)) continue;
        const auto found = table.find(key);
        if (found == table.end() || found->second.size() != 2) continue;
        const FaceRef& other = found->second[0].element == around[i] ? found->second[1] : found->second[0];
        const int j = local_index(other.element);
        if (j < count && around[j] == other.element) components.unite(i, j);
      }
    }
    std::vector<int> side(count, 0);  // per component root: 1 plus, 2 minus, 3 both
    for (int f : crack_faces) {
      const Index plus = faces[f].first_is_plus ? faces[f].first.element : faces[f].second.element;
      const Index minus = faces[f].first_is_plus ? faces[f].second.element : faces[f].first.element;
      side[components.find(local_index(plus))] |= 1;
      side[components.find(local_index(minus))] |= 2;
    }
    bool separated = true;
    for (int i = 0; i < count; ++i) separated = separated && side[components.find(i)] != 3;
    if (!separated) continue;  // the surface does not separate the elements around it: shared
    const Index copy = mesh.n_nodes();
    mesh.nodes.push_back(mesh.nodes[node]);
    minus_of[node] = copy;
    for (int i = 0; i < count; ++i) {
      if (side[components.find(i)] == 2) switches.push_back({around[i], node});
    }
  }
  // Only now renumber the minus side: the components above need the original connectivity.
  for (const auto& [element, node] : switches) {
    Index* nodes = mesh.connectivity.data() + static_cast<std::size_t>(element) * mesh.nodes_per_element();
    for (int a = 0; a < mesh.nodes_per_element(); ++a) {
      if (nodes[a] == node) nodes[a] = minus_of.at(node);
    }
  }
  // Face node sets hold both copies of a split node.
  for (auto& [name, nodes] : mesh.node_sets) {
    const std::size_t size = nodes.size();
    for (std::size_t k = 0; k < size; ++k) {
      const auto found = minus_of.find(nodes[k]);
      if (found != minus_of.end() && found->second != nodes[k]) nodes.push_back(found->second);
    }
  }
  return minus_of;
}

/// Sorted corner coordinates of a face: the key of coincident faces.
std::vector<std::array<double, 3>> coordinate_key(const Mesh& mesh, const FaceKey& key) {
  std::vector<std::array<double, 3>> points;
  for (Index n : key) {
    if (n >= 0) points.push_back({mesh.nodes[n][0], mesh.nodes[n][1], mesh.nodes[n][2]});
  }
  std::sort(points.begin(), points.end());
  return points;
}

}  // namespace

void split_surface_crack(Mesh& mesh, const std::vector<std::vector<Index>>& crack_faces, const std::string& what) {
  if (crack_faces.empty()) throw InputError(what + " has no faces");
  if (mesh.has_crack()) throw InputError(what + ": the mesh already has a crack");
  const FaceTable table = face_table(mesh);
  const std::vector<int> corner_positions = face_corner_positions(mesh.shape, mesh.order);
  const int n_corners = static_cast<int>(corner_positions.size());

  // Classify the faces: inside the body (two elements) or already split (one element each side).
  std::vector<CrackFace> faces;
  std::set<FaceKey> seen;
  int n_interior = 0, n_split = 0;
  std::map<std::vector<std::array<double, 3>>, std::vector<FaceRef>> boundary_by_coordinates;
  for (const std::vector<Index>& corners : crack_faces) {
    const FaceKey key = face_key(corners.data(), static_cast<int>(corners.size()));
    std::vector<Vec3> x;
    for (Index n : corners) x.push_back(mesh.nodes.at(n));
    const auto found = table.find(key);
    if (static_cast<int>(corners.size()) != n_corners || found == table.end()) {
      throw InputError(what + " is not a surface of the mesh: its face with corners " + point_text(x[0]) + ", " +
                       point_text(x[1]) + ", " + point_text(x[2]) + (corners.size() > 3 ? ", ..." : "") +
                       " is not a face of any " + shape_name(mesh.shape));
    }
    if (found->second.size() == 2) {
      ++n_interior;
      if (!seen.insert(key).second) continue;
      CrackFace face;
      face.first = found->second[0];
      face.second = found->second[1];
      face.first_nodes = face_nodes(mesh, face.first);
      for (int position : corner_positions) face.corners.push_back(face.first_nodes[position]);
      faces.push_back(face);
      continue;
    }
    ++n_split;
    if (boundary_by_coordinates.empty()) {
      for (const auto& [boundary_key, refs] : table) {
        if (refs.size() == 1) boundary_by_coordinates[coordinate_key(mesh, boundary_key)].push_back(refs[0]);
      }
    }
    const std::vector<FaceRef>& coincident = boundary_by_coordinates[coordinate_key(mesh, key)];
    std::vector<FaceRef> others;
    for (const FaceRef& ref : coincident) {
      if (face_key(mesh, ref) != key) others.push_back(ref);
    }
    if (others.size() != 1) {
      throw InputError(what + " is not a surface inside the mesh: its face with corners " + point_text(x[0]) + ", " +
                       point_text(x[1]) + ", " + point_text(x[2]) + (corners.size() > 3 ? ", ..." : "") +
                       (others.empty() ? " lies on the outer boundary of the body"
                                       : " coincides with " + std::to_string(others.size()) + " other faces"));
    }
    const FaceKey other_key = face_key(mesh, others[0]);
    if (seen.count(key) || seen.count(other_key)) continue;
    seen.insert(key);
    CrackFace face;
    face.first = found->second[0];
    face.second = others[0];
    face.first_nodes = face_nodes(mesh, face.first);
    const std::vector<Index> second = face_nodes(mesh, face.second);
    for (Index n : face.first_nodes) {
      const auto match = std::find_if(second.begin(), second.end(),
                                      [&](Index m) { return mesh.nodes[m] == mesh.nodes[n]; });
      if (match == second.end()) {
        throw InputError(what + ": the two sides of the split face at " + point_text(mesh.nodes[n]) +
                         " do not have coincident nodes");
      }
      face.second_nodes.push_back(*match);
    }
    for (int position : corner_positions) {
      face.corners.push_back(std::min(face.first_nodes[position], face.second_nodes[position]));
    }
    faces.push_back(face);
  }
  if (n_interior > 0 && n_split > 0) {
    throw InputError(what + " mixes faces inside the body (" + std::to_string(n_interior) + ") with faces already split (" +
                     std::to_string(n_split) + ")");
  }
  orient(mesh, faces, what);

  // Plus and minus node of every crack node.
  std::map<Index, Index> minus_of;  // plus node -> minus node
  if (n_interior > 0) {
    minus_of = split_interior(mesh, table, faces);
  } else {
    std::set<Index> minus_nodes;
    for (CrackFace& face : faces) {
      if (!face.first_is_plus) {
        std::swap(face.first, face.second);
        std::swap(face.first_nodes, face.second_nodes);
        face.first_is_plus = true;
      }
      for (std::size_t a = 0; a < face.first_nodes.size(); ++a) {
        const Index plus = face.first_nodes[a], minus = face.second_nodes[a];
        const auto [entry, inserted] = minus_of.emplace(plus, minus);
        if (!inserted && entry->second != minus) {
          throw InputError(what + ": the node at " + point_text(mesh.nodes[plus]) + " has more than one copy");
        }
        if (minus != plus) minus_nodes.insert(minus);
      }
    }
    for (const auto& [plus, minus] : minus_of) {
      if (minus != plus && minus_nodes.count(plus)) {
        throw InputError(what + ": the sides of the split surface swap at " + point_text(mesh.nodes[plus]) +
                         " (the surface's normal cannot be oriented consistently)");
      }
    }
    // Renumber: the minus copies go after every other node, in the order of their plus nodes.
    std::vector<Index> new_index(mesh.n_nodes(), -1);
    Index next = 0;
    for (Index n = 0; n < mesh.n_nodes(); ++n) {
      if (!minus_nodes.count(n)) new_index[n] = next++;
    }
    mesh.n_original_nodes = next;
    for (const auto& [plus, minus] : minus_of) {
      if (minus != plus) new_index[minus] = next++;
    }
    std::vector<Vec3> nodes(mesh.n_nodes());
    for (Index n = 0; n < mesh.n_nodes(); ++n) nodes[new_index[n]] = mesh.nodes[n];
    mesh.nodes = std::move(nodes);
    for (Index& n : mesh.connectivity) n = new_index[n];
    for (auto& [name, set] : mesh.node_sets) {
      for (Index& n : set) n = new_index[n];
    }
    std::map<Index, Index> renumbered;
    for (const auto& [plus, minus] : minus_of) renumbered[new_index[plus]] = new_index[minus];
    minus_of = std::move(renumbered);
    for (CrackFace& face : faces) {
      for (Index& n : face.first_nodes) n = new_index[n];
    }
  }

  // Tributary areas and normals by nodal quadrature of the faces on the plus side.
  std::map<Index, double> area;
  std::map<Index, Vec3> normal;
  std::vector<double> areas;
  std::vector<Vec3> normals, x;
  double total = 0.0;
  for (const CrackFace& face : faces) {
    x.clear();
    for (Index n : face.first_nodes) x.push_back(mesh.nodes[n]);
    face_nodal_areas(mesh.shape, mesh.order, x, areas, normals);
    for (std::size_t a = 0; a < x.size(); ++a) {
      const Index plus = face.first_nodes[a];
      const Vec3 oriented = normals[a].dot(face.normal) < 0.0 ? Vec3(-normals[a]) : normals[a];
      area[plus] += areas[a];
      if (!normal.count(plus)) normal[plus] = Vec3::Zero();
      normal[plus] += areas[a] * oriented;
      total += areas[a];
    }
  }
  // In a mesh split here the plus nodes are the originals; in a split file the first faces were
  // swapped to the plus side, so both key the maps by plus node.
  mesh.crack_pairs.clear();
  for (const auto& [plus, minus] : minus_of) {
    CrackPair pair;
    pair.plus = plus;
    pair.minus = minus;
    pair.area = area.at(plus);
    pair.normal = normal.at(plus).normalized();
    mesh.crack_pairs.push_back(pair);
  }
  mesh.crack_area = total;
}

}  // namespace crackle::mesh
