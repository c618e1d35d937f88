#pragma once
/// \file Restarted GMRES on linear maps given as actions (Saad and Schultz 1986; Saad, Iterative
/// Methods for Sparse Linear Systems, sec. 6.5 and 9.3.2): the harmonic-balance sweep's matrix-free
/// Newton and continuation solves (sweep/krylov.hpp).
#include <functional>

#include "core/types.hpp"

namespace crackle::linalg {

/// y = A x for GMRES (x and y of the same size; y is resized by the caller).
using LinearAction = std::function<void(const VectorX& x, VectorX& y)>;

/// Result of one GMRES solve.
struct GmresReport {
  int iterations = 0;             ///< Arnoldi steps taken (all restarts)
  double relative_residual = 0.0; ///< ||b - A x|| / ||b|| at the end
  bool converged = false;
};

/// Restarted GMRES with right preconditioning (the residual it monitors is the true one): solves
/// A x = b from x (its initial guess, zero if empty) to ||b - A x|| <= tolerance ||b||, at most
/// `max_iterations` Arnoldi steps, restarting every `restart`.
GmresReport gmres(const LinearAction& apply, const LinearAction& precondition, const VectorX& b, VectorX& x,
                  double tolerance, int max_iterations, int restart);

}  // namespace crackle::linalg
