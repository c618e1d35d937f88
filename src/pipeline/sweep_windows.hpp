#pragma once
/// \file The windows of the range that a sweep's refinement sweeps re-solve (DETECTION.md sec. 1):
/// the sweep's estimate needs each refinement only at the peaks it estimates, so a refinement
/// sweep continues over a window around each peak of the main sweep instead of the whole range,
/// and is taken only when every peak it finds lies inside its own window.
#include <string>
#include <utility>
#include <vector>

#include <nlohmann/json.hpp>

namespace crackle::pipeline {

/// A JSON pointer token (RFC 6901): '~' and '/' escaped.
std::string json_pointer_token(const std::string& text);

/// Half the width of a peak's window, as a fraction of the range: kWindowSteps of the continuation's
/// largest step (1 / sweep.points of the range), and at least kWindowHalfWidth. On data/beam.yaml
/// (200 points) that is 1.75 % of the range; the refinements move the A2/A1 peak by at most 0.1 % of it.
constexpr double kWindowSteps = 3.5;
constexpr double kWindowHalfWidth = 0.01;
/// Windows covering more of the range than this are not worth it: the whole range is swept.
constexpr double kWindowsMostOfRange = 0.6;

/// The windows of a main sweep (its sweep.json document), as fractions of its range, ascending and
/// disjoint, with the window of each peak; empty windows with `reason` where the whole range has to be
/// swept again.
struct SweepWindows {
  std::vector<std::pair<double, double>> windows;
  /// Per estimated peak: its JSON pointer in sweep.json (/probes/<name>/<peak key>) and its window.
  std::vector<std::pair<std::string, std::size_t>> peaks;
  std::string reason;  ///< why there are no windows
  double covered = 0.0;  ///< fraction of the range the windows cover
};

/// The windows around every peak of `probes` in the main sweep's document (`peak_keys` named per
/// probe), or none when the sweep is not a harmonic-balance branch without turning points (a start
/// inside a window must land on the main sweep's branch: no fold, no period doubling, no period-two
/// branch), did not complete, or when the windows would cover most of the range.
SweepWindows sweep_windows(const nlohmann::json& main, const std::vector<std::string>& peak_keys);

/// Whether a windowed refinement sweep's document holds every peak of `windows` inside the window
/// built for it and not at a window's end inside the range; `why` says which peak did not.
bool windows_hold(const SweepWindows& windows, const nlohmann::json& refined, std::string& why);

}  // namespace crackle::pipeline
