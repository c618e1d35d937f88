#pragma once
/// \file Force terms of the semi-discrete system, MODEL.md eq. (26):
/// \f$M\ddot U + \alpha M \dot U = \sum_t F_t(t, U, \dot U)\f$ with F_t the elastic forces -K U,
/// stiffness-proportional damping -beta K U', external loads and crack contact. Each term plugs into
/// a time integrator through this interface (Akantu's contact resolutions, STYLE.md): the
/// integrator loops over the terms for the force, the energy balance and the stable step, and never
/// names a physics.
#include <string>

#include "core/types.hpp"

namespace crackle::fem {

/// What a force evaluation at step i sees: the state and the velocity update the integrator will
/// make with the summed force F, \f$(1 + \alpha h/2) V_{i+1/2} = (1 - \alpha h/2) V_{i-1/2} + h M^{-1} F\f$,
/// \f$U_{i+1} = U_i + \Delta t\, V_{i+1/2}\f$ (MODEL.md eq. 28), so that a term may be made implicit
/// in its own unknowns (the pair springs of the crack).
struct StepInput {
  double time = 0.0;            ///< t_i [s]
  double dt = 0.0;              ///< Delta t(i+1) [s]
  double step = 0.0;            ///< h = (Delta t(i) + Delta t(i+1))/2 of the velocity update [s]
  const VectorX& displacement;  ///< U(i)
  const VectorX& velocity;      ///< V(i-1/2) (V(0) at the first step)
  double mass_damping = 0.0;    ///< alpha [1/s]
  const VectorX& inverse_mass;  ///< diagonal of M^{-1} per DOF, 0 at held DOFs
};

/// How a term enters the energy balance.
enum class EnergyRole {
  potential,    ///< conservative: its stored energy counts (elastic strain, penalty springs)
  external,     ///< work done on the body counts as input (loads)
  dissipative,  ///< its (negative) work counts as dissipated (viscous damping)
};

/// One force term. add_force() is called exactly once per step, in order.
class ForceTerm {
 public:
  virtual ~ForceTerm() = default;
  /// Short name for logs and timings ("elastic", "damping", "load", "contact").
  virtual std::string name() const = 0;
  virtual EnergyRole role() const = 0;
  /// True if the term needs the sum of every other force of the step in `force` (it is then
  /// evaluated after all the others; at most one such term).
  virtual bool needs_other_forces() const { return false; }
  /// Adds the term's force of step i to `force`.
  virtual void add_force(const StepInput& input, VectorX& force) = 0;
  /// \f$F_t(i)\cdot x\f$ of the force of the last add_force().
  virtual double force_dot(const VectorX& x) const = 0;
  /// potential: energy stored [J] at the state the force was evaluated for.
  virtual double stored_energy() const { return 0.0; }
  /// potential: true when the force is that of U(i) (explicit), so that the integrator's modified
  /// energy adds \f$-\tfrac{\Delta t}{2} F_t(i)\cdot V_{i+1/2}\f$ (central differences conserve
  /// \f$E_{i+1/2}\f$, see transient::TransientSolver); false for forces of U(i+1).
  virtual bool explicit_in_time() const { return true; }
  /// Energy the term dissipates internally since its start [J] (friction).
  virtual double dissipated_energy() const { return 0.0; }
  /// Share of the term that is active at the last step, in [0, 1] (contact: closed crack area).
  virtual double active_fraction() const { return 0.0; }
  /// y += its stiffest tangent times x, for the stable time step of explicit integration (only
  /// terms whose springs limit it: explicit contact).
  virtual void add_stiffness_bound(const VectorX& /*x*/, VectorX& /*y*/) const {}
  /// Called once before the first step with U(0).
  virtual void start(const VectorX& /*displacement*/) {}
};

}  // namespace crackle::fem
