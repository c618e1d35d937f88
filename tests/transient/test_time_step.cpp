#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <nlohmann/json.hpp>

#include "core/errors.hpp"
#include "fem/assembly.hpp"
#include "fem/material.hpp"
#include "io/files.hpp"
#include "mesh/box.hpp"
#include "transient/solver.hpp"
#include "transient_testing.hpp"
#include "output/transient_json.hpp"

namespace crackle::transient {
namespace {

mesh::Mesh cracked_block(int order) {
  mesh::BoxSpec box;
  box.size = Vec3(0.2, 0.1, 0.1);
  box.cells = {4, 2, 2};
  box.order = order;
  mesh::CrackSpec crack;
  crack.normal = kX;
  crack.at = 0.1;
  crack.region = {{{0.0, 0.0}, {0.0, 0.1}, {0.05, 0.1}}};
  return mesh::build_box_mesh(box, crack);
}

TEST(TimeStep, CriticalStepFormula) {
  EXPECT_DOUBLE_EQ(critical_time_step(1000.0, 0.0), 2e-3);
  const double omega = 1e4, beta = 2e-5, xi = 0.5 * beta * omega;
  EXPECT_NEAR(critical_time_step(omega, beta), 2.0 / omega * (std::sqrt(1.0 + xi * xi) - xi), 1e-15);
}

/// The Lanczos estimate against a dense eigen-solve of M^-1 (K + K_contact, all closed) over the
/// free DOFs: never above the exact omega_max before the margin, at most a few per cent below.
TEST(TimeStep, EstimateBoundsTheDenseOmegaMaxWithTheContactSprings) {
  for (int order : {1, 2}) {
    for (bool explicit_contact : {false, true}) {
      const mesh::Mesh mesh = cracked_block(order);
      TransientProblem problem;
      problem.materials = {fem::isotropic(7e10, 0.33, 2700.0)};
      problem.dirichlet.push_back({mesh.node_sets.at("x-"), {0, 1, 2}, {0.0, 0.0, 0.0}, "clamp"});
      contact::ContactOptions contact;
      contact.friction_coefficient = 0.3;
      if (explicit_contact) contact.integration = contact::ContactIntegration::explicit_forces;
      const auto contact_term = testing::plug_contact(mesh, problem, contact);
      TransientOptions options;
      options.end_time = 1e-6;
      options.progress = false;
      const TransientSolver solver(mesh, problem, options);

      const mesh::DofMap& dofs = solver.dofs();
      MatrixX stiffness = MatrixX(fem::assemble_stiffness(mesh, dofs, problem.materials));
      if (explicit_contact) {  // dense K_c from the spring bound the term gives the step estimate
        VectorX unit = VectorX::Zero(dofs.n_dofs()), column(dofs.n_dofs());
        for (Index j = 0; j < dofs.n_dofs(); ++j) {
          unit[j] = 1.0;
          column.setZero();
          contact_term->add_stiffness_bound(unit, column);
          stiffness.col(j) += column;
          unit[j] = 0.0;
        }
      }
      const SparseMatrix sparse = stiffness.sparseView();
      const double exact = testing::dense_omega_max(sparse, solver.lumped_mass(), solver.constraints());
      const TimeStepEstimate& estimate = solver.time_step_estimate();
      std::printf("omega_max, p = %d, %s contact: dense %.6e, Lanczos %.6e (%d steps), with margin %.6e rad/s\n", order,
                  explicit_contact ? "explicit" : "implicit", exact, estimate.omega_ritz, estimate.iterations,
                  estimate.omega_max);
      EXPECT_LE(estimate.omega_ritz, exact * (1.0 + 1e-10));
      EXPECT_GE(estimate.omega_ritz, 0.995 * exact);
      EXPECT_GE(estimate.omega_max, exact);
      EXPECT_DOUBLE_EQ(estimate.dt_critical, 2.0 / estimate.omega_max);
      EXPECT_DOUBLE_EQ(solver.dt(), 0.9 * estimate.dt_critical);
    }
  }
}

/// A clamped block with random initial velocities (every mode excited, the highest included).
struct RandomStart {
  mesh::Mesh mesh;
  TransientProblem problem;
  TransientOptions options;
  explicit RandomStart(double beta = 0.0) {
    mesh::BoxSpec box;
    box.size = Vec3(0.2, 0.1, 0.1);
    box.cells = {4, 2, 2};
    box.order = 2;
    mesh = mesh::build_box_mesh(box);
    problem.materials = {fem::isotropic(2e11, 0.3, 7800.0)};
    problem.dirichlet.push_back({mesh.node_sets.at("x-"), {0, 1, 2}, {0.0, 0.0, 0.0}, "clamp"});
    const mesh::DofMap dofs = mesh::make_dof_map(mesh, mesh::Variant::open);
    problem.initial.velocity = VectorX::Random(dofs.n_dofs()) * 0.01;
    options.progress = false;
    options.damping.beta = beta;
    options.end_time = 1.0;  // replaced below
  }
  double critical() {
    options.end_time = 1e-6;
    const TransientSolver probe(mesh, problem, options);
    return probe.time_step_estimate().dt_critical;
  }
};

TEST(TimeStep, BelowTheLimitStaysBoundedAboveItIsRefusedOrCaught) {
  RandomStart start;
  const double critical = start.critical();
  // 0.95 dt_critical: 3000 steps, bounded, energy conserved.
  start.options.time_step = 0.95 * critical;
  start.options.end_time = 3000 * start.options.time_step;
  TransientSolver stable(start.mesh, start.problem, start.options);
  stable.run();
  EXPECT_EQ(stable.summary().status, "completed");
  EXPECT_LT(stable.summary().energy_error, 1e-9);
  double largest = 0.0;
  for (double kinetic : stable.energy().kinetic) largest = std::max(largest, kinetic);
  EXPECT_LT(largest, 20.0 * stable.energy().kinetic.front());

  // 1.05 dt_critical: refused before the run, the limit in the message.
  start.options.time_step = 1.05 * critical;
  try {
    TransientSolver refused(start.mesh, start.problem, start.options);
    FAIL() << "a time step above dt_critical was accepted";
  } catch (const InputError& error) {
    EXPECT_NE(std::string(error.what()).find(format_number(critical)), std::string::npos) << error.what();
  }

  // Forced: the health check stops it, and what was computed so far is on disk.
  const std::filesystem::path directory = std::filesystem::temp_directory_path() / "crackle_test_unstable";
  std::filesystem::remove_all(directory);
  start.options.force_time_step = true;
  TransientSolver forced(start.mesh, start.problem, start.options);
  bool finished = false;
  TransientCallbacks callbacks;
  callbacks.on_finish = [&](const TransientSummary& summary) {
    finished = summary.status == "unstable";
    output::write_transient_outputs(directory, forced);  // as the run pipeline does
  };
  EXPECT_THROW(forced.run(callbacks), SolverError);
  EXPECT_TRUE(finished);
  EXPECT_LT(forced.summary().steps, 1000);
  EXPECT_TRUE(forced.summary().time_step_forced);
  const nlohmann::json json = nlohmann::json::parse(io::read_file(directory / "transient.json"));
  EXPECT_EQ(json["status"], "unstable");
  EXPECT_TRUE(std::filesystem::exists(directory / "energy.csv"));
  std::printf("forced 1.05 dt_critical: stopped after %lld steps: %s\n", static_cast<long long>(forced.summary().steps),
              forced.summary().message.c_str());
  std::filesystem::remove_all(directory);
}

TEST(TimeStep, StiffnessProportionalDampingShrinksTheLimitAndWarns) {
  const double beta = 2e-7;
  RandomStart start(beta);
  start.options.end_time = 2e-4;
  TransientSolver solver(start.mesh, start.problem, start.options);
  const TimeStepEstimate& estimate = solver.time_step_estimate();
  EXPECT_DOUBLE_EQ(estimate.dt_critical, critical_time_step(estimate.omega_max, beta));
  EXPECT_LT(estimate.dt_critical, 2.0 / estimate.omega_max);
  ASSERT_FALSE(solver.summary().warnings.empty());
  EXPECT_NE(solver.summary().warnings.front().find("beta"), std::string::npos);
  solver.run();
  // Damped: the kinetic energy decays, and the balance (with the damping dissipation) holds.
  EXPECT_LT(solver.energy().kinetic.back(), 0.5 * solver.energy().kinetic.front());
  EXPECT_LT(solver.summary().energy_error, 1e-9);
}

}  // namespace
}  // namespace crackle::transient
