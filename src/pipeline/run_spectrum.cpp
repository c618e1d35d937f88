/// \file Stage 3 of `crackle run` (run_stages.hpp): the probes' harmonic tables, spectra and plots of
/// a harmonic run, or the ring-down (and after a pulse the FRF) of a free one.
#include <cmath>
#include <iomanip>
#include <limits>
#include <ostream>

#include "core/errors.hpp"
#include "io/csv.hpp"
#include "io/files.hpp"
#include "pipeline/run_stages.hpp"
#include "spectral/plot.hpp"
#include "spectral/ringdown.hpp"
#include "spectral/signature.hpp"
#include "spectral/spectrum.hpp"
#include "output/spectrum_json.hpp"

namespace crackle::pipeline {
namespace {

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

/// The accumulators' options, once the highest harmonic is known to lie below the Nyquist
/// frequency of the time step (else an error that names the keys, before the accumulators' own).
spectral::HarmonicOptions harmonic_options(const scene::Scene& scene, double frequency, double dt) {
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

/// A1 and the ratios of a table, in ProbeSignature's order.
std::array<double, 4> signature_values(const spectral::HarmonicTable& table) {
  const spectral::DamageIndices indices = spectral::damage_indices(table);
  return {table.amplitude(1), indices.a2_over_a1, indices.a3_over_a1, indices.a_half_over_a1};
}

}  // namespace

SpectrumMonitor::SpectrumMonitor(const scene::Scene& scene, double frequency, double dt)
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

nlohmann::json SpectrumMonitor::write(const scene::Scene& scene, const std::filesystem::path& directory, double dt,
                                      std::vector<ProbeSignature>& signatures, std::ostream& out, bool draw_plots) {
  const double frequency = options_.excitation_frequency_hz;
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
  std::vector<output::ProbeTable> tables;
  const spectral::Sampling sampling{dt, 0.0};  // every step, from t = 0
  spectral::SpectrumAnalyzer analyzer;
  spectral::Window amplitude_window = spectrum_.window;  // auto's choice, once a probe's spectrum is made
  plot::PlotOptions plot;
  plot.draw = draw_plots;
  for (std::size_t p = 0; p < probes_.size(); ++p) {
    const ProbeSpectrum& probe = probes_[p];
    const spectral::HarmonicAccumulator& accumulator = monitor_.accumulator(p);
    const spectral::HarmonicTable table = accumulator.last_table(used);
    tables.push_back({probe.name, probe.label, table});
    ProbeSignature signature;
    signature.name = probe.name;
    signature.value = signature_values(table);
    signature.previous_window.fill(std::numeric_limits<double>::quiet_NaN());
    signature.window_before.fill(std::numeric_limits<double>::quiet_NaN());
    signature.window_s = used / frequency;
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
    spectrum_options.window = spectrum_.window;
    const spectral::AmplitudeSpectrum amplitude = analyzer.amplitude_spectrum(values, sampling, spectrum_options);
    amplitude_window = amplitude.window;
    io::write_file_atomic(directory / ("spectrum_" + probe.name + ".csv"), spectral::spectrum_csv(amplitude, "m"));
    if (spectrum_.plots) {
      plot.title = probe.name + " " + probe.quantity;
      const auto history_plot = spectral::plot_time_history(directory / ("history_" + probe.name + ".png"), values, sampling, plot);
      spectral::plot_spectrum(directory / ("spectrum_" + probe.name + ".png"), amplitude, frequency,
                              spectral::harmonic_orders(options_), plot);
      if (!history_plot.written && draw_plots) out << "note: no plots (" << history_plot.note << ")\n";
    }
    const spectral::DamageIndices indices = spectral::damage_indices(table);
    out << "spectrum " << probe.name << " (" << probe.quantity << "): A1 = " << table.amplitude(1) << " m, A2/A1 = "
        << indices.a2_over_a1 << ", A3/A1 = " << indices.a3_over_a1;
    if (options_.subharmonics) out << ", A1/2/A1 = " << indices.a_half_over_a1;
    out << "\n";
  }
  return output::spectrum_json(frequency, tables, amplitude_window, state, used);
}

namespace {

/// The modal frequency a ring-down is compared with: bilinear for a breathing crack (the open body
/// with contact), else the run variant's own; the mode nearest the measured frequency.
std::optional<output::ModalComparison> modal_comparison(const modal::ModalResult& modes, const TransientSetup& setup,
                                                        double frequency_hz) {
  std::optional<output::ModalComparison> comparison;
  const bool breathing = setup.contact != nullptr;
  double best = std::numeric_limits<double>::infinity();
  if (breathing) {
    for (std::size_t i = 0; i < modes.pairs.size(); ++i) {
      const modal::ModePair& pair = modes.pairs[i];
      if (!pair.paired || std::abs(pair.f_bilinear_hz - frequency_hz) >= best) continue;
      best = std::abs(pair.f_bilinear_hz - frequency_hz);
      comparison = output::ModalComparison{"bilinear", pair.uncracked_mode + 1, pair.f_bilinear_hz,
                                           frequency_hz / pair.f_bilinear_hz - 1.0, pair.f_uncracked_hz,
                                           pair.f_open_hz, pair.f_bilinear_hz};
    }
    return comparison;
  }
  const modal::VariantResult* variant = modes.find(setup.variant);
  if (!variant) return comparison;
  const std::string name = mesh::variant_name(setup.variant);
  for (int i = 0; i < variant->modes.n_modes(); ++i) {
    const double f = variant->modes.frequencies_hz[i];
    if (std::abs(f - frequency_hz) >= best) continue;
    best = std::abs(f - frequency_hz);
    comparison = output::ModalComparison{name, i + 1, f, frequency_hz / f - 1.0, {}, {}, {}};
  }
  return comparison;
}

/// After a pulse: the FRF estimate H = X/F of one probe over the band the pulse excites, written as
/// frf_<probe>.csv; its summary (peaks) for the probe's spectrum.json entry in `summary`.
spectral::FrequencyResponse write_frf(const std::filesystem::path& directory, const std::string& name, const std::vector<double>& values,
                                      const transient::ProbeHistory& history, const spectral::Sampling& sampling,
                                      const scene::ExcitationSection& excitation,
                                      output::FrfSummary& summary, std::ostream& out) {
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
  summary = {"frf_" + name + ".csv", axis_name(excitation.direction), frf.resolution_hz,
             frf.frequency_hz.empty() ? 0.0 : frf.frequency_hz.back(), peaks};
  out << "frf " << name << ": " << frf.frequency_hz.size() << " bins of " << std::setprecision(4)
      << frf.resolution_hz << " Hz, peaks at";
  for (double peak : peaks) out << " " << std::setprecision(6) << peak;
  out << " Hz\n";
  return frf;
}

}  // namespace

/// Stage 3 without a harmonic excitation (free vibration, a pulse, or none): per probe a ring-down
/// analysis (spectral::analyse_ringdown) compared with the modal frequencies when they are at hand,
/// the envelope of its orders plotted; after a pulse also the FRF estimate H = X/F (CSV and plot).
void write_ringdown_spectrum(const scene::Scene& scene, const std::filesystem::path& directory, const transient::ProbeHistory& history,
                             const TransientSetup& setup, const std::optional<modal::ModalResult>& modes,
                             std::ostream& out, bool draw_plots) {
  const scene::SpectrumSection& spectrum = *scene.spectrum;
  const scene::TransientSection& section = *scene.transient;
  const std::optional<scene::ExcitationSection>& excitation = section.excitation;
  const bool pulse = excitation && excitation->kind == scene::ExcitationKind::pulse;
  const int default_component =
      excitation ? excitation->direction : (section.release && section.release->kind == scene::ReleaseKind::static_deflection ? section.release->direction : 2);
  if (history.time.size() < 2) throw SolverError(scene.file + ": spectrum: the run recorded fewer than 2 samples");
  const spectral::Sampling sampling{history.time[1] - history.time[0], history.time.front()};
  spectral::RingdownOptions options;
  options.max_order = spectrum.harmonics;
  options.subharmonics = spectrum.subharmonics;
  options.window_periods = spectrum.ringdown_window_periods + (spectrum.subharmonics && spectrum.ringdown_window_periods % 2);
  options.start_time = spectrum.ringdown_start.value_or(pulse ? excitation->duration : 0.0);
  std::vector<output::RingdownProbe> probes;
  plot::PlotOptions plot;
  plot.draw = draw_plots;
  for (std::size_t p = 0; p < section.probes.size(); ++p) {
    const scene::ProbeSection& probe = section.probes[p];
    const int component = analysed_component(probe, default_component);
    const std::string axis = axis_name(component), quantity = analysed_quantity(probe, component);
    const std::vector<double>& values = history.values[9 * p + component];
    output::RingdownProbe entry{probe.name, analysed_label(probe, component),
                                spectral::analyse_ringdown(values, sampling, options), {}, {}};
    const spectral::RingdownAnalysis& analysis = entry.analysis;
    if (modes) entry.comparison = modal_comparison(*modes, setup, analysis.natural_frequency_hz);
    out << "ringdown " << probe.name << " (" << quantity << "): f = " << std::setprecision(8) << analysis.frequency_hz
        << " Hz, damping ratio " << std::setprecision(4) << analysis.damping_ratio;
    if (entry.comparison) {
      out << ", " << entry.comparison->reference << " f = " << std::setprecision(8) << entry.comparison->reference_hz
          << " Hz (" << std::setprecision(3) << 100.0 * entry.comparison->relative_difference << " %)";
    }
    if (analysis.harmonics.size() > 1) {
      out << std::setprecision(4);
      for (const spectral::RingdownHarmonic& harmonic : analysis.harmonics) {
        if (harmonic.order != 1.0) out << ", A" << harmonic.order << "/A1 = " << harmonic.relative_amplitude;
      }
    }
    out << "\n";
    std::optional<spectral::FrequencyResponse> frf;
    if (pulse) {
      entry.frf.emplace();
      frf = write_frf(directory, probe.name, values, history, sampling, *excitation, *entry.frf, out);
    }
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
        plot::PlotOptions frf_plot = plot;
        frf_plot.title = probe.name + ": H = " + quantity + " / F_" + axis_name(excitation->direction);
        frf_plot.unit = "m/N";
        spectral::plot_frf(directory / ("frf_" + probe.name + ".png"), *frf, reference, frf_plot);
      }
      if (!history_plot.written && draw_plots) out << "note: no plots (" << history_plot.note << ")\n";
    }
    probes.push_back(std::move(entry));
  }
  io::write_json(directory / "spectrum.json",
                 output::ringdown_spectrum_json(pulse ? "pulse" : (excitation ? scene::excitation_kind_name(excitation->kind) : "none"), probes,
                                                setup.release ? text_of(scene::kReleaseKindWords, setup.release->kind) : ""));
}

}  // namespace crackle::pipeline
