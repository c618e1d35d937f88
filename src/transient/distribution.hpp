#pragma once
/// \file How one transient run is spread over processes (MPI ranks), as the transient solver sees
/// it; the distributed module implements it with PETSc (distributed::MeshPartition). The solver's
/// vectors are then over the rank's local DOFs: the DOFs it owns first, [0, n_owned_dofs()), then
/// its ghosts (DOFs owned by another rank that its elements or crack pairs touch). Every rank
/// integrates its owned and its ghost DOFs from the same completed forces, so ghosts stay equal to
/// their owners without a second exchange; sums (energies, dot products) count owned DOFs only.
#include <exception>
#include <vector>

#include "core/types.hpp"

namespace crackle::transient {

class Distribution {
 public:
  virtual ~Distribution() = default;
  virtual int rank() const = 0;
  virtual int ranks() const = 0;
  /// DOFs this rank owns: the first entries of its local vectors.
  virtual Index n_owned_dofs() const = 0;
  /// DOFs of the whole body.
  virtual Index n_global_dofs() const = 0;
  /// Global DOF (the one-process numbering) of each local DOF.
  virtual const std::vector<Index>& global_dofs() const = 0;
  /// Completes a local vector of element contributions: each owned entry becomes the sum over the
  /// ranks that touch it (one scatter-add), each ghost entry a copy of its owner's sum.
  virtual void complete(VectorX& local) const = 0;
  /// complete() in three phases, so that element work can run while the messages travel (every
  /// rank calls them in turn on the same vector, nothing else of the distribution in between):
  /// send_shares() starts the scatter-add of the ghost entries (then complete: every element that
  /// touches a ghost applied); receive_sums() ends it, each owned entry that another rank holds
  /// becomes the sum (it must be complete here too: applied by every element of this rank that
  /// touches it), and starts sending the sums back; receive_ghosts() ends that, each ghost entry
  /// becomes its owner's sum. Entries that no other rank holds are neither read nor written.
  virtual void send_shares(VectorX& local) const = 0;
  virtual void receive_sums(VectorX& local) const = 0;
  virtual void receive_ghosts(VectorX& local) const = 0;
  /// The rank's elements (of its local mesh) are ordered boundary first: the first
  /// n_boundary_elements() touch a DOF that another rank holds (a ghost, or an owned DOF that is a
  /// ghost elsewhere); the rest, the interior, touch only DOFs no other rank holds, so that they
  /// can be applied while the halo travels.
  virtual Index n_boundary_elements() const = 0;
  /// Sums `values` over the ranks, in place (every rank gets the same sums).
  virtual void sum(std::vector<double>& values) const = 0;
  /// Collective: every rank passes its own error (null: none). When some rank failed, every rank
  /// throws the error of the lowest failing rank (the same type and text), so that all stop
  /// together with one message; else returns.
  virtual void agree(std::exception_ptr error) const {
    if (error) std::rethrow_exception(error);
  }
};

}  // namespace crackle::transient
