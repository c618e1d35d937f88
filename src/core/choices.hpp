#pragma once
/// \file Choices of the scene that a solver module below scene/ takes as they are: the enum is
/// shared, the scene's word is converted once (scene/scene.cpp) and named back for the outputs here.
#include <string>

namespace crackle {

/// How harmonic balance solves with its Jacobian J = I - H dP/dG (`sweep.solver`).
enum class LinearSolver {
  automatic,  ///< dense up to HarmonicBalanceOptions::dense_limit unknowns, else krylov
  dense,      ///< J formed (c(2H+1) square) and LU-factorised: fastest for small problems
  krylov,     ///< matrix-free GMRES with the pair-block preconditioner (sweep/krylov.hpp): no square matrix
};

/// The scene's word for a linear solver: auto, dense, krylov.
inline std::string linear_solver_name(LinearSolver solver) {
  return solver == LinearSolver::dense ? "dense" : solver == LinearSolver::krylov ? "krylov" : "auto";
}

}  // namespace crackle
