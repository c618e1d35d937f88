// The full model's stick/slip block test (tests/transient/test_friction.cpp) on the reduced model
// reduced from the same mesh: a block on a base, cut by a crack plane with Coulomb friction
// (MODEL.md eq. 15) and squeezed by a negative gap, slides from v0 and decelerates at mu N / m.
// The block is free in x, y and about z: its rigid-body modes are modes of frequency 0 of the
// reduction, the static images those of the elastic flexibility.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <string>

#include "contact/contact.hpp"
#include "contact_law/penalty.hpp"
#include "core/errors.hpp"
#include "fem/material.hpp"
#include "fem/system.hpp"
#include "mesh/box.hpp"
#include "delaminated_plate.hpp"
#include "reduced/integrator.hpp"
#include "reduction/reduction.hpp"

namespace crackle::reduced {
namespace {

// The full test's block: 0.1 x 0.1 base of height 0.05 under a 0.02 block, nu = 0, sigma = -1 MPa.
constexpr double kWidth = 0.1, kBase = 0.05, kHeight = 0.07, kYoung = 2e11, kDensity = 7800.0;
constexpr double kStress = -1e6, kFriction = 0.3;

/// The block's reduced model and its initial state (preload and v0), as the full test sets them.
struct ReducedBlock {
  Reduction reduction;
  ReducedSystem system;
  VectorX q0, v0_modal;
  VectorX block_row;  ///< block mean x velocity = block_row . q'
  Index n_rigid = 0;
  double v0 = 0.1, normal_force = 0.0, deceleration = 0.0;
};

ReducedBlock reduced_block() {
  ReducedBlock block;
  mesh::BoxSpec box;
  box.size = Vec3(kWidth, kWidth, kHeight);
  box.cells = {4, 4, 7};
  mesh::CrackSpec crack;
  crack.normal = kZ;
  crack.at = kBase;
  crack.region = {{{0.0, kWidth}, {0.0, kWidth}, {0.0, 0.0}}};
  const mesh::Mesh mesh = mesh::build_box_mesh(box, crack);
  const fem::Materials materials = {fem::isotropic(kYoung, 0.0, kDensity)};
  const std::vector<fem::DirichletCondition> conditions = {
      {mesh.node_sets.at("z-"), {0, 1, 2}, {0.0, 0.0, 0.0}, "base"},
      {mesh.node_sets.at("z+"), {2}, {0.0}, "roller"}};
  const fem::System system(mesh, materials, conditions, mesh::Variant::open);
  ReductionOptions options;
  options.modes = 20;
  options.friction = true;
  block.reduction = compute_reduction(system, options, {}, fem::LoadShape{"none", {}, {}});
  const Reduction& reduction = block.reduction;
  while (block.n_rigid < reduction.omega.size() && reduction.omega[block.n_rigid] == 0.0) ++block.n_rigid;

  contact::ContactOptions contact;
  contact.friction_coefficient = kFriction;
  const contact::PenaltyChoice penalty = contact::choose_penalty(mesh, materials, contact);
  block.system = reduced_system(reduction, reduction.n_computed_modes(), 0.0);
  ReducedSystem& reduced = block.system;
  reduced.normal_penalty = penalty.normal_penalty;
  reduced.tangential_penalty = penalty.tangential_penalty;
  reduced.friction_coefficient = kFriction;
  // sigma = eps g0 / (1 + eps H / E)  =>  g0 for the wanted sigma (as the full test).
  reduced.initial_gap.setConstant(kStress * (1.0 + penalty.normal_penalty * kHeight / kYoung) / penalty.normal_penalty);

  // Initial state: the full test's preloaded field (exact uniaxial compression) and the block's
  // velocity v0 along x, projected on the modes; block mean velocity = w^T Phi q' (w: the block's
  // x masses over its mass).
  const mesh::DofMap& dofs = system.dofs();
  const fem::Constraints& constraints = system.constraints();
  const auto on_block = [&](Index node) {
    return node >= mesh.n_original_nodes || mesh.nodes[node].z() > kBase + 1e-9;
  };
  VectorX displacement = VectorX::Zero(system.n_dofs()), velocity = VectorX::Zero(system.n_dofs());
  VectorX weight = VectorX::Zero(system.n_dofs());
  const VectorX lumped = system.lumped_mass();
  double block_mass = 0.0;
  for (Index node = 0; node < mesh.n_nodes(); ++node) {
    const double z = mesh.nodes[node].z();
    displacement[dofs.dof(node, 2)] = on_block(node) ? -kStress * (kHeight - z) / kYoung : kStress * z / kYoung;
    if (!on_block(node)) continue;
    velocity[dofs.dof(node, 0)] = block.v0;
    weight[dofs.dof(node, 0)] = lumped[dofs.dof(node, 0)];
    block_mass += lumped[dofs.dof(node, 0)];
  }
  const Index m = reduced.n_modes();
  block.q0 = reduction.modal_coordinates(fem::restrict_to_free(displacement, constraints), m);
  block.v0_modal = reduction.modal_coordinates(fem::restrict_to_free(velocity, constraints), m);
  block.block_row = reduction.shapes.transpose() * fem::restrict_to_free(weight, constraints) / block_mass;
  block.normal_force = -kStress * kWidth * kWidth;
  block.deceleration = kFriction * block.normal_force / (kDensity * kWidth * kWidth * (kHeight - kBase));
  return block;
}

// The free block's rigid-body modes are kept (frequency 0) and the elastic flexibility carries the
// preload: at t = 0 every pair is closed with the normal forces summing to N, and the block's rigid
// x translation carries v0 exactly.
TEST(ReductionFriction, FreeBlockKeepsItsRigidModesThePreloadAndItsVelocity) {
  const ReducedBlock block = reduced_block();
  EXPECT_EQ(block.n_rigid, 3);  // the block's x, y translations and its rotation about z
  ReducedIntegrator integrator(block.system, 1e-7, [](double) { return 0.0; });
  integrator.set_initial_state(block.q0, block.v0_modal);
  double normal_sum = 0.0;
  for (Index i = 0; i < block.system.n_pairs(); ++i) normal_sum += integrator.pair_forces()[3 * i];
  std::printf("reduced block: %lld modes (%lld rigid), %lld pairs, preload %.6e N (N = %.6e N)\n",
              static_cast<long long>(block.system.n_modes()), static_cast<long long>(block.n_rigid),
              static_cast<long long>(block.system.n_pairs()), normal_sum, block.normal_force);
  EXPECT_EQ(integrator.n_closed(), block.system.n_pairs());
  // The penalty preload is exact in the reduced model (static images of the elastic flexibility):
  // to the fixed point's tolerance.
  EXPECT_NEAR(normal_sum / block.normal_force, 1.0, 1e-6);
  EXPECT_NEAR(block.block_row.dot(integrator.modal_velocity()) / block.v0, 1.0, 1e-12);
}

// The cross-test proper: every pair slips together through the dense flexibility (25 coupled pairs,
// 75 rows), then the block stops and the pairs stick and slip back and forth about it (the case where
// a stick/slip fixed point on frozen slip directions cycles).
TEST(ReductionFriction, SlidingBlockDeceleratesAtMuNOverMAsInTheFullModel) {
  const ReducedBlock block = reduced_block();
  const double stop = block.v0 / block.deceleration;
  ReducedIntegrator integrator(block.system, stop / 400.0, [](double) { return 0.0; });
  integrator.set_initial_state(block.q0, block.v0_modal);
  std::vector<double> times, speeds;
  double late_mean = 0.0;
  int late_count = 0;
  int largest_iterations = 0;
  while (integrator.time() < 2.0 * stop) {
    integrator.step();
    largest_iterations = std::max(largest_iterations, integrator.last_iterations());
    const double t = integrator.time(), v = block.block_row.dot(integrator.modal_velocity());
    if (t > 0.1 * stop && t < 0.7 * stop) {
      times.push_back(t);
      speeds.push_back(v);
    }
    if (t > 1.2 * stop) {
      late_mean += v;
      ++late_count;
    }
  }
  late_mean /= late_count;
  double mt = 0.0, mv = 0.0;
  for (std::size_t k = 0; k < times.size(); ++k) mt += times[k], mv += speeds[k];
  mt /= times.size();
  mv /= speeds.size();
  double num = 0.0, den = 0.0;
  for (std::size_t k = 0; k < times.size(); ++k) num += (times[k] - mt) * (speeds[k] - mv), den += (times[k] - mt) * (times[k] - mt);
  const double measured = -num / den;
  std::printf("reduced block: deceleration %.2f m/s^2 (mu N / m = %.2f), after the stop mean velocity %.2e m/s; "
              "%lld steps, %.2f Newton iterations per step (largest %d), %.3f factorisations and %.3f Gauss-Seidel rounds "
              "per step, energy error %.2e\n",
              measured, block.deceleration, late_mean, static_cast<long long>(integrator.n_steps_taken()),
              double(integrator.total_iterations()) / integrator.n_steps_taken(), largest_iterations,
              double(integrator.total_factorizations()) / integrator.n_steps_taken(),
              double(integrator.total_gauss_seidel_rounds()) / integrator.n_steps_taken(), integrator.energy_error());
  // The full test's tolerances (2 % on the deceleration, 2 % of v0 after the stop).
  EXPECT_NEAR(measured / block.deceleration, 1.0, 0.02);
  EXPECT_LT(std::abs(late_mean), 0.02 * block.v0);
}

// Many coupled pairs, slipping and sticking in turn: a steel plate clamped on x- with a mid-plane
// delamination over its free half (bench_reduced's body, 8 x 8 x 2 cells: 36 pairs, 108 rows) under a
// harmonic z force on the free end's top edge. Bending slides the two sublaminates over each other
// (the closed half-period) and opens them (the other). At every step every pair must satisfy the
// contact law to the solver's tolerance: the penalty p_N = eps_N A max(0, -g_N) and Coulomb's return
// mapping (eq. 15) of the step's tangential increment, recomputed here by contact::coulomb_return_mapping
// (relative to the largest pair force; the solver stops at 1e-9).
TEST(ReductionFriction, ManyCoupledPairsSatisfyThePenaltyAndCoulombAtEveryPairAndStep) {
  contact::ContactOptions contact;
  contact.friction_coefficient = kFriction;
  const testing::DelaminatedPlate plate = testing::delaminated_plate(8, 20, contact);
  const contact::PenaltyChoice& penalty = plate.penalty;
  ReducedSystem reduced = reduced_system(plate.reduction, 20, 1e3);
  reduced.normal_penalty = penalty.normal_penalty;
  reduced.tangential_penalty = penalty.tangential_penalty;
  reduced.friction_coefficient = kFriction;
  const Index n = reduced.n_pairs();
  ASSERT_EQ(n, 36);

  const int steps_per_period = 200;
  const double h = reduced_time_step(reduced, 0.0), frequency = 1.0 / (steps_per_period * h);
  const auto force = [frequency](double t) { return std::sin(2.0 * 3.14159265358979 * frequency * t); };
  // The same run frictionless: its energy error is round-off (the switching steps conserve energy);
  // friction must add none (its dissipation is exact per step).
  ReducedSystem frictionless = reduced;
  frictionless.friction_coefficient = 0.0;
  ReducedIntegrator reference(frictionless, h, force);
  reference.advance(2 * steps_per_period);
  ReducedIntegrator integrator(reduced, h, force);
  VectorX p_old = integrator.pair_forces(), g_old = integrator.gaps();
  double worst_normal = 0.0, worst_tangential = 0.0, worst_cone = 0.0;
  long slip_steps = 0, stick_steps = 0, iterations = 0;
  int largest = 0;
  for (int k = 0; k < 2 * steps_per_period; ++k) {
    integrator.step();
    const VectorX& p = integrator.pair_forces();
    const VectorX& g = integrator.gaps();
    const double scale = std::max(p.lpNorm<Eigen::Infinity>(), 1e-300);
    for (Index i = 0; i < n; ++i) {
      const Index r = 3 * i;
      const double area = reduced.pair_area[i];
      const double normal = reduced.normal_penalty * area * std::max(0.0, -g[r]);
      worst_normal = std::max(worst_normal, std::abs(p[r] - normal) / scale);
      const contact::CoulombUpdate update = contact::coulomb_return_mapping(
          Vec3(0.0, p_old[r + 1], p_old[r + 2]) / area, Vec3(0.0, g[r + 1] - g_old[r + 1], g[r + 2] - g_old[r + 2]),
          Vec3::UnitX(), reduced.tangential_penalty, kFriction, normal / area);
      worst_tangential = std::max(
          worst_tangential, (Vec3(0.0, p[r + 1], p[r + 2]) - area * update.traction).norm() / scale);
      worst_cone = std::max(worst_cone, (std::hypot(p[r + 1], p[r + 2]) - kFriction * p[r]) / scale);
    }
    if (integrator.n_slipping() > 0) ++slip_steps;
    if (integrator.n_closed() > integrator.n_slipping()) ++stick_steps;
    iterations += integrator.last_iterations();
    largest = std::max(largest, integrator.last_iterations());
    p_old = p;
    g_old = g;
  }
  std::printf("plate: %lld pairs, %lld steps with slip, %lld with stick, %.2f iterations per step (largest %d), "
              "%ld Gauss-Seidel rounds, %.2f factorisations per step; worst relative |p_N - eps A max(0,-g)| %.1e, "
              "|p_T - return mapping| %.1e, |p_T| - mu p_N %.1e; energy error %.2e (frictionless %.2e), friction dissipation "
              "%.2e J\n",
              static_cast<long long>(n), slip_steps, stick_steps, double(iterations) / (2 * steps_per_period), largest,
              integrator.total_gauss_seidel_rounds(), double(integrator.total_factorizations()) / (2 * steps_per_period),
              worst_normal, worst_tangential, worst_cone, integrator.energy_error(), reference.energy_error(),
              integrator.energy().friction_dissipation);
  EXPECT_GT(slip_steps, 20);
  EXPECT_GT(stick_steps, 20);
  EXPECT_LT(worst_normal, 1e-8);
  EXPECT_LT(worst_tangential, 1e-8);
  EXPECT_LT(worst_cone, 1e-9);  // the solver's force tolerance
  EXPECT_GT(integrator.energy().friction_dissipation, 0.0);
  EXPECT_LT(integrator.energy_error(), reference.energy_error() + 1e-3);
}

// A friction solve cut short (one Newton solve, no Gauss-Seidel round) fails with a SolverError that
// names the step, the Newton solves and the residual; with the default budget the same step converges.
TEST(ReductionFriction, AnUnconvergedFrictionSolveNamesTheStep) {
  const ReducedBlock block = reduced_block();
  const double h = block.v0 / block.deceleration / 400.0;
  ReducedIntegratorOptions options;
  options.newton_iterations = 1;
  options.max_gauss_seidel_rounds = 0;
  ReducedIntegrator cut(block.system, h, nullptr, options);
  cut.set_initial_state(block.q0, block.v0_modal);
  ReducedIntegrator full(block.system, h, nullptr);
  full.set_initial_state(block.q0, block.v0_modal);
  bool thrown = false;
  for (int k = 0; k < 20 && !thrown; ++k) {
    full.step();
    try {
      cut.step();
    } catch (const SolverError& error) {
      thrown = true;
      const std::string message = error.what();
      EXPECT_NE(message.find("friction solve did not converge in 1 Newton solves"), std::string::npos) << message;
      EXPECT_NE(message.find("at step " + std::to_string(k + 1)), std::string::npos) << message;
    }
  }
  EXPECT_TRUE(thrown);
  EXPECT_GT(full.n_closed(), 0);
}

}  // namespace
}  // namespace crackle::reduced
