#include "mesh/box.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>

#include "core/errors.hpp"
#include "core/quadrature.hpp"

namespace crackle::mesh {
namespace {

/// Positions closer than this fraction of the box size are the same grid line.
constexpr double kRelativeTolerance = 1e-9;

double tolerance(const BoxSpec& box, int axis) { return kRelativeTolerance * box.size[axis]; }

/// The two in-plane axes of a crack with the given normal, in increasing order.
std::array<int, 2> in_plane_axes(int normal) {
  return {normal == kX ? kY : kX, normal == kZ ? kY : kZ};
}

/// Line k of the uniform grid along `axis`.
double uniform_line(const BoxSpec& box, int axis, int k) { return box.origin[axis] + box.size[axis] * k / box.cells[axis]; }

std::vector<double> uniform_lines(const BoxSpec& box, int axis) {
  std::vector<double> lines(box.cells[axis] + 1);
  for (int k = 0; k <= box.cells[axis]; ++k) lines[k] = uniform_line(box, axis, k);
  return lines;
}

/// find_line(uniform_lines(box, axis), position, tol) for a position inside the box, without building
/// the cells + 1 lines: only the few lines within tol of the position are tried, so that checking
/// a crack on a box of 1e9 cells (refused later as too large) takes no memory and no time.
int find_uniform_line(const BoxSpec& box, int axis, double position, double tol) {
  const double cells = box.cells[axis];
  const double first = std::floor((position - tol - box.origin[axis]) / box.size[axis] * cells) - 1.0;
  const double last = std::ceil((position + tol - box.origin[axis]) / box.size[axis] * cells) + 1.0;
  for (int k = static_cast<int>(std::max(0.0, first)); k <= static_cast<int>(std::min(cells, last)); ++k) {
    if (std::abs(uniform_line(box, axis, k) - position) <= tol) return k;
  }
  return -1;
}

/// Index of the line at `position`, or -1.
int find_line(const std::vector<double>& lines, double position, double tol) {
  for (std::size_t k = 0; k < lines.size(); ++k) {
    if (std::abs(lines[k] - position) <= tol) return static_cast<int>(k);
  }
  return -1;
}

std::string range_text(double low, double high) {
  return list_text({low, high});
}

/// Adds the graded lines around `front` along one axis: at front -/+ h_side ratio^k, k = 1..layers,
/// h_side the distance from the front to the next line on that side (before grading).
/// The neighbours are looked up in `base` (the lines before any grading), so that fronts graded
/// one after the other do not depend on the order.
void add_graded_lines(const std::vector<double>& base, std::vector<double>& lines, double front,
                      const Grading& grading, double tol) {
  const auto above = std::upper_bound(base.begin(), base.end(), front + tol);
  if (above == base.begin() || above == base.end()) return;
  const double next = *above;
  auto below = above - 1;
  if (std::abs(*below - front) <= tol) {
    if (below == base.begin()) return;
    --below;
  }
  const double previous = *below;
  std::vector<double> added;
  for (int k = 1; k <= grading.layers; ++k) {
    const double factor = std::pow(grading.ratio, k);
    added.push_back(front - (front - previous) * factor);
    added.push_back(front + (next - front) * factor);
  }
  for (double position : added) {
    if (find_line(lines, position, tol) >= 0) continue;
    lines.insert(std::upper_bound(lines.begin(), lines.end(), position), position);
  }
}

}  // namespace

int auto_layers(int order, double cell_size, double thinnest_side) {
  const int layers = order - 1 + static_cast<int>(std::lround(std::log2(thinnest_side / cell_size)));
  return std::clamp(layers, 1, kMaxAutoLayers);
}

double max_aspect_ratio(const std::array<std::vector<double>, 3>& lines) {
  std::array<double, 3> shortest{}, longest{};
  for (int axis = 0; axis < 3; ++axis) {
    shortest[axis] = std::numeric_limits<double>::infinity();
    longest[axis] = 0.0;
    for (std::size_t k = 0; k + 1 < lines[axis].size(); ++k) {
      const double width = lines[axis][k + 1] - lines[axis][k];
      shortest[axis] = std::min(shortest[axis], width);
      longest[axis] = std::max(longest[axis], width);
    }
  }
  // On a tensor grid every combination of widths is a cell: the worst is a longest width of one
  // axis against a shortest of another.
  double worst = 1.0;
  for (int a = 0; a < 3; ++a)
    for (int b = 0; b < 3; ++b)
      if (a != b && shortest[b] > 0.0) worst = std::max(worst, longest[a] / shortest[b]);
  return worst;
}

double max_aspect_ratio(const Mesh& mesh) {
  double worst = 1.0;
  const Index per_element = mesh.nodes_per_element();
  for (Index e = 0; e < mesh.n_elements(); ++e) {
    Vec3 low = Vec3::Constant(std::numeric_limits<double>::infinity()), high = -low;
    for (Index a = 0; a < per_element; ++a) {
      const Vec3& x = mesh.nodes[mesh.element_nodes(e)[a]];
      low = low.cwiseMin(x);
      high = high.cwiseMax(x);
    }
    const Vec3 extent = high - low;
    if (extent.minCoeff() > 0.0) worst = std::max(worst, extent.maxCoeff() / extent.minCoeff());
  }
  return worst;
}

const std::array<std::string, 6>& box_face_names() {
  static const std::array<std::string, 6> names = {"x-", "x+", "y-", "y+", "z-", "z+"};
  return names;
}

std::string check_crack(const BoxSpec& box, const CrackSpec& crack, bool on_uniform_plane) {
  const int normal = crack.normal;
  const double low = box.origin[normal];
  const double high = low + box.size[normal];
  const std::string axis = axis_name(normal);
  if (!(crack.at > low + tolerance(box, normal) && crack.at < high - tolerance(box, normal))) {
    return "plane.at: expected a position strictly inside the body, " + axis + " in (" +
           format_number(low) + ", " + format_number(high) + "), got " + format_number(crack.at);
  }
  if (on_uniform_plane && find_uniform_line(box, normal, crack.at, tolerance(box, normal)) < 0) {
    const double spacing = box.size[normal] / box.cells[normal];
    const int below = static_cast<int>(std::floor((crack.at - low) / spacing));
    return "plane.at: expected a grid plane of the mesh, " + axis + " = " + format_number(low) +
           " + k*" + format_number(spacing) + " (nearest " + format_number(uniform_line(box, normal, below)) + " or " +
           format_number(uniform_line(box, normal, std::min<int>(below + 1, box.cells[normal]))) + "), got " +
           format_number(crack.at);
  }
  for (int t : in_plane_axes(normal)) {
    const auto& range = crack.region[t];
    const double body_low = box.origin[t], body_high = box.origin[t] + box.size[t];
    const std::string key = std::string("region.") + axis_name(t);
    if (!(range[1] - range[0] > tolerance(box, t))) {
      return key + ": expected [low, high] with low < high (a crack of nonzero area), got " +
             range_text(range[0], range[1]);
    }
    if (range[0] < body_low - tolerance(box, t) || range[1] > body_high + tolerance(box, t)) {
      return key + ": expected a range inside the body, " + axis_name(t) + " in " +
             range_text(body_low, body_high) + ", got " + range_text(range[0], range[1]);
    }
  }
  return "";
}

std::array<std::vector<double>, 3> morph_lines(const BoxSpec& box, const std::array<std::vector<double>, 3>& lines,
                                               const CrackSpec& from, const CrackSpec& to,
                                               const std::array<std::vector<double>, 3>& fixed,
                                               const std::string& key) {
  if (from.normal != to.normal) {
    throw InputError(key + ": expected the crack's own normal " + axis_name(to.normal) + ", got " +
                     axis_name(from.normal));
  }
  std::array<std::vector<double>, 3> moved = lines;
  for (int axis = 0; axis < 3; ++axis) {
    const double low = box.origin[axis], high = low + box.size[axis], tol = tolerance(box, axis);
    // Knots (reference position, moved position): the ends and the fixed lines stay.
    std::vector<std::pair<double, double>> knots = {{low, low}, {high, high}};
    for (double line : fixed[axis])
      if (line > low + tol && line < high - tol) knots.push_back({line, line});
    const std::string name = axis == from.normal ? "at" : std::string("region.") + axis_name(axis);
    std::vector<std::pair<double, double>> moving;
    if (axis == from.normal) {
      moving.push_back({from.at, to.at});
    } else {
      for (int end = 0; end < 2; ++end) {
        const double a = from.region[axis][end], b = to.region[axis][end];
        const bool a_inside = a > low + tol && a < high - tol, b_inside = b > low + tol && b < high - tol;
        if (a_inside != b_inside) {
          throw InputError(key + "." + name + ": expected an edge " +
                           (a_inside ? "inside the body, as the crack's own " : "on the body's surface, as the crack's own ") +
                           format_number(b) + ", got " + format_number(a));
        }
        if (a_inside) moving.push_back({a, b});
      }
    }
    for (const auto& knot : moving) {
      if (!(knot.second > low + tol && knot.second < high - tol)) {
        throw InputError(key + "." + name + ": the crack's position " + format_number(knot.second) +
                         " is not strictly inside the body " + range_text(low, high));
      }
      knots.push_back(knot);
    }
    std::sort(knots.begin(), knots.end());
    for (std::size_t k = 0; k + 1 < knots.size(); ++k) {
      if (!(knots[k + 1].first - knots[k].first > tol) || !(knots[k + 1].second - knots[k].second > tol)) {
        throw InputError(key + "." + name + ": moving the grid from the reference crack to the crack at " +
                         format_number(knots[k + 1].second) + " would pass the grid line at " +
                         format_number(knots[k].second) + " (the body's end, mesh.box.lines, a material region "
                         "or another crack edge); give a reference crack on the same side of it");
      }
    }
    for (double& line : moved[axis]) {
      const auto upper = std::upper_bound(knots.begin(), knots.end(), std::make_pair(line, 0.0),
                                          [](const auto& a, const auto& b) { return a.first < b.first; });
      if (upper == knots.begin()) continue;
      if (upper == knots.end()) { line = high; continue; }
      const auto& a = *(upper - 1);
      const auto& b = *upper;
      if (std::abs(line - a.first) <= tol) { line = a.second; continue; }
      line = a.second + (line - a.first) * (b.second - a.second) / (b.first - a.first);
    }
  }
  return moved;
}

std::array<std::vector<double>, 3> crack_fronts(const BoxSpec& box, const CrackSpec& crack) {
  std::array<std::vector<double>, 3> fronts;
  for (int t : in_plane_axes(crack.normal)) {
    const double low = box.origin[t], high = low + box.size[t];
    for (double edge : crack.region[t]) {
      if (edge > low + tolerance(box, t) && edge < high - tolerance(box, t)) fronts[t].push_back(edge);
    }
    std::sort(fronts[t].begin(), fronts[t].end());
  }
  if (!fronts[0].empty() || !fronts[1].empty() || !fronts[2].empty()) fronts[crack.normal].push_back(crack.at);
  return fronts;
}

Grading resolve_grading(const BoxSpec& box, const CrackSpec& crack) {
  Grading grading = box.grading;
  if (grading.layers != kAutoLayers) return grading;
  double cell = box.size[crack.normal] / box.cells[crack.normal];
  for (int t : in_plane_axes(crack.normal)) {
    for (double edge : crack.region[t])
      if (edge > box.origin[t] + tolerance(box, t) && edge < box.origin[t] + box.size[t] - tolerance(box, t))
        cell = std::max(cell, box.size[t] / box.cells[t]);
  }
  grading.layers = auto_layers(box.order, cell, box.size.minCoeff());
  return grading;
}

std::array<std::vector<double>, 3> grid_lines(const BoxSpec& box, const std::optional<CrackSpec>& crack) {
  std::array<std::vector<double>, 3> lines;
  auto add_line = [&](int axis, double position) {
    if (find_line(lines[axis], position, tolerance(box, axis)) >= 0) return;
    if (position <= box.origin[axis] || position >= box.origin[axis] + box.size[axis]) return;
    lines[axis].insert(std::upper_bound(lines[axis].begin(), lines[axis].end(), position), position);
  };
  for (int axis = 0; axis < 3; ++axis) {
    lines[axis] = uniform_lines(box, axis);
    for (double position : box.extra_lines[axis]) add_line(axis, position);
  }
  if (!crack) return lines;
  for (int t : in_plane_axes(crack->normal)) {
    for (double edge : crack->region[t]) add_line(t, edge);
  }
  if (box.grading.layers == 0) return lines;
  std::array<std::vector<double>, 3> fronts = crack_fronts(box, *crack);
  for (int axis = 0; axis < 3; ++axis) {
    for (double position : box.grading.fronts[axis]) {
      const double low = box.origin[axis], high = low + box.size[axis], tol = tolerance(box, axis);
      if (position > low + tol && position < high - tol) fronts[axis].push_back(position);
    }
  }
  const std::array<std::vector<double>, 3> base = lines;
  const Grading grading = resolve_grading(box, *crack);
  for (int axis = 0; axis < 3; ++axis)
    for (double position : fronts[axis])
      add_graded_lines(base[axis], lines[axis], position, grading, tolerance(box, axis));
  return lines;
}

Mesh build_box_mesh(const BoxSpec& box, const std::optional<CrackSpec>& crack) {
  return build_box_mesh(box, grid_lines(box, crack), crack);
}

Mesh build_box_mesh(const BoxSpec& box, const std::array<std::vector<double>, 3>& lines,
                    const std::optional<CrackSpec>& crack) {
  if (box.order < 1 || box.order > 4) {
    throw InputError("mesh.box.order: expected an integer in 1..4, got " + std::to_string(box.order));
  }
  if (crack) {
    std::string problem = check_crack(box, *crack, false);
    if (!problem.empty()) throw InputError("crack." + problem);
  }
  const int p = box.order;
  const Rule1D gll = gauss_lobatto(p + 1);

  // Node lattice along each axis: the GLL points of every cell, shared at cell boundaries.
  std::array<std::vector<double>, 3> lattice;
  std::array<int, 3> n_cells{};
  for (int axis = 0; axis < 3; ++axis) {
    n_cells[axis] = static_cast<int>(lines[axis].size()) - 1;
    if (n_cells[axis] < 1) throw InputError("mesh: a body left with no elements");
    for (int c = 0; c < n_cells[axis]; ++c) {
      const double a = lines[axis][c], b = lines[axis][c + 1];
      for (int i = 0; i < p; ++i) lattice[axis].push_back(a + 0.5 * (gll.points[i] + 1.0) * (b - a));
    }
    lattice[axis].push_back(lines[axis].back());
  }
  const Index nx = static_cast<Index>(lattice[0].size()), ny = static_cast<Index>(lattice[1].size()),
              nz = static_cast<Index>(lattice[2].size());
  auto lattice_node = [&](Index i, Index j, Index k) { return i + nx * (j + ny * k); };

  Mesh mesh;
  mesh.order = p;
  mesh.axis_aligned_bricks = true;
  mesh.nodes.resize(static_cast<std::size_t>(nx) * ny * nz);
  for (Index k = 0; k < nz; ++k)
    for (Index j = 0; j < ny; ++j)
      for (Index i = 0; i < nx; ++i) mesh.nodes[lattice_node(i, j, k)] = Vec3(lattice[0][i], lattice[1][j], lattice[2][k]);
  mesh.n_original_nodes = mesh.n_nodes();

  const int n = p + 1;
  const Index n_elements = static_cast<Index>(n_cells[0]) * n_cells[1] * n_cells[2];
  mesh.connectivity.resize(static_cast<std::size_t>(n_elements) * n * n * n);
  mesh.element_region.assign(n_elements, 0);
  std::vector<std::array<int, 3>> element_cell(n_elements);
  for (int cz = 0; cz < n_cells[2]; ++cz)
    for (int cy = 0; cy < n_cells[1]; ++cy)
      for (int cx = 0; cx < n_cells[0]; ++cx) {
        const Index e = cx + n_cells[0] * (cy + n_cells[1] * cz);
        element_cell[e] = {cx, cy, cz};
        Index* element = mesh.connectivity.data() + static_cast<std::size_t>(e) * n * n * n;
        for (int c = 0; c < n; ++c)
          for (int b = 0; b < n; ++b)
            for (int a = 0; a < n; ++a) element[a + n * (b + n * c)] = lattice_node(p * cx + a, p * cy + b, p * cz + c);
      }

  // Named sets of the six faces.
  const std::array<Index, 3> extent{nx, ny, nz};
  for (int face = 0; face < 6; ++face) {
    const int axis = face / 2;
    const Index fixed = (face % 2 == 0) ? 0 : extent[axis] - 1;
    std::vector<Index>& nodes = mesh.node_sets[box_face_names()[face]];
    const int u = axis == 0 ? 1 : 0, v = axis == 2 ? 1 : 2;
    for (Index t2 = 0; t2 < extent[v]; ++t2)
      for (Index t1 = 0; t1 < extent[u]; ++t1) {
        Index ijk[3];
        ijk[axis] = fixed;
        ijk[u] = t1;
        ijk[v] = t2;
        nodes.push_back(lattice_node(ijk[0], ijk[1], ijk[2]));
      }
    std::vector<FaceRef>& faces = mesh.face_sets[box_face_names()[face]];
    const int cell = (face % 2 == 0) ? 0 : n_cells[axis] - 1;
    for (Index e = 0; e < n_elements; ++e) {
      if (element_cell[e][axis] == cell) faces.push_back({e, face});
    }
  }

  if (!crack) return mesh;

  // ---- The crack: duplicate the nodes of the crack faces, except on the crack front.
  // Front rule: a node on an edge of the crack rectangle stays shared unless that edge lies on the
  // body's surface (an edge crack opens at the surface; its front is only the edge inside the body).
  const int normal = crack->normal;
  const auto [t1, t2] = in_plane_axes(normal);
  const int plane_cell = find_line(lines[normal], crack->at, tolerance(box, normal));
  if (plane_cell < 0) {
    throw InputError(std::string("crack.plane.at: expected a grid plane of the mesh, got ") + axis_name(normal) +
                     " = " + format_number(crack->at));
  }
  const Index plane_index = static_cast<Index>(p) * plane_cell;
  std::array<std::array<int, 2>, 3> region_cells{};  // first and one-past-last cell of the region
  for (int t : {t1, t2}) {
    const double low = std::max(crack->region[t][0], box.origin[t]);
    const double high = std::min(crack->region[t][1], box.origin[t] + box.size[t]);
    region_cells[t] = {find_line(lines[t], low, tolerance(box, t)), find_line(lines[t], high, tolerance(box, t))};
    if (region_cells[t][0] < 0 || region_cells[t][1] < 0) {
      throw InputError(std::string("crack.region.") + axis_name(t) + ": expected edges on grid lines, got " +
                       range_text(crack->region[t][0], crack->region[t][1]));
    }
  }
  auto on_surface = [&](int t, int line) { return line == 0 || line == n_cells[t]; };

  // Lattice ranges of the crack-face nodes along the in-plane axes.
  const Index i_begin = static_cast<Index>(p) * region_cells[t1][0], i_end = static_cast<Index>(p) * region_cells[t1][1];
  const Index j_begin = static_cast<Index>(p) * region_cells[t2][0], j_end = static_cast<Index>(p) * region_cells[t2][1];
  auto plane_node = [&](Index i1, Index i2) {
    Index ijk[3];
    ijk[normal] = plane_index;
    ijk[t1] = i1;
    ijk[t2] = i2;
    return lattice_node(ijk[0], ijk[1], ijk[2]);
  };
  auto is_front = [&](Index i1, Index i2) {
    return (i1 == i_begin && !on_surface(t1, region_cells[t1][0])) ||
           (i1 == i_end && !on_surface(t1, region_cells[t1][1])) ||
           (i2 == j_begin && !on_surface(t2, region_cells[t2][0])) ||
           (i2 == j_end && !on_surface(t2, region_cells[t2][1]));
  };

  // Tributary areas by GLL nodal quadrature over the crack faces (MODEL.md eq. 25d).
  const Index width = i_end - i_begin + 1;
  std::vector<double> area(static_cast<std::size_t>(width) * (j_end - j_begin + 1), 0.0);
  for (int c2 = region_cells[t2][0]; c2 < region_cells[t2][1]; ++c2)
    for (int c1 = region_cells[t1][0]; c1 < region_cells[t1][1]; ++c1) {
      const double half1 = 0.5 * (lines[t1][c1 + 1] - lines[t1][c1]);
      const double half2 = 0.5 * (lines[t2][c2 + 1] - lines[t2][c2]);
      for (int b = 0; b <= p; ++b)
        for (int a = 0; a <= p; ++a) {
          const Index i1 = static_cast<Index>(p) * c1 + a - i_begin, i2 = static_cast<Index>(p) * c2 + b - j_begin;
          area[i1 + width * i2] += gll.weights[a] * gll.weights[b] * half1 * half2;
        }
    }

  std::vector<Index> duplicate(mesh.nodes.size(), -1);
  Vec3 unit_normal = Vec3::Zero();
  unit_normal[normal] = 1.0;  // n+ points from the plus face (lower side) into the crack
  for (Index i2 = j_begin; i2 <= j_end; ++i2)
    for (Index i1 = i_begin; i1 <= i_end; ++i1) {
      const Index original = plane_node(i1, i2);
      CrackPair pair;
      pair.plus = original;
      pair.minus = original;
      pair.normal = unit_normal;
      pair.area = area[(i1 - i_begin) + width * (i2 - j_begin)];
      if (!is_front(i1, i2)) {
        pair.minus = mesh.n_nodes();
        duplicate[original] = pair.minus;
        mesh.nodes.push_back(mesh.nodes[original]);
      }
      mesh.crack_pairs.push_back(pair);
    }
  // Elements above the plane refer to the duplicates (the minus face).
  for (Index e = 0; e < n_elements; ++e) {
    if (element_cell[e][normal] != plane_cell) continue;
    Index* element = mesh.connectivity.data() + static_cast<std::size_t>(e) * n * n * n;
    for (int a = 0; a < n * n * n; ++a) {
      if (duplicate[element[a]] >= 0) element[a] = duplicate[element[a]];
    }
  }
  // Face node sets hold both copies of a split node.
  for (auto& [name, nodes] : mesh.node_sets) {
    const std::size_t count = nodes.size();
    for (std::size_t k = 0; k < count; ++k) {
      if (duplicate[nodes[k]] >= 0) nodes.push_back(duplicate[nodes[k]]);
    }
  }
  mesh.crack_area = (crack->region[t1][1] - crack->region[t1][0]) * (crack->region[t2][1] - crack->region[t2][0]);
  return mesh;
}

}  // namespace crackle::mesh
