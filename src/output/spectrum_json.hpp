#pragma once
/// \file The harmonic signatures' JSON of spectrum.json (a public contract: the key names below are
/// read by scripts and reports; change them only with a format version bump): harmonic tables,
/// damage indices, the steady-state verdict and the ring-down analysis (the output layer).
#include <optional>
#include <string>
#include <vector>

#include <nlohmann/json_fwd.hpp>

#include "spectral/harmonics.hpp"
#include "spectral/ringdown.hpp"
#include "spectral/signature.hpp"

namespace crackle::output {

/// `[{"order": 0, "frequency_hz": .., "amplitude": .., "phase_rad": ..}, {"order": 0.5, ...},
/// {"order": 1, ...}, ...]`, ascending order; whole orders are written as integers. Conventions
/// of harmonics.hpp: peak amplitudes, cosine phases at absolute time, order 0 the signed mean.
nlohmann::json harmonics_json(const spectral::HarmonicTable& table);

/// `{"A2/A1": .., "A3/A1": .., "A1/2/A1": .., "beta": ..}`, null where not defined.
nlohmann::json indices_json(const spectral::DamageIndices& indices);

/// The per-probe structure `{"component": "z", "harmonics": [...], "indices": {...}}`.
nlohmann::json probe_json(const std::string& component, const spectral::HarmonicTable& table);

/// `{"settled": .., "periods_used": .., "change": ..}` (change null while undefined).
nlohmann::json steady_state_json(const spectral::SteadyState& state);


/// `{"frequency_hz", "natural_frequency_hz", "decay_rate_per_s", "logarithmic_decrement",
/// "damping_ratio", "decay_fit_residual", "mean", "start_time_s", "end_time_s", "periods",
/// "harmonics": [{"order", "frequency_hz", "amplitude", "relative_amplitude", "phase_rad"}],
/// "envelope": {"window_periods", "orders", "start_time_s": [..], "end_time_s": [..],
/// "amplitude": [[A_k per order] per window]}}`; whole orders are written as integers.
nlohmann::json ringdown_json(const spectral::RingdownAnalysis& analysis);

/// One probe's harmonic table over the analysis window (`component`: the axis, or "gap").
struct ProbeTable {
  std::string name, component;
  spectral::HarmonicTable table;
};

/// spectrum.json of a harmonic run: `{"excitation_hz", "amplitude_convention", "probes": {name:
/// probe_json}, "steady_state": {steady_state_json, "window_periods"}, "amplitude_spectrum":
/// {"window", "files"}}` (the pipeline adds the accuracy block); `amplitude_window`: the window of
/// the spectrum_<probe>.csv files.
nlohmann::json spectrum_json(double excitation_hz, const std::vector<ProbeTable>& probes, spectral::Window amplitude_window,
                             const spectral::SteadyState& state, int window_periods);

/// The modal frequency a ring-down is compared with (`reference`: bilinear, open or uncracked; the
/// mode numbered from 1; the pair's three frequencies with the bilinear reference only).
struct ModalComparison {
  std::string reference;
  int mode = 0;
  double reference_hz = 0.0, relative_difference = 0.0;
  std::optional<double> f_uncracked_hz, f_open_hz, f_bilinear_hz;
};

/// The FRF estimate of one probe after a pulse (its table in `file`).
struct FrfSummary {
  std::string file, force_direction;
  double resolution_hz = 0.0, f_max_hz = 0.0;
  std::vector<double> peaks_hz;
};

/// One probe of a free run: its ring-down analysis, the modal comparison and the FRF where there are.
struct RingdownProbe {
  std::string name, component;
  spectral::RingdownAnalysis analysis;
  std::optional<ModalComparison> comparison;
  std::optional<FrfSummary> frf;
};

/// spectrum.json of a free run (`excitation`: pulse, none, ...; `release`: the release's kind or
/// empty): `{"excitation_hz": 0, "excitation", "amplitude_convention", "probes": {name: {"component",
/// "ringdown": {ringdown_json, "modal_comparison"}, "frf"}}, "release"}`.
nlohmann::json ringdown_spectrum_json(const std::string& excitation, const std::vector<RingdownProbe>& probes,
                                      const std::string& release);

}  // namespace crackle::output
