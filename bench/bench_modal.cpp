/// \file Benchmark: modal analysis (issue 3) of a cube of n^3 elements clamped on x-, 10 lowest
/// modes, per eigen-solver route. Usage: bench_modal CELLS ORDER ROUTE [MODES], ROUTE one of
/// slepc-cholmod, slepc-mumps, arpack (ARPACK + CHOLMOD). Run slepc-mumps under mpirun for ranks.
/// Prints one Markdown table row (rank 0): route, p, cells, DOFs, ranks, assembly s,
/// factorisation s, iterations s, whole backend call s, post-processing s, total s,
/// peak RSS MiB (rank 0), f1 Hz.
#include <cstdio>
#include <cstdlib>
#include <string>

#include "core/resources.hpp"
#include "mesh/box.hpp"
#include "modal/modal.hpp"

int main(int argc, char** argv) {
  using namespace crackle;
  if (argc < 4) {
    std::fprintf(stderr, "usage: bench_modal CELLS ORDER slepc-cholmod|slepc-mumps|arpack [MODES]\n");
    return 2;
  }
  const int cells = std::atoi(argv[1]);
  const int order = std::atoi(argv[2]);
  const std::string route = argv[3];
  const int modes = argc > 4 ? std::atoi(argv[4]) : 10;
  int petsc_argc = 1;  // PETSc options only through PETSC_OPTIONS
  modal::SlepcSession session(&petsc_argc, &argv);
  try {
    mesh::BoxSpec box;
    box.size = Vec3(1.0, 1.0, 1.0);
    box.cells = {cells, cells, cells};
    box.order = order;
    const mesh::Mesh mesh = mesh::build_box_mesh(box);
    fem::DirichletCondition clamp;
    clamp.nodes = mesh.node_sets.at("x-");
    clamp.components = {0, 1, 2};
    clamp.values = {0.0, 0.0, 0.0};
    clamp.source = "x-";
    modal::ModalOptions options;
    options.modes = modes;
    if (route == "arpack") {
      options.solver = modal::Solver::arpack;
    } else if (route == "slepc-cholmod") {
      options.factorization = modal::Factorization::cholmod;
    } else if (route == "slepc-mumps") {
      options.factorization = modal::Factorization::mumps;
    } else {
      std::fprintf(stderr, "bench_modal: unknown route '%s'\n", route.c_str());
      return 2;
    }
    const modal::ModalResult result = modal::run_modal(mesh, {fem::isotropic(210e9, 0.3, 7850.0)}, {clamp}, options);
    const modal::VariantResult& variant = result.variants.front();
    if (modal::is_output_rank()) {
      const modal::SolveReport& report = variant.modes.report;
      std::printf("| %s | %d | %d^3 | %d | %d | %.2f | %.2f | %.2f | %.2f | %.2f | %.2f | %.0f | %.10g |\n",
                  route.c_str(), order, cells, variant.constraints.n_free(), report.n_ranks, variant.assembly_s,
                  report.factorization_s, report.iterations_s, report.solve_s, report.postprocess_s, result.total_s,
                  peak_rss_bytes() / double(1 << 20), variant.modes.frequencies_hz[0]);
    }
  } catch (const std::exception& error) {
    std::fprintf(stderr, "bench_modal: %s\n", error.what());
    return 1;
  }
  return 0;
}
