#include "transient/time_step.hpp"

#include <Eigen/Eigenvalues>
#include <cmath>
#include <vector>

#include "core/errors.hpp"

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
  const auto global_sums = [&](std::vector<double> values) {
    if (distribution) distribution->sum(values);
    return values;
  };
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
  const double start_norm = std::sqrt(global_sums({q.head(owned).squaredNorm()})[0]);
  if (!(start_norm > 0.0)) throw InputError("time step: every degree of freedom is held, nothing can move");
  q /= start_norm;
  // Three fused passes per iteration (the iteration is memory-bound on large meshes).
  VectorX q_previous = VectorX::Zero(n), w(n), scaled = scale.cwiseProduct(q), product(n);
  std::vector<double> diagonal, off_diagonal;
  double largest = 0.0, largest_before = 0.0;
  int iteration = 0;
  for (; iteration < options.max_iterations; ++iteration) {
    stiffness.apply(scaled, product);
    const double b_previous = off_diagonal.empty() ? 0.0 : off_diagonal.back();
    double a = 0.0;
#pragma omp parallel for schedule(static) reduction(+ : a) if (n > 100000)
    for (Index k = 0; k < n; ++k) {
      w[k] = scale[k] * product[k] - b_previous * q_previous[k];
      if (k < owned) a += w[k] * q[k];
    }
    if (distribution) a = global_sums({a})[0];
    double norm_squared = 0.0;
#pragma omp parallel for schedule(static) reduction(+ : norm_squared) if (n > 100000)
    for (Index k = 0; k < n; ++k) {
      w[k] -= a * q[k];
      if (k < owned) norm_squared += w[k] * w[k];
    }
    if (distribution) norm_squared = global_sums({norm_squared})[0];
    const double b = std::sqrt(norm_squared);
    diagonal.push_back(a);
    const bool exhausted = !(b > 1e-14 * std::abs(a));
    if ((iteration + 1) % 10 == 0 || exhausted || iteration + 1 == options.max_iterations) {
      const Index size = static_cast<Index>(diagonal.size());
      Eigen::SelfAdjointEigenSolver<MatrixX> solver;
      VectorX d = Eigen::Map<const VectorX>(diagonal.data(), size);
      VectorX e = size > 1 ? VectorX(Eigen::Map<const VectorX>(off_diagonal.data(), size - 1)) : VectorX();
      solver.computeFromTridiagonal(d, e, Eigen::EigenvaluesOnly);
      largest = solver.eigenvalues().maxCoeff();
      if (exhausted || (largest_before > 0.0 && largest - largest_before <= options.tolerance * largest)) {
        ++iteration;
        break;
      }
      largest_before = largest;
    }
    off_diagonal.push_back(b);
    const double inverse_b = 1.0 / b;
#pragma omp parallel for schedule(static) if (n > 100000)
    for (Index k = 0; k < n; ++k) {
      q_previous[k] = q[k];
      q[k] = w[k] * inverse_b;
      scaled[k] = scale[k] * q[k];
    }
  }
  if (!(largest > 0.0) || !std::isfinite(largest)) {
    throw SolverError("time step: the largest eigenvalue of M^-1 K came out as " + format_number(largest) +
                      " (stiffness not positive, or NaN in the model)");
  }
  TimeStepEstimate estimate;
  estimate.iterations = iteration;
  estimate.omega_ritz = std::sqrt(largest);
  estimate.omega_max = (1.0 + options.margin) * estimate.omega_ritz;
  estimate.damping_ratio = 0.5 * beta * estimate.omega_max;
  estimate.dt_critical = critical_time_step(estimate.omega_max, beta);
  estimate.dt_stable = options.safety_factor * estimate.dt_critical;
  return estimate;
}

}  // namespace crackle::transient
