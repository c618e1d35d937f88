#pragma once
/// \file One full explicit transient over MPI ranks (PETSc's PETSC_COMM_WORLD), MODEL.md eq. (28)
/// unchanged: each rank applies the element kernels of eq. (25a) to its own elements and owns a
/// contiguous block of the DOFs; one scatter-add per step (a PETSc ghosted Vec, ADD_VALUES /
/// SCATTER_REVERSE, then INSERT_VALUES / SCATTER_FORWARD of the summed force) completes the shared
/// nodes, and every rank then integrates its owned and ghost DOFs from the same forces.
///
/// First step: every rank still holds the whole mesh (replicated, built by each rank from the
/// scene), and takes from it its local mesh: its elements (those touching a node another rank
/// holds first, the interior after them, each in global order), its owned nodes
/// (increasing global number) and then its ghost nodes. A node belongs to the lowest rank among the
/// elements touching it, except the two nodes of a crack pair, which both belong to the owner of the
/// plus node, so that a pair's contact is computed where both its nodes are owned; a rank whose
/// elements touch one node of a pair also holds the other as a ghost and evaluates the pair
/// alike (ghost pairs are left out of the sums). Box and Gmsh meshes, hexahedra (matrix-free) and
/// tetrahedra (the local assembled K) alike; the `open` DOF map only (DOF = 3 node + component).
#include <exception>
#include <memory>
#include <vector>

#include <petscvec.h>

#include "contact/contact_force.hpp"
#include "core/resources.hpp"
#include "fem/constraints.hpp"
#include "mesh/mesh.hpp"
#include "transient/distribution.hpp"

namespace crackle::distributed {

/// Rank and number of ranks of PETSC_COMM_WORLD (PETSc must be initialised).
int world_rank();
int world_size();

/// Collective over PETSC_COMM_WORLD: every rank passes its own error (null: none). When some rank
/// failed, every rank throws the error of the lowest failing rank: that rank rethrows its own, the
/// others the same type (by exit code: InputError, SolverError, IoError, std::bad_alloc) and text,
/// prefixed with "rank R: " when R > 0. Else returns. One message, one exit code, no hang.
void agree(std::exception_ptr error);

/// Runs `work` on this rank and agrees on its outcome with the others (agree()).
template <class Work>
void collectively(Work&& work) {
  std::exception_ptr error;
  try {
    work();
  } catch (...) {
    error = std::current_exception();
  }
  agree(error);
}

/// The rank of each element from PT-Scotch (PETSc MatPartitioning, type ptscotch unless
/// -mat_partitioning_type says otherwise) on the element dual graph (elements sharing a face),
/// for `ranks` parts; every rank gets the whole vector. Collective. InputError (on every rank,
/// the same text) for more ranks than elements or a part left empty.
std::vector<int> partition_elements(const mesh::Mesh& mesh, int ranks);

/// Halo traffic of one rank per step.
struct HaloCounts {
  Index owned_dofs = 0;
  Index ghost_dofs = 0;
  Index boundary_dofs = 0;  ///< owned DOFs that other ranks hold as ghosts
  /// Elements touching a DOF that another rank holds (applied before the halo starts), and the
  /// others (applied while it travels).
  Index boundary_elements = 0, interior_elements = 0;
  /// Bytes this rank sends and receives per step: ghost DOFs x 8 bytes, twice (the scatter-add of
  /// the element shares, then the completed sums back to the ghosts).
  double bytes_per_step = 0.0;
};

/// min, max and mean over the ranks of a per-rank count.
struct Spread {
  double min = 0.0, max = 0.0, mean = 0.0;
};

/// How even a partition is, and its halo traffic (transient.json's "partition").
struct PartitionBalance {
  Spread elements, owned_dofs, ghost_dofs;
  Spread halo_bytes_per_step;  ///< HaloCounts::bytes_per_step
  Spread boundary_elements;    ///< HaloCounts::boundary_elements
};

/// This rank's share of a mesh partition, and the transient::Distribution of a run over it.
class MeshPartition final : public transient::Distribution {
 public:
  /// Collective. `element_rank`: the rank of each element (the same vector on every rank), e.g.
  /// from partition_elements(). `global` is borrowed and must outlive the partition.
  MeshPartition(const mesh::Mesh& global, std::vector<int> element_rank);
  ~MeshPartition() override;
  MeshPartition(const MeshPartition&) = delete;
  MeshPartition& operator=(const MeshPartition&) = delete;

  const mesh::Mesh& global_mesh() const { return *global_; }
  /// Own elements (boundary first, n_boundary_elements()), owned then ghost nodes; node sets, face sets and crack pairs restricted to them.
  const mesh::Mesh& local_mesh() const { return local_; }
  const std::vector<int>& element_rank() const { return element_rank_; }
  Index n_owned_nodes() const { return n_owned_nodes_; }
  /// Global node of each local node.
  const std::vector<Index>& global_nodes() const { return global_nodes_; }
  /// Local node of a global node, -1 when this rank does not hold it.
  Index local_node(Index global_node) const { return local_of_[global_node]; }
  /// Local node of a global node that this rank owns, else -1 (a probe's node).
  Index owned_node(Index global_node) const;
  HaloCounts halo_counts() const;
  /// Collective: the balance over all ranks (every rank gets it).
  PartitionBalance balance() const;
  /// Wall time spent in complete() and sum() so far [s]: transfers and waiting for the other ranks.
  double communication_seconds() const { return communication_seconds_; }

  /// A field over the global `open` DOFs restricted to the local DOFs.
  VectorX local_field(const VectorX& global_field) const;
  /// Dirichlet conditions restricted to the local nodes.
  std::vector<fem::DirichletCondition> local_dirichlet(const std::vector<fem::DirichletCondition>& global) const;
  /// The crack contact over the local pairs: the penalty chosen on the whole mesh (so that every
  /// rank uses the same one) and the sums restricted to the owned pairs.
  std::shared_ptr<contact::ContactForce> local_contact(const fem::Materials& materials,
                                                       const contact::ContactOptions& options) const;

  int rank() const override { return rank_; }
  int ranks() const override { return ranks_; }
  Index n_owned_dofs() const override { return 3 * n_owned_nodes_; }
  Index n_global_dofs() const override { return 3 * global_->n_nodes(); }
  const std::vector<Index>& global_dofs() const override { return global_dofs_; }
  void complete(VectorX& local) const override;
  void send_shares(VectorX& local) const override;
  void receive_sums(VectorX& local) const override;
  void receive_ghosts(VectorX& local) const override;
  Index n_boundary_elements() const override { return n_boundary_elements_; }
  void sum(std::vector<double>& values) const override;
  void agree(std::exception_ptr error) const override { distributed::agree(error); }

 private:
  const mesh::Mesh* global_;
  std::vector<int> element_rank_;
  int rank_ = 0, ranks_ = 1;
  mesh::Mesh local_;
  Index n_owned_nodes_ = 0;
  Index n_boundary_elements_ = 0;  ///< the first local elements: those touching a shared DOF
  std::vector<Index> global_nodes_, local_of_, global_dofs_;
  Vec halo_ = nullptr;  ///< ghosted: owned DOFs in the PETSc numbering, ghosts after them
  std::vector<Index> boundary_;  ///< owned local DOFs that other ranks hold as ghosts
  mutable double communication_seconds_ = 0.0;
};

}  // namespace crackle::distributed
