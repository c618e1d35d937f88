#include <gtest/gtest.h>

#include <cmath>

#include "core/quadrature.hpp"
#include "fem/material.hpp"
#include "mesh/box.hpp"
#include "transient/integrator.hpp"
#include "transient/solver.hpp"

namespace crackle::transient {
namespace {

/// One DOF: m u'' + alpha m u' + k u = 0.
class Oscillator final : public SecondOrderSystem {
 public:
  Oscillator(double mass, double stiffness, double alpha)
      : mass_(VectorX::Constant(1, mass)), inverse_(VectorX::Constant(1, 1.0 / mass)), stiffness_(stiffness), alpha_(alpha) {}
  Index n_dofs() const override { return 1; }
  const VectorX& mass() const override { return mass_; }
  const VectorX& inverse_mass() const override { return inverse_; }
  double mass_damping() const override { return alpha_; }
  void add_force(const ForceInput& input, VectorX& force) override { force[0] -= stiffness_ * input.displacement[0]; }

 private:
  VectorX mass_, inverse_;
  double stiffness_, alpha_;
};

TEST(CentralDifference, SingleOscillatorFollowsTheDiscreteSolutionExactly) {
  // With V(1/2) = V(0) + dt/2 A(0) and V(0) = 0, eq. (28) gives U_n = U_0 cos(omega_h t_n) with
  // sin(omega_h dt / 2) = omega dt / 2.
  const double mass = 2.0, stiffness = 800.0, omega = std::sqrt(stiffness / mass);
  const double dt = 1.7 / omega;
  const double omega_h = 2.0 / dt * std::asin(0.5 * omega * dt);
  Oscillator system(mass, stiffness, 0.0);
  CentralDifference integrator(1);
  VectorX u = VectorX::Constant(1, 0.01), v = VectorX::Zero(1);
  for (int i = 0; i < 200; ++i) {
    integrator.step(system, i * dt, i == 0 ? 0.0 : dt, dt, u, v);
    EXPECT_NEAR(u[0], 0.01 * std::cos(omega_h * (i + 1) * dt), 1e-13) << "step " << i;
  }
}

TEST(CentralDifference, MassProportionalDampingDecaysAtItsRatio) {
  const double mass = 1.0, stiffness = 1e4, omega = 100.0, ratio = 0.02;
  const double alpha = 2.0 * ratio * omega;
  const double dt = 0.01 / omega;
  Oscillator system(mass, stiffness, alpha);
  CentralDifference integrator(1);
  VectorX u = VectorX::Constant(1, 1.0), v = VectorX::Zero(1);
  const int periods = 10;
  const int steps = static_cast<int>(std::round(periods * 2.0 * M_PI / omega / dt));
  double peak = 0.0, peak_time = 0.0;
  for (int i = 0; i < steps; ++i) {
    integrator.step(system, i * dt, i == 0 ? 0.0 : dt, dt, u, v);
    if (i > steps - static_cast<int>(2.0 * M_PI / omega / dt) && u[0] > peak) {
      peak = u[0];
      peak_time = (i + 1) * dt;
    }
  }
  // Envelope exp(-xi omega t) at the last peak (xi = 0.02: the damped peak lies within 0.1% of it).
  EXPECT_NEAR(peak / std::exp(-ratio * omega * peak_time), 1.0, 2e-3);
}

mesh::Mesh box_mesh(int order, std::array<int, 3> cells) {
  mesh::BoxSpec box;
  box.size = Vec3(0.3, 0.2, 0.1);
  box.cells = cells;
  box.order = order;
  return mesh::build_box_mesh(box);
}

/// Moves the element vertices (not off the box faces) and puts every node at the trilinear image
/// of its reference point: trilinear elements of order p, on which the patch test holds exactly
/// with (p+1)^3 Gauss points.
void distort_vertices(mesh::Mesh& mesh) {
  const int p = mesh.order, m = p + 1;
  const Vec3 low(0.0, 0.0, 0.0), high(0.3, 0.2, 0.1);
  auto moved = [&](const Vec3& x) {
    Vec3 y = x;
    for (int c = 0; c < 3; ++c) {
      const bool on_face = std::abs(x[c] - low[c]) < 1e-12 || std::abs(x[c] - high[c]) < 1e-12;
      if (!on_face) y[c] += 0.05 * (high[c] - low[c]) * std::sin(17.0 * x[(c + 1) % 3] + 11.0 * x[(c + 2) % 3] + c);
    }
    return y;
  };
  std::vector<Vec3> nodes = mesh.nodes;
  const std::vector<double> gll = gauss_lobatto(m).points;
  for (Index e = 0; e < mesh.n_elements(); ++e) {
    const Index* element = mesh.element_nodes(e);
    Vec3 corner[8];
    for (int c = 0; c < 8; ++c) {
      const int i = (c & 1) * p, j = ((c >> 1) & 1) * p, k = ((c >> 2) & 1) * p;
      corner[c] = moved(mesh.nodes[element[i + m * (j + m * k)]]);
    }
    for (int k = 0; k < m; ++k)
      for (int j = 0; j < m; ++j)
        for (int i = 0; i < m; ++i) {
          const double s[3] = {0.5 * (1.0 + gll[i]), 0.5 * (1.0 + gll[j]), 0.5 * (1.0 + gll[k])};
          Vec3 x = Vec3::Zero();
          for (int c = 0; c < 8; ++c) {
            const double w = ((c & 1) ? s[0] : 1.0 - s[0]) * (((c >> 1) & 1) ? s[1] : 1.0 - s[1]) *
                             (((c >> 2) & 1) ? s[2] : 1.0 - s[2]);
            x += w * corner[c];
          }
          nodes[element[i + m * (j + m * k)]] = x;
        }
  }
  mesh.nodes = nodes;
  mesh.axis_aligned_bricks = false;
}

TransientOptions quiet(double end_time) {
  TransientOptions options;
  options.end_time = end_time;
  options.progress = false;
  return options;
}

TEST(PatchTest, FreeBodyInUniformMotionStaysExact) {
  for (int order : {1, 2, 4}) {
    const mesh::Mesh mesh = box_mesh(order, {3, 2, 2});
    TransientProblem problem;
    problem.materials = {fem::isotropic(2e11, 0.3, 7800.0)};
    const Vec3 velocity(0.3, -0.2, 0.1);
    const mesh::DofMap dofs = mesh::make_dof_map(mesh, mesh::Variant::open);
    problem.initial.velocity = nodal_field(mesh, dofs, [&](Index, const Vec3&) { return velocity; });
    TransientSolver solver(mesh, problem, quiet(2e-3));
    solver.run();
    const double time = solver.summary().time;
    for (Index node = 0; node < dofs.n_dof_nodes; ++node) {
      for (int c = 0; c < 3; ++c) {
        ASSERT_EQ(solver.velocity()[3 * node + c], velocity[c]) << "order " << order;  // zero force, exactly
        ASSERT_NEAR(solver.displacement()[3 * node + c], velocity[c] * time, 1e-13 * velocity.norm() * time);
      }
    }
    EXPECT_GT(solver.summary().steps, 50);
    EXPECT_LT(solver.summary().energy_error, 1e-12);
  }
}

TEST(PatchTest, LinearStaticFieldStays) {
  // Boundary nodes held at a linear field, interior nodes start on it: K u = 0 at the free DOFs.
  Eigen::Matrix3d gradient;
  gradient << 1e-4, 2e-5, -3e-5, 0.5e-4, -2e-4, 1e-5, 3e-5, 0.0, 1.5e-4;
  const Vec3 offset(1e-5, -2e-5, 0.5e-5);
  for (int order : {1, 2, 3}) {
    for (bool distorted : {false, true}) {
      mesh::Mesh mesh = box_mesh(order, {3, 3, 2});
      if (distorted) distort_vertices(mesh);
      const auto field = [&](Index, const Vec3& x) { return Vec3(gradient * x + offset); };
      TransientProblem problem;
      problem.materials = {fem::isotropic(7e10, 0.33, 2700.0)};
      std::vector<char> on_boundary(mesh.n_nodes(), 0);
      for (const auto& [name, nodes] : mesh.node_sets)
        for (Index node : nodes) on_boundary[node] = 1;
      for (Index node = 0; node < mesh.n_nodes(); ++node) {
        if (!on_boundary[node]) continue;
        const Vec3 value = field(node, mesh.nodes[node]);
        problem.dirichlet.push_back({{node}, {0, 1, 2}, {value[0], value[1], value[2]}, "patch"});
      }
      const mesh::DofMap dofs = mesh::make_dof_map(mesh, mesh::Variant::open);
      problem.initial.displacement = nodal_field(mesh, dofs, field);
      TransientSolver solver(mesh, problem, quiet(1e-3));
      EXPECT_EQ(solver.elastic_operator().info().kernel, distorted ? "general" : "brick-blocked");
      solver.run();
      const double size = problem.initial.displacement.cwiseAbs().maxCoeff();
      EXPECT_LE((solver.displacement() - problem.initial.displacement).cwiseAbs().maxCoeff(), 1e-10 * size)
          << "order " << order << (distorted ? " distorted" : "");
      EXPECT_LE(solver.velocity().cwiseAbs().maxCoeff(), 1e-10 * size / solver.dt());
      EXPECT_GT(solver.summary().steps, 40);
    }
  }
}

TEST(PatchTest, BodyAtRestKeepsExactlyZeroKineticEnergy) {
  const mesh::Mesh mesh = box_mesh(2, {2, 2, 2});
  TransientProblem problem;
  problem.materials = {fem::isotropic(2e11, 0.3, 7800.0)};
  problem.dirichlet.push_back({mesh.node_sets.at("x-"), {0, 1, 2}, {0.0, 0.0, 0.0}, "clamp"});
  TransientSolver solver(mesh, problem, quiet(1e-4));
  solver.run();
  EXPECT_EQ(solver.velocity().cwiseAbs().maxCoeff(), 0.0);
  EXPECT_EQ(solver.displacement().cwiseAbs().maxCoeff(), 0.0);
  for (double kinetic : solver.energy().kinetic) ASSERT_EQ(kinetic, 0.0);
}

}  // namespace
}  // namespace crackle::transient
