#pragma once
/// \file Where the points of a scene act on the mesh: probes (a node, the chosen copy of a split
/// crack node, or a crack pair's opening) and point loads. Every refusal a run makes for a point
/// (outside the body, not on a crack face, no split pair) is made here, so that `crackle check`
/// makes the same ones before anything runs (check_points).
#include <string>

#include "contact/contact_force.hpp"
#include "mesh/mesh.hpp"
#include "pipeline/model.hpp"
#include "scene/scene.hpp"
#include "transient/solver.hpp"

namespace crackle::pipeline {

/// Where a point of the scene (a probe, a point force) acts: the nearest node, and how far it is.
struct Placement {
  Index node = 0;
  double distance = 0.0;  ///< [m]
};

/// Places points of the scene on nodes. A point is refused (InputError naming `key`) when it lies
/// outside the body's bounding box by more than kOutsideTolerance of its diagonal, or farther from
/// its nearest node than the largest element at that node (a point in a notch of a Gmsh body).
class PointPlacer {
 public:
  static constexpr double kOutsideTolerance = 1e-6;

  PointPlacer(const scene::Scene& scene, const mesh::Mesh& mesh);
  Placement place(const Vec3& point, const std::string& key) const;

 private:
  /// The largest bounding-box diagonal of the elements around a node.
  double element_size_at(Index node) const;

  const scene::Scene& scene_;
  const mesh::Mesh& mesh_;
  Vec3 low_, high_;
};

/// Probe `index` of transient.probes on the mesh: the nearest node (the chosen copy of a split crack
/// node with `side`), or for crack_opening the nearest split crack pair with its frame (n+ and two
/// tangents), g0 and, with `contact`, its contact state (null: no state).
transient::Probe place_probe(const scene::Scene& scene, const Model& model, const mesh::DofMap& dofs,
                             const PointPlacer& placer, std::size_t index, const contact::ContactForce* contact);

/// Places every point of the scene's transient: section as a run would (the excitation point, each
/// probe on the DOFs of transient.variant), throwing the InputError the run would throw. Without a
/// transient: section it does nothing.
void check_points(const scene::Scene& scene, const Model& model);

}  // namespace crackle::pipeline
