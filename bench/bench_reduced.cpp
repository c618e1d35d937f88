/// Benchmark of the reduced transient (HYBRID.md §2-3): cost per step of reduced::ReducedIntegrator
/// against the number of crack pairs and of modes, with the memory of the dense step compliance W
/// (c x c) and the time of the reduction (modes, static images). Body: a steel plate 0.2 x 0.2 x 0.01 m
/// (p = 1, n x n x 2 cells) clamped on x-, with a mid-plane delamination z = 0.005 over x in
/// [0.1, 0.2] (through the width, open at the free edge x+): (n/2) (n + 1) split pairs, frictionless.
/// Load: a harmonic pull in z on the top edge of the free end (the delamination opens and closes
/// every period), 200 steps per excitation period at 40 steps per period of the highest retained mode.
/// Timed: the second period (after one period from rest). `--friction MU` adds Coulomb friction on the
/// delamination (3 rows per pair, the automatic tangential penalty). Usage:
///   bench_reduced [--pairs 100,300,1000] [--modes 10,40] [--steps 200] [--friction 0.3]
/// "CPU us/step": the process's CPU time (run with OPENBLAS_NUM_THREADS=1 OMP_NUM_THREADS=1 to keep
/// worker threads' spinning out). One table row per case on stdout, progress on stderr. "rows/factorisation (largest)": the mean block
/// of the factorisations from scratch in the timed period, and in brackets the largest block factorised
/// or held by the updated factor since the start; "row updates": rows appended to or cut from the
/// frictionless solve's cached factor; "factor Mflop": the factorisations' and updates' floating-point
/// operations counted from the block sizes (frictionless only; independent of the load).
#include <cmath>
#include <ctime>
#include <cstdio>
#include <sstream>
#include <string>
#include <vector>

#include "contact/contact.hpp"
#include "bench_args.hpp"
#include "core/resources.hpp"
#include "fem/material.hpp"
#include "fem/system.hpp"
#include "mesh/box.hpp"
#include "reduced/integrator.hpp"
#include "reduction/reduction.hpp"

namespace {

using crackle::bench::parse_list;


/// CPU time of the process [s] (all threads): on a loaded machine the wall time waits for a core.
double process_cpu_seconds() {
  timespec now{};
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &now);
  return static_cast<double>(now.tv_sec) + 1e-9 * static_cast<double>(now.tv_nsec);
}

}  // namespace

int main(int argc, char** argv) {
  using namespace crackle;
  std::vector<double> pair_targets = {100, 300, 1000}, mode_counts = {10, 40};
  int steps_per_period = 200;
  double friction = 0.0;
  for (int k = 1; k < argc; ++k) {
    const std::string flag = argv[k];
    const std::string value = k + 1 < argc ? argv[k + 1] : "";
    if (flag == "--pairs") pair_targets = parse_list(value), ++k;
    else if (flag == "--modes") mode_counts = parse_list(value), ++k;
    else if (flag == "--steps") steps_per_period = std::stoi(value), ++k;
    else if (flag == "--friction") friction = std::stod(value), ++k;
    else {
      std::fprintf(stderr, "usage: %s [--pairs 100,300] [--modes 10,40] [--steps 200] [--friction 0.3]\n", argv[0]);
      return 2;
    }
  }
  int highest_modes = 0;
  for (double m : mode_counts) highest_modes = std::max(highest_modes, static_cast<int>(m));
  std::printf("| pairs | free DOFs | modes | modes s | static images s | W MiB | us/step | CPU us/step | iterations/step | "
              "factorisations/step | rows/factorisation (largest) | row updates/step | factor Mflop/step | closed fraction | slipping fraction | peak RSS MiB |\n");
  std::printf("|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|\n");
  for (double target : pair_targets) {
    // (n/2) (n + 1) pairs ~ target.
    int n = 4;
    while ((n / 2) * (n + 1) < target) n += 2;
    mesh::BoxSpec box;
    box.size = Vec3(0.2, 0.2, 0.01);
    box.cells = {n, n, 2};
    mesh::CrackSpec crack;
    crack.normal = kZ;
    crack.at = 0.005;
    crack.region = {{{0.1, 0.2}, {0.0, 0.2}, {0.0, 0.0}}};
    const mesh::Mesh mesh = mesh::build_box_mesh(box, crack);
    const fem::Materials materials = {fem::isotropic(210e9, 0.3, 7850.0)};
    const std::vector<fem::DirichletCondition> clamp = {{mesh.node_sets.at("x-"), {0, 1, 2}, {0.0, 0.0, 0.0}, "x-"}};
    const fem::System system(mesh, materials, clamp, mesh::Variant::open);
    std::vector<Index> tip_top;
    for (Index node = 0; node < mesh.n_nodes(); ++node) {
      if (mesh.nodes[node].x() > 0.2 - 1e-9 && mesh.nodes[node].z() > 0.01 - 1e-9) tip_top.push_back(node);
    }
    const fem::LoadShape load = system.load_shape({"pull", tip_top, {}, Vec3(0.0, 0.0, 1.0)});
    reduced::ReductionOptions options;
    options.modes = highest_modes;
    options.friction = friction > 0.0;
    std::fprintf(stderr, "reduction: %d x %d x 2 cells, %lld pairs...\n", n, n,
                 static_cast<long long>(reduced::split_pairs(mesh).size()));
    contact::ContactOptions contact_options;
    contact_options.friction_coefficient = friction;
    const contact::PenaltyChoice penalty = contact::choose_penalty(mesh, materials, contact_options);
    const reduced::Reduction reduction =
        reduced::compute_reduction(system, options, {reduced::OutputPoint{tip_top.front()}}, load);
    for (double modes_value : mode_counts) {
      const Index modes = static_cast<Index>(modes_value);
      reduced::ReducedSystem reduced_system = reduced::reduced_system(reduction, modes, 1.0);
      reduced_system.normal_penalty = penalty.normal_penalty;  // the full model's automatic penalties
      reduced_system.tangential_penalty = penalty.tangential_penalty;
      reduced_system.friction_coefficient = friction;
      const double h = reduced::reduced_time_step(reduced_system, 0.0);
      const double frequency = 1.0 / (steps_per_period * h);
      reduced::ReducedIntegrator integrator(reduced_system, h,
                                            [frequency](double t) { return std::sin(2.0 * kPi * frequency * t); });
      integrator.advance(steps_per_period);
      const long iterations = integrator.total_iterations(), factorizations = integrator.total_factorizations();
      const long factorized_rows = integrator.total_factorized_rows(), updates = integrator.total_factor_updates();
      const double work = integrator.total_factor_work();
      double closed = 0.0, slipping = 0.0;
      Stopwatch clock;
      const double cpu_start = process_cpu_seconds();
      for (int k = 0; k < steps_per_period; ++k) {
        integrator.step();
        closed += integrator.closed_fraction();
        slipping += static_cast<double>(integrator.n_slipping()) / reduced_system.n_pairs();
      }
      const double seconds = clock.seconds(), cpu_seconds = process_cpu_seconds() - cpu_start;
      const double c = static_cast<double>(reduced_system.n_rows());
      std::printf("| %lld | %lld | %lld | %.2f | %.2f | %.1f | %.1f | %.1f | %.2f | %.3f | %.0f (%ld) | %.2f | %.3f | %.2f | %.2f | %.0f |\n",
                  static_cast<long long>(reduced_system.n_pairs()), static_cast<long long>(reduction.shapes.rows()),
                  static_cast<long long>(modes), reduction.modes_s, reduction.flexibility_s,
                  c * c * 8.0 / (1024.0 * 1024.0), 1e6 * seconds / steps_per_period, 1e6 * cpu_seconds / steps_per_period,
                  double(integrator.total_iterations() - iterations) / steps_per_period,
                  double(integrator.total_factorizations() - factorizations) / steps_per_period,
                  double(integrator.total_factorized_rows() - factorized_rows) /
                      std::max(1L, integrator.total_factorizations() - factorizations),
                  integrator.largest_factorized_rows(),
                  double(integrator.total_factor_updates() - updates) / steps_per_period,
                  1e-6 * (integrator.total_factor_work() - work) / steps_per_period,
                  closed / steps_per_period, slipping / steps_per_period, peak_rss_bytes() / (1024.0 * 1024.0));
      std::fflush(stdout);
    }
  }
  return 0;
}
