#include "spectral/signature.hpp"

#include <cmath>
#include <limits>

namespace crackle::spectral {

DamageIndices damage_indices(const HarmonicTable& table) {
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const double a1 = table.has(1.0) ? table.amplitude(1.0) : nan;
  const auto ratio = [&](double order, double denominator) {
    if (!table.has(order) || !(denominator > 0.0)) return nan;
    return table.amplitude(order) / denominator;
  };
  DamageIndices indices;
  indices.a2_over_a1 = ratio(2.0, a1);
  indices.a3_over_a1 = ratio(3.0, a1);
  indices.a_half_over_a1 = ratio(0.5, a1);
  indices.beta = ratio(2.0, a1 * a1);
  return indices;
}

}  // namespace crackle::spectral
