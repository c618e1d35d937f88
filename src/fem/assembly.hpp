#pragma once
/// \file Global stiffness and mass for one DOF map (variant) of a mesh.
/// Threaded with OpenMP over colour classes of elements (no write conflicts); the thread count
/// is OpenMP's (omp_set_num_threads / OMP_NUM_THREADS).
#include <cstdint>
#include <vector>

#include "core/types.hpp"
#include "fem/material.hpp"
#include "mesh/mesh.hpp"

namespace crackle::fem {

/// materials[mesh.element_region[e]] is the material of element e.
using Materials = std::vector<Material>;

/// Sparse symmetric K over all DOFs of the map (constraints not applied): eq. (25a).
SparseMatrix assemble_stiffness(const mesh::Mesh& mesh, const mesh::DofMap& dofs, const Materials& materials);

/// Sparse symmetric consistent mass M over all DOFs of the map: eq. (25c).
SparseMatrix assemble_consistent_mass(const mesh::Mesh& mesh, const mesh::DofMap& dofs,
                                      const Materials& materials);

/// Diagonal lumped mass (one entry per DOF): GLL nodal quadrature on hexahedra, HRZ lumping (diagonal
/// of the consistent mass scaled to the element mass) on tetrahedra. Strictly positive, unless
/// `element_shares` (one rank's elements of a distributed mesh: a node may lie outside them all).
VectorX assemble_lumped_mass(const mesh::Mesh& mesh, const mesh::DofMap& dofs, const Materials& materials,
                             bool element_shares = false);

/// Knobs of the global assembly (defaults are what production runs use).
struct AssemblyOptions {
  /// Reuse element matrices of identical axis-aligned bricks (only if mesh.axis_aligned_bricks):
  /// they depend only on (hx, hy, hz) and the region, keyed on the exact bits of those values.
  bool brick_cache = true;
};

/// What one assembly did, for benchmarks and logs.
struct AssemblyReport {
  Index n_elements = 0;
  Index n_rows = 0;
  std::int64_t n_nonzeros = 0;
  int n_colours = 0;                ///< element colour classes (no two elements of one share a node)
  int n_threads = 0;                ///< OpenMP threads used
  Index n_element_matrices = 0;     ///< element matrices computed (fewer than elements with the cache)
  double graph_seconds = 0.0;       ///< node graph, colouring and CSR pattern
  double element_seconds = 0.0;     ///< cached element matrices (0 without the cache)
  double scatter_seconds = 0.0;     ///< element matrices on the fly and scatter into the CSR values
  double total_seconds = 0.0;
};

/// eq. (25a) with options and a report (benchmarks): same matrix as assemble_stiffness above.
SparseMatrix assemble_stiffness(const mesh::Mesh& mesh, const mesh::DofMap& dofs, const Materials& materials,
                                const AssemblyOptions& options, AssemblyReport* report);

/// eq. (25c) with options and a report (benchmarks): same matrix as assemble_consistent_mass above.
SparseMatrix assemble_consistent_mass(const mesh::Mesh& mesh, const mesh::DofMap& dofs,
                                      const Materials& materials, const AssemblyOptions& options,
                                      AssemblyReport* report);

/// Greedy colouring of the elements: classes of element indices (increasing) such that no two
/// elements of a class share a DOF node. Deterministic, independent of the thread count.
std::vector<std::vector<Index>> colour_elements(const mesh::Mesh& mesh, const mesh::DofMap& dofs);

}  // namespace crackle::fem
