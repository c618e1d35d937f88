/// Benchmark of the transient solver: nanoseconds per DOF and time step (internal forces,
/// central-difference update, loads, contact, health checks) on box meshes of order p = 1..4,
/// for 1 and 2 threads, with and without a crack in contact, and the share of the time spent in
/// the contact forces (--chunk: elements per chunk of the operator, 0 = its own choice). Usage:
///   bench_transient [--orders 1,2,3,4] [--elements 1e4,1e5,1e6] [--threads 1,2] [--seconds 2]
///                   [--max-dofs 3e7] [--chunk 0] [--crack] [--roofline]
/// One line per case on stdout (a table), progress on stderr. --roofline adds, per case, the
/// update of central differences timed alone (a system with no force: u, v, f, 1/m read, u, v, f
/// written, 56 B per DOF) on vectors of the case's size, the bandwidth that gives, and the step's
/// least time at that bandwidth for its minimal traffic (kMinimalBytes per DOF-step).
#include <omp.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <sstream>
#include <string>
#include <vector>

#include "contact/contact_force.hpp"
#include "bench_args.hpp"
#include "core/resources.hpp"
#include "fem/material.hpp"
#include "mesh/box.hpp"
#include "transient/integrator.hpp"
#include "transient/solver.hpp"

namespace {

/// The least bytes a step moves per DOF: the element kernel reads u and reads and writes f (24 B)
/// plus its indices (5-9 B at p = 1-2), the update reads u, v, f, 1/m and writes u, v, f (56 B).
constexpr double kMinimalBytes = 85.0;

/// A system with no force: CentralDifference::step is then the update loop alone.
class FreeSystem final : public crackle::transient::SecondOrderSystem {
 public:
  explicit FreeSystem(crackle::Index n) : mass_(crackle::VectorX::Constant(n, 2.0)), inverse_(crackle::VectorX::Constant(n, 0.5)) {}
  crackle::Index n_dofs() const override { return mass_.size(); }
  const crackle::VectorX& mass() const override { return mass_; }
  const crackle::VectorX& inverse_mass() const override { return inverse_; }
  double mass_damping() const override { return 0.0; }
  void add_force(const crackle::transient::ForceInput&, crackle::VectorX&) override {}

 private:
  crackle::VectorX mass_, inverse_;
};

/// Seconds per DOF of the update alone on n DOFs (median of 5 timings of about 0.2 s each).
double update_seconds_per_dof(crackle::Index n) {
  FreeSystem system(n);
  crackle::transient::CentralDifference integrator(n);
  crackle::VectorX u = crackle::VectorX::Random(n), v = crackle::VectorX::Random(n);
  const int repetitions = std::max(5, static_cast<int>(2e7 / static_cast<double>(n)));
  std::vector<double> timings;
  for (int k = 0; k < 5; ++k) {
    const crackle::Stopwatch watch;
    for (int r = 0; r < repetitions; ++r) integrator.step(system, 0.0, 1e-9, 1e-9, u, v);
    timings.push_back(watch.seconds() / repetitions / static_cast<double>(n));
  }
  std::sort(timings.begin(), timings.end());
  return timings[2];
}

}  // namespace

int main(int argc, char** argv) {
  using namespace crackle;
  using bench::parse_list;
  std::vector<double> orders = {1, 2, 3, 4}, elements = {1e4, 1e5, 1e6}, threads = {1, 2};
  double seconds = 2.0, max_dofs = 3e7, chunk = 0;
  bool crack = false, roofline = false;
  for (int k = 1; k < argc; ++k) {
    const std::string flag = argv[k];
    const std::string value = k + 1 < argc ? argv[k + 1] : "";
    if (flag == "--orders") orders = parse_list(value), ++k;
    else if (flag == "--elements") elements = parse_list(value), ++k;
    else if (flag == "--threads") threads = parse_list(value), ++k;
    else if (flag == "--seconds") seconds = std::stod(value), ++k;
    else if (flag == "--max-dofs") max_dofs = std::stod(value), ++k;
    else if (flag == "--chunk") chunk = std::stod(value), ++k;
    else if (flag == "--crack") crack = true;
    else if (flag == "--roofline") roofline = true;
    else {
      std::fprintf(stderr, "usage: %s [--orders 1,2] [--elements 1e4,1e5] [--threads 1,2] [--seconds s] "
                           "[--max-dofs n] [--chunk elements] [--crack] [--roofline]\n", argv[0]);
      return 2;
    }
  }
  std::printf("%-3s %-9s %-10s %-7s %-14s %-8s %-12s %-12s %-10s %-9s\n", "p", "elements", "dofs", "threads", "kernel",
              "steps", "ns/dof-step", "setup [s]", "contact %", "pairs");
  for (double order_value : orders) {
    const int order = static_cast<int>(order_value);
    for (double target : elements) {
      const int n = std::max(2, static_cast<int>(std::lround(std::cbrt(target))));
      const double dofs_estimate = 3.0 * std::pow(n * order + 1.0, 3);
      if (dofs_estimate > max_dofs) {
        std::fprintf(stderr, "skip p = %d, %d^3 elements: about %.3g DOFs > --max-dofs\n", order, n, dofs_estimate);
        continue;
      }
      mesh::BoxSpec box;
      box.size = Vec3(1.0, 1.0, 1.0);
      box.cells = {n, n, n};
      box.order = order;
      std::optional<mesh::CrackSpec> spec;
      if (crack) {  // a quarter of the mid plane, from the surface y = 0
        mesh::CrackSpec c;
        c.normal = kZ;
        c.at = std::round(0.5 * n) / n;
        c.region = {{{0.25, 0.75}, {0.0, 0.5}, {0.0, 0.0}}};
        c.region[0] = {std::round(0.25 * n) / n, std::round(0.75 * n) / n};
        c.region[1] = {0.0, std::round(0.5 * n) / n};
        spec = c;
      }
      const Stopwatch mesh_watch;
      const mesh::Mesh mesh = mesh::build_box_mesh(box, spec);
      const double mesh_seconds = mesh_watch.seconds();
      transient::TransientProblem problem;
      problem.materials = {fem::isotropic(2e11, 0.3, 7800.0)};
      problem.dirichlet.push_back({mesh.node_sets.at("z-"), {0, 1, 2}, {0.0, 0.0, 0.0}, "clamp"});
      std::shared_ptr<contact::ContactForce> contact_term;
      if (crack) {
        contact_term = std::make_shared<contact::ContactForce>(mesh, mesh::make_dof_map(mesh, mesh::Variant::open),
                                                               problem.materials, contact::ContactOptions{});
        problem.terms.push_back(contact_term);
      }
      transient::ExternalLoad load;
      load.faces = mesh.face_sets.at("z+");
      load.direction = Vec3(0.3, 0.0, 1.0);
      load.amplitude = 1e6;
      load.signal.frequency = 200.0;
      load.signal.ramp_periods = 0.5;
      problem.loads.push_back(load);
      for (double thread_value : threads) {
        const int thread_count = static_cast<int>(thread_value);
        omp_set_num_threads(thread_count);
        transient::TransientOptions options;
        options.progress = false;
        options.elastic.chunk_elements = static_cast<Index>(chunk);
        options.end_time = 1.0;  // replaced once the step is known
        // Calibrate: a short run, then one of about `seconds`.
        options.end_time = 1e-12;
        transient::TransientSolver probe(mesh, problem, options);
        const double dt = probe.dt();
        options.end_time = 20 * dt;
        transient::TransientSolver warm(mesh, problem, options);
        warm.run();
        const double per_step = warm.summary().wall_s / warm.summary().steps;
        const double steps = std::max(20.0, std::min(1e7, seconds / std::max(per_step, 1e-9)));
        options.end_time = steps * dt;
        transient::TransientSolver solver(mesh, problem, options);
        const transient::TransientSummary& summary = solver.run();
        const auto contact_entry = summary.term_seconds.find("contact");
        const double contact_seconds = contact_entry == summary.term_seconds.end() ? 0.0 : contact_entry->second;
        std::printf("%-3d %-9lld %-10lld %-7d %-14s %-8lld %-12.2f %-12.2f %-10.2f %-9lld\n", order,
                    static_cast<long long>(mesh.n_elements()), static_cast<long long>(summary.n_dofs), thread_count,
                    summary.kernel.c_str(), static_cast<long long>(summary.steps), summary.ns_per_dof_step,
                    summary.setup_s + mesh_seconds, 100.0 * contact_seconds / summary.wall_s,
                    static_cast<long long>(contact_term ? contact_term->contact().n_pairs() : 0));
        if (roofline) {
          const double update = update_seconds_per_dof(summary.n_dofs);
          const double bandwidth = 56.0 / update;
          std::printf("    update alone %.3f ns/dof (%.1f GB/s at 56 B/dof); roofline of the step %.2f ns/dof-step "
                      "(%.0f B/dof-step), the step at %.1fx it\n",
                      1e9 * update, 1e-9 * bandwidth, 1e9 * kMinimalBytes / bandwidth, kMinimalBytes,
                      summary.ns_per_dof_step / (1e9 * kMinimalBytes / bandwidth));
        }
        std::fflush(stdout);
      }
    }
  }
  return 0;
}
