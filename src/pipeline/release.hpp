#pragma once
/// \file Initial states of free-vibration runs (MODEL.md eq. 6, `transient.release`): at rest from
/// the static deflection under a load, with the crack's penalty contact active (the nonlinear
/// static problem, solved by an active set on the pair springs), or from a scaled mode shape.
/// Used by the full transient of `crackle run`; the reduced model can start from the same state.
#include <optional>
#include <string>
#include <vector>

#include "contact/contact.hpp"
#include "fem/system.hpp"
#include "modal/modal.hpp"
#include "pipeline/model.hpp"
#include "scene/scene.hpp"
#include "transient/excitation.hpp"

namespace crackle::pipeline {

/// The crack-face penalty springs of a static solve (frictionless, MODEL.md eq. 25d): per split
/// pair a spring \f$\varepsilon_N A\f$ along n+, active where \f$g_N = g_0 + (u_- - u_+)\cdot n^+ < 0\f$.
struct StaticContact {
  std::vector<mesh::CrackPair> pairs;  ///< the mesh's pairs (front pairs, minus == plus, carry nothing)
  double penalty = 0.0;                ///< \f$\varepsilon_N\f$ [Pa/m]
  double gap = 0.0;                    ///< g0 [m]
};

/// A static solution and how it was found.
struct StaticSolution {
  VectorX displacement;  ///< over all DOFs of the system (prescribed values at held DOFs)
  int iterations = 0;    ///< active-set iterations (1 without contact)
  Index n_pairs = 0;     ///< split pairs
  Index n_closed = 0;    ///< pairs in contact at the solution
};

/// Solves \f$(K + K_c(u))\,u = f + f_c\f$ over the free DOFs of `system` (MODEL.md eqs. 24, 25d
/// without inertia): with `contact`, an active set on the pair springs (start open; the closed
/// set is the pairs with g_N < 0 at the last solution; a CHOLMOD factor of K + active springs per
/// set) until the set repeats. Exact for the penalty law: the final u satisfies the piecewise-linear
/// equations with every pair on the side of its spring law. SolverError if K is singular (a free
/// body) or the set cycles.
StaticSolution solve_static(const fem::System& system, const VectorX& force, const StaticContact* contact);

/// What release_state did (for the terminal and transient.json).
struct ReleaseReport {
  scene::ReleaseKind kind = scene::ReleaseKind::static_deflection;
  int iterations = 0;        ///< static: active-set iterations
  Index n_pairs = 0;         ///< static: split crack pairs with contact (0 without)
  Index n_closed = 0;        ///< static: pairs closed at the released state
  double largest_displacement = 0.0;  ///< largest nodal displacement of U(0) [m]
};

/// U(0) (and V(0) = 0) over the DOFs of `model.system(variant)` from `release`: the static
/// deflection (with `contact` when given: the run's crack contact; null: none) or mode
/// `release.mode` of `release.variant` from `modes` scaled to `release.amplitude`. `where` prefixes
/// messages (scene file). InputError for a mode that was not computed.
transient::InitialConditions release_state(const scene::ReleaseSection& release, const Model& model,
                                           mesh::Variant variant, const contact::ContactOptions* contact,
                                           const modal::ModalResult* modes, const std::string& where,
                                           ReleaseReport* report = nullptr);

}  // namespace crackle::pipeline
