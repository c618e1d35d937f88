#pragma once
/// \file The harmonic signatures' JSON of spectrum.json (a public contract: the key names below are
/// read by scripts and reports; change them only with a format version bump): harmonic tables,
/// damage indices, the steady-state verdict and the ring-down analysis (the output layer).
#include <string>

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

}  // namespace crackle::output
