#include "pipeline/placement.hpp"

#include <Eigen/Geometry>
#include <algorithm>
#include <limits>

#include "core/errors.hpp"
#include "transient/excitation.hpp"

namespace crackle::pipeline {
namespace {

/// The split crack pair (not on the front) nearest `point`, or the one with `node` as a face node;
/// nullptr if there is none.
const mesh::CrackPair* nearest_split_pair(const mesh::Mesh& mesh, const Vec3& point, Index node = -1) {
  const mesh::CrackPair* best = nullptr;
  double best_distance = std::numeric_limits<double>::infinity();
  for (const mesh::CrackPair& pair : mesh.crack_pairs) {
    if (pair.on_front()) continue;
    if (node >= 0) {
      if (pair.plus == node || pair.minus == node) return &pair;
      continue;
    }
    const double distance = (mesh.nodes[pair.plus] - point).norm();
    if (distance < best_distance) {
      best_distance = distance;
      best = &pair;
    }
  }
  return best;
}

}  // namespace

PointPlacer::PointPlacer(const scene::Scene& scene, const mesh::Mesh& mesh) : scene_(scene), mesh_(mesh) {
  low_ = high_ = mesh.nodes.front();
  for (const Vec3& x : mesh.nodes) {
    low_ = low_.cwiseMin(x);
    high_ = high_.cwiseMax(x);
  }
}

Placement PointPlacer::place(const Vec3& point, const std::string& key) const {
  Placement placement;
  placement.node = transient::nearest_node(mesh_, point);
  placement.distance = (mesh_.nodes[placement.node] - point).norm();
  const double outside = (low_ - point).cwiseMax(point - high_).cwiseMax(0.0).norm();
  const double element = element_size_at(placement.node);
  if (outside > kOutsideTolerance * (high_ - low_).norm() || placement.distance > element) {
    const auto text = [](const Vec3& x) {
      return "(" + format_number(x[0]) + ", " + format_number(x[1]) + ", " + format_number(x[2]) + ")";
    };
    std::string box;
    for (int axis = 0; axis < 3; ++axis) {
      box += (axis ? " x [" : "[") + format_number(low_[axis]) + ", " + format_number(high_[axis]) + "]";
    }
    throw InputError(scene_.where(key) + ": expected a point in the body (bounding box " + box + " m), got " +
                     text(point) + ", " + format_number(placement.distance) + " m from the nearest node " +
                     text(mesh_.nodes[placement.node]) +
                     (outside > 0.0 ? ", " + format_number(outside) + " m outside the box" : std::string()));
  }
  return placement;
}

double PointPlacer::element_size_at(Index node) const {
  double size = 0.0;
  const int n = mesh_.nodes_per_element();
  for (Index e = 0; e < mesh_.n_elements(); ++e) {
    const Index* nodes = mesh_.element_nodes(e);
    if (std::find(nodes, nodes + n, node) == nodes + n) continue;
    Vec3 low = mesh_.nodes[nodes[0]], high = low;
    for (int a = 1; a < n; ++a) {
      low = low.cwiseMin(mesh_.nodes[nodes[a]]);
      high = high.cwiseMax(mesh_.nodes[nodes[a]]);
    }
    size = std::max(size, (high - low).norm());
  }
  return size;
}

transient::Probe place_probe(const scene::Scene& scene, const Model& model, const mesh::DofMap& dofs,
                             const PointPlacer& placer, std::size_t index, const contact::ContactForce* contact) {
  const scene::ProbeSection& probe = scene.transient->probes[index];
  const std::string entry = "transient.probes[" + std::to_string(index) + "]";
  const mesh::Mesh& mesh = model.mesh;
  transient::Probe placed;
  placed.name = probe.name;
  if (!probe.crack_opening) {
    placed.node = placer.place(probe.point, entry + ".point").node;
    if (!probe.side) return placed;
    const mesh::CrackPair* pair = nearest_split_pair(mesh, probe.point, placed.node);
    if (!pair) {
      const Vec3& x = mesh.nodes[placed.node];
      throw InputError(scene.where(entry + ".side") + ": expected a point on a crack face (side chooses a copy of a "
                       "split crack node), got the nearest node " + std::to_string(placed.node) + " at (" +
                       format_number(x[0]) + ", " + format_number(x[1]) + ", " + format_number(x[2]) +
                       ") that is not split (off the crack or on its front)");
    }
    placed.node = probe.side == scene::FaceSide::upper ? pair->minus : pair->plus;
    return placed;
  }
  placer.place(probe.point, entry + ".crack_opening");  // inside the body
  const mesh::CrackPair* pair = nearest_split_pair(mesh, probe.point);
  if (!pair) {
    throw InputError(scene.where(entry + ".crack_opening") + ": expected a crack with split pairs, got none (every "
                     "crack node is on the front)");
  }
  if (dofs.dof(pair->minus, 0) == dofs.dof(pair->plus, 0)) {
    throw InputError(scene.where(entry + ".crack_opening") + ": expected transient.variant: open (the crack faces "
                     "are tied in the uncracked variant, so the opening is always zero)");
  }
  placed.node = pair->plus;
  placed.minus_node = pair->minus;
  const Vec3 normal = pair->normal.normalized();
  Eigen::Index least = 0;
  normal.cwiseAbs().minCoeff(&least);
  const Vec3 tangent = (Vec3::Unit(least) - normal[least] * normal).normalized();
  placed.frame.row(0) = normal.transpose();
  placed.frame.row(1) = tangent.transpose();
  placed.frame.row(2) = normal.cross(tangent).transpose();
  placed.initial_gap = scene_contact_options(scene).initial_gap;
  if (contact) {
    const Index k = contact->contact().find_pair(dofs.dof(pair->plus, 0));
    if (k >= 0) placed.state = [contact, k] { return contact->contact().pair_state(k); };
    placed.state_at_step_end = contact->contact().implicit();
  }
  return placed;
}

void check_points(const scene::Scene& scene, const Model& model) {
  if (!scene.transient) return;
  const scene::TransientSection& section = *scene.transient;
  const PointPlacer placer(scene, model.mesh);
  if (section.excitation && section.excitation->point) {
    placer.place(*section.excitation->point, "transient.excitation.point");
  }
  const mesh::Variant variant = section.variant;
  const mesh::DofMap& dofs = model.system(variant)->dofs();
  for (std::size_t p = 0; p < section.probes.size(); ++p) place_probe(scene, model, dofs, placer, p, nullptr);
}

}  // namespace crackle::pipeline
