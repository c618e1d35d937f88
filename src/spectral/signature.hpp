#pragma once
/// \file Damage indices of harmonic signatures (their JSON: output/spectrum_json.hpp).
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

}  // namespace crackle::spectral
