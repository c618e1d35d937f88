#pragma once
/// \file What a scene will cost, estimated from the scene before anything is built, so that a job
/// that cannot fit is refused in a second with the key to change (and not ended by std::bad_alloc
/// after minutes). The estimates are lower bounds: what the mesh, the operators and the outputs
/// need at least, not counting the solvers' own workspace (factorisations, Krylov bases).
#include <filesystem>
#include <string>

#include "scene/scene.hpp"

namespace crackle::pipeline {

/// Memory this process may still take [bytes]: MemAvailable of /proc/meminfo (sysconf where that
/// is missing), lowered to the address-space limit (RLIMIT_AS) and the cgroup's memory.max when set.
/// `source` says which figure it is, for messages.
double available_memory_bytes(std::string* source = nullptr);

/// Sizes of the mesh a scene describes, computed without meshing (box: cells and order; a Gmsh
/// mesh: unknown counts, its file size stands for the mesh).
struct MeshEstimate {
  double nodes = 0.0;
  double elements = 0.0;
  double dofs = 0.0;
  double nodes_per_element = 8.0;
  double file_bytes = 0.0;  ///< a Gmsh mesh file's size, 0 for a box
};
MeshEstimate estimate_mesh(const scene::Scene& scene);

/// What a command needs at least [bytes]: the mesh, the DOF maps, the lumped mass and vectors of
/// the DOFs; with `stiffness` also K in CSR (check, modal; transient runs on tetrahedra).
double estimate_memory_bytes(const scene::Scene& scene, const MeshEstimate& mesh, bool stiffness);

/// Refuses (InputError naming the mesh key, the estimate and the memory available) a scene whose
/// mesh and operators cannot fit in memory. Call before build_model.
void check_memory(const scene::Scene& scene, bool stiffness);

/// Refuses a run whose histories (probes at full rate for the spectrum, probes.csv rows, energy
/// rows) cannot fit in memory, naming the run-length key; and snapshots that cannot fit on the
/// disk of `directory` or that outnumber the steps, naming transient.snapshots.count.
void check_run_outputs(const scene::Scene& scene, const MeshEstimate& mesh, double steps, double probe_rows,
                       const std::filesystem::path& directory);

/// "1.5 GiB", "300 MiB", "2.4e7 TiB".
std::string bytes_text(double bytes);

}  // namespace crackle::pipeline
