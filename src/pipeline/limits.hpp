#pragma once
/// \file What a scene will cost, estimated from the scene before anything is built, so that a job
/// that cannot fit is refused in a second with the key to change (and not ended by std::bad_alloc
/// after minutes). The estimates are lower bounds: what the mesh, the operators and the outputs
/// need at least, not counting the solvers' own workspace (factorisations, Krylov bases).
#include <array>
#include <filesystem>
#include <string>

#include "core/resources.hpp"
#include "pipeline/model.hpp"
#include "scene/scene.hpp"

namespace crackle::pipeline {

/// Sizes of the mesh a scene describes, computed without meshing (box: cells and order; a Gmsh
/// mesh: unknown counts, its file size stands for the mesh).
struct MeshEstimate {
  double nodes = 0.0;
  double elements = 0.0;
  double dofs = 0.0;
  double nodes_per_element = 8.0;
  double file_bytes = 0.0;  ///< a Gmsh mesh file's size, 0 for a box
  std::array<double, 3> cells{};  ///< cells per axis of a box: its grid lines less one
};

/// The mesh build_model(scene, use) makes: a box's grid lines as the mesher places them (crack
/// edges, mesh.box.lines, material regions and the grading layers of `use`).
MeshEstimate estimate_mesh(const scene::Scene& scene, MeshUse use = MeshUse::transient);

/// Sparse matrices of K's size [count] a command holds at once besides the mesh and vectors.
namespace matrices {
inline constexpr int none = 0;
inline constexpr int stiffness = 1;  ///< K in CSR: check, a transient on tetrahedra
inline constexpr int static_solve = 2;  ///< K and CHOLMOD's permuted copy: the reduced model's static images
inline constexpr int eigen_solve = 4;  ///< K, M, K - sigma M and CHOLMOD's permuted copy: a modal stage
}  // namespace matrices

/// What a command needs at least [bytes]: the mesh, the DOF maps, the lumped mass and vectors of
/// the DOFs, and `matrices` sparse matrices of K's pattern in CSR (not counting a factor: its size
/// is known after the symbolic analysis, where linalg::CholmodFactor checks it).
double estimate_memory_bytes(const scene::Scene& scene, const MeshEstimate& mesh, int matrices);

/// Refuses (InputError naming the mesh key, the estimate and the memory available) a scene whose
/// mesh and operators cannot fit in memory. Call before build_model.
void check_memory(const scene::Scene& scene, int matrices, MeshUse use = MeshUse::transient);

/// Refuses (InputError naming sweep.harmonics) a harmonic-balance sweep whose solver cannot fit in
/// memory with `rows` pair rows and `modes` modes (sweep::HarmonicBalance::memory_bytes, the dense or
/// matrix-free solver as sweep.solver selects it). Call once the reduced model's size is known.
void check_sweep_memory(const scene::Scene& scene, Index rows, Index modes);

/// Refuses a run whose histories (probes at full rate for the spectrum, probes.csv rows, energy
/// rows) cannot fit in memory, naming the run-length key; and snapshots that cannot fit on the
/// disk of `directory` or that outnumber the steps, naming transient.snapshots.count.
void check_run_outputs(const scene::Scene& scene, const MeshEstimate& mesh, double steps, double probe_rows,
                       const std::filesystem::path& directory);


}  // namespace crackle::pipeline
