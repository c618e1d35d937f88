#pragma once
/// \file What `crackle run` and `crackle sweep` share in estimating their results (DETECTION.md
/// sec. 1): the settings of the numerical parameters and their refinements, the temporary folders
/// the refinement runs write into, the mesh component from the two lower element orders, and the
/// tolerance loop that refines the component with the largest error per second. The numbers are
/// combined by accuracy/estimate.hpp; which runs make a quantity is the caller's.
#include <filesystem>
#include <functional>
#include <iosfwd>
#include <limits>
#include <map>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include <nlohmann/json.hpp>

#include "accuracy/estimate.hpp"
#include "output/accuracy_json.hpp"
#include "scene/scene.hpp"

namespace crackle::pipeline {

/// Rate of the mesh levels (accuracy::kOrderLevelRatio: the order raised by one per level).
inline constexpr double kOrderLevelRatio = accuracy::kOrderLevelRatio;
inline constexpr double kRateMin = accuracy::kOrderRateMin, kRateMax = accuracy::kOrderRateMax;

/// The highest element order (the box mesher's); beyond it the mesh is refined by front layers.
inline constexpr int kHighestOrder = 4;
/// The most front layers the mesh refinement adds to the scene's at the highest order.
inline constexpr int kMostExtraLayers = 3;
/// The most times the steady state is tightened (tolerance / 10, period limit x 4 each).
inline constexpr int kMostWindowRefinements = 2;

/// One setting of the numerical parameters: the element order and the front layers added to the
/// mesh's (at every order of its mesh levels), and how many times each other component was refined:
/// the reduced model's band (x2 each), the steps per period (x2), the penalty (x4), the harmonics
/// of a harmonic balance (+2), the steady state of a run (its tolerance / 10, its period limit x 4).
struct Setting {
  int order = 0, layers = 0;
  int band = 0, steps = 0, penalty = 0, harmonics = 0, window = 0;
  std::string key() const;
};

/// The next finer mesh of a setting: one order up, or at the highest order one more front layer
/// (the graded mesh's front converges geometrically in its layers, docs/benchmarks.md 11.1).
Setting finer_mesh(const Setting& setting);

/// The settings the components of an estimate at a setting need: the two lower orders (the mesh,
/// on a box at order 3 or more) and one refinement of each other component; `band_twice` (the band
/// x4) is run only where the modes component needs its third level (needs_third_band).
struct Neighbours {
  std::optional<Setting> coarse, coarser;
  Setting band, steps, penalty, harmonics, window, band_twice;
};
Neighbours neighbours(const Setting& setting, bool box_mesh);

/// The overrides of a setting's element order and front layers (on a box: the layers the scene's
/// grading gives at that order, plus the setting's) and band (transient.reduced.modes, or
/// max_frequency from the scene's own run's `base_max_frequency_hz`), doubled per band level.
std::vector<scene::Override> order_and_band_overrides(const scene::Scene& scene, const Setting& setting,
                                                      double base_max_frequency_hz);

/// The override of a setting's contact penalty (crack.contact.penalty: the scene's own run's
/// `base_penalty` x4 per level), or none at the scene's own penalty.
std::optional<scene::Override> penalty_override(const Setting& setting, double base_penalty);

/// A setting as the terminal and the `runs` list show it: the order (or "the Gmsh mesh") and every
/// component refined from the scene's own run ("order 3, band x2, penalty x4").
std::string describe_setting(const Setting& setting, bool box_mesh);

/// The mesh component of a quantity `value` from its values q1, q2 at the two lower orders
/// (Richardson with the observed rate); where there are no levels (`levels` false) or a level lacks
/// the quantity (NaN), a component that is not verified, with the reason.
accuracy::Component mesh_component(double value, bool levels, double q1, double q2, bool box_mesh);

/// The mesh component of a frequency at `setting` from the two lower orders of `n`:
/// frequency_mesh_component (Richardson in the modal stage's DOFs^-1/3) over the value and the free
/// DOFs that `value_and_dofs` reads off each level's results.
accuracy::Component frequency_levels_component(const Neighbours& n, const Setting& setting,
                                               const std::function<std::pair<double, double>(const Setting&)>& value_and_dofs);

/// A component whose refinement lacks the quantity (NaN there): not verified, with the reason.
accuracy::Component missing_component(const std::string& name, double value);

/// The order the band refinement assumes with two levels: the static correction leaves the truncated
/// modes' error at their static share times (omega/omega_m+1)^2 (HYBRID.md sec. 2). It holds on the
/// beam (effectivity 1.04) and not where the contact's impacts reach far above the band: the plate's
/// A3/A1 converges at an order 1.1 then 0.7 per doubling (effectivity 0.51; docs/benchmarks.md 11.5c),
/// hence the third level.
inline constexpr double kModesOrder = 2.0;
/// The range of the order the three band levels observe (per doubling of the band) in which the
/// levels count as asymptotic (Fs = 1.25): a factor 1.5 below and 2 above kModesOrder. Outside it
/// the levels are not asymptotic (Fs = 3; Roache: an observed order away from the formal one), and
/// below half its least or above twice its most not verified (accuracy::three_level).
inline constexpr double kModesOrderMin = kModesOrder / 1.5, kModesOrderMax = 2.0 * kModesOrder;
/// Three band levels whose last change has the other sign and at most 1/kSettledRatio of the first
/// have settled with a wiggle (the formal order's ratio, 2^kModesOrder): verified, not asymptotic,
/// three times the change to the band x4 (Roache's Fs = 3 on the oscillation's range). A 5 mm crack
/// of the beam wiggles by 1.4e-4 at 9 modes after a 1.4e-3 change at 6 (docs/benchmarks.md 11.5e).
inline constexpr double kSettledRatio = 4.0;
/// A two-level modes component above this share of the tolerance (of 0.01 without one) is checked by
/// a third band level: an order wrong by the plate's factor of 4 would otherwise hide an error of the
/// tolerance's size.
inline constexpr double kThirdBandShare = 0.1;

/// Whether a quantity's two-level modes component (|delta|) asks for the third band level.
bool needs_third_band(double two_level_delta, std::optional<double> tolerance);

/// The modes component of `value` from the band x2 run's value `band`: read at kModesOrder, or, where
/// `band_twice` (the band x4 run's value) is finite, three levels with the observed order in
/// [kModesOrderMin, kModesOrderMax] (not verified where the changes do not fall: a truncation the
/// band cannot settle). A NaN `band`: missing_component.
accuracy::Component modes_component(double value, double band,
                                    double band_twice = std::numeric_limits<double>::quiet_NaN());

/// Whether and how a command's results are estimated.
struct EstimatePlan {
  bool estimate = false;
  std::string reason;  ///< why not
  std::optional<double> tolerance;
};

/// The folders of a command's refinement runs: DIR/accuracy.tmp.PID/<setting>, removed with this
/// object (also when the command fails), and the modal cache they share (the user's, or one in there).
class RefinementFolders {
 public:
  RefinementFolders(const std::filesystem::path& output_directory, const std::filesystem::path& modal_cache);
  ~RefinementFolders();
  RefinementFolders(const RefinementFolders&) = delete;
  RefinementFolders& operator=(const RefinementFolders&) = delete;

  const std::filesystem::path& cache() const { return cache_; }
  /// The folder of a setting's run: the output folder for the first (the scene's own), else a new
  /// temporary one.
  std::filesystem::path folder(const Setting& setting, bool first);
  /// Moves the files of a setting's run into the output folder (the setting a tolerance settled on).
  void adopt(const Setting& setting) const;

 private:
  std::filesystem::path output_, scratch_, cache_;
  std::map<std::string, std::filesystem::path> folders_;
};

/// The estimate of every quantity at one setting, as the tolerance loop reads it.
struct SettingSummary {
  double worst = 0.0;                      ///< largest error (sum) among the tolerance's quantities
  bool verified = true;                    ///< of those quantities
  std::map<std::string, double> largest;   ///< per component, the largest |delta| among them
};

/// Adds one quantity's estimate to a summary.
void add_to_summary(const accuracy::Estimate& estimate, SettingSummary& summary);

/// A refinement the tolerance loop may take: the component, the setting that refines it and the
/// cost of its run [s].
struct RefinementChoice {
  std::string name;
  Setting next;
  double cost = 0.0;
  std::string blocked;  ///< why `next` cannot be run (the loop stops there if this choice is the best)
};

/// The mesh's refinement from `setting` at cost `cost` [s]: one order up, or at the highest order one
/// more front layer - blocked where the scene's box is not graded (mesh.box.grading other than
/// always: a run meshes it uniformly, so there are no front layers to add) or past the last layer
/// (kMostExtraLayers).
RefinementChoice mesh_choice(const Setting& setting, const scene::Scene& scene, double cost);

/// The choice with the largest error per second of its run - or, with a `tolerance`, the cheapest
/// of those whose refinement alone could meet it (the largest estimate less the component's part at
/// most the tolerance), where there are such - or empty with `blocking` saying why none can go on: no
/// component with an error (`nothing_left`), a choice that is `blocked` (mesh_choice), the last
/// tightening of the steady state, or a run that would exceed what is left of the budget.
std::optional<Setting> choose_refinement(const std::vector<RefinementChoice>& choices, const SettingSummary& summary,
                                         double budget_left, const std::string& nothing_left, std::string& blocking,
                                         std::optional<double> tolerance = std::nullopt);

/// How a tolerance loop ended.
struct ToleranceOutcome {
  std::optional<bool> met;  ///< empty: no tolerance
  std::string blocking;
};

/// The tolerance loop: from `setting` (its summary given), refines while the estimate is above the
/// tolerance and verified, each step by `refine` (empty: blocked, with the reason); `summarize`
/// estimates a setting. `setting` and `summary` end at the setting reported.
ToleranceOutcome reach_tolerance(std::optional<double> tolerance, Setting& setting, SettingSummary& summary,
                                 const std::function<std::optional<Setting>(const Setting&, std::string&)>& refine,
                                 const std::function<SettingSummary(const Setting&)>& summarize,
                                 const std::function<std::string(const Setting&)>& describe, std::ostream& out);

/// A setting as run.json and sweep.json write the one their estimate reached (`accuracy.reached`):
/// {order, layers, band, steps, penalty, harmonics, window}.
nlohmann::json setting_json(const Setting& setting);

/// Where a tolerance loop starts: the scene's own setting `own`, or, with `start_file` (`crackle
/// run|sweep --accuracy-start FILE`: an earlier run.json or sweep.json of a scene on the same mesh,
/// as a study passes it to the cases that share one), the setting that file's estimate reached.
/// Without a tolerance the file is not used and `out` says so. Throws IoError where the file cannot
/// be read, InputError (the file, the key and what was expected) where it holds no such setting or
/// one below the scene's own element order or, on a Gmsh mesh, with front layers.
Setting tolerance_start(const Setting& own, const std::filesystem::path& start_file, const EstimatePlan& plan,
                        bool box_mesh, std::ostream& out);

/// The accuracy block's summary fields (estimated, setting, tolerance, quantities, budget, error,
/// verified, met, blocking, runs, times and the estimate's share of the wall time).
nlohmann::json accuracy_summary(const std::string& setting, std::optional<double> tolerance,
                                const std::vector<std::string>& quantities, double budget_s,
                                const SettingSummary& summary, const ToleranceOutcome& outcome,
                                const nlohmann::json& runs, double run_s, double estimate_s, double wall_s);

/// The closing lines: the tolerance met or not (and what blocks), and the refinement runs' cost
/// (`noun`: "runs" or "sweeps").
void print_accuracy_end(std::ostream& out, std::optional<double> tolerance, const ToleranceOutcome& outcome,
                        const SettingSummary& summary, const std::vector<std::string>& quantities, std::size_t runs,
                        const std::string& noun, double estimate_s, double wall_s);

/// A relative error as text: "0.23 %".
std::string percent(double value);

}  // namespace crackle::pipeline
