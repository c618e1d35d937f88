#pragma once
/// \file `crackle identify scene.yaml -o DIR`: the crack's position and size (any numeric scene
/// keys) from measured signatures, with intervals (DETECTION.md sec. 2).
///
/// ```yaml
/// identify:
///   unknowns:                        # scene key paths (a list entry by its index) with bounds
///     crack.plane.at: [0.02, 0.18]
///     crack.region.z[0]: [0.005, 0.0095]
///   measured:                        # a list, or the path of a CSV file
///     - {quantity: f_bilinear, mode: 1, value: 205.9, sigma: 0.1}
///   map: {points: 7}                 # the global map: points per unknown
///   truth:                           # optional: a synthetic test's truth
///     crack.plane.at: 0.05
///     crack.region.z[0]: 0.007
/// ```
///
/// The forward model is the scene's modal solve (`crackle modal`), or with harmonic quantities the
/// scene's harmonic-balance sweep (`crackle sweep`, narrow about each drive frequency), with the
/// grid made for a reference
/// crack in the middle of the bounds and moved onto each crack (crack.reference, mesh::morph_lines),
/// so that it is smooth in the unknowns. Every forward run is a case of a study (src/study): in
/// parallel, resumable, cached by the hash of its scene. Steps:
/// 1. the map: a grid of points per unknown (DIR/map, or --map-cache), chi^2 (eq. 7) on it, and
///    every local minimum within kMinimaSpread of the best;
/// 2. the model error of each measured quantity, in the map's batch: the forward model in the middle
///    of the bounds on the orders p, p+1, p+2, Richardson (DETECTION.md eq. 2), weighted in as
///    sqrt(sigma^2 + eps^2);
/// 3. from each kept minimum: a bounded Levenberg-Marquardt fit on the map's cubic interpolant;
///    then Gauss-Newton on the forward model from there (the first Jacobians of all minima in one
///    batch) until its step is below 0.1 of the estimate's standard deviation; Levenberg-Marquardt
///    on the forward model (fit::fit_bounded) when a step does not lower chi^2;
/// 4. the Gauss-Newton covariance, 95 % intervals (Student t), correlations, and the flags;
/// 5. the 2D profile of the misfit for each pair of unknowns (fit::profile: the least over the
///    other unknowns on the map's interpolant; with two unknowns the map itself).
/// Outputs: identify.json (profiles among them), identify_map.csv, identify_profiles.csv,
/// identify_map.png (with three unknowns or more: the first two's profile), identify_profiles.png
/// (three or more), identify_fit.png.
#include <iosfwd>
#include <string>
#include <vector>

#include <nlohmann/json_fwd.hpp>

#include "identify/forward.hpp"

namespace crackle::identify {

/// One measurement (a row of the measured list or CSV file).
struct Measurement {
  std::string quantity;  ///< f_uncracked, f_open, f_bilinear, damping_ratio, A1, A2/A1, A3/A1, A1/2/A1
  int mode = 0;          ///< 1-based uncracked mode (frequency quantities)
  std::string probe;     ///< harmonic quantities
  double drive_hz = 0.0;
  double value = 0.0;
  double sigma = 0.0;
  std::string where;  ///< "file:line" for messages
};

/// Modal frequencies (per mode); every quantity the section accepts and identify computes (those,
/// damping_ratio, and a probe's harmonics at a drive frequency by harmonic balance).
const std::vector<std::string>& frequency_quantities();
const std::vector<std::string>& all_quantities();

struct IdentifySpec {
  std::vector<Unknown> unknowns;
  std::vector<Measurement> measured;
  int map_points = 7;        ///< per unknown
  bool scale_by_fit = true;  ///< s^2 = chi^2/(n - k) with Student t (eq. 8); false: sigmas trusted
  /// identify.truth: the known unknowns of a synthetic test, one per unknown (empty: none). The
  /// result then reports the error, whether the intervals hold it, and the Cramer-Rao bound there.
  std::vector<double> truth;
  int line = -1;
};

/// Parses the `identify:` section of a scene file (measurements from the list or from the CSV file
/// it names, relative to the scene's folder). InputError "file:line: key.path: expected ..., got
/// ..." on any problem.
IdentifySpec parse_identify_section(const std::string& text, const std::string& file);

/// Reads a measurements CSV file (header quantity,mode,probe,drive_hz,value,sigma).
std::vector<Measurement> read_measurements_csv(const std::string& path);

struct IdentifyOptions {
  std::string scene_path;
  std::string output_dir;
  std::string executable;  ///< crackle executable for the forward runs (/proc/self/exe)
  int jobs = 0;            ///< forward runs at a time; 0: the cores
  std::string map_cache;   ///< folder of the map's forward runs (kept between measurement sets)
  bool progress = true;    ///< the forward runs' progress lines (the study's case counts)
};

/// Runs the identification; progress to `log`. Returns the identify.json document.
/// InputError on a bad scene or section, SolverError when forward runs fail.
nlohmann::json run_identify(const IdentifyOptions& options, std::ostream& log);

}  // namespace crackle::identify
