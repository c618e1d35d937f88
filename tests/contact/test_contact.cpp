#include <gtest/gtest.h>

#include <cmath>

#include "contact/contact.hpp"
#include "contact_law/penalty.hpp"
#include "core/errors.hpp"
#include "fem/material.hpp"
#include "mesh/box.hpp"

namespace crackle::contact {
namespace {

/// A block with an internal crack on the plane z = 0.1 (front inside the body on three sides).
mesh::Mesh cracked_block() {
  mesh::BoxSpec box;
  box.size = Vec3(0.4, 0.2, 0.2);
  box.cells = {4, 2, 4};
  box.order = 2;
  mesh::CrackSpec crack;
  crack.normal = kZ;
  crack.at = 0.1;
  crack.region = {{{0.1, 0.3}, {0.0, 0.2}, {0.0, 0.0}}};
  return mesh::build_box_mesh(box, crack);
}

TEST(ContactSetup, AutomaticPenaltyIsCTimesModulusOverElementSize) {
  const mesh::Mesh mesh = cracked_block();
  const fem::Materials nu0 = {fem::isotropic(2e11, 0.0, 7800.0)};
  const PenaltyChoice automatic = choose_penalty(mesh, nu0, ContactOptions{});
  EXPECT_TRUE(automatic.automatic);
  EXPECT_DOUBLE_EQ(automatic.factor, kDefaultPenaltyFactor);
  EXPECT_DOUBLE_EQ(automatic.modulus, 2e11);     // nu = 0: C_zzzz = E
  EXPECT_DOUBLE_EQ(automatic.element_size, 0.05);  // h along z
  EXPECT_DOUBLE_EQ(automatic.normal_penalty, kDefaultPenaltyFactor * 2e11 / 0.05);
  EXPECT_DOUBLE_EQ(automatic.tangential_penalty, automatic.normal_penalty);
  // nu = 0.3: the constrained modulus lambda + 2 mu; explicit integration: c = 1.
  ContactOptions options;
  options.integration = ContactIntegration::explicit_forces;
  const PenaltyChoice constrained = choose_penalty(mesh, {fem::isotropic(2e11, 0.3, 7800.0)}, options);
  EXPECT_NEAR(constrained.modulus, 2e11 * 0.7 / (1.3 * 0.4), 1e-3);
  EXPECT_DOUBLE_EQ(constrained.factor, kDefaultExplicitPenaltyFactor);
  // Given values are taken as they are.
  options.normal_penalty = 1e14;
  options.tangential_penalty = 3e13;
  const PenaltyChoice given = choose_penalty(mesh, nu0, options);
  EXPECT_FALSE(given.automatic);
  EXPECT_EQ(given.normal_penalty, 1e14);
  EXPECT_EQ(given.tangential_penalty, 3e13);
  options.friction_coefficient = -0.1;
  EXPECT_THROW(choose_penalty(mesh, nu0, options), InputError);
  EXPECT_THROW(choose_penalty(mesh::build_box_mesh(mesh::BoxSpec{}), nu0, ContactOptions{}), InputError);
}

TEST(ContactForces, EqualAndOppositeAlongTheNormalOnlyWhenClosed) {
  const mesh::Mesh mesh = cracked_block();
  const mesh::DofMap dofs = mesh::make_dof_map(mesh, mesh::Variant::open);
  ContactOptions options;
  options.integration = ContactIntegration::explicit_forces;
  options.initial_gap = 1e-6;
  PenaltyContact contact(mesh, dofs, {fem::isotropic(2e11, 0.3, 7800.0)}, options);
  Index split = 0;
  double split_area = 0.0;
  for (const mesh::CrackPair& pair : mesh.crack_pairs) {
    if (!pair.on_front()) {
      ++split;
      split_area += pair.area;
    }
  }
  EXPECT_EQ(contact.n_pairs(), split);  // front pairs carry no net force: skipped
  EXPECT_NEAR(contact.total_area(), split_area, 1e-15);

  // Move every minus node by -3 um along n+: g = 1 - 3 = -2 um, closed everywhere.
  VectorX u = VectorX::Zero(dofs.n_dofs());
  for (const mesh::CrackPair& pair : mesh.crack_pairs) {
    if (!pair.on_front()) u[dofs.dof(pair.minus, 2)] = -3e-6;
  }
  VectorX force = VectorX::Zero(dofs.n_dofs());
  contact.add_force(u, force);
  const double eps = contact.penalty().normal_penalty;
  EXPECT_EQ(contact.n_closed(), split);
  EXPECT_NEAR(contact.total_force().z(), eps * 2e-6 * split_area, 1e-9 * eps * 2e-6 * split_area);
  EXPECT_NEAR(force.sum(), 0.0, 1e-9 * eps * 2e-6 * split_area);  // equal and opposite
  for (const mesh::CrackPair& pair : mesh.crack_pairs) {
    if (pair.on_front()) continue;
    EXPECT_NEAR(force[dofs.dof(pair.minus, 2)], eps * pair.area * 2e-6, 1e-6 * eps * pair.area * 2e-6);
    EXPECT_EQ(force[dofs.dof(pair.minus, 0)], 0.0);
  }
  EXPECT_NEAR(contact.stored_energy(), 0.5 * eps * 4e-12 * split_area, 1e-9 * eps * 4e-12 * split_area);
  EXPECT_NEAR(contact.force_dot(u), -3e-6 * eps * 2e-6 * split_area, 1e-9 * eps * 6e-12 * split_area);

  // Open again: no force.
  VectorX none = VectorX::Zero(dofs.n_dofs());
  contact.add_force(VectorX::Zero(dofs.n_dofs()), none);
  EXPECT_EQ(none.cwiseAbs().maxCoeff(), 0.0);
  EXPECT_EQ(contact.n_closed(), 0);
}

TEST(ContactForces, ClosedStiffnessIsTheDerivativeOfTheClosedForces) {
  const mesh::Mesh mesh = cracked_block();
  const mesh::DofMap dofs = mesh::make_dof_map(mesh, mesh::Variant::open);
  ContactOptions options;
  options.integration = ContactIntegration::explicit_forces;
  options.initial_gap = -1e-3;  // closed whatever the small motion below
  PenaltyContact contact(mesh, dofs, {fem::isotropic(2e11, 0.3, 7800.0)}, options);
  const VectorX x = 1e-9 * VectorX::Random(dofs.n_dofs());
  VectorX base = VectorX::Zero(dofs.n_dofs()), moved = VectorX::Zero(dofs.n_dofs()), product = VectorX::Zero(dofs.n_dofs());
  contact.add_force(VectorX::Zero(dofs.n_dofs()), base);
  contact.add_force(x, moved);
  contact.add_closed_stiffness(x, product);
  EXPECT_LE((moved - base + product).norm(), 1e-9 * product.norm());  // f(x) - f(0) = -K_c x
}

TEST(ContactForces, ImplicitForcesSatisfyThePenaltyLawAfterTheUpdate) {
  const mesh::Mesh mesh = cracked_block();
  const mesh::DofMap dofs = mesh::make_dof_map(mesh, mesh::Variant::open);
  ContactOptions options;
  options.friction_coefficient = 0.2;
  PenaltyContact contact(mesh, dofs, {fem::isotropic(2e11, 0.3, 7800.0)}, options);
  const Index n = dofs.n_dofs();
  const VectorX u = 1e-7 * VectorX::Random(n), v = 1e-2 * VectorX::Random(n);
  const VectorX inverse_mass = VectorX::Constant(n, 1.0 / 0.3);
  VectorX force = 1e3 * VectorX::Random(n);  // the rest of F
  const VectorX rest = force;
  const double dt = 1e-7, h = 1e-7, alpha = 50.0;
  contact.add_implicit_force(u, v, {dt, h, alpha, &inverse_mass}, force);
  // The integrator's update with the total force; then eq. (25d) must hold at U(i+1).
  const VectorX v_new = (v * (1.0 - 0.5 * alpha * h) + h * inverse_mass.cwiseProduct(force)) / (1.0 + 0.5 * alpha * h);
  const VectorX u_new = u + dt * v_new;
  const double eps = contact.penalty().normal_penalty;
  Index closed = 0;
  for (const mesh::CrackPair& pair : mesh.crack_pairs) {
    if (pair.on_front()) continue;
    const double gap = normal_gap(0.0, u_new.segment<3>(dofs.dof(pair.minus, 0)), u_new.segment<3>(dofs.dof(pair.plus, 0)), pair.normal);
    const Vec3 own = force.segment<3>(dofs.dof(pair.minus, 0)) - rest.segment<3>(dofs.dof(pair.minus, 0));
    EXPECT_NEAR(own.dot(pair.normal), pair.area * penalty_pressure(gap, eps), 1e-6 * std::abs(own.dot(pair.normal)) + 1e-9);
    if (gap < 0.0) ++closed;
  }
  EXPECT_EQ(contact.n_closed(), closed);
  EXPECT_GT(closed, 0);
  EXPECT_LT(closed, contact.n_pairs());
}

}  // namespace
}  // namespace crackle::contact
