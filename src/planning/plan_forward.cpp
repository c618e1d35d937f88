/// \file The forward runs of `crackle plan` (plan_stages.hpp): the checks against the scene, the
/// forward runs' scene, the prior samples, and stages 1-3 (modal frequencies, sweeps at the samples,
/// sweeps at the Jacobian points), each a batch of study cases run by identify/forward.hpp.
#include <algorithm>
#include <cmath>
#include <fstream>
#include <ostream>

#include "core/errors.hpp"
#include "planning/plan_stages.hpp"
#include "scene/schema.hpp"

namespace crackle::planning::detail {
namespace fs = std::filesystem;
using identify::ForwardCase;
using identify::SweepTable;
using nlohmann::json;

std::string sensor_name(std::size_t i) { return "s" + std::to_string(i + 1); }

std::vector<std::string> ratio_quantities(const DriveFrequency& f) {
  return f.subharmonic() ? std::vector<std::string>{"A1/2/A1"} : std::vector<std::string>{"A2/A1", "A3/A1"};
}

namespace {

/// The drive frequencies of the plan against the modes the scene solves and its friction.
void check_frequencies(const PlanSpec& spec, const scene::Scene& scene, const std::string& file) {
  for (std::size_t i = 0; i < spec.frequencies.size(); ++i) {
    if (spec.frequencies[i].mode > scene.modal.modes)
      throw InputError(file + ": plan.drives.frequencies[" + std::to_string(i) + "].mode: expected a mode the scene solves "
                       "(modal.modes = " + std::to_string(scene.modal.modes) + "), got " + std::to_string(spec.frequencies[i].mode));
    if (spec.frequencies[i].subharmonic() && scene.contact.friction > 0.0)
      throw InputError(file + ": plan.drives.frequencies[" + std::to_string(i) + "].ratio: expected a ratio below 1.5 with "
                       "friction (a sub-harmonic needs the sweep's stability, which is frictionless), got " +
                       format_number(spec.frequencies[i].ratio));
  }
}

/// Every point of `points` inside the body's box, else an error naming `key`[i].
void check_inside(const std::vector<Vec3>& points, const scene::Scene& scene, const std::string& file, const std::string& key) {
  const auto inside = [&](const Vec3& x) {
    for (int a = 0; a < 3; ++a)
      if (x[a] < scene.box.origin[a] - 1e-12 || x[a] > scene.box.origin[a] + scene.box.size[a] + 1e-12) return false;
    return true;
  };
  for (std::size_t i = 0; i < points.size(); ++i)
    if (!inside(points[i]))
      throw InputError(file + ": " + key + "[" + std::to_string(i) + "]: expected a point of the body's box, got (" +
                       format_number(points[i][0]) + ", " + format_number(points[i][1]) + ", " +
                       format_number(points[i][2]) + ")");
}

/// The sweep keys of a drive frequency: 2 points about a period-one drive, stability and the
/// period-two branch over kSubharmonicPoints about a sub-harmonic one.
void sweep_keys(const DriveFrequency& f, std::vector<std::pair<std::string, std::string>>& set) {
  set.emplace_back("sweep.points", std::to_string(f.subharmonic() ? kSubharmonicPoints : 2));
  set.emplace_back("sweep.stability", f.subharmonic() ? "true" : "false");
  set.emplace_back("sweep.subharmonic", f.subharmonic() ? "2" : "1");
}

std::string point_text(const Vec3& x) { return list_text({x[0], x[1], x[2]}); }

}  // namespace

YAML::Node forward_base(const std::string& text, const PlanSpec& spec, const scene::Scene& scene, const std::string& file) {
  if (!scene.transient || !scene.transient->excitation || scene.transient->excitation->kind != scene::ExcitationKind::harmonic)
    throw InputError(file + ": plan: expected a scene with a harmonic transient.excitation (its direction, amplitude and "
                     "damping drive every candidate; plan.drives moves it), got " +
                     std::string(!scene.transient || !scene.transient->excitation ? "none" : "a pulse"));
  check_frequencies(spec, scene, file);
  check_inside(spec.drive_points, scene, file, "plan.drives.points");
  check_inside(spec.sensors, scene, file, "plan.sensors.points");

  YAML::Node base = scene::parse_yaml(text, file);
  base.remove("plan");
  base.remove("study");
  base.remove("identify");
  identify::prepare_base(base, scene, spec.prior, file, "plan.prior");
  // The candidate sensors are the sweep's probes; the drive is a point load of the scene's excitation.
  YAML::Node probes(YAML::NodeType::Sequence);
  for (std::size_t i = 0; i < spec.sensors.size(); ++i) {
    YAML::Node probe(YAML::NodeType::Map);
    probe["name"] = sensor_name(i);
    probe["point"] = YAML::Load(point_text(spec.sensors[i]));
    if (spec.component >= 0) probe["component"] = std::string(1, static_cast<char>('x' + spec.component));
    probes.push_back(probe);
  }
  base["transient"]["probes"] = probes;
  YAML::Node excitation = base["transient"]["excitation"];
  for (const char* key : {"face", "group", "point"})
    if (excitation[key]) excitation.remove(key);
  excitation["point"] = YAML::Load(point_text(spec.drive_points.front()));
  return base;
}

PriorGrid prior_grid(const PlanSpec& spec) {
  const std::size_t k = spec.prior.size();
  PriorGrid grid;
  grid.axes.resize(k);
  for (std::size_t j = 0; j < k; ++j) {
    for (int i = 0; i < spec.samples; ++i)
      grid.axes[j].push_back(spec.prior[j].lower + (spec.prior[j].upper - spec.prior[j].lower) * (i + 0.5) / spec.samples);
    grid.n_samples *= grid.axes[j].size();
  }
  grid.bounds = fit::Bounds{VectorX(k), VectorX(k)};
  for (std::size_t j = 0; j < k; ++j) {
    grid.bounds.lower[static_cast<Eigen::Index>(j)] = spec.prior[j].lower;
    grid.bounds.upper[static_cast<Eigen::Index>(j)] = spec.prior[j].upper;
  }
  grid.sample_index.assign(grid.n_samples, std::vector<std::size_t>(k));
  for (std::size_t flat = 0; flat < grid.n_samples; ++flat) {
    VectorX theta(static_cast<Eigen::Index>(k));
    std::size_t rest = flat;
    for (std::size_t j = k; j-- > 0;) {
      grid.sample_index[flat][j] = rest % grid.axes[j].size();
      theta[static_cast<Eigen::Index>(j)] = grid.axes[j][rest % grid.axes[j].size()];
      rest /= grid.axes[j].size();
    }
    grid.samples.push_back(theta);
    grid.points.push_back(theta);
    for (const VectorX& point :
         fit::jacobian_points(theta, grid.bounds, VectorX::Constant(static_cast<Eigen::Index>(k), kStep)))
      grid.points.push_back(point);
  }
  grid.per_sample = k + 1;
  return grid;
}

ModalFigures modal_figures(PlanRun& run, const PriorGrid& grid) {
  const PlanSpec& spec = run.spec;
  run.log << "plan: " << grid.n_samples << " prior samples x " << spec.drive_points.size() << " drive points x "
          << spec.frequencies.size() << " drive frequencies, " << spec.sensors.size()
          << " candidate sensors; 1. modal frequencies at " << grid.points.size() << " points\n";
  // The model error (identify's: the orders p, p+1, p+2 in the middle of the prior) comes first in
  // each batch, the highest order first (the longest runs start while the others fill the cores).
  ModalFigures modal;
  modal.order_run = run.scene.box.order;
  modal.levels = identify::refinement_orders(modal.order_run);
  const std::size_t n_levels = modal.levels.size();
  std::vector<ForwardCase> cases;
  for (std::size_t l = n_levels; l-- > 0;) cases.push_back({grid.middle(), modal.levels[l], {}});
  for (const VectorX& point : grid.points) cases.push_back({point, modal.order_run, {}});
  const std::vector<fs::path> folders =
      identify::run_forward_cases(run.base, spec.prior, cases, "modal", run.dir / "modal", run.runner, run.log, run.progress);
  run.forward_runs += static_cast<int>(folders.size());
  modal.f_u.resize(grid.points.size());
  modal.f_b.resize(grid.points.size());
  modal.level_f_b.resize(n_levels);
  for (std::size_t c = 0; c < folders.size(); ++c) {
    std::ifstream stream(folders[c] / "modal.json");
    const json document = json::parse(stream);
    std::vector<double>& bilinear = c < n_levels ? modal.level_f_b[n_levels - 1 - c] : modal.f_b[c - n_levels];
    for (const json& pair : document["pairs"]) {
      if (c >= n_levels) modal.f_u[c - n_levels].push_back(pair["f_uncracked_hz"].get<double>());
      bilinear.push_back(pair.value("paired", true) ? pair["f_bilinear_hz"].get<double>() : kNaN);
    }
  }
  // the relative model error of each mode's bilinear frequency (the driven ones are used)
  const auto at = [](const std::vector<double>& values, std::size_t i) { return values.size() > i ? values[i] : kNaN; };
  modal.run_level = static_cast<std::size_t>(modal.order_run - modal.levels.front());
  for (std::size_t m = 0; m < static_cast<std::size_t>(run.scene.modal.modes); ++m)
    modal.frequency_error.push_back(identify::refinement_error(at(modal.level_f_b[0], m), at(modal.level_f_b[1], m),
                                                               at(modal.level_f_b[2], m), static_cast<int>(modal.run_level)));
  return modal;
}

namespace {

/// The drive frequencies highest first within each sample and drive point: the cases of one crack
/// share a modal cache folder, and a reduction made for the highest frequency (the most modes) serves
/// the lower ones from the cache (reduced::ReductionOptions::frequency_margin).
void order_frequencies(const PlanSpec& spec, const ModalFigures& modal, SampleSweeps& sweeps) {
  sweeps.freq_order.resize(sweeps.n_freq);
  sweeps.freq_rank.resize(sweeps.n_freq);
  for (std::size_t f = 0; f < sweeps.n_freq; ++f) sweeps.freq_order[f] = f;
  const std::vector<double>& run_f_b = modal.level_f_b[modal.run_level];
  const auto nominal_hz = [&](std::size_t f) {
    const std::size_t mode = static_cast<std::size_t>(spec.frequencies[f].mode - 1);
    const double hz = spec.frequencies[f].ratio * (run_f_b.size() > mode ? run_f_b[mode] : kNaN);
    return std::isfinite(hz) ? hz : 0.0;
  };
  std::stable_sort(sweeps.freq_order.begin(), sweeps.freq_order.end(),
                   [&](std::size_t a, std::size_t b) { return nominal_hz(a) > nominal_hz(b); });
  for (std::size_t i = 0; i < sweeps.n_freq; ++i) sweeps.freq_rank[sweeps.freq_order[i]] = i;
}

/// f_b of `mode` at the run's order over f_b at level l (both in the middle of the prior, from the
/// modal stage): the factor that puts level l's sweep on the run level's drive frequency in Hz. 1 where
/// either is missing.
double level_hz_ratio(const ModalFigures& modal, std::size_t l, int mode) {
  const std::size_t m = static_cast<std::size_t>(mode - 1);
  const std::vector<double>& run = modal.level_f_b[modal.run_level];
  const std::vector<double>& level = modal.level_f_b[l];
  if (m >= run.size() || m >= level.size() || !std::isfinite(run[m]) || !std::isfinite(level[m]) || level[m] <= 0.0)
    return 1.0;
  return run[m] / level[m];
}

/// The largest first harmonic over the sensors of each sample sweep (the reference of noise.floor).
void largest_first_harmonics(const PlanSpec& spec, SampleSweeps& sweeps) {
  sweeps.largest_a1.assign(sweeps.tables.size(), 0.0);
  for (std::size_t a = 0; a < sweeps.tables.size(); ++a) {
    const std::size_t f = sweeps.freq_order[a % sweeps.n_freq];
    for (std::size_t i = 0; i < spec.sensors.size(); ++i) {
      const double a1 = sweep_value(sweeps.tables[a], "A1", sensor_name(i), sweeps.drive_hz(a),
                                    spec.frequencies[f].subharmonic() ? 2 : 1);
      if (std::isfinite(a1)) sweeps.largest_a1[a] = std::max(sweeps.largest_a1[a], a1);
    }
  }
}

}  // namespace

SampleSweeps sample_sweeps(PlanRun& run, const PriorGrid& grid, const ModalFigures& modal) {
  const PlanSpec& spec = run.spec;
  SampleSweeps sweeps;
  sweeps.n_levels = modal.levels.size();
  sweeps.n_drives = spec.drive_points.size();
  sweeps.n_freq = spec.frequencies.size();
  order_frequencies(spec, modal, sweeps);
  YAML::Node base = YAML::Clone(run.base);
  base["sweep"]["frequency"] = YAML::Load("{from: {mode: 1, ratio: 1}, to: {mode: 1, ratio: 2}}");
  std::vector<ForwardCase> cases;
  std::vector<double> drives;  // per case: the drive in Hz from the modal stage, NaN where f_b is missing
  // the model error's levels (the middle of the prior at each refinement order) first, then the samples
  for (std::size_t s = 0; s < sweeps.n_levels + grid.n_samples; ++s)
    for (std::size_t p = 0; p < sweeps.n_drives; ++p)
      for (const std::size_t f : sweeps.freq_order) {
        const DriveFrequency& drive = spec.frequencies[f];
        const double half = drive.subharmonic() ? kSubharmonicHalfWidth : kNarrowHalfWidth;
        // A level sweeps about the run level's drive in Hz, not its own mode's: identify estimates a
        // measured quantity's model error at the measured drive_hz, so the plan's weights are identify's
        // (with each level at its own resonance, A2/A1's error was 14.6 % against identify's 17.9 %
        // on the Plan test scene: log det 0.64 apart).
        const bool is_level = s < sweeps.n_levels;
        const std::size_t level = is_level ? sweeps.n_levels - 1 - s : 0;  // the highest order first
        const double ratio = is_level ? drive.ratio * level_hz_ratio(modal, level, drive.mode) : drive.ratio;
        ForwardCase forward = is_level ? ForwardCase{grid.middle(), modal.levels[level], {}}
                                       : ForwardCase{grid.samples[s - sweeps.n_levels], modal.order_run, {}};
        forward.set = {{"transient.excitation.point", point_text(spec.drive_points[p])},
                       {"sweep.frequency.from.mode", std::to_string(drive.mode)},
                       {"sweep.frequency.from.ratio", format_number(ratio * (1.0 - half))},
                       {"sweep.frequency.to.mode", std::to_string(drive.mode)},
                       {"sweep.frequency.to.ratio", format_number(ratio * (1.0 + half))}};
        // Every branch is solved at the drive in Hz (the run level's f_b at the sample, or in the
        // middle for a level), so that its value is the solution's own, not an interpolation between
        // continuation points that move with the sample (docs/benchmarks.md 13.9).
        const std::size_t m = static_cast<std::size_t>(drive.mode - 1);
        const std::vector<double>& f_b = is_level ? modal.level_f_b[modal.run_level]
                                                  : modal.f_b[(s - sweeps.n_levels) * grid.per_sample];
        const std::vector<double>& f_u = modal.f_u[is_level ? 0 : (s - sweeps.n_levels) * grid.per_sample];
        const double hz = drive.ratio * (f_b.size() > m ? f_b[m] : kNaN);
        drives.push_back(hz);
        const double at = std::isfinite(hz) ? hz : drive.ratio * (f_u.size() > m ? f_u[m] : 1.0);
        forward.set.emplace_back("sweep.solve_at", "[" + format_number(at) + "]");
        sweep_keys(drive, forward.set);
        cases.push_back(forward);
      }
  run.log << "plan: 2. sweeps at the samples: " << cases.size() << " runs ("
          << sweeps.n_levels * sweeps.n_drives * sweeps.n_freq << " of them for the model error)\n";
  const std::vector<fs::path> folders =
      identify::run_forward_cases(base, spec.prior, cases, "sweep", run.dir / "samples", run.runner, run.log, run.progress);
  run.forward_runs += static_cast<int>(folders.size());
  // the model error's runs first: level l (order levels[l]) of drive p and frequency f, at their own drive
  const std::size_t n_level_runs = sweeps.n_levels * sweeps.n_drives * sweeps.n_freq;
  for (std::size_t c = 0; c < folders.size(); ++c) {
    std::ifstream stream(folders[c] / "sweep.json");
    const json sweep = json::parse(stream);
    const std::array<double, 2> range = {sweep["settings"]["from_hz"].get<double>(), sweep["settings"]["to_hz"].get<double>()};
    (c < n_level_runs ? sweeps.level_tables : sweeps.tables).push_back(identify::read_sweep_csv(folders[c] / "sweep.csv"));
    (c < n_level_runs ? sweeps.level_ranges : sweeps.ranges).push_back(range);
    (c < n_level_runs ? sweeps.level_drives : sweeps.drives)
        .push_back(std::isfinite(drives[c]) ? drives[c] : 0.5 * (range[0] + range[1]));
  }
  largest_first_harmonics(spec, sweeps);
  return sweeps;
}

JacobianSweeps jacobian_sweeps(PlanRun& run, const PriorGrid& grid, const SampleSweeps& sweeps) {
  const PlanSpec& spec = run.spec;
  const std::size_t k = spec.prior.size();
  YAML::Node base = YAML::Clone(run.base);
  base["sweep"]["frequency"] = YAML::Load("{from: 1.0, to: 2.0}");
  JacobianSweeps jacobian;
  std::vector<ForwardCase> cases;
  for (std::size_t s = 0; s < grid.n_samples; ++s)
    for (std::size_t j = 1; j <= k; ++j)
      for (std::size_t p = 0; p < sweeps.n_drives; ++p)
        for (const std::size_t f : sweeps.freq_order) {
          const std::size_t a = sweeps.index(s, p, f);
          const std::array<double, 2>& range = sweeps.ranges[a];
          // A sub-harmonic drive without a stable period-two branch at the sample has no response:
          // no Jacobian (its sweeps with stability are the costliest runs).
          if (spec.frequencies[f].subharmonic() && !period_two_exists(sweeps.tables[a], sweeps.drive_hz(a))) continue;
          jacobian.where[{s, j, p, f}] = cases.size();
          ForwardCase forward{grid.points[s * grid.per_sample + j], 0, {}};
          forward.set = {{"transient.excitation.point", point_text(spec.drive_points[p])},
                         {"sweep.frequency.from", format_number(range[0])},
                         {"sweep.frequency.to", format_number(range[1])},
                         {"sweep.solve_at", "[" + format_number(sweeps.drive_hz(a)) + "]"}};
          sweep_keys(spec.frequencies[f], forward.set);
          cases.push_back(forward);
        }
  run.log << "plan: 3. sweeps at the Jacobian points: " << cases.size() << " runs\n";
  const std::vector<fs::path> folders =
      identify::run_forward_cases(base, spec.prior, cases, "sweep", run.dir / "jacobian", run.runner, run.log, run.progress);
  run.forward_runs += static_cast<int>(folders.size());
  for (const fs::path& folder : folders) jacobian.tables.push_back(identify::read_sweep_csv(folder / "sweep.csv"));
  return jacobian;
}

}  // namespace crackle::planning::detail
