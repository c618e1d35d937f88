#pragma once
/// \file Damage indices and the JSON of harmonic signatures (a public contract: the key names
/// below are read by scripts and reports; change them only with a format version bump).
#include <nlohmann/json_fwd.hpp>
#include <string>

#include "spectral/harmonics.hpp"

namespace crackle::spectral {

/// Ratios of harmonic amplitudes that grow with a breathing crack (MODEL.md §5). NaN where the
/// table lacks an order or A_1 = 0.
struct DamageIndices {
  double a2_over_a1 = 0.0;     ///< A_2 / A_1, JSON "A2/A1"
  double a3_over_a1 = 0.0;     ///< A_3 / A_1, JSON "A3/A1"
  double a_half_over_a1 = 0.0; ///< A_{1/2} / A_1, JSON "A1/2/A1"
  double beta = 0.0;           ///< A_2 / A_1^2 [1/unit], JSON "beta"
};

/// Indices of a table.
DamageIndices damage_indices(const HarmonicTable& table);

/// `[{"order": 0, "frequency_hz": .., "amplitude": .., "phase_rad": ..}, {"order": 0.5, ...},
/// {"order": 1, ...}, ...]`, ascending order; whole orders are written as integers. Conventions
/// of harmonics.hpp: peak amplitudes, cosine phases at absolute time, order 0 the signed mean.
nlohmann::json harmonics_json(const HarmonicTable& table);

/// `{"A2/A1": .., "A3/A1": .., "A1/2/A1": .., "beta": ..}`, null where not defined.
nlohmann::json indices_json(const DamageIndices& indices);

/// The per-probe structure `{"component": "z", "harmonics": [...], "indices": {...}}`.
nlohmann::json probe_json(const std::string& component, const HarmonicTable& table);

/// `{"settled": .., "periods_used": .., "change": ..}` (change null while undefined).
nlohmann::json steady_state_json(const SteadyState& state);

}  // namespace crackle::spectral
