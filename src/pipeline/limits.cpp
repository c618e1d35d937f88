#include "pipeline/limits.hpp"

#include <sys/resource.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <string>

#include "core/errors.hpp"
#include "core/resources.hpp"
#include "io/files.hpp"
#include "pipeline/model.hpp"
#include "sweep/harmonic_balance.hpp"

namespace crackle::pipeline {
namespace {

/// Most cells along an axis for which estimate_mesh lists the grid lines (a million lines are 8 MB;
/// a box of even 1e4 cells along each of three axes is far beyond any memory).
constexpr int kListedCells = 1000000;

/// A count or size for messages: whole below 1e6, else two significant digits ("1.2e7").
std::string rounded_text(double value) {
  if (value < 1e6) return format_number(std::round(value));
  char buffer[32];
  std::snprintf(buffer, sizeof buffer, "%.2g", value);
  return format_number(std::strtod(buffer, nullptr));
}

}  // namespace

MeshEstimate estimate_mesh(const scene::Scene& scene, MeshUse use) {
  MeshEstimate estimate;
  if (!scene.gmsh_file.empty()) {
    std::error_code error;
    const auto size = std::filesystem::file_size(scene.gmsh_file, error);
    estimate.file_bytes = error ? 0.0 : static_cast<double>(size);
    return estimate;
  }
  const double p = scene.box.order;
  // The grid lines the mesher will use (grading layers towards the crack front included, which can
  // multiply the cells several times), when there are few enough to list; else the cells requested,
  // which is already far more than fits.
  std::array<double, 3>& cells = estimate.cells;
  if (*std::max_element(scene.box.cells.begin(), scene.box.cells.end()) <= kListedCells) {
    const std::array<std::vector<double>, 3> lines = box_lines(scene, use);
    for (int axis = 0; axis < 3; ++axis) cells[axis] = static_cast<double>(lines[axis].size()) - 1.0;
  } else {
    for (int axis = 0; axis < 3; ++axis) {
      // Grid lines added for the crack edges and `mesh.box.lines` make a few more cells.
      cells[axis] = static_cast<double>(scene.box.cells[axis]) +
                    static_cast<double>(scene.box.extra_lines[axis].size()) + (scene.crack ? 2.0 : 0.0);
    }
  }
  estimate.nodes = 1.0;
  estimate.elements = 1.0;
  for (int axis = 0; axis < 3; ++axis) {
    estimate.nodes *= cells[axis] * p + 1.0;
    estimate.elements *= cells[axis];
  }
  estimate.nodes_per_element = (p + 1.0) * (p + 1.0) * (p + 1.0);
  estimate.dofs = 3.0 * estimate.nodes;
  return estimate;
}

double estimate_memory_bytes(const scene::Scene& scene, const MeshEstimate& mesh, int matrices) {
  if (!scene.gmsh_file.empty()) return mesh.file_bytes;  // the reader holds about as much as the text
  // Mesh: coordinates (3 doubles) and two DOF maps per node, connectivity (int32) and a region per element.
  double bytes = mesh.nodes * (24.0 + 24.0) + mesh.elements * (4.0 * mesh.nodes_per_element + 8.0);
  // The lumped mass, its inverse, U, V, the force and the integrator's work vectors: 8 per DOF.
  bytes += 8.0 * 8.0 * mesh.dofs;
  // A matrix of K's pattern in CSR: a node couples to (p + 2)^3 nodes on average in a hexahedral
  // mesh (exactly, over the lattice's vertex, edge, face and interior nodes), 9 entries each.
  const double p = scene.box.order;
  bytes += matrices * 12.0 * mesh.dofs * 3.0 * std::pow(p + 2.0, 3.0);
  return bytes;
}

void check_memory(const scene::Scene& scene, int matrices, MeshUse use) {
  const MeshEstimate mesh = estimate_mesh(scene, use);
  const double needed = estimate_memory_bytes(scene, mesh, matrices);
  std::string source;
  const double available = available_memory_bytes(&source);
  if (needed <= available) return;
  if (!scene.gmsh_file.empty()) {
    throw InputError(scene.where("mesh.gmsh") + ": expected a mesh that fits in memory, got a file of " +
                     bytes_text(mesh.file_bytes) + ", more than the " + bytes_text(available) + " available (" +
                     source + ")");
  }
  const auto& cells = scene.box.cells;
  std::string graded;  // the lines the crack's edges and the grading layers add, when they add many
  if (mesh.cells[0] * mesh.cells[1] * mesh.cells[2] > 1.5 * cells[0] * cells[1] * cells[2]) {
    graded = " (" + rounded_text(mesh.cells[0]) + " x " + rounded_text(mesh.cells[1]) + " x " +
             rounded_text(mesh.cells[2]) + " with the crack's lines and the grading layers of mesh.box.grading)";
  }
  const std::string matrix_text = matrices == 1  ? ", K"
                                  : matrices > 1 ? ", " + std::to_string(matrices) + " sparse matrices of K's size"
                                                 : "";
  throw InputError(scene.where("mesh.box.cells") + ": expected a mesh that fits in memory, got [" +
                   std::to_string(cells[0]) + ", " + std::to_string(cells[1]) + ", " + std::to_string(cells[2]) +
                   "] cells of order " + std::to_string(scene.box.order) + graded + ": about " + rounded_text(mesh.nodes) +
                   " nodes, " + rounded_text(mesh.elements) + " elements, " + rounded_text(mesh.dofs) +
                   " DOFs, which need at least " + bytes_text(needed) + " for the mesh" + matrix_text +
                   " and the vectors, more than the " + bytes_text(available) + " available (" + source + ")");
}

void check_sweep_memory(const scene::Scene& scene, Index rows, Index modes) {
  if (!scene.sweep || scene.sweep->method != scene::SweepMethod::harmonic_balance) return;
  const scene::SweepSection& section = *scene.sweep;
  sweep::HarmonicBalanceOptions options;
  options.harmonics = section.harmonics;
  options.solver = section.solver;
  const bool matrix_free = sweep::HarmonicBalance::selects_matrix_free(options, rows);
  const double needed = sweep::HarmonicBalance::memory_bytes(rows, modes, section.harmonics, matrix_free);
  std::string source;
  const double available = available_memory_bytes(&source);
  if (needed <= available) return;
  const double unknowns = static_cast<double>(rows) * (2.0 * section.harmonics + 1.0);
  std::string hint;
  if (!matrix_free) {
    const double krylov = sweep::HarmonicBalance::memory_bytes(rows, modes, section.harmonics, true);
    hint = krylov <= available ? "; sweep.solver: krylov (or auto) would need " + bytes_text(krylov)
                               : "; the krylov solver would need " + bytes_text(krylov);
  }
  throw InputError(scene.where("sweep.harmonics") + ": expected a harmonic balance that fits in memory, got " +
                   std::to_string(rows) + " pair rows x (2 x " + std::to_string(section.harmonics) + " + 1) = " +
                   rounded_text(unknowns) + " unknowns, which need at least " + bytes_text(needed) + " with the " +
                   (matrix_free ? "krylov" : "dense") + " solver, more than the " + bytes_text(available) +
                   " available (" + source + ")" + hint);
}

void check_run_outputs(const scene::Scene& scene, const MeshEstimate& mesh, double steps, double probe_rows,
                       const std::filesystem::path& directory) {
  const scene::TransientSection& section = *scene.transient;
  const double probes = static_cast<double>(section.probes.size());
  // Probe rows (9 values per probe and the time), the spectrum's full-rate component per probe,
  // energy rows (every 10 steps, 9 columns), and the CSV text of probes.csv made at the end (~25
  // characters a value).
  const double history = probe_rows * (8.0 + 72.0 * probes) + (scene.spectrum ? 8.0 * steps * probes : 0.0) +
                         steps / 10.0 * 80.0 + probe_rows * (1.0 + 9.0 * probes) * 25.0;
  std::string source;
  const double available = available_memory_bytes(&source);
  const std::string length_key = section.periods ? "transient.periods" : "transient.duration";
  if (history > available) {
    throw InputError(scene.where(length_key) + ": expected a run whose histories fit in memory, got " +
                     rounded_text(steps) + " steps (" + rounded_text(probe_rows) + " probe rows), which need at least " +
                     bytes_text(history) + ", more than the " + bytes_text(available) + " available (" + source +
                     "); shorten the run or lower transient.history.samples_per_period");
  }
  if (section.snapshots > 0) {
    if (static_cast<double>(section.snapshots) > steps) {
      throw InputError(scene.where("transient.snapshots.count") + ": expected at most one snapshot per step (" +
                       rounded_text(steps) + " steps), got " + std::to_string(section.snapshots));
    }
    // A binary VTU: coordinates and displacement (3 + 3 doubles per node), connectivity and offsets.
    const double nodes = mesh.nodes > 0.0 ? mesh.nodes : mesh.file_bytes / 40.0;
    const double elements = mesh.elements > 0.0 ? mesh.elements : mesh.file_bytes / 80.0;
    const double each = 48.0 * nodes + elements * (8.0 * mesh.nodes_per_element + 9.0) + 2000.0;
    const double disk = io::available_disk_bytes(directory);
    const double total = each * section.snapshots;
    if (total > disk) {
      throw InputError(scene.where("transient.snapshots.count") + ": expected snapshots that fit on the disk, got " +
                       std::to_string(section.snapshots) + " of about " + bytes_text(each) + " each (" +
                       bytes_text(total) + "), more than the " + bytes_text(disk) + " free in " + directory.string());
    }
  }
}

}  // namespace crackle::pipeline
