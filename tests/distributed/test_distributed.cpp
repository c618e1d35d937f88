/// The full transient over MPI ranks (issue 17), run under mpirun -np 2 (and -np 1): every rank
/// runs the one-process reference on the whole mesh, then its share of the distributed run; the
/// probe histories, dt and energy balance must agree to 1e-12 relative after 2000 steps, with the
/// crack chattering, with friction, and with partitions forced through the crack and the clamp.
#include <gtest/gtest.h>
#include <omp.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <optional>

#include "core/errors.hpp"
#include "distributed/partition.hpp"
#include "fem/material.hpp"
#include "mesh/box.hpp"
#include "mesh/gmsh.hpp"
#include "transient/excitation.hpp"
#include "transient/solver.hpp"

namespace crackle::distributed {
namespace {

constexpr Index kSteps = 2000;

/// A cantilever (clamped at x = 0) with a breathing crack across its upper half near the root.
mesh::Mesh cracked_cantilever(std::array<int, 3> cells) {
  mesh::BoxSpec box;
  box.size = Vec3(0.3, 0.03, 0.04);
  box.cells = cells;
  mesh::CrackSpec crack;
  crack.normal = kX;
  crack.at = 0.05;
  crack.region = {{{0.0, 0.0}, {0.0, 0.03}, {0.02, 0.04}}};
  return mesh::build_box_mesh(box, crack);
}

struct Outcome {
  transient::TransientSummary summary;
  transient::ProbeHistory probes;
  transient::EnergyHistory energy;
  Index transitions = 0;  ///< steps at which the number of closed pairs changed (one process only)
  VectorX displacement, velocity;  ///< at the end, over the run's (local) DOFs
};

/// 2000 steps of free vibration from a bending velocity field, the crack in contact (implicit
/// penalty, optional friction). With `element_rank`, this rank's share of the distributed run.
/// `overlap_halo` and `beta` (stiffness-proportional damping [s]) as in transient::TransientOptions.
Outcome run_case(const mesh::Mesh& mesh, double friction, const std::vector<int>* element_rank,
                 bool overlap_halo = true, double beta = 0.0) {
  const fem::Materials materials{fem::isotropic(2e11, 0.3, 7800.0)};
  const std::vector<fem::DirichletCondition> clamp{{mesh.node_sets.at("x-"), {0, 1, 2}, {0.0, 0.0, 0.0}, "clamp"}};
  contact::ContactOptions contact_options;
  contact_options.friction_coefficient = friction;
  // Velocity: z-bending plus a twist and an axial part, so that the crack opens, closes and slides.
  VectorX velocity = VectorX::Zero(3 * mesh.n_nodes());
  for (Index i = 0; i < mesh.n_nodes(); ++i) {
    const Vec3& x = mesh.nodes[i];
    const double s = x[0] / 0.3;
    velocity.segment<3>(3 * i) = Vec3(0.3 * s, 0.4 * s * s * (x[2] - 0.02) / 0.02, 2.0 * s * s + 0.5 * s * (x[1] - 0.015) / 0.015);
  }
  const std::vector<Index> probe_nodes{transient::nearest_node(mesh, Vec3(0.3, 0.015, 0.02)), transient::nearest_node(mesh, Vec3(0.3, 0.0, 0.04)),
                                       transient::nearest_node(mesh, Vec3(0.05, 0.015, 0.04)), transient::nearest_node(mesh, Vec3(0.1, 0.015, 0.0))};
  transient::TransientOptions options;
  options.end_time = 1.0;  // replaced below by kSteps x dt
  options.progress = false;
  options.energy_tolerance = 1.0;
  options.overlap_halo = overlap_halo;
  options.damping.beta = beta;

  std::unique_ptr<MeshPartition> partition;
  transient::TransientProblem problem;
  problem.materials = materials;
  const mesh::Mesh* run_mesh = &mesh;
  std::shared_ptr<contact::ContactForce> contact;
  if (element_rank) {
    partition = std::make_unique<MeshPartition>(mesh, *element_rank);
    run_mesh = &partition->local_mesh();
    problem.dirichlet = partition->local_dirichlet(clamp);
    problem.initial.velocity = partition->local_field(velocity);
    contact = partition->local_contact(materials, contact_options);
    for (std::size_t p = 0; p < probe_nodes.size(); ++p) {
      problem.probes.push_back({"p" + std::to_string(p), partition->owned_node(probe_nodes[p])});
    }
    problem.distribution = std::shared_ptr<const transient::Distribution>(partition.get(), [](const auto*) {});
  } else {
    problem.dirichlet = clamp;
    problem.initial.velocity = velocity;
    contact = std::make_shared<contact::ContactForce>(mesh, mesh::make_dof_map(mesh, mesh::Variant::open), materials,
                                                      contact_options);
    for (std::size_t p = 0; p < probe_nodes.size(); ++p) problem.probes.push_back({"p" + std::to_string(p), probe_nodes[p]});
  }
  problem.terms.push_back(contact);
  // The step count is fixed: a first solver finds dt, the run takes kSteps of it.
  const double dt = transient::TransientSolver(*run_mesh, problem, options).dt();
  options.time_step = dt;
  options.end_time = (static_cast<double>(kSteps) - 0.5) * dt;
  transient::TransientSolver solver(*run_mesh, problem, options);
  Outcome outcome;
  Index previous = 0;
  transient::TransientCallbacks callbacks;
  callbacks.on_step = [&](const transient::StepView&) {
    const Index closed = contact->contact().n_closed();
    if (closed != previous) ++outcome.transitions;
    previous = closed;
    return false;
  };
  outcome.summary = solver.run(callbacks);
  outcome.summary.dt = dt;
  outcome.probes = solver.probes();
  outcome.energy = solver.energy();
  outcome.displacement = solver.displacement();
  outcome.velocity = solver.velocity();
  return outcome;
}

/// Largest |a - b| over columns of one quantity (a probe's u_x, u_y, u_z, ...; or the energies)
/// relative to the largest |b| among them.
double relative_difference(const std::vector<std::vector<double>>& a, const std::vector<std::vector<double>>& b) {
  double scale = 0.0, difference = 0.0;
  EXPECT_EQ(a.size(), b.size());
  for (std::size_t c = 0; c < a.size() && c < b.size(); ++c) {
    EXPECT_EQ(a[c].size(), b[c].size());
    for (std::size_t r = 0; r < a[c].size() && r < b[c].size(); ++r) {
      scale = std::max(scale, std::abs(b[c][r]));
      difference = std::max(difference, std::abs(a[c][r] - b[c][r]));
    }
  }
  return scale > 0.0 ? difference / scale : difference;
}

/// The three columns of quantity q (0: u, 1: v, 2: a) of probe p.
std::vector<std::vector<double>> quantity(const transient::ProbeHistory& probes, std::size_t p, int q) {
  return {probes.values[9 * p + 3 * q], probes.values[9 * p + 3 * q + 1], probes.values[9 * p + 3 * q + 2]};
}

/// The worst relative_difference of quantity q over the probes.
double probe_difference(const transient::ProbeHistory& a, const transient::ProbeHistory& b, int q) {
  double worst = 0.0;
  for (std::size_t p = 0; p < b.names.size(); ++p)
    worst = std::max(worst, relative_difference(quantity(a, p, q), quantity(b, p, q)));
  return worst;
}

/// Rounding differs (the shares of a node are summed in another order), so the runs agree to a few
/// ulps per step, grown over the steps of chattering contact. Measured (2 ranks, 2000 steps):
/// displacements 5e-14..3e-13 of the probe's largest, velocities (differences of displacements over
/// dt) 1e-12..6e-12, accelerations (of velocities over dt) 1e-11..1.5e-10; one process on 2 threads
/// differs from 1 thread by as much (TwoThreadsAndRanksMatchOneThread).
void expect_same(const Outcome& distributed, const Outcome& reference, const char* what) {
  const double u = probe_difference(distributed.probes, reference.probes, 0);
  const double v = probe_difference(distributed.probes, reference.probes, 1);
  const double a = probe_difference(distributed.probes, reference.probes, 2);
  const double probes = u;
  EXPECT_LT(v, 1e-11);
  EXPECT_LT(a, 1e-9);
  const std::vector<std::vector<double>> energy_a{distributed.energy.kinetic, distributed.energy.strain,
                                                  distributed.energy.contact, distributed.energy.friction};
  const std::vector<std::vector<double>> energy_b{reference.energy.kinetic, reference.energy.strain,
                                                  reference.energy.contact, reference.energy.friction};
  const double energy = relative_difference(energy_a, energy_b);
  const double dt = std::abs(distributed.summary.dt / reference.summary.dt - 1.0);
  if (world_rank() == 0) {
    std::printf("%s: %d ranks, elements per rank %lld..%lld, probes u %.2e v %.2e a %.2e, energies %.2e, dt %.2e, energy error %.3e vs %.3e, "
                "closed fraction %.4f vs %.4f\n",
                what, distributed.summary.ranks, static_cast<long long>(distributed.summary.elements_min),
                static_cast<long long>(distributed.summary.elements_max), u, v, a, energy, dt,
                distributed.summary.energy_error, reference.summary.energy_error, distributed.summary.contact_fraction,
                reference.summary.contact_fraction);
  }
  EXPECT_EQ(distributed.summary.steps, reference.summary.steps);
  EXPECT_EQ(distributed.summary.n_dofs, reference.summary.n_dofs);
  EXPECT_EQ(distributed.summary.n_elements, reference.summary.n_elements);
  EXPECT_LT(probes, 1e-12);
  EXPECT_LT(energy, 1e-11);
  EXPECT_LT(dt, 1e-12);
  EXPECT_NEAR(distributed.summary.energy_error, reference.summary.energy_error, 1e-12);
  EXPECT_NEAR(distributed.summary.contact_fraction, reference.summary.contact_fraction, 1e-12);
}

/// Each element to the rank of the half (of min(2, ranks)) its centre lies in along `axis`.
std::vector<int> cut_at(const mesh::Mesh& mesh, int axis, double at) {
  std::vector<int> ranks(mesh.n_elements());
  const int npe = mesh.nodes_per_element(), last = world_size() - 1;
  for (Index e = 0; e < mesh.n_elements(); ++e) {
    double centre = 0.0;
    for (int a = 0; a < npe; ++a) centre += mesh.nodes[mesh.element_nodes(e)[a]][axis] / npe;
    ranks[e] = centre < at ? 0 : std::min(1, last);
  }
  return ranks;
}

TEST(DistributedTransient, ChatteringCrackMatchesOneProcess) {
  const mesh::Mesh mesh = cracked_cantilever({24, 2, 4});
  const Outcome reference = run_case(mesh, 0.0, nullptr);
  if (world_rank() == 0) std::printf("reference: %lld contact changes in %lld steps\n",
                                     static_cast<long long>(reference.transitions), static_cast<long long>(kSteps));
  EXPECT_GE(reference.transitions, 4);  // the crack chatters
  const std::vector<int> parts = partition_elements(mesh, world_size());
  expect_same(run_case(mesh, 0.0, &parts), reference, "PT-Scotch, frictionless");
}

TEST(DistributedTransient, WithFrictionMatchesOneProcess) {
  const mesh::Mesh mesh = cracked_cantilever({24, 2, 4});
  const Outcome reference = run_case(mesh, 0.3, nullptr);
  EXPECT_GT(reference.energy.friction.back(), 0.0);  // the crack slides
  const std::vector<int> parts = partition_elements(mesh, world_size());
  expect_same(run_case(mesh, 0.3, &parts), reference, "PT-Scotch, friction 0.3");
}

TEST(DistributedTransient, CutsThroughTheCrackAndTheClampMatchOneProcess) {
  const mesh::Mesh mesh = cracked_cantilever({24, 2, 4});
  const Outcome reference = run_case(mesh, 0.3, nullptr);
  // Along y through the middle: the cut crosses the clamped face and the whole crack face.
  const std::vector<int> along_y = cut_at(mesh, kY, 0.015);
  expect_same(run_case(mesh, 0.3, &along_y), reference, "cut y = 0.015 (clamp and crack)");
  // In the crack plane: the two faces of every pair on different ranks' elements.
  const std::vector<int> crack_plane = cut_at(mesh, kX, 0.05);
  expect_same(run_case(mesh, 0.3, &crack_plane), reference, "cut x = 0.05 (crack plane)");
}

TEST(DistributedTransient, TwoThreadsAndRanksMatchOneThread) {
  // Above 20000 DOFs, so that the element kernel runs on 2 threads.
  const mesh::Mesh mesh = cracked_cantilever({84, 8, 8});
  const int threads = omp_get_max_threads();
  omp_set_num_threads(1);
  const Outcome reference = run_case(mesh, 0.0, nullptr);
  omp_set_num_threads(2);
  const Outcome two_threads = run_case(mesh, 0.0, nullptr);
  EXPECT_EQ(two_threads.summary.n_threads, 2);
  expect_same(two_threads, reference, "one process, 2 threads");
  const std::vector<int> parts = partition_elements(mesh, world_size());
  expect_same(run_case(mesh, 0.0, &parts), reference, "PT-Scotch, large mesh");
  omp_set_num_threads(threads);
}

/// Largest |a - b| relative to the largest |b| over this rank's vector, then over the ranks.
double vector_difference(const VectorX& a, const VectorX& b) {
  EXPECT_EQ(a.size(), b.size());
  double values[2] = {a.size() == b.size() ? (a - b).cwiseAbs().maxCoeff() : 1.0, b.cwiseAbs().maxCoeff()};
  MPI_Allreduce(MPI_IN_PLACE, values, 2, MPI_DOUBLE, MPI_MAX, PETSC_COMM_WORLD);
  return values[1] > 0.0 ? values[0] / values[1] : values[0];
}

TEST(DistributedTransient, OverlappedHaloMatchesTheSequentialHalo) {
  // The same partition, the interior elements applied while the halo travels or after it: the
  // same sums (in another order where damping adds its parts), with the crack chattering and
  // sliding, without and with stiffness-proportional damping (its K product in parts too).
  const mesh::Mesh mesh = cracked_cantilever({24, 2, 4});
  const std::vector<int> parts = partition_elements(mesh, world_size());
  {
    const MeshPartition partition(mesh, parts);
    const HaloCounts halo = partition.halo_counts();
    EXPECT_EQ(halo.boundary_elements + halo.interior_elements, partition.local_mesh().n_elements());
    EXPECT_GT(halo.interior_elements, 0);
    if (world_size() > 1) EXPECT_GT(halo.boundary_elements, 0);
    else EXPECT_EQ(halo.boundary_elements, 0);
    // Boundary first: every interior element touches only owned nodes that no other rank holds.
    std::vector<char> shared(partition.local_mesh().n_nodes(), 0);
    for (Index e = 0; e < halo.boundary_elements; ++e)
      for (int a = 0; a < mesh.nodes_per_element(); ++a) shared[partition.local_mesh().element_nodes(e)[a]] = 1;
    Index interior_on_ghosts = 0;
    for (Index e = halo.boundary_elements; e < partition.local_mesh().n_elements(); ++e)
      for (int a = 0; a < mesh.nodes_per_element(); ++a)
        interior_on_ghosts += partition.local_mesh().element_nodes(e)[a] >= partition.n_owned_nodes();
    EXPECT_EQ(interior_on_ghosts, 0);
  }
  for (double beta : {0.0, 1e-8}) {
    const Outcome overlapped = run_case(mesh, 0.3, &parts, true, beta);
    const Outcome sequential = run_case(mesh, 0.3, &parts, false, beta);
    EXPECT_TRUE(overlapped.summary.halo_overlapped);
    EXPECT_FALSE(sequential.summary.halo_overlapped);
    long long changes = sequential.transitions;  // contact changes of this rank's pairs, summed
    MPI_Allreduce(MPI_IN_PLACE, &changes, 1, MPI_LONG_LONG, MPI_SUM, PETSC_COMM_WORLD);
    EXPECT_GE(changes, 4);  // the crack chatters
    const double u = vector_difference(overlapped.displacement, sequential.displacement);
    const double v = vector_difference(overlapped.velocity, sequential.velocity);
    const double probe_u = probe_difference(overlapped.probes, sequential.probes, 0);
    const double probe_v = probe_difference(overlapped.probes, sequential.probes, 1);
    const double probe_a = probe_difference(overlapped.probes, sequential.probes, 2);
    if (world_rank() == 0) {
      std::printf("overlapped halo, beta %.0e s: %d ranks, U %.2e, V %.2e, probes u %.2e v %.2e a %.2e, %lld contact changes\n",
                  beta, world_size(), u, v, probe_u, probe_v, probe_a, changes);
    }
    // Without damping the sums are the same in the same order (one thread): equal to the last bit,
    // asserted to 1e-13. With it, the damping force's parts are added in turn (rounding of 1e-16
    // per step), grown by the chattering contact over 2000 steps as between 1 and 2 ranks.
    const bool damped = beta > 0.0;
    EXPECT_LT(u, 1e-13);
    EXPECT_LT(probe_u, 1e-13);
    EXPECT_LT(v, damped ? 1e-12 : 1e-13);
    EXPECT_LT(probe_v, damped ? 1e-11 : 1e-13);
    EXPECT_LT(probe_a, damped ? 1e-9 : 1e-13);
    EXPECT_NEAR(overlapped.summary.energy_error, sequential.summary.energy_error, 1e-13);
    EXPECT_EQ(overlapped.summary.steps, sequential.summary.steps);
  }
}

/// 500 steps of a 10-node tetrahedral cantilever (assembled local K per rank) from a bending velocity.
Outcome run_tetrahedra(const mesh::Mesh& mesh, const std::vector<int>* element_rank) {
  const fem::Materials materials{fem::isotropic(2e11, 0.3, 7800.0)};
  const std::vector<fem::DirichletCondition> clamp{{mesh.node_sets.at("clamp"), {0, 1, 2}, {0.0, 0.0, 0.0}, "clamp"}};
  VectorX velocity = VectorX::Zero(3 * mesh.n_nodes());
  for (Index i = 0; i < mesh.n_nodes(); ++i) velocity[3 * i + 2] = mesh.nodes[i][0] * mesh.nodes[i][0];
  const Index tip = transient::nearest_node(mesh, Vec3(0.2, 0.025, 0.04));
  transient::TransientProblem problem;
  problem.materials = materials;
  std::unique_ptr<MeshPartition> partition;
  const mesh::Mesh* run_mesh = &mesh;
  if (element_rank) {
    partition = std::make_unique<MeshPartition>(mesh, *element_rank);
    run_mesh = &partition->local_mesh();
    problem.dirichlet = partition->local_dirichlet(clamp);
    problem.initial.velocity = partition->local_field(velocity);
    problem.probes.push_back({"tip", partition->owned_node(tip)});
    problem.distribution = std::shared_ptr<const transient::Distribution>(partition.get(), [](const auto*) {});
  } else {
    problem.dirichlet = clamp;
    problem.initial.velocity = velocity;
    problem.probes.push_back({"tip", tip});
  }
  transient::TransientOptions options;
  options.progress = false;
  options.end_time = 1e-12;
  const double dt = transient::TransientSolver(*run_mesh, problem, options).dt();
  options.time_step = dt;
  options.end_time = (500 - 0.5) * dt;  // the shortest step of the tests: 500 steps
  transient::TransientSolver solver(*run_mesh, problem, options);
  Outcome outcome;
  outcome.summary = solver.run();
  outcome.summary.dt = dt;
  outcome.probes = solver.probes();
  outcome.energy = solver.energy();
  return outcome;
}

TEST(DistributedTransient, TetrahedraMatchOneProcess) {
  const mesh::Mesh mesh = mesh::read_gmsh(std::string(CRACKLE_SOURCE_DIR) + "/data/meshes/box-tet10.msh");
  const Outcome reference = run_tetrahedra(mesh, nullptr);
  EXPECT_EQ(reference.summary.kernel, "assembled");
  const std::vector<int> parts = partition_elements(mesh, world_size());
  const Outcome distributed = run_tetrahedra(mesh, &parts);
  EXPECT_FALSE(distributed.summary.halo_overlapped);  // the assembled K: all rows, then the halo
  expect_same(distributed, reference, "10-node tetrahedra, PT-Scotch");
}

/// A pointwise term (after the halo, as the crack contact) that fails on one rank at one step.
class FailingTerm final : public fem::ForceTerm {
 public:
  FailingTerm(int rank, Index step) : rank_(rank), step_(step) {}
  std::string name() const override { return "failing"; }
  fem::EnergyRole role() const override { return fem::EnergyRole::external; }
  bool needs_other_forces() const override { return true; }
  void add_force(const fem::StepInput&, VectorX&) override {  // once per step
    if (calls_++ == step_ && world_rank() == rank_) throw SolverError("contact: no solution on rank " + std::to_string(rank_));
  }
  double force_dot(const VectorX&) const override { return 0.0; }

 private:
  int rank_;
  Index step_;
  Index calls_ = 0;
};

TEST(DistributedTransient, AFailureOnOneRankStopsEveryRankWithItsError) {
  // The last rank's step 7 throws: every rank leaves run() with that SolverError (no hang), and
  // ranks other than the failing one name it.
  const mesh::Mesh mesh = cracked_cantilever({24, 2, 4});
  const std::vector<int> parts = partition_elements(mesh, world_size());
  MeshPartition partition(mesh, parts);
  transient::TransientProblem problem;
  problem.materials = {fem::isotropic(2e11, 0.3, 7800.0)};
  problem.dirichlet = partition.local_dirichlet({{mesh.node_sets.at("x-"), {0, 1, 2}, {0.0, 0.0, 0.0}, "clamp"}});
  problem.initial.velocity = partition.local_field(VectorX::Ones(3 * mesh.n_nodes()));
  problem.terms.push_back(std::make_shared<FailingTerm>(world_size() - 1, 7));
  problem.distribution = std::shared_ptr<const transient::Distribution>(&partition, [](const auto*) {});
  transient::TransientOptions options;
  options.progress = false;
  options.end_time = 1e-3;
  transient::TransientSolver solver(partition.local_mesh(), problem, options);
  try {
    solver.run();
    FAIL() << "expected SolverError";
  } catch (const SolverError& error) {
    const std::string expected = (world_rank() == world_size() - 1 || world_size() == 1 ? "" : "rank 1: ") +
                                 std::string("contact: no solution on rank ") + std::to_string(world_size() - 1);
    EXPECT_EQ(std::string(error.what()), expected);
  }
  EXPECT_EQ(solver.summary().status, "unstable");
  EXPECT_EQ(solver.summary().steps, 7);  // steps 0..6 completed on every rank
}

TEST(DistributedTransient, AgreeThrowsTheLowestFailingRanksErrorEverywhere) {
  if (world_size() < 2) GTEST_SKIP() << "needs 2 ranks";
  agree(nullptr);  // nobody failed: returns
  std::exception_ptr mine;
  if (world_rank() == 1) mine = std::make_exception_ptr(IoError("cannot write snapshot_0001_1.vtu"));
  try {
    agree(mine);
    FAIL() << "expected IoError";
  } catch (const IoError& error) {
    EXPECT_EQ(std::string(error.what()), world_rank() == 1 ? "cannot write snapshot_0001_1.vtu"
                                                            : "rank 1: cannot write snapshot_0001_1.vtu");
  }
}

TEST(DistributedTransient, MoreRanksThanElementsIsRefusedOnEveryRank) {
  if (world_size() < 2) GTEST_SKIP() << "needs 2 ranks";
  mesh::BoxSpec box;
  box.cells = {1, 1, 1};
  const mesh::Mesh mesh = mesh::build_box_mesh(box);
  try {
    partition_elements(mesh, world_size());
    FAIL() << "expected InputError";
  } catch (const InputError& error) {
    EXPECT_NE(std::string(error.what()).find("more ranks than the 1 elements"), std::string::npos) << error.what();
  }
}

}  // namespace
}  // namespace crackle::distributed
