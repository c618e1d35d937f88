#pragma once
/// \file Central differences, MODEL.md eqs. (27)-(28), separated from the physics (MFEM
/// SecondOrderODESolver, Akantu solveStep): the integrator knows a diagonal mass, a
/// mass-proportional damping coefficient and a force callback, nothing else.
#include "core/types.hpp"
#include "fem/force_term.hpp"

namespace crackle::transient {

/// What a force evaluation at step i sees (the state and the integrator's velocity update).
using ForceInput = fem::StepInput;

/// The semi-discrete system (26) as the integrator sees it:
/// \f$M\ddot U + \alpha M \dot U = F(t, U, \dot U)\f$, M diagonal (lumped, eq. 27).
/// F holds everything else: external loads, -K U, -beta K U', contact forces.
class SecondOrderSystem {
 public:
  virtual ~SecondOrderSystem() = default;
  virtual Index n_dofs() const = 0;
  /// DOFs that the step sums count: the first n_owned() (a rank's owned DOFs when a run is
  /// distributed, transient::Distribution; the others are ghosts, updated but not counted).
  virtual Index n_owned() const { return n_dofs(); }
  /// Diagonal of M per DOF [kg]; 0 at held (Dirichlet) DOFs.
  virtual const VectorX& mass() const = 0;
  /// Diagonal of M^{-1} per DOF; 0 at held DOFs, which therefore never move.
  virtual const VectorX& inverse_mass() const = 0;
  /// alpha of the damping alpha M [1/s].
  virtual double mass_damping() const = 0;
  /// Adds F(t_i) at U(i) and the half-step velocity V(i-1/2) to `force`, which is zero on entry.
  /// A term may also make itself implicit by adding the force that gives the velocity update it
  /// wants (knowing h, alpha, M^{-1} from the input and the rest of F), as the crack contact does.
  virtual void add_force(const ForceInput& input, VectorX& force) = 0;
};

/// Sums over the counted DOFs (SecondOrderSystem::n_owned) that one step computes in passing (no extra pass over memory), for the
/// energy balance. h = (dt_previous + dt)/2.
struct StepSums {
  double kinetic_half = 0.0;        ///< \f$\tfrac12 V_{i+1/2}^T M V_{i+1/2}\f$ [J]
  double kinetic_mid = 0.0;         ///< \f$\tfrac12 \bar V_i^T M \bar V_i\f$, \f$\bar V_i = (V_{i-1/2}+V_{i+1/2})/2\f$ [J]
  double force_displacement = 0.0;  ///< \f$F_i \cdot U_i\f$ [J]
  double force_velocity = 0.0;      ///< \f$F_i \cdot V_{i+1/2}\f$ [W]
  /// Energy dissipated by alpha M over the step: \f$\tfrac{\alpha h}{4} (V_{i+1/2}+V_{i-1/2})^T M (V_{i+1/2}+V_{i-1/2})\f$ [J].
  double mass_damping_dissipation = 0.0;
};

/// Explicit central differences, eq. (28), with alpha M U' taken at the mean of the two half-step
/// velocities (which keeps eq. (28)'s stability limit whatever alpha):
/// \f[ (1 + \tfrac{\alpha h}{2}) V_{i+1/2} = (1 - \tfrac{\alpha h}{2}) V_{i-1/2} + h M^{-1} F_i, \quad
///     U_{i+1} = U_i + \Delta t_{i+1} V_{i+1/2}, \quad h = \tfrac{\Delta t_i + \Delta t_{i+1}}{2}. \f]
///
/// Contract of step(): **in** U(i), V(i-1/2) (at the first step V(0) with dt_previous = 0, so that
/// the first update is the half step V(1/2) = V(0) + dt/2 A(0)), t_i, dt_previous = Delta t(i),
/// dt = Delta t(i+1). **Out** U(i+1), V(i+1/2), in place; the force F_i was evaluated once, through
/// system.add_force({t_i, dt, h, U(i), V(i-1/2)}, F). The acceleration of eq. (27) is
/// A(i) = (V(i+1/2) - V(i-1/2))/h (= M^{-1} F_i without damping).
class CentralDifference {
 public:
  explicit CentralDifference(Index n_dofs);
  /// One step; with `sums` non-null also the energy sums of that step.
  void step(SecondOrderSystem& system, double time, double dt_previous, double dt, VectorX& displacement,
            VectorX& velocity, StepSums* sums = nullptr);

 private:
  VectorX force_;  ///< zero between steps (cleared in the update loop)
};

}  // namespace crackle::transient
