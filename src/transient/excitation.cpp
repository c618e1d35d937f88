#include "transient/excitation.hpp"

#include <cmath>
#include <limits>

#include "core/errors.hpp"

namespace crackle::transient {

double smooth_ramp(double time, double length) {
  if (time < 0.0) return 0.0;
  if (time >= length) return 1.0;
  const double s = std::sin(0.5 * M_PI * time / length);
  return s * s;
}

double Signal::value(double time) const {
  const double t = time - start;
  if (t < 0.0) return 0.0;
  switch (kind) {
    case SignalKind::harmonic: {
      const double ramp = ramp_periods > 0.0 ? smooth_ramp(t, ramp_periods / frequency) : 1.0;
      return ramp * std::sin(2.0 * M_PI * frequency * t + phase);
    }
    case SignalKind::pulse:
      return t <= duration ? std::sin(M_PI * t / duration) : 0.0;
    case SignalKind::step:
      return duration > 0.0 ? smooth_ramp(t, duration) : 1.0;
  }
  return 0.0;
}

void check_signal(const Signal& signal, const std::string& where) {
  if (!std::isfinite(signal.start) || !std::isfinite(signal.phase)) {
    throw InputError(where + ": expected a finite start and phase, got start = " + format_number(signal.start) +
                     " s, phase = " + format_number(signal.phase));
  }
  switch (signal.kind) {
    case SignalKind::harmonic:
      if (!(signal.frequency > 0.0) || !std::isfinite(signal.frequency) || !(signal.ramp_periods >= 0.0)) {
        throw InputError(where + ": expected frequency > 0 Hz and ramp_periods >= 0, got frequency = " +
                         format_number(signal.frequency) + ", ramp_periods = " + format_number(signal.ramp_periods));
      }
      break;
    case SignalKind::pulse:
      if (!(signal.duration > 0.0) || !std::isfinite(signal.duration)) {
        throw InputError(where + ": expected a pulse duration > 0 s, got " + format_number(signal.duration));
      }
      break;
    case SignalKind::step:
      if (!(signal.duration >= 0.0) || !std::isfinite(signal.duration)) {
        throw InputError(where + ": expected a ramp duration >= 0 s, got " + format_number(signal.duration));
      }
      break;
  }
}

VectorX nodal_field(const mesh::Mesh& mesh, const mesh::DofMap& dofs, const NodalField& field) {
  VectorX values = VectorX::Zero(dofs.n_dofs());
  for (Index node = 0; node < mesh.n_nodes(); ++node) {
    const Vec3 value = field(node, mesh.nodes[node]);
    for (int c = 0; c < 3; ++c) values[dofs.dof(node, c)] = value[c];
  }
  return values;
}

VectorX uniform_on_nodes(const mesh::DofMap& dofs, const std::vector<Index>& nodes, const Vec3& value) {
  VectorX values = VectorX::Zero(dofs.n_dofs());
  for (Index node : nodes) {
    if (node < 0 || node >= static_cast<Index>(dofs.dof_node.size())) {
      throw InputError("node " + std::to_string(node) + " outside a mesh of " + std::to_string(dofs.dof_node.size()) +
                       " nodes");
    }
    for (int c = 0; c < 3; ++c) values[dofs.dof(node, c)] = value[c];
  }
  return values;
}

Index nearest_node(const mesh::Mesh& mesh, const Vec3& point) {
  Index best = -1;
  double best_distance = std::numeric_limits<double>::infinity();
  for (Index node = 0; node < mesh.n_nodes(); ++node) {
    const double distance = (mesh.nodes[node] - point).squaredNorm();
    if (distance < best_distance) {
      best_distance = distance;
      best = node;
    }
  }
  if (best < 0) throw InputError("nearest node: the mesh has no nodes");
  return best;
}

}  // namespace crackle::transient
