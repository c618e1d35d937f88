#pragma once
/// \file The stages of `crackle plan` (planning.hpp's `run_plan`), private to src/planning:
/// the forward runs (plan_forward.cpp: the prior samples, the modal frequencies, the sweeps at the
/// samples and at their Jacobian points), the candidates' figures (plan_figures.cpp: Fisher
/// information, widths, detectability, ranking) and the files (plan_output.cpp: plan.json,
/// plan_sensors.vtu, the plots). DETECTION.md sec. 3.
#include <array>
#include <cstddef>
#include <filesystem>
#include <iosfwd>
#include <limits>
#include <map>
#include <string>
#include <utility>
#include <vector>

#include <nlohmann/json.hpp>
#include <yaml-cpp/yaml.h>

#include "fit/fit.hpp"
#include "identify/forward.hpp"
#include "planning/planning.hpp"
#include "scene/scene.hpp"

namespace crackle::planning::detail {

inline constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
inline constexpr double kInf = std::numeric_limits<double>::infinity();
/// Finite-difference step of the Jacobian, as a fraction of each prior width (identify's, chosen
/// against the forward model's noise: docs/benchmarks.md 13.4).
inline constexpr double kStep = 1e-4;
/// Half-width of the narrow sweep about a period-one drive, relative (identify's).
inline constexpr double kNarrowHalfWidth = 1e-4;
using identify::kSubharmonicHalfWidth;  // the sweep about a sub-harmonic drive (identify's)
using identify::kSubharmonicPoints;
using identify::period_two_exists;
/// Detection threshold (DETECTION.md sec. 3) and the 95 % normal quantile of the widths.
inline constexpr double kDetect = 3.0;
inline constexpr double kZ95 = 1.959963984540054;

/// The probe name of candidate sensor i: "s1", "s2", ...
std::string sensor_name(std::size_t i);
/// The quantities a candidate measures at its sensor.
std::vector<std::string> ratio_quantities(const DriveFrequency& f);

/// What every stage reads: the plan, its scene, the scene of every forward run (`base`: the plan's
/// scene with the candidate sensors as probes and the drive a point load) and where they run.
struct PlanRun {
  const PlanSpec& spec;
  const scene::Scene& scene;
  const std::string& file;
  YAML::Node base;
  std::filesystem::path dir;
  identify::ForwardRunner runner;
  std::ostream& log;
  bool progress = true;
  int forward_runs = 0;
};

/// Refuses a plan its scene cannot run (file: key: what was expected), then the forward runs' scene.
YAML::Node forward_base(const std::string& text, const PlanSpec& spec, const scene::Scene& scene, const std::string& file);

/// The prior samples (centres of equal bins per key) and, after each, its k Jacobian points.
struct PriorGrid {
  std::vector<std::vector<double>> axes;  ///< per key, the bin centres
  fit::Bounds bounds;
  std::vector<VectorX> samples;
  std::vector<VectorX> points;  ///< per sample, the sample then its k Jacobian points
  std::vector<std::vector<std::size_t>> sample_index;  ///< per sample, its bin along each key
  std::size_t n_samples = 1, per_sample = 1;
  VectorX middle() const { return 0.5 * (bounds.lower + bounds.upper); }
};
PriorGrid prior_grid(const PlanSpec& spec);

/// Stage 1: the frequencies of every point (crackle modal), and of the middle of the prior at the
/// orders p, p+1, p+2 for the model error (identify's).
struct ModalFigures {
  std::vector<int> levels;     ///< the orders of the model error's levels
  int order_run = 1;           ///< the scene's order
  std::size_t run_level = 0;   ///< its index in `levels`
  std::vector<std::vector<double>> f_u, f_b;  ///< per point of the grid, per mode [Hz]
  std::vector<std::vector<double>> level_f_b; ///< per level, per mode [Hz]
  std::vector<identify::RefinementError> frequency_error;  ///< of each mode's bilinear frequency
};
ModalFigures modal_figures(PlanRun& run, const PriorGrid& grid);

/// Stage 2: a sweep about each drive frequency at every sample and at the model error's levels,
/// every sensor at once; the drive frequencies highest first within a sample and drive point.
struct SampleSweeps {
  std::size_t n_levels = 0, n_drives = 0, n_freq = 0;
  std::vector<std::size_t> freq_order, freq_rank;
  std::vector<identify::SweepTable> tables, level_tables;
  std::vector<std::array<double, 2>> ranges, level_ranges;  ///< each sweep's range [Hz]
  /// Each sweep's drive [Hz]: the ratio times the modal stage's f_b there, where the sweep solved
  /// every branch (sweep.solve_at); the middle of its range where that f_b is missing.
  std::vector<double> drives, level_drives;
  std::vector<double> largest_a1;  ///< per sample sweep: the largest first harmonic over the sensors
  /// The sweep of sample s, drive point p, frequency f; of level l.
  std::size_t index(std::size_t s, std::size_t p, std::size_t f) const { return (s * n_drives + p) * n_freq + freq_rank[f]; }
  std::size_t level_run(std::size_t l, std::size_t p, std::size_t f) const {
    return ((n_levels - 1 - l) * n_drives + p) * n_freq + freq_rank[f];
  }
  double drive_hz(std::size_t a) const { return drives[a]; }
};
SampleSweeps sample_sweeps(PlanRun& run, const PriorGrid& grid, const ModalFigures& modal);

/// Stage 3: the same sweeps at the Jacobian points, the drive fixed in Hz (none where a
/// sub-harmonic drive has no period-two branch at the sample).
struct JacobianSweeps {
  std::vector<identify::SweepTable> tables;
  std::map<std::array<std::size_t, 4>, std::size_t> where;  ///< (s, j, p, f) -> sweep
  identify::SweepTable none;
  const identify::SweepTable& table(std::size_t s, std::size_t j, std::size_t p, std::size_t f) const {
    const auto it = where.find({s, j, p, f});
    return it == where.end() ? none : tables[it->second];
  }
};
JacobianSweeps jacobian_sweeps(PlanRun& run, const PriorGrid& grid, const SampleSweeps& sweeps);

/// One sample's figures for a candidate.
struct SampleFigures {
  bool responds = true;
  /// A forward value the figures need is not finite although the drive responds (a period-one drive, or
  /// a sub-harmonic one whose branch exists): its sweep did not reach the drive frequency. Counted as
  /// not responding, and reported (plan.json `notes`, `per_sample[].missing`), never silently.
  bool missing = false;
  MatrixX frequency_fisher;  ///< of the driven mode's bilinear frequency
  MatrixX sensor_fisher;     ///< of the sensor's ratios
  double z = 0.0;            ///< the largest detection statistic
  std::vector<double> values;  ///< the sensor's ratios at the sample
  std::vector<double> sigmas;  ///< their standard deviations: noise and model error
  std::vector<double> noise_sigmas;  ///< the noise's part (a synthetic measurement's sigma)
  double frequency_hz = kNaN, frequency_sigma = kNaN;  ///< the driven mode's bilinear frequency
};

/// A candidate (sensor, drive point, drive frequency) with its figures over the samples.
struct Candidate {
  std::size_t sensor = 0, drive = 0, frequency = 0;
  std::vector<SampleFigures> samples;
  int responding = 0;
  double mean_log_det = -kInf;
  std::vector<double> worst_width, mean_width;
  std::vector<double> smallest_crack;  ///< per position
  std::vector<identify::RefinementError> model_error;  ///< of each ratio quantity, then of f_bilinear
};

/// The 95 % interval widths 2 x 1.96 sqrt(diag F^-1) over Fisher matrices (one per sample) of k
/// unknowns: their mean and the worst (infinite where an F is singular).
struct IntervalWidths {
  std::vector<double> mean, worst;
};
IntervalWidths interval_widths(const std::vector<MatrixX>& fishers, std::size_t k);

/// Stage 4: every candidate's figures at every sample and their averages where it responds.
std::vector<Candidate> candidate_figures(const PlanSpec& spec, const PriorGrid& grid, const ModalFigures& modal,
                                         const SampleSweeps& sweeps, const JacobianSweeps& jacobian);

/// The smallest detectable crack of each candidate (`Candidate::smallest_crack`) at each position:
/// along the size key from its small end (where the first driven mode's frequency drops least).
struct Detectability {
  bool small_first = true;                      ///< the small end is the size key's lower bound
  std::vector<std::size_t> position_samples;    ///< a sample at the smallest crack of each position
  std::vector<std::vector<bool>> at_or_below;   ///< per candidate and position: detected at the prior's end
};
Detectability detectability(const PlanSpec& spec, const PriorGrid& grid, const ModalFigures& modal,
                            std::vector<Candidate>& candidates);

/// The candidates' order: responding at every sample first, then by the mean log det.
std::vector<std::size_t> ranking(const std::vector<Candidate>& candidates, std::size_t n_samples);

/// Everything plan.json, plan_sensors.vtu and the plots are made of.
struct PlanFigures {
  const PriorGrid& grid;
  const ModalFigures& modal;
  const SampleSweeps& sweeps;
  const std::vector<Candidate>& candidates;
  const Detectability& detect;
  const std::vector<std::size_t>& order;
};

/// plan.json's content but the files, times and run counts (run_plan adds them).
nlohmann::json plan_document(const PlanRun& run, const PlanFigures& figures);

/// plan_sensors.vtu, plan_log_det.png and plan_map.png; their names in `files`, why a plot is
/// missing in `notes`.
void write_sensor_figures(const PlanRun& run, const PlanFigures& figures, nlohmann::json& files, nlohmann::json& notes);

}  // namespace crackle::planning::detail
