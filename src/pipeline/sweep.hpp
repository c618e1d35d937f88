#pragma once
/// \file `crackle sweep`: frequency response curves of the reduced model (HYBRID.md §4-5), by
/// harmonic balance with pseudo-arclength continuation and Hill stability, or by a stepped sine
/// (the reduced transient run to steady state at each frequency, up then down, as a lab does).
///
/// The pieces work on a `reduced::ReducedSystem` and the scene's `sweep:` section, so that tests
/// can drive them with a system written by hand; `run_sweep_command` wires the scene, the modal
/// stage and the reduced model to them and writes sweep.csv, sweep.json and one PNG per probe.
///
/// **Conventions.** Frequencies in the files are in Hz, the solvers' in rad/s. The load is
/// a(t) = cos(2 pi f t) times the excitation's shape and amplitude; a probe's order-k response is
/// A_k cos(2 pi k f t + phi_k) (phases relative to the load, lagging < 0).
#include <filesystem>
#include <functional>
#include <iosfwd>
#include <string>
#include <utility>
#include <vector>


#include "io/csv.hpp"
#include "output/sweep_json.hpp"
#include "reduced/system.hpp"
#include "scene/scene.hpp"
#include "plot/gnuplot.hpp"
#include "sweep/curve.hpp"
#include "sweep/harmonic_balance.hpp"

namespace crackle::pipeline {

using sweep::SweepEvent;
using sweep::SweepPoint;
using sweep::SweepProbe;
using sweep::SweepResult;

/// Where the windows of SweepSettings::windows start from: per window, the gap harmonics of another
/// sweep of the same body at the window's start (`harmonics` H of it, the layout of
/// sweep::Solution::gaps), or an empty vector. A window starts from the linear solution where it has
/// none, where its pair rows differ from the system's, or where Newton fails from it.
struct WindowStarts {
  int harmonics = 0;
  std::vector<VectorX> gaps;
};

/// The sweep of a scene with its frequency range resolved.
struct SweepSettings {
  scene::SweepSection section;
  double from_hz = 0.0, to_hz = 0.0;  ///< excitation frequencies [Hz]
  double bilinear_hz = 0.0;           ///< f_b of the mode the range refers to (0: given in Hz)
  std::vector<SweepProbe> probes;
  /// Harmonic balance only: continue over these parts of the range alone, each a segment of its own
  /// (fractions of [from_hz, to_hz], ascending, not overlapping; empty: the whole range). The
  /// accuracy's refinement sweeps use them to re-solve only around the peaks (DETECTION.md sec. 1).
  std::vector<std::pair<double, double>> windows;
  WindowStarts window_starts;
};

/// The probes of the scene's transient section: the analysed component (the excitation direction
/// unless given), row 3 p + component.
std::vector<SweepProbe> sweep_probes(const scene::Scene& scene);

/// Called after each point: points so far, and the fraction of the range covered.
using SweepProgress = std::function<void(const SweepResult&, double fraction)>;

/// Harmonic-balance sweep: continuation from from_hz to to_hz (started from the linear solution), or
/// over each of `settings.windows` with the step limit of the whole range (segments 0, 1, ...).
/// With `subharmonic: 2` (and stability): the period-one branch (H/2 harmonics of the excitation, the
/// same orders), then the period-two branch (nu = 2, H harmonics of half the excitation) from its first
/// period doubling: where the odd-harmonic block of the nu = 2 Jacobian turns singular along the
/// period-one branch (bisection in Omega), `sweep::branch_off` along the block's null vector; continued
/// down and up over the whole range until it rejoins the period-one branch (its A1/2 share of the gaps
/// < 1e-3), its odd part reverses (it went through the doubling) or it leaves the range. `completed`
/// refers to the period-one branch.
SweepResult harmonic_balance_sweep(const reduced::ReducedSystem& system, const SweepSettings& settings,
                                   const SweepProgress& progress = SweepProgress());

/// The gaps of a harmonic-balance sweep's first branch (`result`, of H = `harmonics` over
/// [from_hz, to_hz]) at the start of each window (fractions of that range), linear between the two
/// points around it: the starts of a windowed sweep of a refinement of the same body.
WindowStarts window_starts(const SweepResult& result, double from_hz, double to_hz, int harmonics,
                           const std::vector<std::pair<double, double>>& windows);

/// Stepped sine: `points` frequencies up, then the same down, each run from the previous state until
/// no harmonic of any probe changes by more than `tolerance` A1 over a base period.
SweepResult stepped_sine_sweep(const reduced::ReducedSystem& system, const SweepSettings& settings,
                               const SweepProgress& progress = SweepProgress());

/// What sweep.json and sweep.csv (output/sweep_json.hpp) state of `settings`.
output::SweepFileSettings file_settings(const SweepSettings& settings);

/// Response curve of one probe: A1, A2, A3 (and A1/2 with subharmonic 2) against frequency, log y,
/// unstable parts dashed, f_b/2, f_b/3 and f_b marked when known.
plot::PlotResult plot_sweep(const std::filesystem::path& png, const SweepResult& result,
                                const SweepSettings& settings, std::size_t probe,
                                const plot::PlotOptions& options = plot::PlotOptions());

struct SweepCommandOptions {
  std::string scene_path;
  std::vector<std::string> overrides;  ///< `key.path=value`
  std::filesystem::path output_directory = "out";
  std::filesystem::path modal_cache;   ///< folder sharing the uncracked solve between runs
  bool progress = true;                ///< progress line on stderr
  /// sweep.json or run.json of an earlier estimate on the same mesh: where the tolerance loop starts
  /// (RunCommandOptions::accuracy_start).
  std::filesystem::path accuracy_start;
  std::vector<std::pair<double, double>> windows;  ///< SweepSettings::windows (refinement sweeps only)
  WindowStarts window_starts;                      ///< SweepSettings::window_starts
  /// false: the figures' data and scripts only (RunCommandOptions::draw_plots; refinement sweeps).
  bool draw_plots = true;
};

/// `crackle sweep`: modal stage (for mode-relative ranges) -> reduced model -> sweep; writes
/// sweep.csv, sweep.json and sweep_<probe>.png. Progress goes to `progress` (stderr), the summary
/// to `out`.
void run_sweep_command(const SweepCommandOptions& options, std::ostream& out, std::ostream& progress);

}  // namespace crackle::pipeline
