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
