#pragma once
/// \file Which model and mesh `crackle run` takes for a scene (`transient.model: auto`): the reduced
/// model on its own graded box mesh for a harmonic-drive signature run where its validity conditions
/// hold, else the full explicit model; the choice and its reason go into run.json `route`.
#include <array>
#include <string>
#include <vector>

#include "scene/scene.hpp"

namespace crackle::pipeline {

/// The element order the automatic route runs at: the highest the box mesh supports, so that the
/// mesh estimate has the two lower orders as its coarser levels (order 1 on a grid one cell thick
/// is not in the asymptotic range: docs/benchmarks.md section 11).
inline constexpr int kRouteOrder = 4;
/// The most DOFs the automatic route's mesh takes before it lowers the order (to the scene's own at
/// the least): the beam's order-4 mesh has 93k and runs in about half a minute; the plate's order-3
/// mesh (104k, a two-dimensional factor and 289 pairs) took minutes (docs/benchmarks.md section 11).
inline constexpr double kRouteDofs = 100e3;

struct RunRoute {
  std::string model;     ///< "full" or "reduced"
  bool automatic = false;  ///< chosen by transient.model: auto (else as the scene says)
  std::string reason;    ///< why this model (and mesh)
  bool own_mesh = false;  ///< the route replaced the scene's cells, order and grading
  std::array<int, 3> cells{0, 0, 0};
  int order = 0;
  std::array<int, 3> scene_cells{0, 0, 0};
  int scene_order = 0;
  /// Overrides that turn the scene into the routed one (transient.model and, for its own mesh,
  /// mesh.box.cells, mesh.box.order, mesh.box.grading.mode); applied after the user's.
  std::vector<scene::Override> overrides;
};

/// The route of a scene for `crackle run` on `ranks` processes.
RunRoute choose_route(const scene::Scene& scene, int ranks);

/// The mesh of `crackle sweep` (always the reduced model): with transient.model: auto and a
/// breathing crack in a box, the automatic route's own graded mesh (as choose_route takes it);
/// otherwise the scene's mesh as written. `overrides` hold only the mesh keys.
RunRoute choose_sweep_route(const scene::Scene& scene);

/// The box cells of the automatic route: the scene's cells coarsened along each axis to about the
/// body's thinnest side (never finer than the scene's), keeping every crack-plane position a grid
/// plane; a cell count that cannot keep it stays the scene's.
std::array<int, 3> route_cells(const scene::Scene& scene);

}  // namespace crackle::pipeline
