#include "output/spectrum_json.hpp"

#include <cmath>

#include <nlohmann/json.hpp>

#include "spectral/window.hpp"

namespace crackle::output {
namespace {

nlohmann::json number_or_null(double value) {
  return std::isfinite(value) ? nlohmann::json(value) : nlohmann::json(nullptr);
}

nlohmann::json order_json(double order) {
  if (order == std::floor(order) && std::abs(order) < 1e9) {
    return nlohmann::json(static_cast<int>(order));
  }
  return nlohmann::json(order);
}

}  // namespace

nlohmann::json harmonics_json(const spectral::HarmonicTable& table) {
  nlohmann::json list = nlohmann::json::array();
  for (const spectral::Harmonic& h : table.harmonics) {
    list.push_back({{"order", order_json(h.order)},
                    {"frequency_hz", h.frequency_hz},
                    {"amplitude", h.amplitude},
                    {"phase_rad", h.phase_rad}});
  }
  return list;
}

nlohmann::json indices_json(const spectral::DamageIndices& indices) {
  return {{"A2/A1", number_or_null(indices.a2_over_a1)},
          {"A3/A1", number_or_null(indices.a3_over_a1)},
          {"A1/2/A1", number_or_null(indices.a_half_over_a1)},
          {"beta", number_or_null(indices.beta)}};
}

nlohmann::json probe_json(const std::string& component, const spectral::HarmonicTable& table) {
  return {{"component", component},
          {"harmonics", harmonics_json(table)},
          {"indices", indices_json(spectral::damage_indices(table))}};
}

nlohmann::json steady_state_json(const spectral::SteadyState& state) {
  return {{"settled", state.settled},
          {"periods_used", state.periods_used},
          {"change", number_or_null(state.change)}};
}

nlohmann::json ringdown_json(const spectral::RingdownAnalysis& analysis) {
  nlohmann::json harmonics = nlohmann::json::array();
  nlohmann::json orders = nlohmann::json::array();
  for (const spectral::RingdownHarmonic& h : analysis.harmonics) {
    harmonics.push_back({{"order", order_json(h.order)},
                         {"frequency_hz", h.frequency_hz},
                         {"amplitude", h.amplitude},
                         {"relative_amplitude", number_or_null(h.relative_amplitude)},
                         {"phase_rad", h.phase_rad}});
    orders.push_back(order_json(h.order));
  }
  nlohmann::json starts = nlohmann::json::array();
  nlohmann::json ends = nlohmann::json::array();
  nlohmann::json amplitudes = nlohmann::json::array();
  for (const spectral::EnvelopeWindow& w : analysis.envelope) {
    starts.push_back(w.start_time);
    ends.push_back(w.end_time);
    amplitudes.push_back(w.amplitude);
  }
  return {{"frequency_hz", analysis.frequency_hz},
          {"natural_frequency_hz", analysis.natural_frequency_hz},
          {"decay_rate_per_s", analysis.decay_rate_per_s},
          {"logarithmic_decrement", analysis.logarithmic_decrement},
          {"damping_ratio", analysis.damping_ratio},
          {"decay_fit_residual", analysis.decay_fit_residual},
          {"mean", analysis.mean},
          {"start_time_s", analysis.start_time},
          {"end_time_s", analysis.end_time},
          {"periods", analysis.periods},
          {"harmonics", harmonics},
          {"envelope",
           {{"window_periods", analysis.window_periods},
            {"orders", orders},
            {"start_time_s", starts},
            {"end_time_s", ends},
            {"amplitude", amplitudes}}}};
}

nlohmann::json spectrum_json(double excitation_hz, const std::vector<ProbeTable>& probes, spectral::Window amplitude_window,
                             const spectral::SteadyState& state, int window_periods) {
  nlohmann::json probes_json = nlohmann::json::object();
  for (const ProbeTable& probe : probes) probes_json[probe.name] = probe_json(probe.component, probe.table);
  nlohmann::json document = {
      {"excitation_hz", excitation_hz},
      {"amplitude_convention",
       "peak amplitude A_k of x(t) = A_0 + sum A_k cos(2 pi k f t + phi_k), t from the start of the run"},
      {"probes", probes_json},
      {"steady_state", steady_state_json(state)}};
  document["steady_state"]["window_periods"] = window_periods;
  document["amplitude_spectrum"] = {{"window", spectral::window_name(amplitude_window)},
                                    {"files", "spectrum_<probe>.csv (frequency [Hz], peak amplitude)"}};
  return document;
}

namespace {

nlohmann::json comparison_json(const ModalComparison& comparison) {
  nlohmann::json json = {{"reference", comparison.reference},
                         {"mode", comparison.mode},
                         {"reference_hz", comparison.reference_hz},
                         {"relative_difference", comparison.relative_difference}};
  if (comparison.f_uncracked_hz) json["f_uncracked_hz"] = *comparison.f_uncracked_hz;
  if (comparison.f_open_hz) json["f_open_hz"] = *comparison.f_open_hz;
  if (comparison.f_bilinear_hz) json["f_bilinear_hz"] = *comparison.f_bilinear_hz;
  return json;
}

}  // namespace

nlohmann::json ringdown_spectrum_json(const std::string& excitation, const std::vector<RingdownProbe>& probes,
                                      const std::string& release) {
  nlohmann::json probes_json = nlohmann::json::object();
  for (const RingdownProbe& probe : probes) {
    nlohmann::json entry = {{"component", probe.component}};
    nlohmann::json ringdown = ringdown_json(probe.analysis);
    if (probe.comparison) ringdown["modal_comparison"] = comparison_json(*probe.comparison);
    entry["ringdown"] = ringdown;
    if (probe.frf) {
      entry["frf"] = {{"file", probe.frf->file},
                      {"unit", "m/N"},
                      {"force_direction", probe.frf->force_direction},
                      {"resolution_hz", probe.frf->resolution_hz},
                      {"f_max_hz", probe.frf->f_max_hz},
                      {"peaks_hz", probe.frf->peaks_hz}};
    }
    probes_json[probe.name] = entry;
  }
  nlohmann::json document = {
      {"excitation_hz", 0.0},
      {"excitation", excitation},
      {"amplitude_convention", "ringdown: peak amplitudes A_k of the orders k f of the dominant frequency f, "
                               "the fitted decay removed (amplitudes at the analysis start time)"},
      {"probes", probes_json}};
  if (!release.empty()) document["release"] = release;
  return document;
}

}  // namespace crackle::output
