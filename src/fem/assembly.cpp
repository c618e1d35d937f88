#include "fem/assembly.hpp"

#include <omp.h>

#include <algorithm>
#include <array>
#include <atomic>
#include <cstring>
#include <limits>
#include <map>
#include <string>

#include "core/errors.hpp"
#include "core/interrupt.hpp"
#include "fem/colouring.hpp"
#include "fem/element_basis.hpp"

namespace crackle::fem {
namespace {

/// Element matrices kept by the brick cache at most (bytes); beyond it they are computed on the fly.
constexpr double kCacheLimitBytes = 512.0 * 1024 * 1024;

/// The DOF-node graph of a mesh: which DOF nodes each element touches, which elements touch each
/// DOF node, and the sorted DOF-node neighbours of each DOF node (the CSR pattern per node).
struct NodeGraph {
  Index n_dof_nodes = 0;
  Index n_elements = 0;
  int nodes_per_element = 0;
  std::vector<Index> element_dof_nodes;     ///< n_elements x nodes_per_element
  std::vector<std::int64_t> element_start;  ///< per DOF node, into `elements`
  std::vector<Index> elements;
  std::vector<std::int64_t> neighbour_start;  ///< per DOF node, into `neighbours`
  std::vector<Index> neighbours;              ///< sorted per DOF node, itself included

  Index degree(Index node) const {
    return static_cast<Index>(neighbour_start[node + 1] - neighbour_start[node]);
  }
  /// Position of DOF node `column` in the neighbour list of `row`.
  Index position(Index row, Index column) const {
    const Index* begin = neighbours.data() + neighbour_start[row];
    const Index* end = neighbours.data() + neighbour_start[row + 1];
    return static_cast<Index>(std::lower_bound(begin, end, column) - begin);
  }
};

void check_inputs(const mesh::Mesh& mesh, const mesh::DofMap& dofs, const Materials* materials) {
  if (static_cast<Index>(dofs.dof_node.size()) != mesh.n_nodes()) {
    throw InputError("DOF map has " + std::to_string(dofs.dof_node.size()) + " entries for a mesh of " +
                     std::to_string(mesh.n_nodes()) + " nodes");
  }
  if (mesh.connectivity.size() % mesh.nodes_per_element() != 0) {
    throw InputError("mesh connectivity size " + std::to_string(mesh.connectivity.size()) +
                     " is not a multiple of the " + std::to_string(mesh.nodes_per_element()) +
                     " nodes of an element of order " + std::to_string(mesh.order));
  }
  for (std::size_t i = 0; i < mesh.connectivity.size(); ++i) {
    const Index node = mesh.connectivity[i];
    if (node < 0 || node >= mesh.n_nodes()) {
      throw InputError("element " + std::to_string(i / mesh.nodes_per_element()) + " refers to node " +
                       std::to_string(node) + " of a mesh of " + std::to_string(mesh.n_nodes()) + " nodes");
    }
    const Index dof_node = dofs.dof_node[node];
    if (dof_node < 0 || dof_node >= dofs.n_dof_nodes) {
      throw InputError("node " + std::to_string(node) + " maps to DOF node " + std::to_string(dof_node) +
                       " of " + std::to_string(dofs.n_dof_nodes));
    }
  }
  if (!materials) return;
  if (static_cast<Index>(mesh.element_region.size()) != mesh.n_elements()) {
    throw InputError("mesh has " + std::to_string(mesh.element_region.size()) + " element regions for " +
                     std::to_string(mesh.n_elements()) + " elements");
  }
  for (Index e = 0; e < mesh.n_elements(); ++e) {
    const int region = mesh.element_region[e];
    if (region < 0 || region >= static_cast<int>(materials->size())) {
      throw InputError("element " + std::to_string(e) + " has region " + std::to_string(region) + " but " +
                       std::to_string(materials->size()) + " materials are given");
    }
  }
}

NodeGraph build_graph(const mesh::Mesh& mesh, const mesh::DofMap& dofs, bool with_neighbours) {
  NodeGraph graph;
  graph.n_dof_nodes = dofs.n_dof_nodes;
  graph.n_elements = mesh.n_elements();
  graph.nodes_per_element = mesh.nodes_per_element();
  const std::size_t n_entries = mesh.connectivity.size();
  graph.element_dof_nodes.resize(n_entries);
  for (std::size_t i = 0; i < n_entries; ++i)
    graph.element_dof_nodes[i] = dofs.dof_node[mesh.connectivity[i]];

  // DOF node -> elements (CSR by counting).
  const Index n = graph.n_dof_nodes;
  const int npe = graph.nodes_per_element;
  graph.element_start.assign(n + 1, 0);
  for (std::size_t i = 0; i < n_entries; ++i) ++graph.element_start[graph.element_dof_nodes[i] + 1];
  for (Index r = 0; r < n; ++r) graph.element_start[r + 1] += graph.element_start[r];
  graph.elements.resize(n_entries);
  {
    std::vector<std::int64_t> next(graph.element_start.begin(), graph.element_start.end() - 1);
    for (Index e = 0; e < graph.n_elements; ++e) {
      for (int a = 0; a < npe; ++a) {
        const Index r = graph.element_dof_nodes[static_cast<std::size_t>(e) * npe + a];
        // An element touching the same DOF node twice is listed once.
        if (next[r] > graph.element_start[r] && graph.elements[next[r] - 1] == e) continue;
        graph.elements[next[r]++] = e;
      }
    }
    // Close the gaps left by skipped duplicates.
    std::int64_t out = 0;
    for (Index r = 0; r < n; ++r) {
      const std::int64_t begin = graph.element_start[r];
      graph.element_start[r] = out;
      for (std::int64_t i = begin; i < next[r]; ++i) graph.elements[out++] = graph.elements[i];
    }
    graph.element_start[n] = out;
    graph.elements.resize(out);
  }
  if (!with_neighbours) return graph;

  // DOF node -> sorted neighbouring DOF nodes, directly from the graph (no triplet lists):
  // count with a per-thread marker, then fill and sort.
  graph.neighbour_start.assign(n + 1, 0);
#pragma omp parallel
  {
    std::vector<Index> marker(n, -1);
#pragma omp for schedule(dynamic, 256)
    for (Index r = 0; r < n; ++r) {
      std::int64_t count = 0;
      for (std::int64_t i = graph.element_start[r]; i < graph.element_start[r + 1]; ++i) {
        const Index* nodes = &graph.element_dof_nodes[static_cast<std::size_t>(graph.elements[i]) * npe];
        for (int a = 0; a < npe; ++a) {
          if (marker[nodes[a]] != r) {
            marker[nodes[a]] = r;
            ++count;
          }
        }
      }
      graph.neighbour_start[r + 1] = count;
    }
  }
  for (Index r = 0; r < n; ++r) graph.neighbour_start[r + 1] += graph.neighbour_start[r];
  graph.neighbours.resize(graph.neighbour_start[n]);
#pragma omp parallel
  {
    std::vector<Index> marker(n, -1);
#pragma omp for schedule(dynamic, 256)
    for (Index r = 0; r < n; ++r) {
      Index* out = graph.neighbours.data() + graph.neighbour_start[r];
      Index* begin = out;
      for (std::int64_t i = graph.element_start[r]; i < graph.element_start[r + 1]; ++i) {
        const Index* nodes = &graph.element_dof_nodes[static_cast<std::size_t>(graph.elements[i]) * npe];
        for (int a = 0; a < npe; ++a) {
          if (marker[nodes[a]] != r) {
            marker[nodes[a]] = r;
            *out++ = nodes[a];
          }
        }
      }
      std::sort(begin, out);
    }
  }
  return graph;
}

std::vector<std::vector<Index>> colour(const NodeGraph& graph) {
  // Elements sharing a DOF node get different colours.
  const int npe = graph.nodes_per_element;
  return greedy_colouring(
      graph.n_elements, graph.n_dof_nodes,
      [&](Index e, auto&& visit) {
        const Index* nodes = &graph.element_dof_nodes[static_cast<std::size_t>(e) * npe];
        for (int a = 0; a < npe; ++a) visit(nodes[a]);
      },
      [&](Index node, auto&& visit) {
        for (std::int64_t i = graph.element_start[node]; i < graph.element_start[node + 1]; ++i) visit(graph.elements[i]);
      });
}

/// Empty CSR matrix with the pattern of the graph: full 3x3 node blocks (`block`, stiffness) or
/// only the component diagonal of each block (mass). Sorted column indices, compressed.
SparseMatrix make_pattern(const NodeGraph& graph, bool block) {
  const Index n = graph.n_dof_nodes;
  const int per_block = block ? 3 : 1;
  const std::int64_t nnz = 3 * per_block * graph.neighbour_start[n];
  if (nnz > std::numeric_limits<Index>::max() ||
      3 * static_cast<std::int64_t>(n) > std::numeric_limits<Index>::max()) {
    throw InputError("matrix with " + std::to_string(nnz) + " nonzeros exceeds 32-bit indices");
  }
  SparseMatrix matrix(3 * n, 3 * n);
  matrix.resizeNonZeros(static_cast<Index>(nnz));
  Index* row_start = matrix.outerIndexPtr();
  Index* columns = matrix.innerIndexPtr();
  double* values = matrix.valuePtr();
  // In blocks of rows, with a host's stop polled between them: the first touch of a pattern of a
  // gigabyte takes about a second.
  constexpr Index kBlock = 4096;
  std::atomic<bool> stopped{false};
#pragma omp parallel
  for (Index first = 0; first < n; first += kBlock) {
#pragma omp master
    if (interrupt_requested()) stopped = true;
    const Index last = std::min(first + kBlock, n);
#pragma omp for schedule(dynamic, 256)
    for (Index r = first; r < last; ++r) {
      if (stopped) continue;
      const std::int64_t begin = graph.neighbour_start[r];
      const Index degree = graph.degree(r);
      for (int c = 0; c < 3; ++c) {
        const std::int64_t start = 3 * per_block * begin + static_cast<std::int64_t>(c) * per_block * degree;
        row_start[3 * r + c] = static_cast<Index>(start);
        for (Index k = 0; k < degree; ++k) {
          const Index s = graph.neighbours[begin + k];
          for (int d = 0; d < per_block; ++d) {
            columns[start + per_block * k + d] = 3 * s + (block ? d : c);
            values[start + per_block * k + d] = 0.0;
          }
        }
      }
    }
  }
  if (stopped) throw Interrupted("interrupted");
  row_start[3 * n] = static_cast<Index>(nnz);
  return matrix;
}

enum class Kind { stiffness, mass };

/// Corner-based brick size and region of an element, as exact bits (the cache key).
using BrickKey = std::array<std::uint64_t, 4>;

BrickKey brick_key(const mesh::Mesh& mesh, Index e, std::array<double, 3>& size) {
  const int p = mesh.order;
  const int m = p + 1;
  const Index* nodes = mesh.element_nodes(e);
  const Vec3& origin = mesh.nodes[nodes[0]];
  size[0] = mesh.nodes[nodes[p]].x() - origin.x();
  size[1] = mesh.nodes[nodes[p * m]].y() - origin.y();
  size[2] = mesh.nodes[nodes[p * m * m]].z() - origin.z();
  BrickKey key;
  for (int i = 0; i < 3; ++i) std::memcpy(&key[i], &size[i], sizeof(double));
  key[3] = static_cast<std::uint64_t>(mesh.element_region[e]);
  return key;
}

/// Element matrix of `kind` (stiffness 3n x 3n, or rho times the scalar n x n mass).
void element_matrix(Kind kind, const ElementBasis& basis, const double* coords, const Material& material,
                    MatrixX& matrix) {
  if (kind == Kind::stiffness) {
    basis.stiffness(coords, material, matrix);
  } else {
    basis.mass_scalar(coords, matrix);
    matrix *= material.density;
  }
}

SparseMatrix assemble(Kind kind, const mesh::Mesh& mesh, const mesh::DofMap& dofs, const Materials& materials,
                      const AssemblyOptions& options, AssemblyReport* report) {
  const double t0 = omp_get_wtime();
  check_inputs(mesh, dofs, &materials);
  const ElementBasis basis(mesh);
  const int npe = basis.n_nodes();
  const NodeGraph graph = build_graph(mesh, dofs, true);
  const std::vector<std::vector<Index>> classes = colour(graph);
  SparseMatrix matrix = make_pattern(graph, kind == Kind::stiffness);
  const double t1 = omp_get_wtime();
  poll_interrupt();  // between the phases, outside the parallel regions (a host may stop a run)

  // Brick cache: one element matrix per distinct (hx, hy, hz, region), on a canonical brick.
  std::vector<int> matrix_id;
  std::vector<MatrixX> cached;
  if (options.brick_cache && mesh.axis_aligned_bricks && mesh.shape == mesh::ElementShape::hexahedron &&
      graph.n_elements > 0) {
    std::map<BrickKey, int> ids;
    std::vector<std::array<double, 4>> shapes;  // hx, hy, hz, region of each distinct key
    matrix_id.resize(graph.n_elements);
    for (Index e = 0; e < graph.n_elements; ++e) {
      std::array<double, 3> size;
      const auto inserted = ids.emplace(brick_key(mesh, e, size), static_cast<int>(ids.size()));
      if (inserted.second) shapes.push_back({size[0], size[1], size[2], double(mesh.element_region[e])});
      matrix_id[e] = inserted.first->second;
    }
    const double rows = kind == Kind::stiffness ? 3.0 * npe : npe;
    if (static_cast<double>(shapes.size()) * rows * rows * sizeof(double) > kCacheLimitBytes) {
      matrix_id.clear();  // too many distinct bricks: compute on the fly
    } else {
      cached.resize(shapes.size());
      std::atomic<bool> failed{false}, stopped{false};
      std::string error;
#pragma omp parallel
      {
        std::vector<double> coords(3 * npe);
#pragma omp for schedule(dynamic, 1)
        for (int id = 0; id < static_cast<int>(shapes.size()); ++id) {
          // a host's stop, polled by the calling thread between its element matrices (hundreds of
          // distinct graded bricks at order 4 take seconds; the check is rate-limited by the host)
          if (omp_get_thread_num() == 0 && interrupt_requested()) stopped = true;
          if (stopped) continue;
          try {
            brick_coordinates(*basis.hexahedron(), shapes[id][0], shapes[id][1], shapes[id][2], coords.data());
            element_matrix(kind, basis, coords.data(), materials[static_cast<int>(shapes[id][3])],
                           cached[id]);
          } catch (const std::exception& exception) {
#pragma omp critical(crackle_fem_assembly_error)
            if (!failed.exchange(true)) {
              error = "brick " + format_number(shapes[id][0]) + " x " + format_number(shapes[id][1]) + " x " +
                      format_number(shapes[id][2]) + ": " + exception.what();
            }
          }
        }
      }
      if (stopped) throw Interrupted("interrupted");
      if (failed) throw InputError(error);
    }
  }
  const double t2 = omp_get_wtime();
  poll_interrupt();

  // Scatter, one colour class at a time: no two elements of a class share a row, so the threads
  // never write to the same entry, and every entry sums its contributions in colour order
  // whatever the thread count (bitwise identical results).
  double* values = matrix.valuePtr();
  std::atomic<bool> failed{false}, stopped{false};
  std::string error;
  int n_threads = 1;
#pragma omp parallel
  {
#pragma omp single
    n_threads = omp_get_num_threads();
    MatrixX local;
    std::vector<double> coords(3 * npe);
    std::vector<Index> positions(static_cast<std::size_t>(npe) * npe);
    for (const std::vector<Index>& members : classes) {
#pragma omp for schedule(dynamic, 4)
      for (std::size_t i = 0; i < members.size(); ++i) {
        // a host's stop, polled by the calling thread between its elements (a colour class of
        // order-4 elements computed on the fly takes seconds)
        if (omp_get_thread_num() == 0 && interrupt_requested()) stopped = true;
        if (failed || stopped) continue;
        const Index e = members[i];
        try {
          const MatrixX* element = &local;
          if (!matrix_id.empty()) {
            element = &cached[matrix_id[e]];
          } else {
            const Index* nodes = mesh.element_nodes(e);
            for (int a = 0; a < npe; ++a) {
              for (int c = 0; c < 3; ++c) coords[3 * a + c] = mesh.nodes[nodes[a]][c];
            }
            element_matrix(kind, basis, coords.data(), materials[mesh.element_region[e]], local);
          }
          const Index* dof_nodes = &graph.element_dof_nodes[static_cast<std::size_t>(e) * npe];
          for (int a = 0; a < npe; ++a) {
            const Index r = dof_nodes[a];
            const Index degree = graph.degree(r);
            const std::int64_t begin = graph.neighbour_start[r];
            for (int b = 0; b < npe; ++b) positions[a * npe + b] = graph.position(r, dof_nodes[b]);
            if (kind == Kind::stiffness) {
              for (int c = 0; c < 3; ++c) {
                double* row = values + 9 * begin + 3 * static_cast<std::int64_t>(c) * degree;
                // column 3a+c of the symmetric element matrix is row 3a+c, contiguous in memory
                const double* column = element->data() + static_cast<std::size_t>(3 * a + c) * 3 * npe;
                for (int b = 0; b < npe; ++b) {
                  double* target = row + 3 * positions[a * npe + b];
                  target[0] += column[3 * b];
                  target[1] += column[3 * b + 1];
                  target[2] += column[3 * b + 2];
                }
              }
            } else {
              const double* column = element->data() + static_cast<std::size_t>(a) * npe;
              for (int c = 0; c < 3; ++c) {
                double* row = values + 3 * begin + static_cast<std::int64_t>(c) * degree;
                for (int b = 0; b < npe; ++b) row[positions[a * npe + b]] += column[b];
              }
            }
          }
        } catch (const std::exception& exception) {
#pragma omp critical(crackle_fem_assembly_error)
          if (!failed.exchange(true)) error = "element " + std::to_string(e) + ": " + exception.what();
        }
      }
    }
  }
  if (stopped) throw Interrupted("interrupted");
  if (failed) throw InputError(error);
  const double t3 = omp_get_wtime();

  if (report) {
    report->n_elements = graph.n_elements;
    report->n_rows = static_cast<Index>(matrix.rows());
    report->n_nonzeros = matrix.nonZeros();
    report->n_colours = static_cast<int>(classes.size());
    report->n_threads = n_threads;
    report->n_element_matrices = matrix_id.empty() ? graph.n_elements : static_cast<Index>(cached.size());
    report->graph_seconds = t1 - t0;
    report->element_seconds = t2 - t1;
    report->scatter_seconds = t3 - t2;
    report->total_seconds = t3 - t0;
  }
  return matrix;
}

}  // namespace

SparseMatrix assemble_stiffness(const mesh::Mesh& mesh, const mesh::DofMap& dofs, const Materials& materials,
                                const AssemblyOptions& options, AssemblyReport* report) {
  return assemble(Kind::stiffness, mesh, dofs, materials, options, report);
}

SparseMatrix assemble_stiffness(const mesh::Mesh& mesh, const mesh::DofMap& dofs,
                                const Materials& materials) {
  return assemble(Kind::stiffness, mesh, dofs, materials, AssemblyOptions{}, nullptr);
}

SparseMatrix assemble_consistent_mass(const mesh::Mesh& mesh, const mesh::DofMap& dofs,
                                      const Materials& materials, const AssemblyOptions& options,
                                      AssemblyReport* report) {
  return assemble(Kind::mass, mesh, dofs, materials, options, report);
}

SparseMatrix assemble_consistent_mass(const mesh::Mesh& mesh, const mesh::DofMap& dofs,
                                      const Materials& materials) {
  return assemble(Kind::mass, mesh, dofs, materials, AssemblyOptions{}, nullptr);
}

VectorX assemble_lumped_mass(const mesh::Mesh& mesh, const mesh::DofMap& dofs, const Materials& materials,
                             bool element_shares) {
  // GLL nodal quadrature of eq. (25c) (hexahedra) or HRZ lumping (tetrahedra): diagonal, one entry
  // per DOF, same for the 3 components.
  check_inputs(mesh, dofs, &materials);
  const ElementBasis basis(mesh);
  const int npe = basis.n_nodes();
  VectorX nodal = VectorX::Zero(dofs.n_dof_nodes);
  std::vector<double> coords(3 * npe), mass(npe);
  for (Index e = 0; e < mesh.n_elements(); ++e) {
    const Index* nodes = mesh.element_nodes(e);
    for (int a = 0; a < npe; ++a) {
      for (int c = 0; c < 3; ++c) coords[3 * a + c] = mesh.nodes[nodes[a]][c];
    }
    try {
      basis.lumped_mass_scalar(coords.data(), mass.data());
    } catch (const InputError& exception) {
      throw InputError("element " + std::to_string(e) + ": " + exception.what());
    }
    const double density = materials[mesh.element_region[e]].density;
    for (int a = 0; a < npe; ++a) nodal[dofs.dof_node[nodes[a]]] += density * mass[a];
  }
  VectorX lumped(dofs.n_dofs());
  for (Index r = 0; r < dofs.n_dof_nodes; ++r) {
    if (!(nodal[r] > 0.0) && !(element_shares && nodal[r] == 0.0)) {
      throw InputError("lumped mass " + format_number(nodal[r]) + " of DOF node " + std::to_string(r) +
                       " is not positive (material density <= 0, or a node outside every element)");
    }
    for (int c = 0; c < 3; ++c) lumped[3 * r + c] = nodal[r];
  }
  return lumped;
}

std::vector<std::vector<Index>> colour_elements(const mesh::Mesh& mesh, const mesh::DofMap& dofs) {
  check_inputs(mesh, dofs, nullptr);
  return colour(build_graph(mesh, dofs, false));
}

}  // namespace crackle::fem
