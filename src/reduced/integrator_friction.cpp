/// \file The reduced integrator's Coulomb friction (HYBRID.md sec. 3): the condensed pair equations
/// p = P(z(p)) by a semi-smooth Newton (penalty and return mapping, generalized Jacobian, line search)
/// falling back to rounds of projected Gauss-Seidel sweeps where it stalls; compiled apart from the
/// frictionless steps.
#include <Eigen/LU>
#include <algorithm>
#include <cmath>
#include <string>
#include <utility>

#include "contact_law/penalty.hpp"
#include "core/errors.hpp"
#include "reduced/integrator.hpp"
#include "reduced/integrator_detail.hpp"

namespace crackle::reduced {
using detail::kLocalNormal;
using detail::nonzero_rows;

double ReducedIntegrator::friction_map(const VectorX& p, const VectorX& free_gap, VectorX& gap, VectorX& projected,
                                      std::vector<FrictionJacobian>& jacobians) const {
  // g = g_free + W p over the loaded rows; per pair the trial forces z (normal -k_N g_N, tangential
  // the elastic predictor p_T^old - k_T (g_T - g_T^old)) and their projection P(z): the penalty
  // (eq. 25d) and Coulomb's return mapping (eq. 15) with the end-of-step pressure max(0, z_N).
  const Index n = system_.n_pairs();
  const double mu = system_.friction_coefficient;
  gap = free_gap;
  const std::vector<Index> loaded = nonzero_rows(p);
  for (const Index row : loaded) gap.noalias() += p[row] * w_.col(row);
  projected.setZero(p.size());
  jacobians.assign(n, FrictionJacobian{});
  double residual = 0.0;
  for (Index i = 0; i < n; ++i) {
    const Index r = 3 * i;
    const double trial_normal = -normal_stiffness_[i] * gap[r];
    if (normal_stiffness_[i] > 0.0 && trial_normal > 0.0) {
      const double area = system_.pair_area[i];
      const contact::CoulombUpdate update = contact::coulomb_return_mapping(
          Vec3(0.0, p_old_[r + 1], p_old_[r + 2]) / area,
          Vec3(0.0, gap[r + 1] - g_old_[r + 1], gap[r + 2] - g_old_[r + 2]), kLocalNormal,
          system_.tangential_penalty, mu, trial_normal / area);
      projected[r] = trial_normal;
      projected[r + 1] = area * update.traction[1];
      projected[r + 2] = area * update.traction[2];
      FrictionJacobian& jacobian = jacobians[i];
      jacobian.state = update.slipping ? PairState::kSlip : PairState::kStick;
      if (update.slipping) {
        const Eigen::Vector2d trial(p_old_[r + 1] - tangential_stiffness_[i] * (gap[r + 1] - g_old_[r + 1]),
                                    p_old_[r + 2] - tangential_stiffness_[i] * (gap[r + 2] - g_old_[r + 2]));
        jacobian.direction = trial.normalized();
        jacobian.radial_ratio = mu * trial_normal / trial.norm();
      }
    }
    for (Index j = 0; j < 3; ++j) residual = std::max(residual, std::abs(p[r + j] - projected[r + j]));
  }
  return residual;
}

VectorX ReducedIntegrator::friction_newton_direction(const VectorX& p, const VectorX& residual,
                                                     const std::vector<FrictionJacobian>& jacobians) {
  // Generalized Jacobian of F(p) = p - P(z0 - K W p): J = I + D K W, D = dP/dz per pair: 0 (open),
  // I (stick), or for slip (e the slip direction, beta = mu z_N / |z_T|)
  //   dP_N = dz_N,  dP_T = mu e dz_N + beta (I - e e^T) dz_T.
  // Open pairs' rows give delta = -F = -p. The closed pairs' rows, scaled by K^{-1} (E = K^{-1} D K):
  //   (K^{-1} + E W_AA) delta_A = -K^{-1} F_A + E W_AI p_I,
  // symmetric positive definite (Cholesky, cached) when every closed pair sticks, else LU.
  const Index n = system_.n_pairs();
  VectorX delta = -residual;
  std::vector<Index> rows, released;
  bool any_slip = false;
  for (Index i = 0; i < n; ++i) {
    if (jacobians[i].state == PairState::kOpen) {
      for (Index j = 0; j < 3; ++j)
        if (p[3 * i + j] != 0.0) released.push_back(3 * i + j);
      continue;
    }
    for (Index j = 0; j < 3; ++j) rows.push_back(3 * i + j);
    any_slip = any_slip || jacobians[i].state == PairState::kSlip;
  }
  if (rows.empty()) return delta;
  const Index size = static_cast<Index>(rows.size());
  const auto compliance = [&](Index row) {
    return 1.0 / (row % 3 == 0 ? normal_stiffness_[row / 3] : tangential_stiffness_[row / 3]);
  };
  VectorX coupling = VectorX::Zero(size);  // W_AI p_I
  if (!released.empty()) coupling = w_(rows, released) * p(released);
  VectorX rhs(size);
  for (Index k = 0; k < size; ++k) rhs[k] = -compliance(rows[k]) * residual[rows[k]];
  if (!any_slip) {
    rhs += coupling;
    if (!step_factor_.valid || step_factor_.rows != rows) {
      MatrixX matrix = w_(rows, rows);
      for (Index k = 0; k < size; ++k) matrix(k, k) += compliance(rows[k]);
      step_factor_.factor.compute(matrix);
      if (step_factor_.factor.info() != Eigen::Success) fail("Cholesky factor of the stick contact block failed");
      step_factor_.rows = rows;
      step_factor_.valid = true;
      ++total_factorizations_;
      total_factorized_rows_ += size;
      largest_factorized_rows_ = std::max(largest_factorized_rows_, static_cast<long>(size));
    }
    const VectorX solution = step_factor_.factor.solve(rhs);
    delta(rows) = solution;
    return delta;
  }
  MatrixX matrix = w_(rows, rows);
  for (Index k = 0; k < size; k += 3) {
    const FrictionJacobian& jacobian = jacobians[rows[k] / 3];
    if (jacobian.state != PairState::kSlip) {
      rhs.segment(k, 3) += coupling.segment(k, 3);
      continue;
    }
    // Tangential rows of E: [mu (k_N / k_T) e, beta (I - e e^T)] applied to the pair's (N, T) rows.
    const Index pair = rows[k] / 3;
    const Eigen::Vector2d e = jacobian.direction;
    const Eigen::Matrix2d transverse = jacobian.radial_ratio * (Eigen::Matrix2d::Identity() - e * e.transpose());
    const double ratio = system_.friction_coefficient * normal_stiffness_[pair] / tangential_stiffness_[pair];
    const MatrixX normal_row = matrix.row(k);
    const MatrixX tangent_rows = matrix.middleRows(k + 1, 2);
    matrix.middleRows(k + 1, 2) = ratio * e * normal_row + transverse * tangent_rows;
    rhs[k] += coupling[k];
    rhs.segment(k + 1, 2) += ratio * e * coupling[k] + transverse * coupling.segment(k + 1, 2);
  }
  for (Index k = 0; k < size; ++k) matrix(k, k) += compliance(rows[k]);
  const VectorX solution = matrix.partialPivLu().solve(rhs);
  delta(rows) = solution;
  ++total_factorizations_;
  total_factorized_rows_ += size;
  largest_factorized_rows_ = std::max(largest_factorized_rows_, static_cast<long>(size));
  return delta;
}

bool ReducedIntegrator::friction_converged(const FrictionIterate& iterate) const {
  return iterate.residual <= options_.force_tolerance * std::max(iterate.force.lpNorm<Eigen::Infinity>(),
                                                                 iterate.projected.lpNorm<Eigen::Infinity>());
}

void ReducedIntegrator::evaluate(const VectorX& free_gap, FrictionIterate& iterate) const {
  iterate.residual = friction_map(iterate.force, free_gap, iterate.gap, iterate.projected, iterate.jacobians);
}

bool ReducedIntegrator::friction_newton(const VectorX& free_gap, int budget, FrictionIterate& iterate, int& solves) {
  // Backtracking (Armijo) on the merit |K^{-1} F|^2 / 2, of which the Newton direction is a descent
  // direction where P is differentiable.
  const auto merit = [&](const FrictionIterate& at) {
    return 0.5 * (at.force - at.projected).cwiseProduct(row_compliance_).squaredNorm();
  };
  FrictionIterate trial;
  for (int k = 0; k < budget; ++k) {
    if (friction_converged(iterate)) return true;
    const VectorX delta = friction_newton_direction(iterate.force, iterate.force - iterate.projected,
                                                    iterate.jacobians);
    ++solves;
    const double current = merit(iterate);
    double step = 1.0;
    trial.force = iterate.force + delta;
    evaluate(free_gap, trial);
    while (step > options_.min_line_search_step && merit(trial) > (1.0 - 1e-4 * step) * current) {
      step *= 0.5;
      trial.force = iterate.force + step * delta;
      evaluate(free_gap, trial);
    }
    std::swap(iterate, trial);
  }
  return friction_converged(iterate);
}

void ReducedIntegrator::friction_gauss_seidel(const VectorX& free_gap, int sweeps, FrictionIterate& iterate) {
  // Projected Gauss-Seidel on the step's Delassus matrix H = K^{-1} + W, pair by pair: the normal row
  // p_N <- max(0, p_N - r_N / H_NN) with r = K^{-1} p + g (the penalty's complementarity), then the
  // tangential pair of rows minimised over the disc |p_T| <= mu p_N (Coulomb, eq. 15):
  // r_T = K_T^{-1} (p_T - p_T^old) + g_T - g_T^old, the 2 x 2 block's exact minimiser if it lies in the
  // disc, else a projected gradient step of length 1 / lambda_max. Its fixed points are the solutions
  // p = P(z(p)); the gaps follow each change (O(c) per row).
  const Index n = system_.n_pairs();
  const double mu = system_.friction_coefficient;
  VectorX& p = iterate.force;
  VectorX& g = iterate.gap;
  for (int sweep = 0; sweep < sweeps; ++sweep) {
    for (Index i = 0; i < n; ++i) {
      const Index r = 3 * i;
      if (!(normal_stiffness_[i] > 0.0)) continue;
      const double normal = std::max(0.0, p[r] - (p[r] / normal_stiffness_[i] + g[r]) /
                                                     (1.0 / normal_stiffness_[i] + w_(r, r)));
      if (normal != p[r]) {
        g.noalias() += (normal - p[r]) * w_.col(r);
        p[r] = normal;
      }
      const double kt = tangential_stiffness_[i];
      const Eigen::Vector2d old_force(p[r + 1], p[r + 2]);
      const Eigen::Vector2d gradient(
          (p[r + 1] - p_old_[r + 1]) / kt + g[r + 1] - g_old_[r + 1],
          (p[r + 2] - p_old_[r + 2]) / kt + g[r + 2] - g_old_[r + 2]);
      Eigen::Matrix2d block = w_.block(r + 1, r + 1, 2, 2);
      block.diagonal().array() += 1.0 / kt;
      const double limit = mu * p[r];
      Eigen::Vector2d force = old_force - block.ldlt().solve(gradient);
      if (force.norm() > limit) {
        // The larger eigenvalue of the symmetric 2 x 2 block, in closed form.
        const double mean = 0.5 * (block(0, 0) + block(1, 1)), half = 0.5 * (block(0, 0) - block(1, 1));
        const double largest = mean + std::hypot(half, block(0, 1));
        force = old_force - gradient / largest;
        const double norm = force.norm();
        if (norm > limit) force *= norm > 0.0 ? limit / norm : 0.0;
      }
      const Eigen::Vector2d change = force - old_force;
      if (change.squaredNorm() > 0.0) {
        g.noalias() += w_.middleCols(r + 1, 2) * change;
        p[r + 1] = force[0];
        p[r + 2] = force[1];
      }
    }
  }
  ++total_gauss_seidel_rounds_;
  evaluate(free_gap, iterate);
}

void ReducedIntegrator::solve_with_friction(const VectorX& free_gap) {
  // Semi-smooth Newton on F(p) = p - P(z(p)) = 0 (friction_map), warm-started from the previous step:
  // one or two solves while the stick/slip/open states hold. Where the states change, Newton can stall
  // or cycle at the kinks of P on many coupled pairs; then rounds of projected Gauss-Seidel sweeps
  // (robust, linear) bring the iterate near the solution and Newton finishes it.
  FrictionIterate iterate;
  iterate.force = p_;
  evaluate(free_gap, iterate);
  const FrictionIterate start = iterate;
  int solves = 0, rounds = 0;
  bool converged = friction_newton(free_gap, options_.newton_iterations, iterate, solves);
  if (!converged) iterate = start;  // Newton may have wandered off: the sweeps restart from the warm start
  while (!converged) {
    if (rounds == options_.max_gauss_seidel_rounds)
      fail(("friction solve did not converge in " + std::to_string(solves) + " Newton solves and " +
            std::to_string(rounds * options_.gauss_seidel_sweeps) + " Gauss-Seidel sweeps (residual " +
            format_number(iterate.residual) + " N)")
               .c_str());
    friction_gauss_seidel(free_gap, options_.gauss_seidel_sweeps, iterate);
    ++rounds;
    converged = friction_converged(iterate);
    if (converged) break;
    FrictionIterate polished = iterate;  // a Newton finish from the sweeps' iterate, kept only if it converges
    if (friction_newton(free_gap, options_.newton_iterations, polished, solves)) {
      iterate = std::move(polished);
      converged = true;
    }
  }
  // The solution p = P(z(p)) to the tolerance, and its gaps. (Storing P instead, and recomputing the
  // gaps, would amplify the residual by eps_N A W.)
  p_ = iterate.force;
  g_ = iterate.gap;
  for (Index i = 0; i < system_.n_pairs(); ++i) state_[i] = iterate.jacobians[i].state;
  last_iterations_ = std::max(solves + rounds * options_.gauss_seidel_sweeps, 1);
  total_iterations_ += last_iterations_;
}

}  // namespace crackle::reduced
