#pragma once
/// \file A frequency response curve as plain data: the points of a harmonic-balance or stepped-sine
/// sweep, the folds and bifurcations found along it, and the probes whose rows it holds. The sweep
/// drivers (pipeline/sweep.hpp) fill it; output/sweep_json.hpp and output/sweep_csv.hpp write it.
#include <cstddef>
#include <string>
#include <vector>

#include "core/types.hpp"
#include "sweep/harmonic_balance.hpp"
#include "sweep/krylov.hpp"

namespace crackle::sweep {

/// A probe of the sweep: its name, the analysed displacement component and its output row.
struct SweepProbe {
  std::string name;
  int component = 2;  ///< 0, 1, 2 for x, y, z
  Index row = 0;      ///< row of the reduced system's outputs (3 p + component)
};

/// One solution point.
struct SweepPoint {
  Solution solution;            ///< omega, subharmonic, outputs (probe rows only), iterations, residual
  bool stability_known = false; ///< the stability was computed (Floquet multipliers)
  bool stable = true;
  bool fold = false;            ///< a fold lies between the previous point and this one
  bool period_doubling = false; ///< a multiplier crossed -1 there
  int direction = 1;            ///< stepped_sine: +1 up, -1 down; harmonic_balance: +1
  int periods = 0;              ///< stepped_sine: periods run to steady state
  int segment = 0;              ///< harmonic_balance: 0 the first branch; 1, 2 the period-two branch down, up
  double frequency_hz() const { return solution.omega / kTwoPi; }
};

/// A fold or bifurcation found along the branch.
struct SweepEvent {
  std::string kind;        ///< fold, period_doubling, neimark_sacker, stability_change
  double frequency_hz = 0.0;  ///< interpolated between the two points around it
  std::size_t point = 0;   ///< index of the point after it
  /// Where the unstable counts change: 1 when Hill's method finds the monodromy's counts at both
  /// points around it, 0 when not; -1 not checked (sweep.json `hill_agrees`).
  int hill_check = -1;
};

/// A whole sweep: its points in the order they were found, events, warnings and the solver's figures.
struct SweepResult {
  std::vector<SweepPoint> points;
  std::vector<SweepEvent> events;
  std::vector<std::string> warnings;  ///< H-convergence, unsettled frequencies, an unfinished branch
  double max_top_share = 0.0;         ///< largest top-harmonic share of the gap response
  double solve_s = 0.0;               ///< seconds spent in the solver
  std::string linear_solver;          ///< harmonic_balance: "dense" or "krylov" (of the period-one branch)
  KrylovStatistics krylov;            ///< harmonic_balance with krylov: GMRES statistics (both branches)
  bool completed = true;              ///< the branch reached the end of the range
};

}  // namespace crackle::sweep
