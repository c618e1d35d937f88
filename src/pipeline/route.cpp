#include "pipeline/route.hpp"

#include "core/errors.hpp"
#include "pipeline/model.hpp"

#include <algorithm>
#include <cmath>

namespace crackle::pipeline {
namespace {

std::string cells_text(const std::array<int, 3>& cells) {
  return "[" + std::to_string(cells[0]) + ", " + std::to_string(cells[1]) + ", " + std::to_string(cells[2]) + "]";
}

/// `mesh.box.grading` as a map with mode always and the scene's layers, ratio and fronts (the scene
/// may have written the key as a plain mode, which a `.mode` override could not reach).
std::string grading_always(const scene::Scene& scene) {
  const mesh::Grading& grading = scene.grading.grading;
  std::string text = "{mode: always, layers: " +
                     (grading.layers == mesh::kAutoLayers ? std::string("auto") : std::to_string(grading.layers)) +
                     ", ratio: " + format_number(grading.ratio);
  static const char* axes[3] = {"x", "y", "z"};
  std::string fronts;
  for (int axis = 0; axis < 3; ++axis) {
    if (grading.fronts[axis].empty()) continue;
    fronts += std::string(fronts.empty() ? "" : ", ") + axes[axis] + ": [";
    for (std::size_t i = 0; i < grading.fronts[axis].size(); ++i) {
      fronts += (i ? ", " : "") + format_number(grading.fronts[axis][i]);
    }
    fronts += "]";
  }
  if (!fronts.empty()) text += ", fronts: {" + fronts + "}";
  return text + "}";
}

/// DOFs of the scene's box graded at `order` on `cells` (the grid lines box_lines() makes).
double graded_dofs(const scene::Scene& scene, const std::array<int, 3>& cells, int order) {
  scene::Scene graded = scene;
  graded.box.cells = cells;
  graded.box.order = order;
  graded.grading.mode = scene::GradingMode::always;
  const std::array<std::vector<double>, 3> lines = box_lines(graded, MeshUse::transient);
  double nodes = 1.0;
  for (const std::vector<double>& axis : lines) nodes *= static_cast<double>(axis.size() - 1) * order + 1.0;
  return 3.0 * nodes;
}

/// The highest order up to kRouteOrder whose graded mesh stays within kRouteDofs, and not below the
/// scene's own (below order 3 the mesh estimate lacks its two lower orders and says so).
int route_order(const scene::Scene& scene, const std::array<int, 3>& cells) {
  int order = kRouteOrder;
  while (order > std::max(1, scene.box.order) && graded_dofs(scene, cells, order) > kRouteDofs) --order;
  return order;
}

/// The automatic route's mesh: on a box, its own cells and order graded towards the crack front
/// (overrides and reason appended); a Gmsh mesh stays as it is.
void take_own_mesh(const scene::Scene& scene, RunRoute& route) {
  if (!scene.gmsh_file.empty()) {
    route.reason += " on the scene's Gmsh mesh";
    return;
  }
  route.own_mesh = true;
  route.cells = route_cells(scene);
  route.order = route_order(scene, route.cells);
  const std::string cells = route.cells == route.scene_cells
                                ? "the scene's cells " + cells_text(route.cells)
                                : "the scene's cells " + cells_text(route.scene_cells) + " coarsened to " +
                                      cells_text(route.cells) + " (about the thinnest side)";
  route.reason += ", on its own mesh: " + cells + ", order " + std::to_string(route.order) +
                  ", graded towards the crack front (the signature converges with the front resolved, "
                  "docs/benchmarks.md section 5.1)";
  route.overrides.push_back({"mesh.box.cells", cells_text(route.cells)});
  route.overrides.push_back({"mesh.box.order", std::to_string(route.order)});
  route.overrides.push_back({"mesh.box.grading", grading_always(scene)});
}

}  // namespace

std::array<int, 3> route_cells(const scene::Scene& scene) {
  const mesh::BoxSpec& box = scene.box;
  const double thinnest = box.size.minCoeff();
  std::array<int, 3> cells = box.cells;
  for (int axis = 0; axis < 3; ++axis) {
    const int target = std::max(1, static_cast<int>(std::lround(box.size[axis] / thinnest)));
    if (target >= box.cells[axis]) continue;
    if (!scene.crack || scene.crack->normal != axis) {
      cells[axis] = target;
      continue;
    }
    // The crack plane (of the reference crack the grid is made for, crack.reference) must stay a
    // grid plane: the fewest cells from the target up that keep it one.
    const double at = scene.crack_reference ? scene.crack_reference->at : scene.crack->at;
    const double position = (at - box.origin[axis]) / box.size[axis];
    for (int n = target; n <= box.cells[axis]; ++n) {
      if (std::abs(position * n - std::round(position * n)) < 1e-9 * n) {
        cells[axis] = n;
        break;
      }
    }
  }
  return cells;
}

RunRoute choose_route(const scene::Scene& scene, int ranks) {
  RunRoute route;
  const scene::TransientSection& transient = *scene.transient;
  route.scene_cells = scene.box.cells;
  route.scene_order = scene.box.order;
  route.cells = scene.box.cells;
  route.order = scene.box.order;
  if (transient.model != scene::TransientModel::automatic) {
    route.model = scene::model_name(transient.model);
    route.reason = "transient.model: " + route.model + " as the scene says";
    return route;
  }
  route.automatic = true;
  const std::string refusal = scene::reduced_route_refusal(scene, ranks);
  if (!refusal.empty()) {
    route.model = "full";
    route.reason = "transient.model: auto took the full explicit model: " + refusal;
    route.overrides.push_back({"transient.model", "full"});
    return route;
  }
  route.model = "reduced";
  route.overrides.push_back({"transient.model", "reduced"});
  route.reason = "transient.model: auto took the reduced model for a harmonic-drive signature run (a breathing crack, "
                 "a spectrum, one process, no explicit time step or initial fields)";
  take_own_mesh(scene, route);
  return route;
}

RunRoute choose_sweep_route(const scene::Scene& scene) {
  RunRoute route;
  route.model = "reduced";
  route.scene_cells = route.cells = scene.box.cells;
  route.scene_order = route.order = scene.box.order;
  const std::string model = scene.transient ? scene::model_name(scene.transient->model) : std::string("auto");
  if (model != "auto") {
    route.reason = "transient.model: " + model + ": the sweep's reduced model on the scene's mesh as written";
    return route;
  }
  route.automatic = true;
  route.reason = "transient.model: auto: the sweep's reduced model";
  if (scene.gmsh_file.empty() && !scene::takes_route_mesh(scene, "sweep")) {
    route.reason += " on the scene's mesh (no breathing crack whose front needs the graded mesh)";
    return route;
  }
  take_own_mesh(scene, route);
  return route;
}

}  // namespace crackle::pipeline
