#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>

#include "fem/material.hpp"
#include "mesh/box.hpp"
#include "transient/solver.hpp"
#include "transient_testing.hpp"

namespace crackle::transient {
namespace {

/// A block (z in [0.05, 0.07]) on a base (z in [0, 0.05]) separated by a crack plane with Coulomb
/// friction (MODEL.md eq. 15). The base stands on a clamped face, the block's top is held in z
/// only (a frictionless roller), and a negative gap g0 squeezes the two: with nu = 0 the static
/// state is an exact uniaxial compression sigma, the normal force N = |sigma| A.
struct BlockOnBase {
  static constexpr double kWidth = 0.1, kBase = 0.05, kHeight = 0.07, kYoung = 2e11, kDensity = 7800.0;
  static constexpr double kStress = -1e6, kFriction = 0.3;
  mesh::Mesh mesh;
  mesh::DofMap dofs;
  TransientProblem problem;
  TransientOptions options;

  BlockOnBase() {
    mesh::BoxSpec box;
    box.size = Vec3(kWidth, kWidth, kHeight);
    box.cells = {4, 4, 7};
    mesh::CrackSpec crack;
    crack.normal = kZ;
    crack.at = kBase;
    crack.region = {{{0.0, kWidth}, {0.0, kWidth}, {0.0, 0.0}}};
    mesh = mesh::build_box_mesh(box, crack);
    dofs = mesh::make_dof_map(mesh, mesh::Variant::open);
    problem.materials = {fem::isotropic(kYoung, 0.0, kDensity)};
    problem.dirichlet.push_back({mesh.node_sets.at("z-"), {0, 1, 2}, {0.0, 0.0, 0.0}, "base"});
    problem.dirichlet.push_back({mesh.node_sets.at("z+"), {2}, {0.0}, "roller"});
    contact::ContactOptions contact;
    contact.friction_coefficient = kFriction;
    const double penalty = contact::choose_penalty(mesh, problem.materials, contact).normal_penalty;
    // sigma = eps g0 / (1 + eps H / E)  =>  g0 for the wanted sigma.
    contact.initial_gap = kStress * (1.0 + penalty * kHeight / kYoung) / penalty;
    contact_term = testing::plug_contact(mesh, problem, contact);
    problem.initial.displacement = nodal_field(mesh, dofs, [&](Index node, const Vec3& x) {
      const double uz = on_block(node) ? -kStress * (kHeight - x.z()) / kYoung : kStress * x.z() / kYoung;
      return Vec3(0.0, 0.0, uz);
    });
    options.progress = false;
  }
  std::shared_ptr<contact::ContactForce> contact_term;
  bool on_block(Index node) const { return node >= mesh.n_original_nodes || mesh.nodes[node].z() > kBase + 1e-9; }
  double normal_force() const { return -kStress * kWidth * kWidth; }
  double block_mass() const { return kDensity * kWidth * kWidth * (kHeight - kBase); }
  /// Mass-weighted mean of the block's x component of a DOF vector.
  double block_mean(const VectorX& field, const VectorX& mass) const {
    double sum = 0.0, total = 0.0;
    for (Index node = 0; node < mesh.n_nodes(); ++node) {
      if (!on_block(node)) continue;
      sum += mass[dofs.dof(node, 0)] * field[dofs.dof(node, 0)];
      total += mass[dofs.dof(node, 0)];
    }
    return sum / total;
  }
  /// A push along x on the block's x- face, ramped in smoothly over `ramp` seconds.
  void push(double force, double ramp) {
    ExternalLoad load;
    load.name = "push";
    for (const mesh::FaceRef& face : mesh.face_sets.at("x-")) {
      Vec3 centre = Vec3::Zero();
      const Index* nodes = mesh.element_nodes(face.element);
      for (int a = 0; a < mesh.nodes_per_element(); ++a) centre += mesh.nodes[nodes[a]];
      if (centre.z() / mesh.nodes_per_element() > kBase) load.faces.push_back(face);
    }
    load.direction = Vec3::UnitX();
    load.amplitude = force;
    load.signal.kind = SignalKind::step;
    load.signal.duration = ramp;
    problem.loads.push_back(load);
  }
};

/// Least-squares slope of y(t).
double slope(const std::vector<double>& t, const std::vector<double>& y) {
  double mt = 0.0, my = 0.0;
  for (std::size_t k = 0; k < t.size(); ++k) {
    mt += t[k];
    my += y[k];
  }
  mt /= t.size();
  my /= y.size();
  double num = 0.0, den = 0.0;
  for (std::size_t k = 0; k < t.size(); ++k) {
    num += (t[k] - mt) * (y[k] - my);
    den += (t[k] - mt) * (t[k] - mt);
  }
  return num / den;
}

struct Motion {
  std::vector<double> time, velocity, displacement;
};

Motion run(BlockOnBase& setup, double end_time, TransientSummary* summary = nullptr, Index* slipping = nullptr) {
  setup.options.end_time = end_time;
  TransientSolver solver(setup.mesh, setup.problem, setup.options);
  Motion motion;
  TransientCallbacks callbacks;
  if (slipping) *slipping = 0;
  callbacks.on_step = [&](const StepView& view) {
    motion.time.push_back(view.time + view.dt);
    motion.velocity.push_back(setup.block_mean(view.velocity, solver.lumped_mass()));
    motion.displacement.push_back(setup.block_mean(view.displacement, solver.lumped_mass()));
    if (slipping) *slipping = std::max(*slipping, setup.contact_term->contact().n_slipping());
    return false;
  };
  solver.run(callbacks);
  if (summary) *summary = solver.summary();
  return motion;
}

TEST(Friction, PreloadIsStatic) {
  BlockOnBase setup;
  TransientSummary summary;
  const Motion motion = run(setup, 2e-4, &summary);
  double largest = 0.0;
  for (double v : motion.velocity) largest = std::max(largest, std::abs(v));
  EXPECT_LT(largest, 1e-9);
  EXPECT_EQ(summary.contact_fraction, 1.0);
}

TEST(Friction, SlidingBlockDeceleratesAtMuNOverMAndSticks) {
  BlockOnBase setup;
  const double v0 = 0.1;
  setup.problem.initial.velocity = nodal_field(setup.mesh, setup.dofs, [&](Index node, const Vec3&) {
    return setup.on_block(node) ? Vec3(v0, 0.0, 0.0) : Vec3::Zero();
  });
  const double deceleration = BlockOnBase::kFriction * setup.normal_force() / setup.block_mass();
  const double stop = v0 / deceleration;
  TransientSummary summary;
  const Motion motion = run(setup, 2.0 * stop, &summary);
  std::vector<double> t, v;
  for (std::size_t k = 0; k < motion.time.size(); ++k) {
    if (motion.time[k] > 0.1 * stop && motion.time[k] < 0.7 * stop) {
      t.push_back(motion.time[k]);
      v.push_back(motion.velocity[k]);
    }
  }
  const double measured = -slope(t, v);
  // After the stop the block sticks: it only rings elastically about a fixed position.
  double mean_late = 0.0, ringing = 0.0;
  int count = 0;
  for (std::size_t k = 0; k < motion.time.size(); ++k) {
    if (motion.time[k] > 1.2 * stop) {
      mean_late += motion.velocity[k];
      ringing = std::max(ringing, std::abs(motion.velocity[k]));
      ++count;
    }
  }
  mean_late /= count;
  std::printf("friction, sliding: deceleration %.2f m/s^2 (mu N / m = %.2f); after the stop mean velocity %.2e m/s, "
              "elastic ringing %.2e m/s (v0 = %g m/s); energy error %.1e\n",
              measured, deceleration, mean_late, ringing, v0, summary.energy_error);
  EXPECT_NEAR(measured / deceleration, 1.0, 0.02);
  EXPECT_LT(std::abs(mean_late), 0.02 * v0);
  // The friction work is counted by the return mapping, the rest by the central-difference work
  // rule: they differ by O(dt) where sliding starts abruptly (here at t = 0, at full speed).
  EXPECT_LT(summary.energy_error, 0.03);
}

TEST(Friction, PushBelowMuNSticksAndAboveItSlidesAtTheRightAcceleration) {
  const double ramp = 1e-4, end = 4e-4;
  {
    BlockOnBase setup;
    const double push = 0.5 * BlockOnBase::kFriction * setup.normal_force();
    setup.push(push, ramp);
    TransientSummary summary;
    Index slipping = 0;
    const Motion motion = run(setup, end, &summary, &slipping);
    double largest_displacement = 0.0, late_velocity = 0.0;
    for (std::size_t k = 0; k < motion.time.size(); ++k) {
      largest_displacement = std::max(largest_displacement, std::abs(motion.displacement[k]));
      if (motion.time[k] > 1.5 * ramp) late_velocity = std::max(late_velocity, std::abs(motion.velocity[k]));
    }
    std::printf("friction, push 0.5 mu N: largest block displacement %.3e m, |v| after the ramp < %.3e m/s, "
                "pairs slipping locally at most %lld\n",
                largest_displacement, late_velocity, static_cast<long long>(slipping));
    // Edge pairs may slip locally (partial slip where the push unloads them); the block sticks.
    EXPECT_LT(largest_displacement, 2e-6);  // elastic only (sliding would give ~1e-4 m)
    EXPECT_LT(late_velocity, 2e-3);
  }
  {
    BlockOnBase setup;
    const double push = 2.0 * BlockOnBase::kFriction * setup.normal_force();
    setup.push(push, ramp);
    const Motion motion = run(setup, end);
    std::vector<double> t, v;
    for (std::size_t k = 0; k < motion.time.size(); ++k) {
      if (motion.time[k] > 1.5 * ramp) {
        t.push_back(motion.time[k]);
        v.push_back(motion.velocity[k]);
      }
    }
    const double expected = (push - BlockOnBase::kFriction * setup.normal_force()) / setup.block_mass();
    const double measured = slope(t, v);
    std::printf("friction, push 2 mu N: acceleration %.2f m/s^2 ((T - mu N) / m = %.2f)\n", measured, expected);
    EXPECT_NEAR(measured / expected, 1.0, 0.02);
  }
}

}  // namespace
}  // namespace crackle::transient
