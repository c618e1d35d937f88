#pragma once
/// \file Rayleigh damping C = alpha M + beta K, MODEL.md eq. (26).

#include <optional>

namespace crackle::transient {

/// Coefficients of \f$C = \alpha M + \beta K\f$: alpha [1/s], beta [s].
struct RayleighDamping {
  double alpha = 0.0;
  double beta = 0.0;
};

/// Mass-proportional damping with ratio xi at angular frequency omega [rad/s]: alpha = 2 xi omega
/// (the default choice: it costs nothing per step and does not shrink the stable time step).
RayleighDamping mass_proportional_damping(double ratio, double omega);

/// Stiffness-proportional damping with ratio xi at omega: beta = 2 xi / omega. It damps the highest
/// frequencies most, shrinks the stable time step (see critical_time_step) and costs a second
/// K product per step.
RayleighDamping stiffness_proportional_damping(double ratio, double omega);

/// The damping a scene states (transient.damping): a ratio at a frequency `at_hz` [Hz], mass- or
/// (`stiffness`) stiffness-proportional, or without a ratio alpha and beta as given. The one place a scene's
/// damping becomes C (crackle run, the reduced model, identify's damping_ratio quantity).
RayleighDamping stated_damping(std::optional<double> ratio, bool stiffness, double at_hz, double alpha, double beta);

/// Modal damping ratio of C at angular frequency omega: \f$\xi = \alpha/(2\omega) + \beta\omega/2\f$.
double damping_ratio(const RayleighDamping& damping, double omega);

/// InputError unless alpha >= 0 and beta >= 0 (finite).
void check_damping(const RayleighDamping& damping);

}  // namespace crackle::transient
