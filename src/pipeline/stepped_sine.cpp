/// \file The stepped sine: the reduced transient run to steady state at each frequency, up then down,
/// as a lab does (sweep.hpp).
#include <algorithm>
#include <cmath>
#include <limits>
#include <string>
#include <vector>

#include "core/errors.hpp"
#include "core/interrupt.hpp"
#include "core/resources.hpp"
#include "linalg/threads.hpp"
#include "pipeline/sweep.hpp"
#include "reduced/integrator.hpp"
#include "spectral/harmonics.hpp"

namespace crackle::pipeline {
namespace {

/// One stepped-sine frequency: from the state (q, v), periods of the base period until the table
/// settles; leaves the final state in (q, v).
SweepPoint stepped_sine_point(const reduced::ReducedSystem& system, const SweepSettings& settings, double frequency_hz,
                              VectorX& q, VectorX& v) {
  const scene::SweepSection& section = settings.section;
  const int nu = section.subharmonic;
  const double omega = kTwoPi * frequency_hz, base_period = nu / frequency_hz;
  // Four times the default resolution: near a resonance the scheme's frequency error, (omega h)^2 / 12,
  // is amplified by 1 / (2 zeta) in the amplitude.
  const double recommended =
      reduced::reduced_time_step(system, section.harmonics * frequency_hz / nu, 4 * reduced::kDefaultStepsPerPeriod);
  const Index n = std::max<Index>(4 * section.harmonics + 4, Index(std::ceil(base_period / recommended)));
  reduced::ReducedIntegrator integrator(system, base_period / double(n), [omega](double t) { return std::cos(omega * t); });
  integrator.set_initial_state(q, v, 0.0);
  SweepPoint point;
  point.solution.omega = omega;
  point.solution.subharmonic = nu;
  point.solution.residual = std::numeric_limits<double>::infinity();
  MatrixX samples(system.n_outputs(), n);
  std::vector<Index> probe_rows;
  for (const SweepProbe& probe : settings.probes) probe_rows.push_back(probe.row);
  sweep::ComplexMatrixX before;
  for (point.periods = 1; point.periods <= section.max_periods; ++point.periods) {
    poll_interrupt();
    for (Index j = 0; j < n; ++j) {
      samples.col(j) = integrator.outputs();
      integrator.step();
    }
    // The table of one base period (its harmonic k is order k / nu of the drive), and the probes'
    // change from the period before (spectral's steady-state measure).
    sweep::ComplexMatrixX table = spectral::period_harmonics(samples, section.harmonics);
    if (point.periods > 1) point.solution.residual = spectral::period_table_change(table, before, probe_rows, nu);
    before = std::move(table);
    if (point.solution.residual <= section.tolerance) break;
  }
  point.periods = std::min(point.periods, section.max_periods);
  point.solution.outputs = before;
  point.solution.converged = point.solution.residual <= section.tolerance;
  q = integrator.modal_displacement();
  v = integrator.modal_velocity();
  return point;
}

}  // namespace

SweepResult stepped_sine_sweep(const reduced::ReducedSystem& system, const SweepSettings& settings,
                               const SweepProgress& progress) {
  const linalg::SingleThreadedEigen one_thread;
  Stopwatch clock;
  const int count = settings.section.points;
  VectorX q = VectorX::Zero(system.n_modes()), v = VectorX::Zero(system.n_modes());
  SweepResult result;
  std::vector<double> unsettled;
  for (int step = 0; step < 2 * count; ++step) {
    const int i = step < count ? step : 2 * count - 1 - step;
    const double f = settings.from_hz + (settings.to_hz - settings.from_hz) * i / double(count - 1);
    SweepPoint point = stepped_sine_point(system, settings, f, q, v);
    point.direction = step < count ? 1 : -1;
    if (!point.solution.converged) unsettled.push_back(f);
    result.points.push_back(std::move(point));
    if (progress) progress(result, (step + 1.0) / (2.0 * count));
  }
  if (!unsettled.empty()) {
    result.warnings.push_back(std::to_string(unsettled.size()) + " of " + std::to_string(2 * count) +
                              " frequencies did not settle to sweep.tolerance within sweep.max_periods = " +
                              std::to_string(settings.section.max_periods) + " periods, first at " +
                              format_number(unsettled.front()) + " Hz");
  }
  result.solve_s = clock.seconds();
  return result;
}

}  // namespace crackle::pipeline
