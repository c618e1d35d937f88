#pragma once
/// \file `crackle plan scene.yaml -o DIR`: which sensor, drive point and drive frequency detect and
/// locate a crack of the prior (DETECTION.md sec. 3), on identify's forward model (src/identify/
/// forward.hpp: the unknowns by key path, the moved grid, batches of study cases).
///
/// ```yaml
/// plan:
///   prior: {crack.plane.at: [0.02, 0.18], crack.region.z[0]: [0.007, 0.0095]}
///   samples: 3                                 # per prior key: the centres of equal bins
///   sensors: {face: z+, spacing: 0.01}         # or {points: [[x, y, z], ...]}
///   drives:
///     points: [[0.2, 0.01, 0.01], [0.1, 0.01, 0.01]]
///     frequencies: [{mode: 1, ratio: 0.5}, {mode: 1, ratio: 2.0}]
///   noise: {frequency: 0.0005, ratio: 0.05, floor: 1.0e-4}
/// ```
///
/// For each prior sample theta, drive point and drive frequency (ratio times the sample's bilinear
/// frequency of the mode), one `crackle sweep` case gives the harmonics at every candidate sensor
/// (the sensors are the sweep's probes): a narrow sweep about the drive (A2/A1, A3/A1) or, for a
/// ratio >= 1.5, a sweep with stability and the period-two branch over +-kSubharmonicHalfWidth
/// (A1/2/A1 where that branch exists and is stable). The same cases at theta + h e_j (fixed drive
/// in Hz) give the Jacobian; `crackle modal` cases at the same points give the bilinear frequency of
/// each driven mode. Figures per candidate and sample:
/// - Fisher information F = J^T Sigma^-1 J of the bilinear frequency (sigma = hypot(noise.frequency,
///   eps) f_b) and the sensor's ratios (sigma^2 = (noise.ratio v)^2 + (floor / A1)^2 + (eps v)^2,
///   floor = noise.floor times the largest A1 over the sensors: the acquisition's noise floor in m),
///   eps the relative model error of the quantity as identify weighs it (identify::refinement_error
///   on the orders p, p+1, p+2 in the middle of the prior: 3 modal runs and 3 sweeps per drive point
///   and frequency more); log det F and the 95 % widths 1.96 sqrt(diag F^-1);
/// - detection: z = (f_u - f_b) / (noise.frequency f_u) and, for each harmonic, its amplitude over
///   the floor (the uncracked body's harmonics are zero: a measurement of it reads the floor); detected when the
///   largest z exceeds 3; the smallest detectable crack per position interpolates z along the size
///   key (plan.size) between samples;
/// - existence: a sub-harmonic candidate responds at a sample only where the stable period-two
///   branch covers the drive frequency.
/// Candidates are ranked by the mean of log det F over the samples where they respond (those that
/// respond at every sample first); the best k = 1..combine sensors for the best drive are chosen
/// greedily on the mean log det of the summed F, each set with its 95 % widths from that F.
/// Outputs: plan.json, plan_sensors.vtu, plan_log_det.png (log det along the sensors), plan_map.png (over a face of sensors).
#include <iosfwd>
#include <string>
#include <vector>

#include <nlohmann/json_fwd.hpp>

#include "core/types.hpp"
#include "identify/forward.hpp"

namespace crackle::planning {

/// A drive frequency: ratio times the bilinear frequency of an uncracked mode (1-based).
struct DriveFrequency {
  int mode = 1;
  double ratio = 0.5;
  bool subharmonic() const { return ratio >= 1.5; }  ///< driven near 2 f: the f/2 response
};

struct PlanSpec {
  std::vector<identify::Unknown> prior;
  int samples = 3;       ///< per prior key
  int size_key = -1;     ///< index into prior of the crack-size key (plan.size; default the last)
  std::vector<Vec3> sensors;
  std::string face;      ///< sensors sampled on this face ("" for a list of points)
  int grid[2] = {0, 0};  ///< the face grid's points along its two axes (sensors row-major, second fastest)
  int component = -1;    ///< analysed displacement component (-1: the excitation direction)
  std::vector<Vec3> drive_points;
  std::vector<DriveFrequency> frequencies;
  double noise_frequency = 5e-4;  ///< relative sigma of a measured frequency
  double noise_ratio = 0.05;      ///< relative sigma of a measured harmonic ratio
  double noise_floor = 1e-4;      ///< noise floor relative to the largest A1 over the sensors (dynamic range)
  int combine = 3;                ///< best sets of 1..combine sensors
  int line = -1;
};

/// Parses the `plan:` section of a scene file; the sensors of a face need the box (origin, size),
/// so `origin`/`size` come from the scene. InputError "file:line: plan.key: expected ..., got ...".
PlanSpec parse_plan_section(const std::string& text, const std::string& file, const Vec3& origin, const Vec3& size);

struct PlanOptions {
  std::string scene_path;
  std::string output_dir;
  std::string executable;  ///< crackle executable for the forward runs (/proc/self/exe)
  int jobs = 0;            ///< forward runs at a time; 0: the cores
  bool progress = true;    ///< the forward runs' progress lines (the study's case counts)
};

/// Runs the plan; progress to `log`. Returns the plan.json document.
nlohmann::json run_plan(const PlanOptions& options, std::ostream& log);

/// One step of the greedy sensor choice: the sensor added, the mean log det over samples after it,
/// and each sample's Fisher information of the set so far.
struct GreedyStep {
  int sensor = -1;
  double log_det = 0.0;
  std::vector<MatrixX> fisher;
};

/// Greedy choice of sensors on the mean log det over samples of base[s] + sum over chosen of
/// per_sensor[c][s] (k x k Fisher matrices): the chosen candidates in order (at most `count`).
std::vector<GreedyStep> greedy_sensors(const std::vector<MatrixX>& base, const std::vector<std::vector<MatrixX>>& per_sensor,
                                       int count);

/// log det of a symmetric positive semi-definite matrix; -infinity when it is singular (an
/// eigenvalue at most 1e-12 of the largest).
double log_det(const MatrixX& fisher);

}  // namespace crackle::planning
