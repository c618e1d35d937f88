// The frictionless contact solve of the reduced transient against a reference: the dense primal-dual
// active set it replaced (kept here), which solves the same piecewise-linear problem per step
//   p >= 0,  K^{-1} p + g >= 0,  p^T (K^{-1} p + g) = 0,  g = g~ + W p   (K = eps_N A),
// refactorising every new active set. The problem has one solution, so both must give the same
// forces and gaps to round-off at every pair and step, and the updated factor must cost less
// factorisation work (a counter, not a timing).
#include <gtest/gtest.h>

#include <Eigen/Cholesky>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <random>
#include <vector>

#include "contact/contact.hpp"
#include "fem/material.hpp"
#include "fem/system.hpp"
#include "mesh/box.hpp"
#include "delaminated_plate.hpp"
#include "reduced/integrator.hpp"
#include "reduction/reduction.hpp"

namespace crackle::reduced {
namespace {


/// The reference: the primal-dual active set on the normal rows (one row per pair), warm-started from
/// `warm`, each new set factorised densely (the integrator's solve before 2026-12-02).
struct DenseActiveSet {
  VectorX force, gap;
  long largest_set = 0;  ///< rows of the largest set factorised
  double work = 0.0;     ///< floating-point operations of its factorisations, |A|^3/3 each (cache hits free)
  int iterations = 0;
};

DenseActiveSet dense_active_set(const MatrixX& w, const VectorX& stiffness, const VectorX& free_gap,
                                const VectorX& warm) {
  const Index n = free_gap.size();
  DenseActiveSet result;
  std::vector<char> active(n);
  for (Index i = 0; i < n; ++i) active[i] = warm[i] > 0.0;
  for (result.iterations = 1; result.iterations <= 1000; ++result.iterations) {
    std::vector<Index> rows;
    for (Index i = 0; i < n; ++i)
      if (active[i]) rows.push_back(i);
    result.force = VectorX::Zero(n);
    result.gap = free_gap;
    if (!rows.empty()) {
      MatrixX matrix = w(rows, rows);
      for (std::size_t k = 0; k < rows.size(); ++k) matrix(k, k) += 1.0 / stiffness[rows[k]];
      const VectorX x = Eigen::LLT<MatrixX>(matrix).solve(-free_gap(rows));
      result.force(rows) = x;
      result.gap += w(Eigen::all, rows) * x;
      result.largest_set = std::max(result.largest_set, static_cast<long>(rows.size()));
      // The first set is the previous step's final one, whose factor the old solve had cached.
      if (result.iterations > 1) result.work += std::pow(static_cast<double>(rows.size()), 3) / 3.0;
    }
    bool changed = false;
    for (Index i = 0; i < n; ++i) {
      const bool now = active[i] ? result.force[i] > 0.0 : result.gap[i] < 0.0;
      changed = changed || now != static_cast<bool>(active[i]);
      active[i] = now;
    }
    if (!changed) return result;
  }
  ADD_FAILURE() << "reference active set did not settle";
  return result;
}

/// Worst deviations of a run from the reference and from the complementarity conditions.
struct Comparison {
  double force = 0.0;           ///< max |p - p_ref| / max|p_ref| over pairs and steps
  double gap = 0.0;             ///< max |g - g_ref| / max|g~| (free gaps)
  double complementarity = 0.0; ///< max |p - eps A max(0, -g)| / max|p|
  double negative = 0.0;        ///< most negative force [N]
  long reference_largest = 0;   ///< the reference's largest factorised set (warm-started as it was)
  double reference_work = 0.0;  ///< the reference's factorisation work, summed over the steps
  long largest_final = 0;       ///< the largest final active set
  long changes = 0;             ///< rows entering or leaving the final set, summed over the steps
};

/// Steps `integrator` `n_steps` times; at each step recovers the free gaps g~ = g - W p and solves the
/// step's problem again with the reference, warm-started from the previous step's forces as before.
Comparison compare_with_reference(ReducedIntegrator& integrator, const ReducedSystem& system, int n_steps) {
  const MatrixX& w = integrator.step_compliance();
  const VectorX stiffness = system.normal_penalty * system.pair_area;
  Comparison result;
  VectorX previous = integrator.pair_forces();
  for (int k = 0; k < n_steps; ++k) {
    integrator.step();
    const VectorX& p = integrator.pair_forces();
    const VectorX& g = integrator.gaps();
    const VectorX free_gap = g - w * p;
    const DenseActiveSet reference = dense_active_set(w, stiffness, free_gap, previous);
    const double force_scale = std::max(reference.force.lpNorm<Eigen::Infinity>(), 1e-300);
    result.force = std::max(result.force, (p - reference.force).lpNorm<Eigen::Infinity>() / force_scale);
    result.gap = std::max(result.gap, (g - reference.gap).lpNorm<Eigen::Infinity>() /
                                          std::max(free_gap.lpNorm<Eigen::Infinity>(), 1e-300));
    const VectorX law = stiffness.cwiseProduct((-g).cwiseMax(0.0));
    result.complementarity =
        std::max(result.complementarity, (p - law).lpNorm<Eigen::Infinity>() / std::max(p.lpNorm<Eigen::Infinity>(), 1e-300));
    result.negative = std::min(result.negative, p.minCoeff());
    result.reference_largest = std::max(result.reference_largest, reference.largest_set);
    result.reference_work += reference.work;
    long closed = 0;
    for (Index i = 0; i < p.size(); ++i) {
      closed += p[i] > 0.0;
      result.changes += (p[i] > 0.0) != (previous[i] > 0.0);
    }
    result.largest_final = std::max(result.largest_final, closed);
    previous = p;
  }
  return result;
}

// bench_reduced's body (a steel plate clamped on x-, a mid-plane delamination over its free half
// opened and closed by a harmonic pull on the free end), 16 x 16 x 2 cells: 136 pairs, 10 modes. The
// steps follow the highest retained mode, so with few modes they are long: the free gaps of most of
// the delamination go negative in a closing step while the final set is a few pairs near the tip.
TEST(ReducedActiveSet, PlateWithLongStepsMatchesTheDenseActiveSetForLessWork) {
  const testing::DelaminatedPlate plate = testing::delaminated_plate(16, 10);
  ReducedSystem reduced = reduced_system(plate.reduction, 10, 1.0);
  reduced.normal_penalty = plate.penalty.normal_penalty;
  ASSERT_EQ(reduced.n_pairs(), 136);

  const int steps_per_period = 200;
  const double h = reduced_time_step(reduced, 0.0), frequency = 1.0 / (steps_per_period * h);
  ReducedIntegrator integrator(reduced, h, [frequency](double t) { return std::sin(2.0 * kPi * frequency * t); });
  const Comparison comparison = compare_with_reference(integrator, reduced, 2 * steps_per_period);
  std::printf("plate, 136 pairs, 10 modes: |p - p_ref| %.1e, |g - g_ref| %.1e, complementarity %.1e, min p %.1e N; "
              "largest final set %ld, reference's largest factorised set %ld, new %ld; factorisation work %.3g "
              "flop (reference %.3g, ratio %.2f); %ld factorisations, %ld row updates, %.2f iterations per step\n",
              comparison.force, comparison.gap, comparison.complementarity, comparison.negative,
              comparison.largest_final, comparison.reference_largest, integrator.largest_factorized_rows(),
              integrator.total_factor_work(), comparison.reference_work,
              integrator.total_factor_work() / comparison.reference_work, integrator.total_factorizations(),
              integrator.total_factor_updates(), double(integrator.total_iterations()) / integrator.n_steps_taken());
  // The same solution to round-off; the penalty law p = eps A max(0, -g) holds to the amplification
  // of round-off by eps A W (as in the friction test).
  EXPECT_LT(comparison.force, 1e-10);
  EXPECT_LT(comparison.gap, 1e-10);
  EXPECT_LT(comparison.complementarity, 1e-8);
  EXPECT_GE(comparison.negative, 0.0);
  // The case the change is for: long steps, intermediate sets larger than the final ones, the whole
  // crack closing at the impacts. The updated factor does less work than the refactorisations (the
  // warm set's, cached, counted free) and never holds a larger set than they factorised.
  EXPECT_EQ(comparison.largest_final, 136);
  EXPECT_LT(integrator.total_factor_work(), 0.8 * comparison.reference_work);  // measured 0.70
  EXPECT_LE(integrator.largest_factorized_rows(), comparison.reference_largest);
}

/// m modes and c strongly coupled pairs, random but reproducible: R = A A^T / c + 1e-3 I (SPD), B Phi
/// and the load random, small random initial gaps (some pairs preloaded).
ReducedSystem random_system(Index m, Index c) {
  std::mt19937 generator(12345);
  std::uniform_real_distribution<double> uniform(-1.0, 1.0);
  const auto random = [&](Index rows, Index cols) {
    return MatrixX::NullaryExpr(rows, cols, [&]() { return uniform(generator); }).eval();
  };
  ReducedSystem system;
  system.omega = VectorX::LinSpaced(m, 2.0 * kPi, 2.0 * kPi * m);
  system.rayleigh_alpha = 0.1;
  system.pair_area = VectorX::Ones(c) + 0.5 * random(c, 1);
  system.initial_gap = 1e-3 * random(c, 1);
  system.normal_penalty = 1e3;
  system.pair_modes = random(c, m);
  const MatrixX a = random(c, c);
  system.residual = a * a.transpose() / c + 1e-3 * MatrixX::Identity(c, c);
  system.load_modal = random(m, 1);
  system.load_residual = 1e-2 * random(c, 1);
  system.output_modes = MatrixX(0, m);
  system.output_residual_pairs = MatrixX(0, c);
  system.output_residual_load = VectorX(0);
  return system;
}

// Densely coupled pairs, a preloaded start (the first step rebuilds the factor of its warm set) and
// steps long against the modes: many rows enter and leave per step.
TEST(ReducedActiveSet, RandomCoupledPairsMatchTheDenseActiveSetAtEveryStep) {
  const ReducedSystem system = random_system(6, 60);
  const double h = 0.05;
  ReducedIntegrator integrator(system, h, [](double t) { return 3.0 * std::sin(2.0 * kPi * 1.3 * t); });
  VectorX q0 = VectorX::Zero(6);
  q0[0] = -2e-3;  // presses part of the pairs closed at t = 0
  integrator.set_initial_state(q0, VectorX::Zero(6));
  const Index closed_at_start = integrator.n_closed();
  const Comparison comparison = compare_with_reference(integrator, system, 400);
  std::printf("random, 60 pairs, 6 modes: %lld closed at t0; |p - p_ref| %.1e, |g - g_ref| %.1e, complementarity "
              "%.1e; largest final set %ld, reference's largest %ld, new %ld; %ld set changes; factorisation work "
              "%.3g flop (reference %.3g, ratio %.2f)\n",
              static_cast<long long>(closed_at_start), comparison.force, comparison.gap, comparison.complementarity,
              comparison.largest_final, comparison.reference_largest, integrator.largest_factorized_rows(),
              comparison.changes, integrator.total_factor_work(), comparison.reference_work,
              integrator.total_factor_work() / comparison.reference_work);
  EXPECT_GT(closed_at_start, 0);
  EXPECT_GT(comparison.changes, 400);
  EXPECT_LT(comparison.force, 1e-10);
  EXPECT_LT(comparison.gap, 1e-10);
  EXPECT_LT(comparison.complementarity, 1e-10);
  EXPECT_GE(comparison.negative, 0.0);
  EXPECT_LT(integrator.total_factor_work(), 0.6 * comparison.reference_work);  // measured 0.49
}

}  // namespace
}  // namespace crackle::reduced
