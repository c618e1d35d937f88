/// \file `crackle run`: the whole pipeline of a scene, each stage only if the scene needs it:
/// modal (only when something refers to a mode or the scene asks for modal output) -> transient
/// (with contact only when there is a crack) -> spectrum (harmonics, damage indices, plots).
#include <Eigen/Geometry>
#include <cmath>
#include <iomanip>
#include <iostream>
#include <limits>
#include <set>

#include "pipeline/commands.hpp"
#include "pipeline/distributed_run.hpp"
#include "core/errors.hpp"
#include "core/interrupt.hpp"
#include "core/resources.hpp"
#include "io/csv.hpp"
#include "io/files.hpp"
#include "io/vtu.hpp"
#include "pipeline/limits.hpp"
#include "pipeline/model.hpp"
#include "pipeline/release.hpp"
#include "pipeline/reduced_model.hpp"
#include "pipeline/stages.hpp"
#include "reduced/integrator.hpp"
#include "pipeline/output_folder.hpp"
#include "pipeline/placement.hpp"
#include "pipeline/accuracy.hpp"
#include "pipeline/route.hpp"
#include "pipeline/run_scene.hpp"
#include "modal/modal.hpp"
#include "spectral/harmonics.hpp"
#include "spectral/steady_monitor.hpp"
#include "spectral/plot.hpp"
#include "spectral/ringdown.hpp"
#include "spectral/signature.hpp"
#include "spectral/spectrum.hpp"
#include "transient/damping.hpp"
#include "transient/excitation.hpp"
#include "transient/solver.hpp"
#include "contact/contact_force.hpp"

namespace crackle::pipeline {
namespace {

namespace fs = std::filesystem;

/// The modal variants the scene needs (empty: no modal stage).
std::vector<mesh::Variant> needed_variants(const scene::Scene& scene, std::string& reason) {
  std::set<mesh::Variant> variants;
  const scene::TransientSection& transient = *scene.transient;
  if (transient.excitation && transient.excitation->mode > 0) {
    const std::string& of = transient.excitation->of;
    if (of != "open") variants.insert(mesh::Variant::uncracked);
    if (of != "uncracked") variants.insert(mesh::Variant::open);
    reason = "transient.excitation.frequency refers to mode " + std::to_string(transient.excitation->mode);
  }
  if (transient.release && transient.release->kind == "mode") {
    variants.insert(transient.release->variant == "open" ? mesh::Variant::open : mesh::Variant::uncracked);
    if (reason.empty()) reason = "transient.release.mode refers to mode " + std::to_string(transient.release->mode);
  }
  if (transient.damping.at_mode > 0) {
    variants.insert(mesh::Variant::uncracked);
    if (reason.empty()) reason = "transient.damping.at refers to mode " + std::to_string(transient.damping.at_mode);
  }
  if (scene.sweep) {
    for (const scene::SweepFrequencySection* end : {&scene.sweep->from, &scene.sweep->to}) {
      if (end->mode == 0) continue;
      if (end->of != "open") variants.insert(mesh::Variant::uncracked);
      if (end->of != "uncracked") variants.insert(mesh::Variant::open);
      if (reason.empty()) reason = "sweep.frequency refers to mode " + std::to_string(end->mode);
    }
  }
  if (scene.has_modal_section) {
    for (const std::string& name : scene.modal.variants) {
      variants.insert(name == "open" ? mesh::Variant::open : mesh::Variant::uncracked);
    }
    if (reason.empty()) reason = "the scene has a modal: section";
  }
  // Keep the uncracked limit first, as the modal module lists it.
  std::vector<mesh::Variant> ordered;
  for (mesh::Variant variant : {mesh::Variant::uncracked, mesh::Variant::open}) {
    if (variants.count(variant)) ordered.push_back(variant);
  }
  return ordered;
}

std::vector<Index> nodes_in_range(const mesh::Mesh& mesh, const scene::InitialSection& initial) {
  std::vector<Index> nodes;
  for (Index node = 0; node < mesh.n_nodes(); ++node) {
    bool inside = true;
    for (int axis = 0; axis < 3; ++axis) {
      if (!initial.range[axis]) continue;
      const double x = mesh.nodes[node][axis];
      inside = inside && x >= (*initial.range[axis])[0] && x <= (*initial.range[axis])[1];
    }
    if (inside) nodes.push_back(node);
  }
  return nodes;
}

/// Per probe: the analysed component's accumulator, and that component at every step (probes.csv
/// holds decimated rows; the amplitude spectra and the history plots take every step).
struct ProbeSpectrum {
  std::string name;
  std::string quantity;  ///< "u_x" ... or "gap" (an opening probe), for messages and plot titles
  std::string label;     ///< spectrum.json's "component": the axis, or "gap"
  int component = 2;
};

/// The probe column the spectrum analyses: the normal gap (column 0) of an opening probe, else the
/// probe's component or the default one.
int analysed_component(const scene::ProbeSection& probe, int default_component) {
  return probe.crack_opening ? 0 : probe.component >= 0 ? probe.component : default_component;
}

/// The analysed quantity's name in spectrum.json ("component": the axis, or "gap") and in messages
/// ("u_x", or "gap").
std::string analysed_label(const scene::ProbeSection& probe, int component) {
  return probe.crack_opening ? "gap" : axis_name(component);
}
std::string analysed_quantity(const scene::ProbeSection& probe, int component) {
  return probe.crack_opening ? "gap" : std::string("u_") + axis_name(component);
}


/// The transient stage's inputs, from the scene and the modes.
struct TransientSetup {
  transient::TransientProblem problem;
  transient::TransientOptions settings;
  mesh::Variant variant = mesh::Variant::open;
  double frequency = 0.0;  ///< excitation frequency [Hz], 0 without a harmonic excitation
  std::shared_ptr<contact::ContactForce> contact;  ///< null without contact
  std::optional<ReleaseReport> release;            ///< how U(0) was made from transient.release
  nlohmann::json probes_json = nlohmann::json::array();  ///< per probe: name, node, snapping distance
  std::vector<std::string> warnings;  ///< found while setting up (for transient.json and stderr)
  /// Under mpirun -np N > 1: this rank's share of the full transient (the problem above is the
  /// whole body's, from which it is made).
  std::unique_ptr<DistributedTransient> distributed;
};

/// The excitation as a load, and its frequency (0 for a pulse).
transient::ExternalLoad excitation_load(const scene::Scene& scene, const Model& model,
                                        const std::optional<modal::ModalResult>& modes, double& frequency) {
  const scene::ExcitationSection& excitation = *scene.transient->excitation;
  transient::ExternalLoad load;
  load.name = "transient.excitation";
  if (!excitation.face.empty()) load.faces = model.mesh.face_sets.at(excitation.face);
  if (!excitation.group.empty()) load.nodes = model.mesh.node_sets.at(excitation.group);  // checked by build_model
  if (excitation.point) {
    load.nodes = {PointPlacer(scene, model.mesh).place(*excitation.point, "transient.excitation.point").node};
  }
  load.direction = Vec3::Unit(excitation.direction);
  load.amplitude = excitation.amplitude;
  if (excitation.kind == "harmonic") {
    frequency = excitation.frequency_hz ? *excitation.frequency_hz
                                        : excitation.ratio * mode_frequency(*modes, excitation.mode, excitation.of,
                                                                            scene.file + ": transient.excitation.frequency.mode");
    load.signal.kind = transient::SignalKind::harmonic;
    load.signal.frequency = frequency;
    load.signal.ramp_periods = excitation.ramp_periods;
  } else {
    load.signal.kind = transient::SignalKind::pulse;
    load.signal.duration = excitation.duration;
  }
  return load;
}

}  // namespace

/// Rayleigh damping from a ratio at a frequency (or a mode), or from alpha and beta.
transient::RayleighDamping scene_damping(const scene::Scene& scene, const std::optional<modal::ModalResult>& modes) {
  const scene::DampingSection& damping = scene.transient->damping;
  const double at_hz = !damping.ratio ? 0.0
                       : damping.at_hz ? *damping.at_hz
                                       : mode_frequency(*modes, damping.at_mode, "uncracked",
                                                        scene.file + ": transient.damping.at.mode");
  return transient::stated_damping(damping.ratio, damping.type == "stiffness", at_hz, damping.alpha, damping.beta);
}

namespace {

/// Initial fields (uniform per coordinate box) over the run's DOFs.
void add_initial_fields(const scene::TransientSection& section, const Model& model, const mesh::DofMap& dofs,
                        transient::InitialConditions& initial) {
  for (const scene::InitialSection& box : section.initial) {
    const std::vector<Index> nodes = nodes_in_range(model.mesh, box);
    if (initial.velocity.size() == 0) initial.velocity = VectorX::Zero(dofs.n_dofs());
    if (initial.displacement.size() == 0) initial.displacement = VectorX::Zero(dofs.n_dofs());
    initial.velocity += transient::uniform_on_nodes(dofs, nodes, box.velocity);
    initial.displacement += transient::uniform_on_nodes(dofs, nodes, box.displacement);
  }
}

TransientSetup transient_setup(const scene::Scene& scene, const Model& model,
                               const std::optional<modal::ModalResult>& modes, const RunCommandOptions& options) {
  const scene::TransientSection& section = *scene.transient;
  TransientSetup setup;
  if (section.excitation) setup.problem.loads.push_back(excitation_load(scene, model, modes, setup.frequency));
  transient::TransientOptions& settings = setup.settings;
  settings.damping = scene_damping(scene, modes);
  setup.variant = section.variant == "open" ? mesh::Variant::open : mesh::Variant::uncracked;
  settings.variant = setup.variant;
  const fem::System& system = *model.system(setup.variant);
  const bool with_contact =
      setup.variant == mesh::Variant::open && model.mesh.has_crack() && scene.contact.model != "none";
  const contact::ContactOptions contact_options = scene_contact_options(scene);
  if (with_contact) {
    setup.contact = std::make_shared<contact::ContactForce>(model.mesh, system.dofs(), model.materials, contact_options);
    setup.problem.terms.push_back(setup.contact);
  }
  if (section.release) {
    ReleaseReport report;
    setup.problem.initial =
        release_state(*section.release, model, setup.variant, with_contact ? &contact_options : nullptr,
                      modes ? &*modes : nullptr, scene.file, &report);
    setup.release = report;
  }
  add_initial_fields(section, model, system.dofs(), setup.problem.initial);
  const PointPlacer placer(scene, model.mesh);
  for (std::size_t p = 0; p < section.probes.size(); ++p) {
    const scene::ProbeSection& probe = section.probes[p];
    const transient::Probe placed = place_probe(scene, model, system.dofs(), placer, p, setup.contact.get());
    setup.problem.probes.push_back(placed);
    const Vec3& x = model.mesh.nodes[placed.node];
    setup.probes_json.push_back({{"name", probe.name},
                                 {"point", {probe.point[0], probe.point[1], probe.point[2]}},
                                 {"node", placed.node},
                                 {"node_point", {x[0], x[1], x[2]}},
                                 {"distance_m", (x - probe.point).norm()}});
    if (placed.opening()) {
      setup.probes_json.back()["kind"] = "crack_opening";
      setup.probes_json.back()["minus_node"] = placed.minus_node;
      setup.probes_json.back()["normal"] = {placed.frame(0, 0), placed.frame(0, 1), placed.frame(0, 2)};
      continue;
    }
    if (!probe.side.empty()) setup.probes_json.back()["side"] = probe.side;
    // A probe whose analysed component is held (a clamped face) has A1 = 0: its ratios are NaN.
    const int component = probe.component >= 0 ? probe.component
                          : section.excitation  ? section.excitation->direction
                                                : -1;
    const fem::Constraints& constraints = system.constraints();
    for (int c = 0; c < 3; ++c) {
      if (c != component || !constraints.fixed[system.dofs().dof(placed.node, c)]) continue;
      setup.warnings.push_back("probe '" + probe.name + "' (node " + std::to_string(placed.node) + ") has its u_" +
                               axis_name(c) + " held by a boundary condition: its response is the prescribed value" +
                               (scene.spectrum ? ", so A1 = 0 and its damage indices are undefined (NaN)" : ""));
    }
  }
  // A hair beyond the last period, so that rounding in n dt cannot leave it one step short.
  settings.end_time = section.periods ? *section.periods / setup.frequency * (1.0 + 1e-9) : *section.duration;
  settings.run_length_key = scene.where(section.periods ? "transient.periods" : "transient.duration");
  settings.time_step_key = scene.where("transient.time_step");
  settings.time_step = section.time_step.value_or(0.0);
  settings.time_step_options.safety_factor = section.safety_factor;
  settings.force_time_step = section.force_time_step;
  if (setup.frequency > 0.0) settings.whole_steps_per_period = 1.0 / setup.frequency;
  settings.progress = section.progress && options.progress;
  return setup;
}

/// Steps between probes.csv rows: transient.history.samples_per_period rows per excitation period
/// (per pulse duration), every step when it is `all` or without an excitation.
Index probe_interval(const scene::Scene& scene, double frequency, double dt) {
  const scene::TransientSection& section = *scene.transient;
  if (section.history_samples_per_period <= 0) return 1;
  double period = 0.0;
  if (frequency > 0.0) period = 1.0 / frequency;
  if (section.excitation && section.excitation->kind == "pulse") period = section.excitation->duration;
  if (!(period > 0.0)) return 1;
  const double steps = std::floor(period / dt / section.history_samples_per_period);
  return static_cast<Index>(std::clamp(steps, 1.0, 1e9));
}

/// The probes' spectra of a run: spectral::SteadyStateMonitor over the analysed component of each
/// probe (fed every step), and the spectrum stage's files.
class SpectrumMonitor {
 public:
  SpectrumMonitor(const scene::Scene& scene, double frequency, double dt)
      : spectrum_(*scene.spectrum), options_(harmonic_options(scene, frequency, dt)),
        monitor_(options_, dt, scene.transient->probes.size(), spectrum_.window_periods, spectrum_.tolerance,
                 spectrum_.min_periods) {
    const scene::TransientSection& section = *scene.transient;
    for (const scene::ProbeSection& probe : section.probes) {
      ProbeSpectrum entry;
      entry.name = probe.name;
      entry.component = analysed_component(probe, section.excitation->direction);
      entry.label = analysed_label(probe, entry.component);
      entry.quantity = analysed_quantity(probe, entry.component);
      probes_.push_back(std::move(entry));
    }
  }

  std::string progress_note(double elapsed) const { return monitor_.progress_note(elapsed); }

  /// Feeds one step; true when every probe's table has settled (the run may stop).
  bool add(const transient::StepView& view) {
    return monitor_.add(view.time, [&](std::size_t p) { return view.probe_sample[9 * p + probes_[p].component]; });
  }

  /// Stage 3: closes the records, writes the spectra and the plots; returns spectrum.json's content
  /// (written by the command once the accuracy is known) and the probes' signatures.
  nlohmann::json write(const scene::Scene& scene, const std::filesystem::path& directory, double dt,
                       std::vector<ProbeSignature>& signatures, std::ostream& out);

 private:
  /// The accumulators' options, once the highest harmonic is known to lie below the Nyquist
  /// frequency of the time step (else an error that names the keys, before the accumulators' own).
  static spectral::HarmonicOptions harmonic_options(const scene::Scene& scene, double frequency, double dt) {
    const scene::SpectrumSection& spectrum = *scene.spectrum;
    if (!(2.0 * spectrum.harmonics * frequency * dt < 1.0)) {
      throw InputError(scene.where("transient.excitation.frequency") +
                       ": expected a frequency whose harmonic " + std::to_string(spectrum.harmonics) +
                       " (spectrum.harmonics) lies below the Nyquist frequency " + format_number(0.5 / dt) +
                       " Hz of the time step " + format_number(dt) + " s, got " + format_number(frequency) +
                       " Hz; lower the frequency or spectrum.harmonics, or set a smaller transient.time_step");
    }
    spectral::HarmonicOptions options;
    options.excitation_frequency_hz = frequency;
    options.max_order = spectrum.harmonics;
    options.subharmonics = spectrum.subharmonics;
    return options;
  }

  const scene::SpectrumSection& spectrum_;
  spectral::HarmonicOptions options_;
  spectral::SteadyStateMonitor monitor_;
  std::vector<ProbeSpectrum> probes_;
};

/// A1 and the ratios of a table, in ProbeSignature's order.
std::array<double, 4> signature_values(const spectral::HarmonicTable& table) {
  const spectral::DamageIndices indices = spectral::damage_indices(table);
  return {table.amplitude(1), indices.a2_over_a1, indices.a3_over_a1, indices.a_half_over_a1};
}

nlohmann::json SpectrumMonitor::write(const scene::Scene& scene, const std::filesystem::path& directory, double dt,
                                      std::vector<ProbeSignature>& signatures, std::ostream& out) {
  const double frequency = options_.excitation_frequency_hz;
  nlohmann::json spectrum_json = {{"excitation_hz", frequency}, {"amplitude_convention",
                                  "peak amplitude A_k of x(t) = A_0 + sum A_k cos(2 pi k f t + phi_k), t from the start of the run"}};
  // Close the record: grid points of the last period still waiting for stencil samples.
  for (std::size_t p = 0; p < probes_.size(); ++p) monitor_.accumulator(p).finish();
  const int periods = monitor_.accumulator(0).n_periods();
  const int used = std::min(monitor_.window_periods(), periods - (options_.subharmonics ? periods % 2 : 0));
  if (used < 1) {
    throw SolverError(scene.file + ": spectrum: the run completed " + std::to_string(periods) +
                      " excitation periods, too few for a harmonic table (raise transient.periods)");
  }
  spectral::SteadyState state = monitor_.verdict().value_or(spectral::SteadyState{});
  state.periods_used = periods;
  state.limit_reached = !state.settled;
  nlohmann::json probes_json = nlohmann::json::object();
  const spectral::Sampling sampling{dt, 0.0};  // every step, from t = 0
  spectral::SpectrumAnalyzer analyzer;
  spectral::PlotOptions plot;
  for (std::size_t p = 0; p < probes_.size(); ++p) {
    const ProbeSpectrum& probe = probes_[p];
    const spectral::HarmonicAccumulator& accumulator = monitor_.accumulator(p);
    const spectral::HarmonicTable table = accumulator.last_table(used);
    probes_json[probe.name] = spectral::probe_json(probe.label, table);
    ProbeSignature signature;
    signature.name = probe.name;
    signature.value = signature_values(table);
    signature.previous_window.fill(std::numeric_limits<double>::quiet_NaN());
    signature.window_before.fill(std::numeric_limits<double>::quiet_NaN());
    if (periods >= 2 * used) {
      signature.previous_window = signature_values(accumulator.table(periods - 2 * used, used));
    }
    if (periods >= 3 * used) {
      signature.window_before = signature_values(accumulator.table(periods - 3 * used, used));
    }
    signatures.push_back(signature);
    const std::vector<double>& values = monitor_.values(p);
    spectral::SpectrumOptions spectrum_options;
    spectrum_options.excitation_frequency_hz = frequency;
    spectrum_options.periods = used;
    spectrum_options.subharmonics = options_.subharmonics;
    const spectral::AmplitudeSpectrum amplitude = analyzer.amplitude_spectrum(values, sampling, spectrum_options);
    io::write_file_atomic(directory / ("spectrum_" + probe.name + ".csv"), spectral::spectrum_csv(amplitude, "m"));
    if (spectrum_.plots) {
      plot.title = probe.name + " " + probe.quantity;
      const auto history_plot = spectral::plot_time_history(directory / ("history_" + probe.name + ".png"), values, sampling, plot);
      spectral::plot_spectrum(directory / ("spectrum_" + probe.name + ".png"), amplitude, frequency,
                              spectral::harmonic_orders(options_), plot);
      if (!history_plot.written) out << "note: no plots (" << history_plot.note << ")\n";
    }
    const spectral::DamageIndices indices = spectral::damage_indices(table);
    out << "spectrum " << probe.name << " (" << probe.quantity << "): A1 = " << table.amplitude(1) << " m, A2/A1 = "
        << indices.a2_over_a1 << ", A3/A1 = " << indices.a3_over_a1;
    if (options_.subharmonics) out << ", A1/2/A1 = " << indices.a_half_over_a1;
    out << "\n";
  }
  spectrum_json["probes"] = probes_json;
  spectrum_json["steady_state"] = spectral::steady_state_json(state);
  spectrum_json["steady_state"]["window_periods"] = used;
  return spectrum_json;
}

/// The modal frequency a ring-down is compared with: bilinear for a breathing crack (the open body
/// with contact), else the run variant's own; the mode nearest the measured frequency.
nlohmann::json modal_comparison(const modal::ModalResult& modes, const TransientSetup& setup, double frequency_hz) {
  nlohmann::json comparison;
  const bool breathing = setup.contact != nullptr;
  double best = std::numeric_limits<double>::infinity();
  if (breathing) {
    for (std::size_t i = 0; i < modes.pairs.size(); ++i) {
      const modal::ModePair& pair = modes.pairs[i];
      if (!pair.paired || std::abs(pair.f_bilinear_hz - frequency_hz) >= best) continue;
      best = std::abs(pair.f_bilinear_hz - frequency_hz);
      comparison = {{"reference", "bilinear"},
                    {"mode", pair.uncracked_mode + 1},
                    {"f_uncracked_hz", pair.f_uncracked_hz},
                    {"f_open_hz", pair.f_open_hz},
                    {"f_bilinear_hz", pair.f_bilinear_hz},
                    {"reference_hz", pair.f_bilinear_hz},
                    {"relative_difference", frequency_hz / pair.f_bilinear_hz - 1.0}};
    }
    return comparison;
  }
  const modal::VariantResult* variant = modes.find(setup.variant);
  if (!variant) return comparison;
  const std::string name = setup.variant == mesh::Variant::open ? "open" : "uncracked";
  for (int i = 0; i < variant->modes.n_modes(); ++i) {
    const double f = variant->modes.frequencies_hz[i];
    if (std::abs(f - frequency_hz) >= best) continue;
    best = std::abs(f - frequency_hz);
    comparison = {{"reference", name}, {"mode", i + 1}, {"reference_hz", f},
                  {"relative_difference", frequency_hz / f - 1.0}};
  }
  return comparison;
}

/// After a pulse: the FRF estimate H = X/F of one probe over the band the pulse excites, written as
/// frf_<probe>.csv; its peaks go into the probe's spectrum.json entry.
spectral::FrequencyResponse write_frf(const fs::path& directory, const std::string& name, const std::vector<double>& values,
                                      const transient::ProbeHistory& history, const spectral::Sampling& sampling,
                                      const scene::ExcitationSection& excitation,
                                      nlohmann::json& probe_json, std::ostream& out) {
  std::vector<double> force(history.time.size());
  for (std::size_t i = 0; i < force.size(); ++i) {
    force[i] = spectral::half_sine_pulse(history.time[i], 0.0, excitation.duration, excitation.amplitude);
  }
  const double nyquist = 0.5 / sampling.time_step;
  spectral::FrequencyResponse frf =
      spectral::estimate_frf(values, force, sampling, 0.0, std::min(1.0 / excitation.duration, nyquist));
  io::CsvTable table;
  table.add("frequency [Hz]", frf.frequency_hz);
  table.add("|H| [m/N]", frf.magnitude);
  table.add("arg H [rad]", frf.phase_rad);
  std::vector<double> real, imaginary;
  for (const std::complex<double>& value : frf.response) {
    real.push_back(value.real());
    imaginary.push_back(value.imag());
  }
  table.add("Re H [m/N]", real);
  table.add("Im H [m/N]", imaginary);
  io::write_csv(directory / ("frf_" + name + ".csv"), table);
  const std::vector<double> peaks = spectral::frf_peaks(frf);
  probe_json["frf"] = {{"file", "frf_" + name + ".csv"},
                       {"unit", "m/N"},
                       {"force_direction", axis_name(excitation.direction)},
                       {"resolution_hz", frf.resolution_hz},
                       {"f_max_hz", frf.frequency_hz.empty() ? 0.0 : frf.frequency_hz.back()},
                       {"peaks_hz", peaks}};
  out << "frf " << name << ": " << frf.frequency_hz.size() << " bins of " << std::setprecision(4)
      << frf.resolution_hz << " Hz, peaks at";
  for (double peak : peaks) out << " " << std::setprecision(6) << peak;
  out << " Hz\n";
  return frf;
}

/// Stage 3 without a harmonic excitation (free vibration, a pulse, or none): per probe a ring-down
/// analysis (spectral::analyse_ringdown) compared with the modal frequencies when they are at hand,
/// the envelope of its orders plotted; after a pulse also the FRF estimate H = X/F (CSV and plot).
void write_ringdown_spectrum(const scene::Scene& scene, const fs::path& directory, const transient::ProbeHistory& history,
                             const TransientSetup& setup, const std::optional<modal::ModalResult>& modes,
                             std::ostream& out) {
  const scene::SpectrumSection& spectrum = *scene.spectrum;
  const scene::TransientSection& section = *scene.transient;
  const std::optional<scene::ExcitationSection>& excitation = section.excitation;
  const bool pulse = excitation && excitation->kind == "pulse";
  const int default_component =
      excitation ? excitation->direction : (section.release && section.release->kind == "static" ? section.release->direction : 2);
  if (history.time.size() < 2) throw SolverError(scene.file + ": spectrum: the run recorded fewer than 2 samples");
  const spectral::Sampling sampling{history.time[1] - history.time[0], history.time.front()};
  spectral::RingdownOptions options;
  options.max_order = spectrum.harmonics;
  options.subharmonics = spectrum.subharmonics;
  options.window_periods = spectrum.ringdown_window_periods + (spectrum.subharmonics && spectrum.ringdown_window_periods % 2);
  options.start_time = spectrum.ringdown_start.value_or(pulse ? excitation->duration : 0.0);
  nlohmann::json probes_json = nlohmann::json::object();
  spectral::PlotOptions plot;
  for (std::size_t p = 0; p < section.probes.size(); ++p) {
    const scene::ProbeSection& probe = section.probes[p];
    const int component = analysed_component(probe, default_component);
    const std::string axis = axis_name(component), quantity = analysed_quantity(probe, component);
    const std::vector<double>& values = history.values[9 * p + component];
    nlohmann::json probe_json = {{"component", analysed_label(probe, component)}};
    const spectral::RingdownAnalysis analysis = spectral::analyse_ringdown(values, sampling, options);
    nlohmann::json ringdown = spectral::ringdown_json(analysis);
    if (modes) {
      const nlohmann::json comparison = modal_comparison(*modes, setup, analysis.natural_frequency_hz);
      if (!comparison.is_null()) ringdown["modal_comparison"] = comparison;
    }
    probe_json["ringdown"] = ringdown;
    out << "ringdown " << probe.name << " (" << quantity << "): f = " << std::setprecision(8) << analysis.frequency_hz
        << " Hz, damping ratio " << std::setprecision(4) << analysis.damping_ratio;
    if (ringdown.contains("modal_comparison")) {
      const nlohmann::json& comparison = ringdown["modal_comparison"];
      out << ", " << comparison["reference"].get<std::string>() << " f = " << std::setprecision(8)
          << comparison["reference_hz"].get<double>() << " Hz (" << std::setprecision(3)
          << 100.0 * comparison["relative_difference"].get<double>() << " %)";
    }
    if (analysis.harmonics.size() > 1) {
      out << std::setprecision(4);
      for (const spectral::RingdownHarmonic& harmonic : analysis.harmonics) {
        if (harmonic.order != 1.0) out << ", A" << harmonic.order << "/A1 = " << harmonic.relative_amplitude;
      }
    }
    out << "\n";
    std::optional<spectral::FrequencyResponse> frf;
    if (pulse) frf = write_frf(directory, probe.name, values, history, sampling, *excitation, probe_json, out);
    if (spectrum.plots) {
      plot.title = probe.name + " " + quantity;
      const auto history_plot = spectral::plot_time_history(directory / ("history_" + probe.name + ".png"), values, sampling, plot);
      spectral::plot_ringdown_envelope(directory / ("ringdown_" + probe.name + ".png"), analysis, plot);
      if (frf) {
        std::vector<double> reference;
        const modal::VariantResult* variant = modes ? modes->find(setup.variant) : nullptr;
        if (variant) {
          for (int i = 0; i < variant->modes.n_modes(); ++i) reference.push_back(variant->modes.frequencies_hz[i]);
        }
        spectral::PlotOptions frf_plot = plot;
        frf_plot.title = probe.name + ": H = " + quantity + " / F_" + axis_name(excitation->direction);
        frf_plot.unit = "m/N";
        spectral::plot_frf(directory / ("frf_" + probe.name + ".png"), *frf, reference, frf_plot);
      }
      if (!history_plot.written) out << "note: no plots (" << history_plot.note << ")\n";
    }
    probes_json[probe.name] = probe_json;
  }
  nlohmann::json spectrum_json = {
      {"excitation_hz", 0.0},
      {"excitation", pulse ? "pulse" : (excitation ? excitation->kind : "none")},
      {"amplitude_convention", "ringdown: peak amplitudes A_k of the orders k f of the dominant frequency f, "
                               "the fitted decay removed (amplitudes at the analysis start time)"},
      {"probes", probes_json}};
  if (setup.release) spectrum_json["release"] = setup.release->kind;
  io::write_json(directory / "spectrum.json", spectrum_json);
}

/// Displacement snapshots (VTU) at evenly spaced steps of a run, only when asked, and
/// snapshots.pvd: the collection with their times, rewritten after each one (ParaView plays it as
/// a time series, also of a run that failed halfway).
class SnapshotWriter {
 public:
  /// `mesh` and `dofs`: the run's (a distributed run's: the rank's local mesh and DOF map, whose
  /// `partition` then writes one piece per rank and a .pvtu per snapshot).
  SnapshotWriter(const std::filesystem::path& directory, const mesh::Mesh& mesh, const mesh::DofMap& dofs, int count,
                 Index n_steps, const distributed::MeshPartition* partition = nullptr)
      : directory_(directory), mesh_(mesh), dofs_(dofs), count_(count), n_steps_(n_steps), partition_(partition) {}
  /// Whether on_step at this step writes a snapshot (a model that computes its field only when written asks first).
  bool due(Index step) const { return next_ < count_ && step >= step_of(next_); }
  void on_step(const transient::StepView& view) {
    if (!due(view.step)) return;
    io::PointField field{"displacement", 3, std::vector<double>(3 * static_cast<std::size_t>(mesh_.n_nodes()))};
    for (Index node = 0; node < mesh_.n_nodes(); ++node) {
      for (int c = 0; c < 3; ++c) field.values[3 * node + c] = view.displacement[dofs_.dof(node, c)];
    }
    char stem[32];
    std::snprintf(stem, sizeof stem, "snapshot_%04d", next_);
    std::string name = std::string(stem) + ".vtu";
    if (partition_) {
      name = write_snapshot_pieces(directory_, stem, *partition_, field);
    } else {
      io::write_vtu(directory_ / name, mesh_, {field});
    }
    // The displacement is U(i+1), at t_(i+1).
    collection_ += "    <DataSet timestep=\"" + format_number(view.time + view.dt) + "\" group=\"\" part=\"0\" file=\"" +
                   name + "\"/>\n";
    on_writer_rank([&] {
      io::write_file_atomic(directory_ / "snapshots.pvd",
                            "<?xml version=\"1.0\"?>\n<VTKFile type=\"Collection\" version=\"0.1\">\n  <Collection>\n" +
                                collection_ + "  </Collection>\n</VTKFile>\n");
    });
    ++next_;
  }

 private:
  /// The step of snapshot k (0-based): evenly spread, the last at the last step.
  Index step_of(int k) const {
    const long long step = static_cast<long long>(n_steps_) * (k + 1) / count_;
    return static_cast<Index>(std::max<long long>(1, step) - 1);
  }

  std::filesystem::path directory_;
  const mesh::Mesh& mesh_;
  const mesh::DofMap& dofs_;
  int count_ = 0;
  Index n_steps_ = 0;
  const distributed::MeshPartition* partition_ = nullptr;
  int next_ = 0;
  std::string collection_;
};

/// Stage 2: the transient, with the harmonic accumulators fed every step when a spectrum is asked;
/// probes.csv, energy.csv and transient.json written once, when it ends (also when it fails).
std::unique_ptr<transient::TransientSolver> run_transient_stage(const scene::Scene& scene, const Model& model,
                                                                TransientSetup& setup, const fs::path& directory,
                                                                std::optional<SpectrumMonitor>& spectrum) {
  const scene::TransientSection& section = *scene.transient;
  std::unique_ptr<transient::TransientSolver> solver;
  const distributed::MeshPartition* partition = nullptr;
  if (run_ranks() > 1) {
    if (setup.variant != mesh::Variant::open && model.mesh.has_crack()) {
      throw InputError(scene.where("transient.variant") + ": expected open under mpirun -np " +
                       std::to_string(run_ranks()) + " (the distributed run keeps the crack faces split), got uncracked");
    }
    const contact::ContactOptions contact_options = scene_contact_options(scene);
    setup.distributed = std::make_unique<DistributedTransient>(
        distribute_transient(model, setup.problem, setup.contact ? &contact_options : nullptr));
    partition = setup.distributed->partition.get();
    setup.settings.overlap_halo = halo_overlap_option();
    solver = std::make_unique<transient::TransientSolver>(partition->local_mesh(), setup.distributed->problem,
                                                          setup.settings);
  } else {
    solver = std::make_unique<transient::TransientSolver>(model.system(setup.variant), setup.problem, setup.settings);
  }
  // The time step is known once the solver is set up: decimate probes.csv, and check the histories
  // and the snapshots against the memory and the disk before the first step.
  const Index finished_interval = probe_interval(scene, setup.frequency, solver->dt());
  solver->set_probe_interval(finished_interval);
  const double steps = static_cast<double>(solver->n_steps());
  on_every_rank([&] { check_run_outputs(scene, estimate_mesh(scene), steps, std::ceil(steps / finished_interval), directory); });
  if (scene.spectrum && setup.frequency > 0.0) spectrum.emplace(scene, setup.frequency, solver->dt());
  SnapshotWriter snapshots(directory, partition ? partition->local_mesh() : model.mesh, solver->dofs(),
                           section.snapshots, solver->n_steps(), partition);
  transient::TransientCallbacks callbacks;
  callbacks.on_step = [&](const transient::StepView& view) {
    snapshots.on_step(view);
    return spectrum ? spectrum->add(view) : false;
  };
  if (spectrum) callbacks.progress_note = [&](double elapsed) { return spectrum->progress_note(elapsed); };
  if (is_writer_rank()) {
    for (const std::string& warning : setup.warnings) std::cerr << "crackle: warning: " << warning << "\n";
  }
  const transient::TransientSolver& finished = *solver;
  callbacks.on_finish = [&](const transient::TransientSummary& summary) {
    nlohmann::json extra = setup.contact ? contact::contact_json(setup.contact->contact()) : nlohmann::json::object();
    extra["probes"] = setup.probes_json;
    extra["probe_interval"] = finished_interval;
    if (setup.distributed) extra["partition"] = setup.distributed->partition_json;
    std::vector<std::string> warnings = setup.warnings;
    warnings.insert(warnings.end(), summary.warnings.begin(), summary.warnings.end());
    extra["warnings"] = warnings;
    // Every rank holds the same records (summed each step): rank 0 writes them.
    on_writer_rank([&] { transient::write_transient_outputs(directory, finished, extra); });
  };
  solver->run(callbacks);
  return solver;
}

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
  nlohmann::json json = transient::transient_json(summary);
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
  // The per-step products are small: Eigen's OpenMP threads would only spin between them.
  const int eigen_threads = Eigen::nbThreads();
  Eigen::setNbThreads(1);
  try {
    march_reduced(integrator, reduced, n_steps, dt, load, snapshots, spectrum, records, summary);
  } catch (const SolverError& error) {
    summary.status = "unstable";
    summary.message = error.what();
  }
  Eigen::setNbThreads(eigen_threads);
  summary.wall_s = run_clock.seconds();
  summary.time = integrator.time();
  summary.steps = integrator.n_steps_taken();
  summary.energy_error = integrator.energy_error();
  const fs::path& directory = options.output_directory;
  transient::write_probe_csv(directory / "probes.csv", records.probes);
  transient::write_energy_csv(directory / "energy.csv", records.energy);
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

}  // namespace

/// Frequency [Hz] of elastic mode `mode` (1-based) of the given kind from a modal result.
double mode_frequency(const modal::ModalResult& result, int mode, const std::string& of, const std::string& key) {
  const int index = mode - 1;
  if (of == "bilinear") {
    if (index >= static_cast<int>(result.pairs.size())) {
      throw InputError(key + ": mode " + std::to_string(mode) + " asked, but only " +
                       std::to_string(result.pairs.size()) + " modes were paired (raise modal.modes)");
    }
    const modal::ModePair& pair = result.pairs[index];
    if (!pair.paired) {
      throw InputError(key + ": mode " + std::to_string(mode) + " has no open partner among the " +
                       std::to_string(result.mac.cols()) + " open modes computed (best MAC " +
                       format_number(pair.mac) + " < " + format_number(modal::kPairingMac) +
                       "), so its bilinear frequency is undefined (raise modal.modes)");
    }
    return pair.f_bilinear_hz;
  }
  const modal::VariantResult* variant =
      result.find(of == "open" ? mesh::Variant::open : mesh::Variant::uncracked);
  if (!variant || index >= variant->modes.n_modes()) {
    throw InputError(key + ": mode " + std::to_string(mode) + " of the " + of + " body asked, but only " +
                     std::to_string(variant ? variant->modes.n_modes() : 0) + " modes were computed");
  }
  return variant->modes.frequencies_hz[index];
}

std::optional<modal::ModalResult> run_modal_stage(const scene::Scene& scene, const Model& model,
                                                  const fs::path& output_directory, const fs::path& modal_cache,
                                                  Stage& stage, std::ostream& out, bool reduced_follows) {
  const std::vector<mesh::Variant> variants = needed_variants(scene, stage.reason);
  if (variants.empty()) {
    stage.reason = "nothing refers to a mode";
    return std::nullopt;
  }
  const scene::TransientSection& section = *scene.transient;
  Stopwatch clock;
  modal::ModalOptions modal_settings = modal_options(scene.modal);
  modal_settings.variants = variants;
  int highest = scene.has_modal_section ? scene.modal.modes : 1;
  if (section.excitation) highest = std::max(highest, section.excitation->mode);
  if (section.release) highest = std::max(highest, section.release->mode);
  if (scene.sweep) highest = std::max({highest, scene.sweep->from.mode, scene.sweep->to.mode});
  modal_settings.modes = std::max(highest, section.damping.at_mode);
  modal_settings.cache_directory = modal_cache;
  // The reduced model solves with the transient variant's K again: its factor is kept.
  if (reduced_follows) {
    modal_settings.factors = &model.factors();
    modal_settings.factors_variant = transient_variant(scene, model);  // the reduced model's system
  }
  modal::ModalResult modes = modal::run_modal(
      [&model](mesh::Variant variant) -> const fem::System& { return *model.system(variant); }, modal_settings);
  on_writer_rank([&] { modal::write_modal_outputs(output_directory, model.mesh, modes); });
  stage.ran = true;
  stage.seconds = clock.seconds();
  out << modal::modal_table(modes);
  return modes;
}

/// The frequencies of the mode the excitation refers to, when it is paired.
static std::optional<ModeSignature> excitation_mode(const scene::Scene& scene, const std::optional<modal::ModalResult>& modes) {
  const std::optional<scene::ExcitationSection>& excitation = scene.transient->excitation;
  if (!modes || !excitation || excitation->mode <= 0) return std::nullopt;
  for (const modal::ModePair& pair : modes->pairs) {
    if (!pair.paired || pair.uncracked_mode + 1 != excitation->mode) continue;
    return ModeSignature{excitation->mode, pair.f_uncracked_hz, pair.f_open_hz, pair.f_bilinear_hz,
                         static_cast<double>(modes->free_dofs())};
  }
  return std::nullopt;
}

RunOutcome run_scene(const scene::Scene& scene, const RunCommandOptions& options, std::ostream& out, RunReuse* reuse) {
  Stopwatch total;
  RunOutcome outcome;
  const fs::path& directory = options.output_directory;
  std::unique_ptr<Model> own_model;
  const bool shared = reuse && reuse->models.count(reuse->key);
  if (!shared) own_model = std::make_unique<Model>(build_model(scene, MeshUse::transient));
  const Model& model = shared ? *reuse->models.at(reuse->key) : *own_model;
  std::vector<Stage>& stages = outcome.stages;

  Stage modal_stage{"modal", false, "", 0.0};
  std::optional<modal::ModalResult> modes;
  if (shared && reuse->modes.count(reuse->key)) {
    modes = reuse->modes.at(reuse->key);
    modal_stage = {"modal", modes.has_value(), "shared with the run of the same mesh in this process", 0.0};
  } else {
    modes = run_modal_stage(scene, model, directory, options.modal_cache, modal_stage, out,
                            scene.transient->model == scene::TransientModel::reduced);
  }
  stages.push_back(modal_stage);
  outcome.mode = excitation_mode(scene, modes);

  Stage transient_stage{"transient", true, "the scene has a transient: section (model: " + scene::model_name(scene.transient->model) + ")"};
  Stopwatch transient_clock;
  TransientSetup setup = transient_setup(scene, model, modes, options);
  std::optional<SpectrumMonitor> spectrum;
  std::unique_ptr<transient::TransientSolver> solver;
  transient::ProbeHistory reduced_probes;
  double dt = 0.0;
  if (scene.transient->model == scene::TransientModel::reduced) {
    reduced_probes = run_reduced_stage(scene, model, setup, options, spectrum, dt, outcome, out);
  } else {
    solver = run_transient_stage(scene, model, setup, directory, spectrum);
    dt = solver->dt();
  }
  transient_stage.seconds = transient_clock.seconds();
  stages.push_back(transient_stage);
  if (setup.release) {
    out << "release (" << setup.release->kind << "): largest displacement " << setup.release->largest_displacement
        << " m";
    if (setup.release->n_pairs > 0) {
      out << ", " << setup.release->n_closed << " of " << setup.release->n_pairs << " crack pairs closed after "
          << setup.release->iterations << " active-set iterations";
    }
    out << "\n";
  }
  if (solver) {
    const transient::TransientSummary& summary = solver->summary();
    out << "transient: " << summary.steps << " steps of " << summary.dt << " s (dt_critical " << summary.dt_critical
        << " s), " << summary.status << ", energy error " << summary.energy_error << ", " << std::setprecision(3)
        << summary.wall_s << " s\n";
  }

  Stage spectrum_stage{"spectrum", false, "the scene has no spectrum: section", 0.0};
  if (spectrum) {
    Stopwatch clock;
    spectrum_stage.ran = true;
    spectrum_stage.reason = "the scene has a spectrum: section";
    on_writer_rank([&] { outcome.spectrum = spectrum->write(scene, directory, dt, outcome.probes, out); });
    spectrum_stage.seconds = clock.seconds();
  } else if (scene.spectrum) {
    Stopwatch clock;
    spectrum_stage.ran = true;
    spectrum_stage.reason = "the scene has a spectrum: section; no harmonic excitation: ring-down analysis";
    on_writer_rank([&] {
      write_ringdown_spectrum(scene, directory, solver ? solver->probes() : reduced_probes, setup, modes, out);
    });
    spectrum_stage.seconds = clock.seconds();
  }
  stages.push_back(spectrum_stage);
  if (reuse && !shared) {
    reuse->modes[reuse->key] = modes;
    reuse->models[reuse->key] = std::move(own_model);
  }
  outcome.frequency = setup.frequency;
  outcome.wall_s = total.seconds();
  return outcome;
}

void write_run_json(const scene::Scene& scene, const fs::path& directory, const RunOutcome& outcome,
                    const nlohmann::json& route, const nlohmann::json& accuracy, double wall_s) {
  nlohmann::json run_json = {{"scene", scene.file}, {"output", directory.string()}};
  nlohmann::json stage_list = nlohmann::json::array();
  for (const Stage& stage : outcome.stages) {
    stage_list.push_back({{"name", stage.name}, {"ran", stage.ran}, {"reason", stage.reason}, {"seconds", stage.seconds}});
  }
  run_json["stages"] = stage_list;
  run_json["excitation_hz"] = outcome.frequency;
  if (!route.is_null()) run_json["route"] = route;
  if (!accuracy.is_null()) run_json["accuracy"] = accuracy;
  run_json["wall_s"] = wall_s;
  io::write_json(directory / "run.json", run_json);
}


void run_run_command(const RunCommandOptions& options, std::ostream& out) {
  std::vector<scene::Override> overrides = parse_overrides(options.overrides);
  const scene::Scene written = scene::load_scene(options.scene_path, overrides);
  if (!written.transient) {
    throw InputError(written.file + ": transient: expected a transient section for crackle run (crackle modal "
                     "computes modes alone), got none");
  }
  const int ranks = run_ranks();
  // transient.model: auto becomes full or reduced (and the reduced route's own mesh) by overrides
  // after the user's, so every later check and message sees the scene that runs.
  const RunRoute route = choose_route(written, ranks);
  overrides.insert(overrides.end(), route.overrides.begin(), route.overrides.end());
  const scene::Scene scene = route.overrides.empty() ? written : scene::load_scene(options.scene_path, overrides);
  if (ranks > 1 && scene.transient->model == scene::TransientModel::reduced) {
    throw InputError(scene.where("transient.model") + ": expected full under mpirun -np " + std::to_string(ranks) +
                     " (one transient over several processes is the full explicit model), got reduced; run the "
                     "reduced model without mpirun (it takes seconds on one process)");
  }
  const fs::path& directory = options.output_directory;
  // Before anything is computed: the folder can be written and is ours (leftovers of an earlier run
  // removed), and the mesh fits in memory. Under mpirun rank 0 owns the folder and prints.
  std::string modal_reason;
  on_every_rank([&] {
    check_memory(scene, !needed_variants(scene, modal_reason).empty() ? matrices::eigen_solve
                        : scene.transient->model == scene::TransientModel::reduced ? matrices::static_solve
                        : !scene.gmsh_file.empty()                  ? matrices::stiffness
                                                                    : matrices::none);
  });
  std::optional<OutputFolder> folder;
  on_writer_rank([&] { folder.emplace(directory, "run", options.scene_path, options.overwrite, std::cerr); });
  NullStream silent;
  std::exception_ptr error;
  try {
    run_with_accuracy(scene, route, overrides, options, is_writer_rank() ? out : silent);
  } catch (...) {
    error = std::current_exception();
  }
  if (ranks > 1) {  // the same error (and exit code) on every rank
    try {
      distributed::agree(error);
    } catch (...) {
      error = std::current_exception();
    }
  }
  if (error) {
    try {
      if (folder) folder->finish("failed");
    } catch (const std::exception&) {
      // The run's own error says more than a failure to record it.
    }
    std::rethrow_exception(error);
  }
  if (folder) folder->finish("done");
}

}  // namespace crackle::pipeline
