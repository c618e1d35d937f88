#include "pipeline/limits.hpp"

#include <sys/resource.h>
#include <unistd.h>

#include <cmath>
#include <cstdio>
#include <fstream>
#include <string>

#include "core/errors.hpp"
#include "io/files.hpp"

namespace crackle::pipeline {
namespace {

/// The first number of a line starting with `key` in a /proc-style file [kB for meminfo], or -1.
double field_of(const char* file, const std::string& key) {
  std::ifstream in(file);
  std::string line;
  while (std::getline(in, line)) {
    if (line.compare(0, key.size(), key) == 0) return std::strtod(line.c_str() + key.size(), nullptr);
  }
  return -1.0;
}

/// A cgroup v2 limit less what the group uses, or -1 without a limit.
double cgroup_room() {
  std::ifstream max_file("/sys/fs/cgroup/memory.max");
  std::string max_text;
  if (!(max_file >> max_text) || max_text == "max") return -1.0;
  const double limit = std::strtod(max_text.c_str(), nullptr);
  std::ifstream current_file("/sys/fs/cgroup/memory.current");
  double current = 0.0;
  current_file >> current;
  return std::max(0.0, limit - current);
}

std::string number_text(double value) {
  if (value < 1e6) return format_number(std::round(value));
  char buffer[32];
  std::snprintf(buffer, sizeof buffer, "%.2g", value);
  return format_number(std::strtod(buffer, nullptr));
}

}  // namespace

std::string bytes_text(double bytes) {
  const char* units[] = {"B", "KiB", "MiB", "GiB", "TiB"};
  int unit = 0;
  while (unit < 4 && bytes >= 1024.0) {
    bytes /= 1024.0;
    ++unit;
  }
  char buffer[48];
  std::snprintf(buffer, sizeof buffer, bytes < 1e4 ? "%.3g %s" : "%.2g %s", bytes, units[unit]);
  return buffer;
}

double available_memory_bytes(std::string* source) {
  double bytes = field_of("/proc/meminfo", "MemAvailable:") * 1024.0;
  std::string from = "MemAvailable in /proc/meminfo";
  if (bytes < 0.0) {
    bytes = static_cast<double>(::sysconf(_SC_AVPHYS_PAGES)) * static_cast<double>(::sysconf(_SC_PAGESIZE));
    from = "available physical pages (sysconf)";
  }
  struct rlimit limit {};
  if (::getrlimit(RLIMIT_AS, &limit) == 0 && limit.rlim_cur != RLIM_INFINITY &&
      static_cast<double>(limit.rlim_cur) < bytes) {
    bytes = static_cast<double>(limit.rlim_cur);
    from = "the address-space limit (ulimit -v)";
  }
  const double cgroup = cgroup_room();
  if (cgroup >= 0.0 && cgroup < bytes) {
    bytes = cgroup;
    from = "the cgroup's memory.max";
  }
  if (source) *source = from;
  return bytes;
}

MeshEstimate estimate_mesh(const scene::Scene& scene) {
  MeshEstimate estimate;
  if (!scene.gmsh_file.empty()) {
    std::error_code error;
    const auto size = std::filesystem::file_size(scene.gmsh_file, error);
    estimate.file_bytes = error ? 0.0 : static_cast<double>(size);
    return estimate;
  }
  const double p = scene.box.order;
  estimate.nodes = 1.0;
  estimate.elements = 1.0;
  for (int axis = 0; axis < 3; ++axis) {
    // Grid lines added for the crack edges and `mesh.box.lines` make a few more cells.
    const double cells = static_cast<double>(scene.box.cells[axis]) + static_cast<double>(scene.box.extra_lines[axis].size()) +
                         (scene.crack ? 2.0 : 0.0);
    estimate.nodes *= cells * p + 1.0;
    estimate.elements *= cells;
  }
  estimate.nodes_per_element = (p + 1.0) * (p + 1.0) * (p + 1.0);
  estimate.dofs = 3.0 * estimate.nodes;
  return estimate;
}

double estimate_memory_bytes(const scene::Scene& scene, const MeshEstimate& mesh, bool stiffness) {
  if (!scene.gmsh_file.empty()) return mesh.file_bytes;  // the reader holds about as much as the text
  // Mesh: coordinates (3 doubles) and two DOF maps per node, connectivity (int32) and a region per element.
  double bytes = mesh.nodes * (24.0 + 24.0) + mesh.elements * (4.0 * mesh.nodes_per_element + 8.0);
  // The lumped mass, its inverse, U, V, the force and the integrator's work vectors: 8 per DOF.
  bytes += 8.0 * 8.0 * mesh.dofs;
  if (stiffness) {
    // K in CSR: a node couples to about (p + 2)^3 nodes on average in a hexahedral mesh, 9 entries each.
    const double p = scene.box.order;
    bytes += 12.0 * mesh.dofs * 3.0 * std::pow(p + 2.0, 3.0);
  }
  return bytes;
}

void check_memory(const scene::Scene& scene, bool stiffness) {
  const MeshEstimate mesh = estimate_mesh(scene);
  const double needed = estimate_memory_bytes(scene, mesh, stiffness);
  std::string source;
  const double available = available_memory_bytes(&source);
  if (needed <= available) return;
  if (!scene.gmsh_file.empty()) {
    throw InputError(scene.where("mesh.gmsh") + ": expected a mesh that fits in memory, got a file of " +
                     bytes_text(mesh.file_bytes) + ", more than the " + bytes_text(available) + " available (" +
                     source + ")");
  }
  const auto& cells = scene.box.cells;
  throw InputError(scene.where("mesh.box.cells") + ": expected a mesh that fits in memory, got [" +
                   std::to_string(cells[0]) + ", " + std::to_string(cells[1]) + ", " + std::to_string(cells[2]) +
                   "] cells of order " + std::to_string(scene.box.order) + ": about " + number_text(mesh.nodes) +
                   " nodes, " + number_text(mesh.elements) + " elements, " + number_text(mesh.dofs) +
                   " DOFs, which need at least " + bytes_text(needed) + " for the mesh" +
                   (stiffness ? ", K" : "") + " and the vectors, more than the " + bytes_text(available) +
                   " available (" + source + ")");
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
                     number_text(steps) + " steps (" + number_text(probe_rows) + " probe rows), which need at least " +
                     bytes_text(history) + ", more than the " + bytes_text(available) + " available (" + source +
                     "); shorten the run or lower transient.history.samples_per_period");
  }
  if (section.snapshots > 0) {
    if (static_cast<double>(section.snapshots) > steps) {
      throw InputError(scene.where("transient.snapshots.count") + ": expected at most one snapshot per step (" +
                       number_text(steps) + " steps), got " + std::to_string(section.snapshots));
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
