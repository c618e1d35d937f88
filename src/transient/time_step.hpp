#pragma once
/// \file Stable time step of central differences (MODEL.md sec. 4): \f$\Delta t \le 2/\omega_{max}\f$,
/// with stiffness-proportional damping \f$(2/\omega_{max})(\sqrt{1+\xi^2} - \xi)\f$,
/// \f$\xi = \beta\omega_{max}/2\f$ (Akantu getStableTimeStep).
#include "core/defaults.hpp"
#include "core/types.hpp"
#include "linalg/linear_operator.hpp"
#include "transient/distribution.hpp"

namespace crackle::transient {

struct TimeStepOptions {
  double safety_factor = defaults::kSafetyFactor;  ///< time step used when none is given: safety_factor * dt_critical
  /// The estimate of omega_max is raised by this fraction: Lanczos approaches omega_max from below.
  double margin = 0.02;
  int max_iterations = 300;    ///< Lanczos steps at most
  double tolerance = 1e-6;     ///< relative change of the largest Ritz value over 10 steps that stops it
};

struct TimeStepEstimate {
  double omega_ritz = 0.0;     ///< largest Ritz value of the Lanczos iteration, as sqrt [rad/s]
  double omega_max = 0.0;      ///< (1 + margin) omega_ritz [rad/s]
  double damping_ratio = 0.0;  ///< xi = beta omega_max / 2
  double dt_critical = 0.0;    ///< limit of eq. (28) at omega_max [s]
  double dt_stable = 0.0;      ///< safety_factor * dt_critical [s]
  int iterations = 0;
};

/// \f$\Delta t_{crit} = (2/\omega_{max})(\sqrt{1+\xi^2} - \xi)\f$, \f$\xi = \beta\omega_{max}/2\f$ (= 2/omega_max for beta = 0).
double critical_time_step(double omega_max, double beta);

/// omega_max^2 = largest eigenvalue of \f$M^{-1/2} K M^{-1/2}\f$ over the DOFs with inverse_mass > 0,
/// by the Lanczos iteration (no reorthogonalisation: its largest Ritz value never exceeds the
/// largest eigenvalue, and converges much faster than the power iteration), from a fixed
/// pseudo-random start. K (symmetric positive semi-definite, over all DOFs) should include the contact springs all closed. InputError if no DOF moves.
/// With a distribution the vectors are a rank's local DOFs, `stiffness` returns completed products,
/// the start is the same function of the global DOF and the dot products are summed over the
/// ranks (distributed Lanczos: every rank finds the same omega_max up to summation order).
TimeStepEstimate estimate_time_step(const linalg::LinearOperator& stiffness, const VectorX& inverse_mass, double beta,
                                    const TimeStepOptions& options = {}, const Distribution* distribution = nullptr);

}  // namespace crackle::transient
