#pragma once
/// \file The error estimate of `crackle modal`'s frequencies (DETECTION.md sec. 1): the mesh component
/// from element-order levels on a box mesh (the only numerical parameter of a modal solve whose error
/// is not at the eigen-solver's tolerance). Which orders are the levels, and the estimates of every
/// frequency of modal.json from the levels' frequencies; the solves themselves are the caller's.
#include <array>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "accuracy/estimate.hpp"
#include "modal/modal.hpp"
#include "scene/scene.hpp"

namespace crackle::pipeline {

/// The element orders whose solves estimate a solve at the scene's order. Order 1 is a level only
/// of a solve at order 1: its error is far from the asymptotic rate (linear elements lock in
/// bending: data/beam.yaml's f_open 1 changes 6.4 % from order 1 to 2 and 0.14 % from 2 to 3), so
/// levels 1, 2, 3 give a rate too fast and an estimate below the true error at order 3.
/// Three lower orders are checked by a level of another family, order 2 on the cells doubled in each
/// direction (the nodes of the order-4 grid, a sparser matrix: about a tenth of the order-4 solve):
/// p-levels on a coarse grid can look asymptotic and be far from it (accuracy::checked_against).
struct ModalLevelPlan {
  bool estimate = false;
  std::string reason;              ///< why not
  int run_order = 0;               ///< the scene's element order, among `orders`
  std::vector<int> orders;         ///< ascending: two or three consecutive orders
  std::optional<double> tolerance;
  std::optional<std::array<int, 3>> check_cells;  ///< the check level's cells (at order kCheckOrder)
};
inline constexpr int kCheckOrder = 2;

/// auto: on a box at order 3 or more (the levels are lower orders: about a quarter of the solve; at
/// order 4 and above with the check level); on: also below, with the orders above (up to 4); off, a
/// Gmsh mesh, or several ranks: none.
ModalLevelPlan modal_level_plan(const scene::Scene& scene, int ranks);

/// The mesh component of a frequency from its values and the free DOFs at consecutive element orders
/// (ascending, `run_order` among them; NaN: a level lacks it): Richardson in DOFs^-1/3 with Fs = 3
/// over three levels, three times the change over two; order 1 is dropped when it is not the order
/// that ran (it locks in bending). `crackle modal`'s estimate and `crackle run`'s of its mode.
accuracy::Component frequency_mesh_component(std::vector<int> orders, std::vector<double> values,
                                             std::vector<double> dofs, int run_order);

/// The frequencies of one solve that the estimate compares across orders.
struct ModalLevel {
  int order = 0;
  bool check = false;  ///< the plan's check level (order 2 on check_cells), not one of `orders`
  long dofs = 0;
  double wall_s = 0.0;
  std::map<std::string, std::vector<double>> variants;  ///< elastic frequencies [Hz] per variant name
  std::vector<modal::ModePair> pairs;
};
ModalLevel modal_level(const modal::ModalResult& result, int order, double wall_s);

/// modal.json's `accuracy` block (the summary as run's and sweep's, `orders`, and an estimate at the
/// same place as each value: `variants.<name>.frequencies_hz[i]`, `pairs[i].f_uncracked_hz`,
/// `f_open_hz`, `f_bilinear_hz`, `ratio`) and one terminal line per mode. `levels` holds every order
/// of the plan that was solved (the run's among them) and the check level if it was; an order that
/// could not be solved is missing.
struct ModalAccuracy {
  nlohmann::json block;
  std::vector<std::string> lines;
};
ModalAccuracy modal_accuracy(const ModalLevelPlan& plan, const std::vector<ModalLevel>& levels, double estimate_s,
                             double wall_s);

/// The block of a solve that was not estimated: `estimated: false` and the reason.
nlohmann::json modal_accuracy_not_estimated(const std::string& reason);

}  // namespace crackle::pipeline
