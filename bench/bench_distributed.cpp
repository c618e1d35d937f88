/// Benchmark of the full transient over MPI ranks (issue 17): nanoseconds per DOF and time step on
/// box meshes with a crack in contact (a quarter of the mid plane), the partition's balance, the
/// halo traffic per step (from the ghost counts) and the memory per rank. Run under mpirun:
///   mpirun -np R bench_distributed [--orders 1,2] [--elements 1e4,1e5] [--steps 200] [--serial]
///                                  [--overlap on,off]
/// (OMP_NUM_THREADS threads per rank). --serial also times the one-process solver (no
/// distribution) on rank 0 alone, for the cost of the distributed path at one rank. --overlap:
/// the halo overlapped with the interior elements (on), after all elements (off), or both in turn
/// on the same partition (the default); the elements per rank split into boundary (touching a DOF
/// another rank holds) and interior.
/// One line per case on stdout from rank 0.
#include <omp.h>
#include <petscsys.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <sstream>
#include <string>
#include <vector>

#include "bench_args.hpp"
#include "core/resources.hpp"
#include "distributed/partition.hpp"
#include "fem/material.hpp"
#include "mesh/box.hpp"
#include "transient/solver.hpp"

namespace {

using namespace crackle;

using bench::parse_list;

double max_over_ranks(double value) {
  MPI_Allreduce(MPI_IN_PLACE, &value, 1, MPI_DOUBLE, MPI_MAX, PETSC_COMM_WORLD);
  return value;
}

struct Case {
  mesh::Mesh mesh;
  fem::Materials materials{fem::isotropic(2e11, 0.3, 7800.0)};
  std::vector<fem::DirichletCondition> clamp;
  VectorX velocity;
};

Case make_case(int order, int n) {
  Case c;
  mesh::BoxSpec box;
  box.size = Vec3(1.0, 1.0, 1.0);
  box.cells = {n, n, n};
  box.order = order;
  mesh::CrackSpec crack;
  crack.normal = kZ;
  crack.at = std::round(0.5 * n) / n;
  crack.region = {{{std::round(0.25 * n) / n, std::round(0.75 * n) / n}, {0.0, std::round(0.5 * n) / n}, {0.0, 0.0}}};
  c.mesh = mesh::build_box_mesh(box, crack);
  c.clamp.push_back({c.mesh.node_sets.at("z-"), {0, 1, 2}, {0.0, 0.0, 0.0}, "clamp"});
  c.velocity = VectorX::Zero(3 * c.mesh.n_nodes());
  for (Index i = 0; i < c.mesh.n_nodes(); ++i) c.velocity[3 * i] = c.mesh.nodes[i][2];  // bending
  return c;
}

/// Runs `steps` steps; returns the summary of this rank and, with a partition, the wall time of the
/// steps spent in its halo and reductions.
transient::TransientSummary run(const mesh::Mesh& mesh, transient::TransientProblem problem, double steps,
                                const distributed::MeshPartition* partition = nullptr, double* communication = nullptr,
                                bool overlap = true) {
  transient::TransientOptions options;
  options.progress = false;
  options.overlap_halo = overlap;
  options.end_time = 1e-12;
  const double dt = transient::TransientSolver(mesh, problem, options).dt();
  options.time_step = dt;
  options.end_time = (steps - 0.5) * dt;
  transient::TransientSolver solver(mesh, problem, options);
  const double before = partition ? partition->communication_seconds() : 0.0;
  transient::TransientSummary summary = solver.run();
  if (communication) *communication = partition->communication_seconds() - before;
  return summary;
}

}  // namespace

int main(int argc, char** argv) {
  std::vector<double> orders = {1, 2}, elements = {1e4};
  double steps = 200;
  bool serial = false;
  std::vector<bool> overlaps = {true, false};
  std::vector<char*> petsc_arguments{argv[0]};
  for (int k = 1; k < argc; ++k) {
    const std::string flag = argv[k];
    const std::string value = k + 1 < argc ? argv[k + 1] : "";
    if (flag == "--orders") orders = parse_list(value), ++k;
    else if (flag == "--elements") elements = parse_list(value), ++k;
    else if (flag == "--steps") steps = std::stod(value), ++k;
    else if (flag == "--serial") serial = true;
    else if (flag == "--overlap" && (value == "on" || value == "off" || value == "on,off" || value == "off,on")) {
      overlaps.clear();
      std::stringstream list(value);
      for (std::string item; std::getline(list, item, ',');) overlaps.push_back(item == "on");
      ++k;
    } else {
      std::fprintf(stderr, "usage: %s [--orders 1,2] [--elements 1e4,1e5] [--steps n] [--serial] [--overlap on,off]\n",
                   argv[0]);
      return 2;
    }
  }
  int petsc_argc = 1;
  char** petsc_argv = petsc_arguments.data();
  if (PetscInitialize(&petsc_argc, &petsc_argv, nullptr, nullptr) != 0) return 1;
  const int rank = distributed::world_rank(), ranks = distributed::world_size();
  if (rank == 0) {
    std::printf("%-3s %-9s %-10s %-5s %-7s %-6s %-8s %-12s %-16s %-16s %-11s %-14s %-12s %-12s %-8s\n", "p", "elements",
                "dofs", "ranks", "threads", "steps", "overlap", "ns/dof-step", "elements/rank", "boundary/rank",
                "ghost dofs", "halo B/step", "RSS/rank MB", "1-proc ns", "comm %");
  }
  for (double order_value : orders) {
    const int order = static_cast<int>(order_value);
    for (double target : elements) {
      const int n = std::max(2, static_cast<int>(std::lround(std::cbrt(target))));
      const Case c = make_case(order, n);
      double serial_ns = 0.0;
      if (serial && rank == 0) {  // the one-process solver on the whole mesh, rank 0 alone
        transient::TransientProblem problem;
        problem.materials = c.materials;
        problem.dirichlet = c.clamp;
        problem.initial.velocity = c.velocity;
        problem.terms.push_back(std::make_shared<contact::ContactForce>(
            c.mesh, mesh::make_dof_map(c.mesh, mesh::Variant::open), c.materials, contact::ContactOptions{}));
        serial_ns = run(c.mesh, problem, steps).ns_per_dof_step;
      }
      MPI_Barrier(PETSC_COMM_WORLD);
      const distributed::MeshPartition partition(c.mesh, distributed::partition_elements(c.mesh, ranks));
      transient::TransientProblem problem;
      problem.materials = c.materials;
      problem.dirichlet = partition.local_dirichlet(c.clamp);
      problem.initial.velocity = partition.local_field(c.velocity);
      problem.terms.push_back(partition.local_contact(c.materials, contact::ContactOptions{}));
      problem.distribution = std::shared_ptr<const transient::Distribution>(&partition, [](const auto*) {});
      const distributed::HaloCounts halo = partition.halo_counts();
      const auto range_over_ranks = [](double value) {
        double low = value, high = value;
        MPI_Allreduce(MPI_IN_PLACE, &low, 1, MPI_DOUBLE, MPI_MIN, PETSC_COMM_WORLD);
        MPI_Allreduce(MPI_IN_PLACE, &high, 1, MPI_DOUBLE, MPI_MAX, PETSC_COMM_WORLD);
        char text[64];
        std::snprintf(text, sizeof text, "%.0f..%.0f", low, high);
        return std::string(text);
      };
      const std::string boundary = range_over_ranks(static_cast<double>(halo.boundary_elements));
      const double ghosts = max_over_ranks(static_cast<double>(halo.ghost_dofs));
      const double bytes = max_over_ranks(halo.bytes_per_step);
      for (bool overlap : overlaps) {
        double communication = 0.0;  // of the steps, in the halo and the reductions (waits included)
        const transient::TransientSummary summary =
            run(partition.local_mesh(), problem, steps, &partition, &communication, overlap);
        communication = max_over_ranks(communication);
        const double rss = max_over_ranks(static_cast<double>(peak_rss_bytes())) / 1e6;
        const double ns = max_over_ranks(summary.ns_per_dof_step);
        if (rank == 0) {
          char balance[64];
          std::snprintf(balance, sizeof balance, "%lld..%lld", static_cast<long long>(summary.elements_min),
                        static_cast<long long>(summary.elements_max));
          std::printf("%-3d %-9lld %-10lld %-5d %-7d %-6lld %-8s %-12.2f %-16s %-16s %-11.0f %-14.0f %-12.0f %-12.2f %-8.1f\n",
                      order, static_cast<long long>(summary.n_elements), static_cast<long long>(summary.n_dofs), ranks,
                      omp_get_max_threads(), static_cast<long long>(summary.steps),
                      summary.halo_overlapped ? "on" : "off", ns, balance, boundary.c_str(), ghosts, bytes, rss,
                      serial_ns, 100.0 * communication / std::max(summary.wall_s, 1e-12));
          std::fflush(stdout);
        }
      }
    }
  }
  PetscFinalize();
  return 0;
}
