#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>

#include "fem/assembly.hpp"
#include "fem/material.hpp"
#include "mesh/box.hpp"
#include "transient/solver.hpp"
#include "transient_testing.hpp"

namespace crackle::transient {
namespace {

struct ChatterResult {
  TransientSummary summary;
  Index transitions = 0;  ///< steps where the number of closed pairs changed
  double frequency = 0.0; ///< first bending frequency of the uncracked beam [Hz]
};

/// A cantilever with a breathing crack (upper half of the section near the root, g0 = 0) in free
/// vibration, started from its first bending mode: the crack opens and closes every cycle.
ChatterResult breathing_cantilever(contact::ContactIntegration integration, double periods) {
  mesh::BoxSpec box;
  box.size = Vec3(0.3, 0.03, 0.04);
  box.cells = {24, 2, 4};
  box.order = 1;
  mesh::CrackSpec crack;
  crack.normal = kX;
  crack.at = 0.05;
  crack.region = {{{0.0, 0.0}, {0.0, 0.03}, {0.02, 0.04}}};
  const mesh::Mesh mesh = mesh::build_box_mesh(box, crack);
  TransientProblem problem;
  problem.materials = {fem::isotropic(2e11, 0.3, 7800.0)};
  problem.dirichlet.push_back({mesh.node_sets.at("x-"), {0, 1, 2}, {0.0, 0.0, 0.0}, "clamp"});
  contact::ContactOptions contact;
  contact.integration = integration;
  const auto contact_term = testing::plug_contact(mesh, problem, contact);

  // Initial displacement: the z-bending mode of the uncracked beam, 0.1 mm at the tip.
  const mesh::DofMap dofs = mesh::make_dof_map(mesh, mesh::Variant::open);
  const mesh::DofMap tied = mesh::make_dof_map(mesh, mesh::Variant::uncracked);
  const testing::DenseModes modes =
      testing::dense_modes(fem::assemble_stiffness(mesh, tied, problem.materials),
                           fem::assemble_lumped_mass(mesh, tied, problem.materials),
                           fem::make_constraints(tied, problem.dirichlet), 3);
  const Index tip = nearest_node(mesh, Vec3(0.3, 0.015, 0.02));
  int k = 0;
  for (int j = 1; j < 3; ++j) {
    if (std::abs(modes.shapes(tied.dof(tip, 2), j)) > std::abs(modes.shapes(tied.dof(tip, 2), k))) k = j;
  }
  const double scale = 1e-4 / modes.shapes(tied.dof(tip, 2), k);
  problem.initial.displacement =
      nodal_field(mesh, dofs, [&](Index node, const Vec3&) { return Vec3(scale * modes.shapes.block<3, 1>(tied.dof(node, 0), k)); });

  ChatterResult result;
  result.frequency = modes.omega[k] / (2.0 * M_PI);
  TransientOptions options;
  options.end_time = periods / result.frequency;
  options.progress = false;
  options.energy_tolerance = 1.0;  // measured below
  TransientSolver solver(mesh, problem, options);
  Index previous = 0;
  TransientCallbacks callbacks;
  callbacks.on_step = [&](const StepView&) {
    const Index closed = contact_term->contact().n_closed();
    if (closed != previous) ++result.transitions;
    previous = closed;
    return false;
  };
  result.summary = solver.run(callbacks);
  return result;
}

TEST(Chatter, UndampedBreathingCrackKeepsTheEnergyBalanceOverLongRuns) {
  const ChatterResult result = breathing_cantilever(contact::ContactIntegration::implicit, 60.0);
  std::printf("breathing crack: %lld steps (%.0f periods of %.1f Hz), %lld contact changes, closed fraction %.3f, "
              "energy error %.2e\n",
              static_cast<long long>(result.summary.steps), 60.0, result.frequency,
              static_cast<long long>(result.transitions), result.summary.contact_fraction, result.summary.energy_error);
  EXPECT_GE(result.summary.steps, 100000);
  EXPECT_GT(result.transitions, 120);  // opens and closes every cycle
  EXPECT_GT(result.summary.contact_fraction, 0.2);
  EXPECT_LT(result.summary.contact_fraction, 0.8);
  EXPECT_LT(result.summary.energy_error, 0.01);
}

}  // namespace
}  // namespace crackle::transient
