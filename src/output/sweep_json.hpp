#pragma once
/// \file sweep.json and sweep.csv: a frequency response curve (sweep/curve.hpp) with the settings it
/// was swept with; the pipeline adds the route, the model, the stages and the accuracy block.
#include <string>
#include <utility>
#include <vector>

#include <nlohmann/json_fwd.hpp>

#include "io/csv.hpp"
#include "sweep/curve.hpp"

namespace crackle::output {

/// The settings the files state: the range in Hz, the scene's `sweep:` keys that shape the curve,
/// the probes and the windows of a refinement sweep (fractions of the range; empty: the whole range).
struct SweepFileSettings {
  double from_hz = 0.0, to_hz = 0.0;  ///< excitation frequencies [Hz]
  double bilinear_hz = 0.0;           ///< f_b of the mode the range refers to (0: given in Hz)
  int harmonics = 15, subharmonic = 1;
  std::string method = "harmonic_balance";
  bool stability = true;
  int points = 200;
  double tolerance = 1e-6;
  int max_periods = 2000;
  std::vector<sweep::SweepProbe> probes;
  std::vector<std::pair<double, double>> windows;
};

/// Amplitude of order k / nu of a probe at a point (nu the sweep's: a period-one point of a
/// `subharmonic: 2` sweep has no odd k).
double amplitude_of(const sweep::SweepPoint& point, const sweep::SweepProbe& probe, int k, int nu);

/// sweep.csv: one row per point (units in the header).
io::CsvTable sweep_table(const sweep::SweepResult& result, const SweepFileSettings& settings);

/// sweep.json: settings, the events, warnings, the linear solver and a per-probe summary (the peaks
/// of A1, A2/A1, A3/A1 and, with `subharmonic: 2`, A1/2/A1).
nlohmann::json sweep_json(const sweep::SweepResult& result, const SweepFileSettings& settings);

}  // namespace crackle::output
