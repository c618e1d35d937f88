#include "transient/time_step.hpp"

#include <cmath>
#include <vector>

#include "core/errors.hpp"
#include "linalg/lanczos.hpp"

namespace crackle::transient {

double critical_time_step(double omega_max, double beta) {
  const double xi = 0.5 * beta * omega_max;
  // (sqrt(1 + xi^2) - xi) written without cancellation for large xi.
  return (2.0 / omega_max) / (std::sqrt(1.0 + xi * xi) + xi);
}

TimeStepEstimate estimate_time_step(const linalg::LinearOperator& stiffness, const VectorX& inverse_mass, double beta,
                                    const TimeStepOptions& options, const Distribution* distribution) {
  if (!(options.safety_factor > 0.0 && options.safety_factor <= 1.0) || !(options.margin >= 0.0)) {
    throw InputError("time step: expected 0 < safety_factor <= 1 and margin >= 0, got safety_factor = " +
                     format_number(options.safety_factor) + ", margin = " + format_number(options.margin));
  }
  const Index n = static_cast<Index>(inverse_mass.size());
  // Sums count the owned DOFs [0, owned) and add over the ranks.
  const Index owned = distribution ? distribution->n_owned_dofs() : n;
  const VectorX scale = inverse_mass.cwiseMax(0.0).cwiseSqrt();
  // Deterministic pseudo-random start on the moving DOFs, a function of the global DOF.
  VectorX q(n);
  {
    const Index n_global = distribution ? distribution->n_global_dofs() : n;
    std::vector<double> sequence(n_global);
    std::uint64_t state = 0x9E3779B97F4A7C15ULL;
    for (Index k = 0; k < n_global; ++k) {
      state = state * 6364136223846793005ULL + 1442695040888963407ULL;
      sequence[k] = static_cast<double>(state >> 11) / 9007199254740992.0 - 0.5;
    }
    for (Index k = 0; k < n; ++k) {
      q[k] = scale[k] > 0.0 ? sequence[distribution ? distribution->global_dofs()[k] : k] : 0.0;
    }
  }
  linalg::VectorShares shares;
  if (distribution) shares = {owned, [distribution](std::vector<double>& values) { distribution->sum(values); }};
  const linalg::LanczosResult lanczos = linalg::lanczos_largest(
      stiffness, scale, std::move(q), {options.max_iterations, options.tolerance}, distribution ? &shares : nullptr);
  if (lanczos.zero_start) throw InputError("time step: every degree of freedom is held, nothing can move");
  const double largest = lanczos.largest;
  if (!(largest > 0.0) || !std::isfinite(largest)) {
    throw SolverError("time step: the largest eigenvalue of M^-1 K came out as " + format_number(largest) +
                      " (stiffness not positive, or NaN in the model)");
  }
  TimeStepEstimate estimate;
  estimate.iterations = lanczos.iterations;
  estimate.omega_ritz = std::sqrt(largest);
  estimate.omega_max = (1.0 + options.margin) * estimate.omega_ritz;
  estimate.damping_ratio = 0.5 * beta * estimate.omega_max;
  estimate.dt_critical = critical_time_step(estimate.omega_max, beta);
  estimate.dt_stable = options.safety_factor * estimate.dt_critical;
  return estimate;
}

}  // namespace crackle::transient
