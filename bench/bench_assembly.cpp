/// \file Benchmark: assembly time and memory of K and the lumped M on a cube of n^3 elements.
/// Usage: bench_assembly CELLS ORDER [REPEATS]; threads from OMP_NUM_THREADS.
/// Prints one Markdown table row: order, cells, DOFs, threads, K nonzeros, K MiB, K s, M s, peak MiB.
#include <omp.h>

#include <cstdio>
#include <cstdlib>

#include "core/resources.hpp"
#include "fem/assembly.hpp"
#include "mesh/box.hpp"

int main(int argc, char** argv) {
  using namespace crackle;
  if (argc < 3) {
    std::fprintf(stderr, "usage: bench_assembly CELLS ORDER [REPEATS]\n");
    return 2;
  }
  const int cells = std::atoi(argv[1]);
  const int order = std::atoi(argv[2]);
  const int repeats = argc > 3 ? std::atoi(argv[3]) : 3;
  mesh::BoxSpec box;
  box.size = Vec3(1.0, 1.0, 1.0);
  box.cells = {cells, cells, cells};
  box.order = order;
  const mesh::Mesh mesh = mesh::build_box_mesh(box);
  const mesh::DofMap dofs = mesh::make_dof_map(mesh, mesh::Variant::open);
  const fem::Materials materials = {fem::isotropic(210e9, 0.3, 7850.0)};

  double best_stiffness = 1e300, best_mass = 1e300;
  Index nonzeros = 0;
  double bytes = 0;
  for (int r = 0; r < repeats; ++r) {
    Stopwatch clock;
    SparseMatrix stiffness = fem::assemble_stiffness(mesh, dofs, materials);
    best_stiffness = std::min(best_stiffness, clock.seconds());
    nonzeros = static_cast<Index>(stiffness.nonZeros());
    bytes = nonzeros * (sizeof(double) + sizeof(Index)) + (stiffness.rows() + 1) * sizeof(Index);
    clock.restart();
    VectorX lumped = fem::assemble_lumped_mass(mesh, dofs, materials);
    best_mass = std::min(best_mass, clock.seconds());
    if (!(lumped.minCoeff() > 0.0)) return 1;
  }
  std::printf("| %d | %d^3 | %d | %d | %d | %.0f | %.3f | %.4f | %.0f |\n", order, cells, dofs.n_dofs(),
              omp_get_max_threads(), nonzeros, bytes / (1 << 20), best_stiffness, best_mass,
              peak_rss_bytes() / double(1 << 20));
  return 0;
}
