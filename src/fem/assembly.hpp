#pragma once
/// \file Global stiffness and mass for one DOF map (variant) of a mesh.
/// Threaded with OpenMP over colour classes of elements (no write conflicts); the thread count
/// is OpenMP's (omp_set_num_threads / OMP_NUM_THREADS).
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

/// Diagonal lumped mass (one entry per DOF) by GLL nodal quadrature: strictly positive.
VectorX assemble_lumped_mass(const mesh::Mesh& mesh, const mesh::DofMap& dofs, const Materials& materials);

}  // namespace crackle::fem
