/// \file Stage 2 of `crackle run` with transient.model: reduced (run_stages.hpp): the reduced
/// model's time loop and its records in the full transient's files.
#include <cmath>
#include <iomanip>
#include <iostream>

#include "core/errors.hpp"
#include "core/interrupt.hpp"
#include "core/resources.hpp"
#include "io/files.hpp"
#include "linalg/threads.hpp"
#include "pipeline/limits.hpp"
#include "pipeline/reduced_model.hpp"
#include "pipeline/run_stages.hpp"
#include "reduced/integrator.hpp"
#include "output/energy_csv.hpp"
#include "output/probes_csv.hpp"
#include "output/transient_json.hpp"

namespace crackle::pipeline {
namespace {

/// Probe and energy records of the reduced transient, in the full transient's CSV layout.
struct ReducedRecords {
  transient::ProbeHistory probes;
  transient::EnergyHistory energy;
  std::vector<double> sample;   ///< 9 per probe: u, v, a (x, y, z each)
  VectorX previous_residual;    ///< residual (massless) part of the outputs at the previous sample
  VectorX previous_residual_rate;
  Index probe_interval = 1;     ///< samples between probes.csv rows (transient.history.samples_per_period)
  Index samples = 0;            ///< samples taken so far
};

/// The probe sample of the integrator's state: the modal part of v and a exactly, the massless
/// residual part (C G_res (B^T p + f a)) by differences of successive samples; an opening probe's
/// gap gets g0 and its pair's contact state.
void reduced_sample(const reduced::ReducedIntegrator& integrator, const ReducedModel& reduced, double h,
                    ReducedRecords& records) {
  const reduced::ReducedSystem& system = reduced.system;
  const VectorX outputs = integrator.outputs() + reduced.output_offsets;
  const VectorX modal = system.output_modes * integrator.modal_displacement();
  const VectorX residual = outputs - modal;
  const bool first = records.previous_residual.size() == 0;
  const VectorX rate = first ? VectorX::Zero(residual.size()).eval() : ((residual - records.previous_residual) / h).eval();
  const VectorX rate_change = first ? VectorX::Zero(residual.size()).eval()
                                    : ((rate - records.previous_residual_rate) / h).eval();
  const VectorX velocity = system.output_modes * integrator.modal_velocity() + rate;
  const VectorX acceleration = system.output_modes * integrator.modal_acceleration() + rate_change;
  records.sample.assign(3 * static_cast<std::size_t>(outputs.size()), 0.0);
  for (Index row = 0; row < outputs.size(); ++row) {
    const Index probe = row / 3, c = row % 3;
    records.sample[9 * probe + c] = outputs[row];
    records.sample[9 * probe + 3 + c] = velocity[row];
    records.sample[9 * probe + 6 + c] = acceleration[row];
  }
  records.previous_residual = residual;
  records.previous_residual_rate = rate;
  if (records.samples++ % records.probe_interval != 0) return;
  records.probes.time.push_back(integrator.time());
  for (std::size_t k = 0; k < records.sample.size(); ++k) records.probes.values[k].push_back(records.sample[k]);
  for (std::size_t p = 0; p < records.probes.names.size(); ++p) {
    if (!records.probes.opening[p]) continue;
    const Index pair = reduced.probe_pairs[p];
    const double gap = records.sample[9 * p];
    records.probes.states[p].push_back(pair >= 0 ? integrator.pair_state(pair) : gap < 0.0 ? 2 : 0);
  }
}

void reduced_energy_row(const reduced::ReducedIntegrator& integrator, double initial_total, ReducedRecords& records) {
  const reduced::ReducedEnergy& e = integrator.energy();
  transient::EnergyHistory& history = records.energy;
  history.time.push_back(integrator.time());
  history.kinetic.push_back(e.kinetic);
  history.strain.push_back(e.modal_strain + e.residual_strain);
  history.contact.push_back(e.penalty);
  history.external_work.push_back(e.external_work);
  history.damping.push_back(e.damping_dissipation);
  history.friction.push_back(e.friction_dissipation);
  history.balance.push_back(e.total() - initial_total);
  history.relative_error.push_back(integrator.energy_error());
}

/// transient.json of the reduced model: the full model's common fields and the reduction's.
nlohmann::json reduced_transient_json(const ReducedModel& reduced, const reduced::ReducedIntegrator& integrator,
                                      int steps_per_period, const transient::TransientSummary& summary) {
  nlohmann::json json = output::transient_json(summary);
  json["model"] = "reduced";
  json["modes"] = reduced.modes;
  json["pairs"] = reduced.pairs;
  json["rows"] = reduced.system.n_rows();
  json["max_frequency_hz"] = reduced.max_frequency_hz;
  json["highest_mode_hz"] = reduced.system.n_modes() > 0 ? reduced.system.omega.maxCoeff() / (2.0 * M_PI) : 0.0;
  json["steps_per_period"] = steps_per_period;
  json["reduction_cached"] = reduced.from_cache;
  json["reduction"] = {{"modes_s", reduced.modes_s}, {"flexibility_s", reduced.flexibility_s},
                       {"computed_modes", reduced.computed_modes}};
  json["penalty"] = {{"normal", reduced.system.normal_penalty}, {"tangential", reduced.system.tangential_penalty},
                     {"friction", reduced.system.friction_coefficient}};
  json["contact_iterations"] = integrator.total_iterations();
  json["contact_factorizations"] = integrator.total_factorizations();
  json["switching"] = {{"steps", integrator.switching_steps()},
                       {"end_of_step_force_steps", integrator.implicit_switching_steps()},
                       {"unconserved_steps", integrator.unconserved_switching_steps()},
                       {"corrected_energy_j", integrator.switching_correction()}};
  return json;
}

transient::TransientSummary reduced_summary(const ReducedModel& reduced, const TransientSetup& setup, double dt,
                                            double setup_s) {
  transient::TransientSummary summary;
  summary.status = "completed";
  summary.dt = dt;
  summary.damping = setup.settings.damping;
  summary.setup_s = setup_s;
  summary.n_dofs = reduced.system.n_modes();
  summary.kernel = "reduced";
  return summary;
}

/// The time loop: sample (time t_i), feed the spectrum, step, then a snapshot when one is due (the
/// displacement field recovered only then, at t_(i+1)); energy rows every 10 steps.
void march_reduced(reduced::ReducedIntegrator& integrator, ReducedModel& reduced, Index n_steps, double dt,
                   const reduced::ReducedIntegrator::LoadFunction& load, SnapshotWriter& snapshots,
                   std::optional<SpectrumMonitor>& spectrum, ReducedRecords& records,
                   transient::TransientSummary& summary) {
  constexpr Index kEnergyInterval = 10;
  const double initial_total = integrator.energy().total();
  const VectorX empty;
  double closed = 0.0;
  for (Index i = 0; i < n_steps; ++i) {
    if ((i & 63) == 63) poll_interrupt();
    reduced_sample(integrator, reduced, dt, records);
    if (i % kEnergyInterval == 0) reduced_energy_row(integrator, initial_total, records);
    const double time = integrator.time();
    const transient::StepView view{i, time, dt, records.sample, empty, empty};
    if (spectrum && spectrum->add(view)) {
      summary.status = "stopped";
      summary.message = "steady state reached";
      break;
    }
    integrator.step();
    closed += integrator.closed_fraction();
    if (reduced.fields && snapshots.due(i)) {
      const VectorX field = reduced.fields->displacement(integrator.modal_displacement(),
                                                         reduced.system.n_rows() > 0 ? integrator.pair_forces() : empty,
                                                         load(integrator.time()));
      snapshots.on_step(transient::StepView{i, time, dt, records.sample, field, empty});
    }
  }
  summary.contact_fraction = integrator.n_steps_taken() > 0 ? closed / integrator.n_steps_taken() : 0.0;
}

/// The reduced model's time step: steps_per_period over the highest retained mode or max_frequency,
/// lowered to divide the excitation period into whole steps (exact DFT bins).
double reduced_step(const ReducedModel& reduced, int steps_per_period, double frequency) {
  double dt = reduced::reduced_time_step(reduced.system, reduced.max_frequency_hz, steps_per_period);
  if (frequency > 0.0) dt = 1.0 / frequency / std::ceil(1.0 / frequency / dt - 1e-9);
  return dt;
}

}  // namespace

/// Stage 2 with transient.model: reduced: the same callbacks and files as the full transient (probes.csv,
/// energy.csv of the reduced model's energy balance, transient.json with the reduction's fields).
transient::ProbeHistory run_reduced_stage(const scene::Scene& scene, const Model& model, TransientSetup& setup,
                                          const RunCommandOptions& options, std::optional<SpectrumMonitor>& spectrum,
                                          double& dt, RunOutcome& outcome, std::ostream& out) {
  const scene::TransientSection& section = *scene.transient;
  Stopwatch clock;
  const transient::InitialConditions& initial = setup.problem.initial;
  const bool has_initial = initial.displacement.size() > 0 || initial.velocity.size() > 0;
  ReducedModel reduced = build_reduced_model(scene, model, setup.frequency, options.modal_cache,
                                             has_initial ? &initial : nullptr, &setup.problem.probes);
  reduced.system.rayleigh_alpha = setup.settings.damping.alpha;
  reduced.system.rayleigh_beta = setup.settings.damping.beta;
  const int steps_per_period = section.reduced.steps_per_period;
  dt = reduced_step(reduced, steps_per_period, setup.frequency);
  outcome.normal_penalty = reduced.system.normal_penalty;
  outcome.max_frequency_hz = reduced.max_frequency_hz;
  outcome.modes = reduced.modes;
  outcome.pairs = static_cast<int>(reduced.pairs);
  if (reduced.system.n_modes() > 0) outcome.slowest_decay_per_s = reduced.system.slowest_decay_rate();
  const transient::Signal signal = setup.problem.loads.empty() ? transient::Signal{} : setup.problem.loads[0].signal;
  const bool loaded = !setup.problem.loads.empty();
  const reduced::ReducedIntegrator::LoadFunction load = [signal, loaded](double t) {
    return loaded ? signal.value(t) : 0.0;
  };
  reduced::ReducedIntegrator integrator(reduced.system, dt, load);
  integrator.set_initial_state(reduced.initial_displacement, reduced.initial_velocity);
  const double setup_s = clock.seconds();
  if (scene.spectrum && setup.frequency > 0.0) spectrum.emplace(scene, setup.frequency, dt);
  transient::TransientSummary summary = reduced_summary(reduced, setup, dt, setup_s);
  ReducedRecords records;
  for (const transient::Probe& probe : setup.problem.probes) {
    records.probes.names.push_back(probe.name);
    records.probes.opening.push_back(probe.opening() ? 1 : 0);
  }
  records.probes.values.assign(9 * section.probes.size(), {});
  records.probes.states.assign(section.probes.size(), {});
  const Index n_steps = static_cast<Index>(std::ceil(setup.settings.end_time / dt - 1e-9));
  records.probe_interval = probe_interval(scene, setup.frequency, dt);
  check_run_outputs(scene, estimate_mesh(scene), static_cast<double>(n_steps),
                    std::ceil(static_cast<double>(n_steps) / records.probe_interval), options.output_directory);
  SnapshotWriter snapshots(options.output_directory, model.mesh, model.system(setup.variant)->dofs(),
                           section.snapshots, n_steps);
  for (const std::string& warning : setup.warnings) std::cerr << "crackle: warning: " << warning << "\n";
  Stopwatch run_clock;
  {
    // The per-step products are small: Eigen's OpenMP threads would only spin between them (restored
    // also when an interruption leaves the loop).
    const linalg::SingleThreadedEigen one_thread;
    try {
      march_reduced(integrator, reduced, n_steps, dt, load, snapshots, spectrum, records, summary);
    } catch (const SolverError& error) {
      summary.status = "unstable";
      summary.message = error.what();
    }
  }
  summary.wall_s = run_clock.seconds();
  summary.time = integrator.time();
  summary.steps = integrator.n_steps_taken();
  summary.energy_error = integrator.energy_error();
  const std::filesystem::path& directory = options.output_directory;
  output::write_probe_csv(directory / "probes.csv", records.probes);
  output::write_energy_csv(directory / "energy.csv", records.energy);
  nlohmann::json json = reduced_transient_json(reduced, integrator, steps_per_period, summary);
  json["probes"] = setup.probes_json;
  json["probe_interval"] = records.probe_interval;
  json["warnings"] = setup.warnings;
  if (reduced.fields) json["snapshots"] = {{"count", section.snapshots}, {"static_factor", reduced.fields->factored()}};
  if (has_initial) {
    json["initial_state"] = {{"displacement_lost", reduced.initial_displacement_lost},
                             {"velocity_lost", reduced.initial_velocity_lost}};
    out << "reduced initial state: mass-norm share outside the " << reduced.modes << " modes: displacement "
        << reduced.initial_displacement_lost << ", velocity " << reduced.initial_velocity_lost << "\n";
  }
  io::write_json(directory / "transient.json", json);
  out << "reduced model: " << reduced.modes << " modes (to " << reduced.max_frequency_hz << " Hz), " << reduced.pairs
      << " pairs, " << steps_per_period << " steps per period, setup " << reduced.setup_s << " s"
      << (reduced.from_cache ? " (reduction from the cache)" : "") << "\n";
  out << "transient: " << summary.steps << " steps of " << dt << " s (reduced), " << summary.status
      << ", energy error " << summary.energy_error << ", " << std::setprecision(3) << summary.wall_s << " s\n";
  if (summary.status == "unstable") throw SolverError(scene.file + ": transient (reduced): " + summary.message);
  return std::move(records.probes);
}

}  // namespace crackle::pipeline
