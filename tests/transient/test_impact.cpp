#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>

#include "fem/material.hpp"
#include "mesh/box.hpp"
#include "transient/solver.hpp"
#include "transient_testing.hpp"

namespace crackle::transient {
namespace {

/// Two identical bars of length L, one moving at v0 onto the other (MODEL.md eqs. 9, 25d):
/// a bar of length 2L cut through its whole section at x = L with a small gap g0, nu = 0 and free
/// lateral faces (a 1D problem). Classical solution: the contact lasts 2L/c0, the interface stress
/// is rho c0 v0 / 2, and the bars exchange their velocities.
TEST(Impact, TwoIdenticalBarsExchangeVelocities) {
  const double length = 0.1, width = 0.02, young = 2e11, density = 8000.0, v0 = 1.0, gap = 2e-7;
  const double c0 = std::sqrt(young / density);
  mesh::BoxSpec box;
  box.size = Vec3(2.0 * length, width, width);
  box.cells = {100, 1, 1};
  box.order = 1;
  mesh::CrackSpec crack;
  crack.normal = kX;
  crack.at = length;
  crack.region = {{{0.0, 0.0}, {0.0, width}, {0.0, width}}};
  crack.gap = gap;
  const mesh::Mesh mesh = mesh::build_box_mesh(box, crack);

  TransientProblem problem;
  problem.materials = {fem::isotropic(young, 0.0, density)};
  contact::ContactOptions contact;
  contact.initial_gap = gap;
  const auto contact_term = testing::plug_contact(mesh, problem, contact);
  const mesh::DofMap dofs = mesh::make_dof_map(mesh, mesh::Variant::open);
  // The right bar: nodes beyond the crack plane and the minus copies of the crack nodes.
  auto on_right = [&](Index node) { return node >= mesh.n_original_nodes || mesh.nodes[node].x() > length + 1e-9; };
  problem.initial.velocity = nodal_field(mesh, dofs, [&](Index node, const Vec3&) {
    return on_right(node) ? Vec3(-v0, 0.0, 0.0) : Vec3::Zero();
  });
  TransientOptions options;
  options.end_time = gap / v0 + 3.0 * length / c0;
  options.progress = false;
  TransientSolver solver(mesh, problem, options);
  const double area = width * width;

  std::vector<double> times, stress;
  TransientCallbacks callbacks;
  callbacks.on_step = [&](const StepView& view) {
    times.push_back(view.time);
    stress.push_back(contact_term->contact().total_force().x() / area);  // compression on the minus face: +x
    return false;
  };
  solver.run(callbacks);

  // Contact duration: first to last step with a closed pair, and between half-plateau crossings.
  const double expected_stress = 0.5 * density * c0 * v0;
  double first = -1.0, last = -1.0, rise = -1.0, fall = -1.0;
  for (std::size_t k = 0; k < stress.size(); ++k) {
    if (stress[k] > 0.0) {
      if (first < 0.0) first = times[k];
      last = times[k];
    }
    if (k > 0 && stress[k - 1] < 0.5 * expected_stress && stress[k] >= 0.5 * expected_stress && rise < 0.0) {
      rise = times[k - 1] + (times[k] - times[k - 1]) * (0.5 * expected_stress - stress[k - 1]) / (stress[k] - stress[k - 1]);
    }
    if (k > 0 && stress[k - 1] >= 0.5 * expected_stress && stress[k] < 0.5 * expected_stress) {
      fall = times[k - 1] + (times[k] - times[k - 1]) * (stress[k - 1] - 0.5 * expected_stress) / (stress[k - 1] - stress[k]);
    }
  }
  const double duration = 2.0 * length / c0;
  double plateau = 0.0;
  int count = 0;
  for (std::size_t k = 0; k < stress.size(); ++k) {
    if (times[k] > rise + 0.25 * duration && times[k] < rise + 0.75 * duration) {
      plateau += stress[k];
      ++count;
    }
  }
  plateau /= count;

  // Mass-weighted mean velocities of the two bars after the impact.
  const VectorX& mass = solver.lumped_mass();
  double momentum[2] = {0.0, 0.0}, bar_mass[2] = {0.0, 0.0};
  for (Index node = 0; node < mesh.n_nodes(); ++node) {
    const int side = on_right(node) ? 1 : 0;
    const Index dof = dofs.dof(node, 0);
    momentum[side] += mass[dof] * solver.velocity()[dof];
    bar_mass[side] += mass[dof];
  }
  const double v_left = momentum[0] / bar_mass[0], v_right = momentum[1] / bar_mass[1];
  std::printf("impact: dt %.3g s (dt_crit %.3g), penalty %.3g Pa/m; duration first-last %.4g, half-plateau %.4g, "
              "exact %.4g s; stress %.4g (exact %.4g) Pa; velocities %.4f %.4f m/s; energy error %.2e\n",
              solver.dt(), solver.summary().dt_critical, contact_term->contact().penalty().normal_penalty, last - first,
              fall - rise, duration, plateau, expected_stress, v_left, v_right, solver.summary().energy_error);
  EXPECT_NEAR((fall - rise) / duration, 1.0, 0.02);
  EXPECT_NEAR((last - first) / duration, 1.0, 0.02);
  EXPECT_NEAR(plateau / expected_stress, 1.0, 0.02);
  EXPECT_NEAR(v_left / v0, -1.0, 0.02);
  EXPECT_NEAR(v_right / v0, 0.0, 0.02);
  EXPECT_NEAR(first, gap / v0, 0.02 * duration);
}

}  // namespace
}  // namespace crackle::transient
