#pragma once
/// \file `crackle run` under `mpirun -np N`: one full explicit transient spread over the N ranks
/// (src/distributed). Every rank builds the scene's model (the mesh is replicated) and the
/// one-process problem over the whole body (loads, initial fields, probes placed on the whole mesh);
/// distribute_transient() then gives each rank its share over its local mesh. Rank 0 writes every
/// file; errors are agreed by all ranks (distributed::agree) so that they stop together.
#include <filesystem>
#include <memory>
#include <ostream>
#include <streambuf>
#include <string>

#include <nlohmann/json.hpp>

#include "contact/contact_force.hpp"
#include "distributed/partition.hpp"
#include "io/vtu.hpp"
#include "pipeline/model.hpp"
#include "transient/solver.hpp"

namespace crackle::pipeline {

/// MPI ranks of this process's job: 1 when PETSc (MPI) is not started.
int run_ranks();
/// True on the rank that writes files and prints (rank 0; any process without MPI).
bool is_writer_rank();
/// Whether the distributed run overlaps the halo with the interior elements: the PETSc option
/// `-crackle_halo_overlap` (`crackle run scene.yaml -o DIR -- -crackle_halo_overlap`); off by
/// default, because on one machine (shared-memory MPI) it did not pay (docs/benchmarks.md section 10).
bool halo_overlap_option();

/// Runs `work` on every rank; with several ranks, all agree on its outcome (one error, thrown on
/// every rank, when one failed). Without MPI it simply runs it.
template <class Work>
void on_every_rank(Work&& work) {
  if (run_ranks() > 1) {
    distributed::collectively(std::forward<Work>(work));
  } else {
    work();
  }
}

/// Runs `work` on the writer rank only (files, stdout); with several ranks, all agree on its outcome.
template <class Work>
void on_writer_rank(Work&& work) {
  on_every_rank([&] {
    if (is_writer_rank()) work();
  });
}

/// A stream that drops what it is given (stdout of the ranks that do not write).
class NullStream : public std::ostream {
 public:
  NullStream() : std::ostream(&buffer_) {}

 private:
  struct Buffer : std::streambuf {
    int overflow(int c) override { return c; }
  } buffer_;
};

/// This rank's share of the scene's full transient.
struct DistributedTransient {
  std::unique_ptr<distributed::MeshPartition> partition;
  transient::TransientProblem problem;              ///< over the rank's local DOFs; distribution set
  std::shared_ptr<contact::ContactForce> contact;   ///< the local crack contact, null without
  nlohmann::json partition_json;                    ///< transient.json's "partition"
};

/// Collective. From the one-process problem `global` over the `open` DOFs of the whole mesh (the
/// loads as placed by the scene, initial fields, probes, the contact term when `contact_options`
/// is given), each rank's share: PT-Scotch partition, the local mesh, loads as the owned DOFs'
/// part of the forces placed on the whole body (so node-set, point and face loads keep their total),
/// initial fields and Dirichlet conditions restricted, probes on the rank that owns their node (or
/// crack pair), the contact over the local pairs.
DistributedTransient distribute_transient(const Model& model, const transient::TransientProblem& global,
                                          const contact::ContactOptions* contact_options);

/// Snapshots of a distributed run: one .vtu piece per rank (its local mesh, owned and ghost nodes)
/// and, from rank 0, a .pvtu naming the pieces; returns the .pvtu's file name for snapshots.pvd.
std::string write_snapshot_pieces(const std::filesystem::path& directory, const std::string& stem,
                                  const distributed::MeshPartition& partition, const io::PointField& field);

}  // namespace crackle::pipeline
