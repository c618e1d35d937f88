#pragma once
/// \file The forward model of identification and test planning (DETECTION.md secs. 2-3): scene keys
/// as unknowns, the grid made for a reference crack and moved onto each crack, and batches of
/// forward runs as one study of `crackle modal` or `crackle sweep` cases (parallel, resumable, cached
/// by the hash of each case's scene). `crackle identify` and `crackle plan` both run it.
#include <filesystem>
#include <iosfwd>
#include <string>
#include <utility>
#include <vector>

#include <yaml-cpp/yaml.h>

#include "core/types.hpp"

namespace crackle::scene {
struct Scene;
}

namespace crackle::identify {

/// Section-parsing helpers of identify: and plan: (their messages: "file:line: path: expected ..., got ...").
/// A finite number (an integer when `integer`) at `node`, else InputError naming `path`.
double number_of(const YAML::Node& node, const std::string& file, const std::string& path, bool integer = false);
/// InputError for the first key of the map `map` not in `keys`, with a "did you mean" suggestion.
void only_keys(const YAML::Node& map, const std::vector<std::string>& keys, const std::string& file,
               const std::string& path);

/// One unknown: a scene key (path, or a list entry path[index]) and its bounds.
struct Unknown {
  std::string key;   ///< as written: crack.region.z[0]
  std::string path;  ///< the scene key: crack.region.z
  int index = -1;    ///< list entry, or -1 for a scalar key
  double lower = 0.0, upper = 0.0;
  int line = -1;
};

/// Parses a map {key.path: [low, high]} (identify.unknowns, plan.prior): numeric scene keys, a list
/// entry by its index, low < high, each key once. `where`: the section's key path for messages.
/// InputError "file:line: where.key: expected ..., got ..." on any problem.
std::vector<Unknown> parse_unknowns(const YAML::Node& map, const std::string& file, const std::string& where, int line);

/// Checks the unknowns against the scene document (a list entry must exist, a list key needs an
/// index), then sets crack.reference to the middle of the bounds (its plane on the nearest uniform
/// grid plane), so that every forward run's grid is the same one moved (mesh::morph_lines).
/// InputError when the scene has no box mesh with a crack.
void prepare_base(YAML::Node& base, const scene::Scene& scene, const std::vector<Unknown>& unknowns,
                  const std::string& file, const std::string& where);

/// The value of a dotted key path in a document (map keys only), or an undefined node.
YAML::Node node_at(const YAML::Node& document, const std::string& path);

/// One forward run: the unknowns' values, an optional mesh.box.order, and further scene keys set
/// for this run (key path -> YAML text; every case of a batch must set the same keys).
struct ForwardCase {
  VectorX theta;
  int order = 0;  ///< 0: the scene's
  std::vector<std::pair<std::string, std::string>> set;
};

struct ForwardRunner {
  std::string executable;  ///< the crackle executable
  int jobs = 0;            ///< forward runs at a time; 0: the cores
  /// One modal cache folder for every batch, modal and sweep (its entries are keyed by content): a
  /// sweep case then reads the modes a modal case of the same crack and order solved. Empty: sweep
  /// batches keep a folder per crack, modal batches none.
  std::string modal_cache;
};

/// Runs the cases as one study of `crackle <command>` cases (command "modal" or "sweep") in
/// `folder` (forward.yaml, runs/): a rerun with the same cases reuses them. Returns the case
/// folders in order. SolverError names a case that failed; "identify: interrupted" on Ctrl-C.
std::vector<std::filesystem::path> run_forward_cases(const YAML::Node& base, const std::vector<Unknown>& unknowns,
                                                     const std::vector<ForwardCase>& cases, const std::string& command,
                                                     const std::filesystem::path& folder, const ForwardRunner& runner,
                                                     std::ostream& log, bool progress);

/// Rows of a sweep.csv: the excitation frequency and the named columns.
struct SweepTable {
  std::vector<std::string> header;
  std::vector<std::vector<double>> rows;
  /// The column "<probe> u_<c> <name>" (name e.g. "A2/A1 [-]"), or -1.
  int probe_column(const std::string& probe, const std::string& name) const;
  /// A column by its whole header, or -1.
  int column(const std::string& name) const;
};

/// The cells of one CSV line (RFC 4180 quoting), trimmed.
std::vector<std::string> split_csv_line(const std::string& line);

SweepTable read_sweep_csv(const std::filesystem::path& path);

/// A harmonic quantity (A1, A2/A1, A3/A1, A1/2/A1) of a probe at the drive frequency, linearly
/// interpolated between the two points around it on the branch of `branch_period` excitation
/// periods (1: period one; 2: the period-two branch of a sub-harmonic sweep); NaN where no two
/// neighbouring points of that branch enclose it.
double sweep_value(const SweepTable& table, const std::string& quantity, const std::string& probe, double drive_hz,
                   int branch_period = 1);

/// The sweep about a drive frequency at which a sub-harmonic (A1/2/A1) is read: this half-width,
/// relative, and this many points, with stability and `subharmonic: 2`. The period-two branch is born
/// at a period doubling somewhere around 2 f_b; the sweep must find it and follow it.
inline constexpr double kSubharmonicHalfWidth = 0.15;
inline constexpr int kSubharmonicPoints = 40;

/// Whether the table's period-two branch is stable at the drive frequency (a row there, or two
/// neighbouring rows around it, all stable).
bool period_two_exists(const SweepTable& table, double drive_hz);

/// A1/2/A1 of a probe at the drive frequency, as a lab driving there at steady state measures it:
/// on the stable period-two branch where the table has one at the drive (its row at the drive from
/// sweep.solve_at, else interpolated); 0 where the period-one response is stable there and no stable
/// period-two one exists (no sub-harmonic); NaN where neither is stable (no periodic steady state
/// the sweep knows) or the table does not reach the drive.
double subharmonic_value(const SweepTable& table, const std::string& probe, double drive_hz);

/// A harmonic quantity of a probe at the drive as identify and plan read it: A1/2/A1 by
/// subharmonic_value, the others by sweep_value on the branch of `branch_period`.
double harmonic_value(const SweepTable& table, const std::string& quantity, const std::string& probe, double drive_hz,
                      int branch_period = 1);

/// The mesh orders of the model-error estimate of a forward model run at order p: {min(p, 2),
/// +1, +2} (identify's and plan's; DETECTION.md sec. 1, the p-refinement of MODEL.md's elements).
std::vector<int> refinement_orders(int p);

/// The numerical error of a quantity from its values q0, q1, q2 at the three refinement_orders, of
/// the level `run_level` (0, 1, 2) that is run: src/accuracy's three-level Richardson read
/// geometrically in the order (accuracy::three_level_at with kOrderLevelRatio and its rate range:
/// Fs 1.25 with a sane rate, 3 outside it; non-monotone or not converging: 3 times the change to
/// the next level, not verified). Relative to the run's value. A level without a value (NaN): 3
/// times the change from the run's level to the nearest other level with one (the finer first), not
/// verified; 0 and not verified when only the run's level has a value. Measured on identify's beam:
/// effectivity 1.25-1.31 (docs/benchmarks.md 13).
struct RefinementError {
  double relative = 0.0;
  bool verified = true;
};
RefinementError refinement_error(double q0, double q1, double q2, int run_level);

}  // namespace crackle::identify
