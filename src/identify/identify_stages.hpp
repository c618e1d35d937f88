#pragma once
/// \file What `crackle identify` (identify.hpp's `run_identify`) hands its files, private to
/// src/identify: the fitted minima, the map and profiles of the misfit, the model error and the
/// flags; identify_output.cpp writes identify.json, identify_map.csv, identify_profiles.csv and
/// the plots from them (DETECTION.md sec. 2).
#include <cstddef>
#include <filesystem>
#include <iosfwd>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "fit/fit.hpp"
#include "identify/identify.hpp"

namespace crackle::identify::detail {

/// chi^2 quantile of 2 degrees of freedom at 95 % (the joint region of two unknowns).
inline constexpr double kChi2Two95 = 5.991464547107979;

/// A local fit from one kept minimum of the map.
struct Fitted {
  VectorX theta;
  double chi2 = 0.0;
  VectorX residuals;
  VectorX model;
  fit::Uncertainty uncertainty;
  std::vector<bool> at_bound;
  bool converged = false;
};

/// Everything identify.json, its tables and its plots are made of.
struct IdentifyFigures {
  explicit IdentifyFigures(const IdentifySpec& of) : spec(of) {}
  const IdentifySpec& spec;
  std::vector<std::vector<double>> axes;  ///< the map's values of each unknown
  std::vector<VectorX> grid;              ///< the map's points, row-major over the unknowns
  std::vector<double> map_chi2;           ///< the misfit at each map point, with the final weights
  std::filesystem::path map_dir;          ///< the map's forward runs (--map-cache or DIR/map)
  double best_map = 0.0;                  ///< the least misfit on the map
  std::size_t starts = 0;                 ///< map minima a local fit started from
  std::vector<Fitted> minima;             ///< distinct fitted minima, the best first
  std::vector<fit::Profile> profiles;     ///< the misfit's profile of each pair of unknowns
  VectorX values, sigma;                  ///< the measurements and their sigmas
  VectorX model_error;                    ///< relative model error of each measured quantity
  std::vector<bool> error_verified;
  VectorX weights;                        ///< sqrt(sigma^2 + (model error x value)^2)
  std::vector<std::string> reasons;       ///< why the crack is not identifiable (empty: it is)
  double reference_at = 0.0;              ///< the reference crack's plane (the middle of the bounds)
  int gauss_newton = 0, levenberg_marquardt = 0;
  int from_map_point = 0;  ///< local fits redone from their map point (the first ended above it)
  const Fitted& best() const { return minima.front(); }
};

/// {key: value} over the unknowns.
nlohmann::json keyed(const IdentifySpec& spec, const VectorX& v);
/// "A2/A1 tip @ 102.9 Hz", "f_bilinear mode 1": a measurement in messages and plots.
std::string measurement_label(const Measurement& m);

/// identify.json but `truth`, `forward_runs`, `wall_s` and `notes` (run_identify adds them).
nlohmann::json identify_json(const IdentifyFigures& figures);

/// identify_map.csv (the map: the unknowns and chi^2 with the final weights) and, with profiles,
/// identify_profiles.csv (every pair's profile as one long table).
void write_identify_tables(const std::filesystem::path& dir, const IdentifyFigures& figures);

/// identify_map.png, identify_profiles.png (three unknowns or more) and identify_fit.png; a note
/// in `notes` for each plot that could not be drawn.
void draw_identify_plots(const std::filesystem::path& dir, const IdentifyFigures& figures, std::vector<std::string>& notes);

/// The estimate with its intervals, chi^2, the verdict, the reasons and notes on the terminal.
void print_identify_summary(std::ostream& log, const IdentifyFigures& figures, int forward_runs,
                            const std::vector<std::string>& notes);

}  // namespace crackle::identify::detail
