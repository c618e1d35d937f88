#pragma once
/// \file Choices of the scene that a solver module below scene/ takes as they are: the enum and its
/// words (core/words.hpp) are shared; the scene's word is converted once (scene/scene.cpp) and named
/// back for the outputs with `text_of`.
#include <string>

#include "core/words.hpp"

namespace crackle {

/// How harmonic balance solves with its Jacobian J = I - H dP/dG (`sweep.solver`).
enum class LinearSolver {
  automatic,  ///< dense up to HarmonicBalanceOptions::dense_limit unknowns, else krylov
  dense,      ///< J formed (c(2H+1) square) and LU-factorised: fastest for small problems
  krylov,     ///< matrix-free GMRES with the pair-block preconditioner (sweep/krylov.hpp): no square matrix
};
inline constexpr Words<LinearSolver, 3> kLinearSolverWords{
    {{"auto", LinearSolver::automatic}, {"dense", LinearSolver::dense}, {"krylov", LinearSolver::krylov}}};

/// The scene's word for a linear solver: auto, dense, krylov.
inline std::string linear_solver_name(LinearSolver solver) { return text_of(kLinearSolverWords, solver); }

/// Window applied to a record before a DFT (`spectrum.window`, spectral/window.hpp). `automatic`
/// lets the analysis choose (see spectral's HarmonicOptions and SpectrumOptions); the others are
/// applied as asked.
enum class Window { automatic, rectangular, hann, flattop };
inline constexpr Words<Window, 4> kWindowWords{{{"auto", Window::automatic},
                                                {"rectangular", Window::rectangular},
                                                {"hann", Window::hann},
                                                {"flattop", Window::flattop}}};

/// How the crack's penalty law is integrated in the full explicit model (`crack.contact.integration`,
/// contact/contact.hpp).
enum class ContactIntegration {
  implicit,         ///< penalty law at U(i+1), closed form per pair (default)
  explicit_forces,  ///< penalty law at U(i); the springs limit the stable time step
};
inline constexpr Words<ContactIntegration, 2> kContactIntegrationWords{
    {{"implicit", ContactIntegration::implicit}, {"explicit", ContactIntegration::explicit_forces}}};

}  // namespace crackle
