/// \file The figures of `crackle plan`'s candidates (plan_stages.hpp, stage 4): at each prior
/// sample the Fisher information of the driven mode's bilinear frequency and of the sensor's ratios
/// (sigma^2 = noise^2 + model error^2, DETECTION.md sec. 3), the detection statistic; over the
/// samples the mean log det and the 95 % widths; the smallest detectable crack; the ranking.
#include <algorithm>
#include <cmath>

#include <Eigen/LU>

#include "planning/plan_stages.hpp"

namespace crackle::planning::detail {
namespace {

/// The relative model error of a quantity of a sensor under drive p, frequency f (identify's
/// p-refinement over the level sweeps in the middle of the prior).
identify::RefinementError ratio_error(const PlanSpec& spec, const ModalFigures& modal, const SampleSweeps& sweeps,
                                      const std::string& quantity, const std::string& sensor, std::size_t p, std::size_t f) {
  const int branch = spec.frequencies[f].subharmonic() ? 2 : 1;
  std::vector<double> q(sweeps.n_levels);
  for (std::size_t l = 0; l < sweeps.n_levels; ++l) {
    const std::size_t r = sweeps.level_run(l, p, f);
    q[l] = identify::harmonic_value(sweeps.level_tables[r], quantity, sensor, sweeps.level_drives[r], branch);
  }
  return identify::refinement_error(q[0], q[1], q[2], static_cast<int>(modal.run_level));
}

/// The finite-difference step of Jacobian point j (1..k) of sample s along its key.
double step_of(const PriorGrid& grid, std::size_t s, std::size_t j) {
  const std::size_t p0 = s * grid.per_sample;
  return grid.points[p0 + j][static_cast<Eigen::Index>(j - 1)] - grid.points[p0][static_cast<Eigen::Index>(j - 1)];
}

/// The figures of candidate `c` (its model errors set) at sample s.
SampleFigures sample_figures(const PlanSpec& spec, const PriorGrid& grid, const ModalFigures& modal,
                             const SampleSweeps& sweeps, const JacobianSweeps& jacobian, const Candidate& c, std::size_t s) {
  const std::size_t k = spec.prior.size();
  const DriveFrequency& drive = spec.frequencies[c.frequency];
  const int branch = drive.subharmonic() ? 2 : 1;
  const std::size_t mode = static_cast<std::size_t>(drive.mode - 1);
  const std::string name = sensor_name(c.sensor);
  SampleFigures figures;
  const std::size_t a = sweeps.index(s, c.drive, c.frequency);
  const double drive_hz = sweeps.drive_hz(a);
  const std::size_t p0 = s * grid.per_sample;
  figures.frequency_fisher = MatrixX::Zero(static_cast<Eigen::Index>(k), static_cast<Eigen::Index>(k));
  figures.sensor_fisher = figures.frequency_fisher;
  VectorX row(static_cast<Eigen::Index>(k));
  const double fb0 = modal.f_b[p0].size() > mode ? modal.f_b[p0][mode] : kNaN;
  const double fu0 = modal.f_u[p0].size() > mode ? modal.f_u[p0][mode] : kNaN;
  // sigma of the frequency: the measurement's and the model's error (as identify weighs it)
  const double frequency_sigma = std::hypot(spec.noise_frequency, c.model_error.back().relative) * fb0;
  for (std::size_t j = 1; j <= k; ++j)
    row[static_cast<Eigen::Index>(j - 1)] = (modal.f_b[p0 + j][mode] - fb0) / step_of(grid, s, j) / frequency_sigma;
  if (row.allFinite()) figures.frequency_fisher = row * row.transpose();
  figures.frequency_hz = fb0;
  figures.frequency_sigma = frequency_sigma;
  const double frequency_z = std::isfinite(fb0) ? (fu0 - fb0) / (spec.noise_frequency * fu0) : 0.0;
  figures.z = frequency_z;
  if (drive.subharmonic()) figures.responds = period_two_exists(sweeps.tables[a], drive_hz);
  // The acquisition's noise floor in m: noise.floor of the largest first harmonic over the sensors.
  const double a1 = sweep_value(sweeps.tables[a], "A1", name, drive_hz, branch);
  const double floor_m = spec.noise_floor * sweeps.largest_a1[a];
  const std::vector<std::string> quantities = ratio_quantities(drive);
  for (std::size_t qi = 0; qi < quantities.size(); ++qi) {
    const std::string& q = quantities[qi];
    const double v0 = identify::harmonic_value(sweeps.tables[a], q, name, drive_hz, branch);
    figures.values.push_back(v0);
    if (!std::isfinite(v0)) {
      figures.sigmas.push_back(kNaN);
      figures.noise_sigmas.push_back(kNaN);
      if (figures.responds) figures.missing = true;
      figures.responds = false;
      continue;
    }
    const double sigma = std::sqrt(std::pow(spec.noise_ratio * v0, 2) + std::pow(floor_m / a1, 2) +
                                   std::pow(c.model_error[qi].relative * v0, 2));
    figures.sigmas.push_back(sigma);
    figures.noise_sigmas.push_back(std::hypot(spec.noise_ratio * v0, floor_m / a1));
    for (std::size_t j = 1; j <= k; ++j) {
      const double v = identify::harmonic_value(jacobian.table(s, j, c.drive, c.frequency), q, name, drive_hz, branch);
      row[static_cast<Eigen::Index>(j - 1)] = (v - v0) / step_of(grid, s, j) / sigma;
    }
    if (!row.allFinite()) {
      if (figures.responds) figures.missing = true;
      figures.responds = false;
      continue;
    }
    figures.sensor_fisher += row * row.transpose();
    figures.z = std::max(figures.z, v0 * a1 / floor_m);
  }
  if (!figures.responds) {
    figures.z = frequency_z;
    figures.sensor_fisher.setZero();
  }
  return figures;
}

/// The averages over the samples where the candidate responds: log det and the 95 % widths.
void average(Candidate& c, std::size_t k) {
  double sum = 0.0;
  std::vector<MatrixX> fishers;
  for (const SampleFigures& figures : c.samples) {
    if (!figures.responds) continue;
    ++c.responding;
    fishers.push_back(figures.frequency_fisher + figures.sensor_fisher);
    sum += log_det(fishers.back());
  }
  IntervalWidths widths = interval_widths(fishers, k);
  c.mean_width = std::move(widths.mean);
  c.worst_width = std::move(widths.worst);
  if (c.responding > 0) c.mean_log_det = sum / c.responding;
}

}  // namespace

IntervalWidths interval_widths(const std::vector<MatrixX>& fishers, std::size_t k) {
  IntervalWidths widths{std::vector<double>(k, 0.0), std::vector<double>(k, 0.0)};
  for (const MatrixX& fisher : fishers) {
    const bool regular = std::isfinite(log_det(fisher));
    const MatrixX covariance = regular ? MatrixX(fisher.inverse()) : MatrixX();
    for (std::size_t j = 0; j < k; ++j) {
      const auto i = static_cast<Eigen::Index>(j);
      const double width = regular ? 2.0 * kZ95 * std::sqrt(covariance(i, i)) : kInf;
      widths.worst[j] = std::max(widths.worst[j], width);
      widths.mean[j] += width;
    }
  }
  if (!fishers.empty())
    for (double& width : widths.mean) width /= static_cast<double>(fishers.size());
  return widths;
}

std::vector<Candidate> candidate_figures(const PlanSpec& spec, const PriorGrid& grid, const ModalFigures& modal,
                                         const SampleSweeps& sweeps, const JacobianSweeps& jacobian) {
  std::vector<Candidate> candidates;
  for (std::size_t p = 0; p < spec.drive_points.size(); ++p)
    for (std::size_t f = 0; f < spec.frequencies.size(); ++f)
      for (std::size_t i = 0; i < spec.sensors.size(); ++i) candidates.push_back({i, p, f, {}, 0, -kInf, {}, {}, {}, {}});
  for (Candidate& c : candidates) {
    const DriveFrequency& drive = spec.frequencies[c.frequency];
    for (const std::string& q : ratio_quantities(drive))
      c.model_error.push_back(ratio_error(spec, modal, sweeps, q, sensor_name(c.sensor), c.drive, c.frequency));
    c.model_error.push_back(modal.frequency_error[static_cast<std::size_t>(drive.mode - 1)]);
    for (std::size_t s = 0; s < grid.n_samples; ++s)
      c.samples.push_back(sample_figures(spec, grid, modal, sweeps, jacobian, c, s));
    average(c, spec.prior.size());
  }
  return candidates;
}

Detectability detectability(const PlanSpec& spec, const PriorGrid& grid, const ModalFigures& modal,
                            std::vector<Candidate>& candidates) {
  const std::size_t k = spec.prior.size(), size = static_cast<std::size_t>(spec.size_key);
  const std::vector<double>& axis = grid.axes[size];
  Detectability detect;
  // The small end of the size key: where the first driven mode's frequency drops least.
  double drop_first = 0.0, drop_last = 0.0;
  for (std::size_t s = 0; s < grid.n_samples; ++s) {
    const std::size_t mode = static_cast<std::size_t>(spec.frequencies.front().mode - 1);
    const double drop = modal.f_u[s * grid.per_sample][mode] - modal.f_b[s * grid.per_sample][mode];
    if (grid.sample_index[s][size] == 0) drop_first += drop;
    if (grid.sample_index[s][size] + 1 == axis.size()) drop_last += drop;
  }
  detect.small_first = drop_first <= drop_last;
  for (std::size_t s = 0; s < grid.n_samples; ++s)
    if (grid.sample_index[s][size] == (detect.small_first ? 0 : axis.size() - 1)) detect.position_samples.push_back(s);
  std::size_t size_stride = 1;
  for (std::size_t j = k; j-- > size + 1;) size_stride *= grid.axes[j].size();
  detect.at_or_below.resize(candidates.size());
  for (std::size_t ci = 0; ci < candidates.size(); ++ci) {
    Candidate& c = candidates[ci];
    for (std::size_t s0 : detect.position_samples) {
      double smallest = kNaN;
      bool below = false;
      double previous_z = 0.0, previous_value = 0.0;
      for (std::size_t step = 0; step < axis.size(); ++step) {
        const std::size_t along = detect.small_first ? step : axis.size() - 1 - step;
        const std::size_t s = detect.small_first ? s0 + step * size_stride : s0 - step * size_stride;
        const double z = c.samples[s].z, value = axis[along];
        if (z >= kDetect) {
          if (step == 0) {
            smallest = value;
            below = true;
          } else {
            smallest = previous_value + (kDetect - previous_z) / (z - previous_z) * (value - previous_value);
          }
          break;
        }
        previous_z = z;
        previous_value = value;
      }
      c.smallest_crack.push_back(smallest);
      detect.at_or_below[ci].push_back(below);
    }
  }
  return detect;
}

std::vector<std::size_t> ranking(const std::vector<Candidate>& candidates, std::size_t n_samples) {
  std::vector<std::size_t> order(candidates.size());
  for (std::size_t i = 0; i < order.size(); ++i) order[i] = i;
  const auto all = static_cast<int>(n_samples);
  std::stable_sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) {
    const Candidate &x = candidates[a], &y = candidates[b];
    if ((x.responding == all) != (y.responding == all)) return x.responding == all;
    if (x.responding != y.responding) return x.responding > y.responding;
    return x.mean_log_det > y.mean_log_det;
  });
  return order;
}

}  // namespace crackle::planning::detail
