#include "spectral/signature.hpp"

#include <cmath>
#include <limits>
#include <nlohmann/json.hpp>

namespace crackle::spectral {
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

nlohmann::json harmonics_json(const HarmonicTable& table) {
  nlohmann::json list = nlohmann::json::array();
  for (const Harmonic& h : table.harmonics) {
    list.push_back({{"order", order_json(h.order)},
                    {"frequency_hz", h.frequency_hz},
                    {"amplitude", h.amplitude},
                    {"phase_rad", h.phase_rad}});
  }
  return list;
}

nlohmann::json indices_json(const DamageIndices& indices) {
  return {{"A2/A1", number_or_null(indices.a2_over_a1)},
          {"A3/A1", number_or_null(indices.a3_over_a1)},
          {"A1/2/A1", number_or_null(indices.a_half_over_a1)},
          {"beta", number_or_null(indices.beta)}};
}

nlohmann::json probe_json(const std::string& component, const HarmonicTable& table) {
  return {{"component", component},
          {"harmonics", harmonics_json(table)},
          {"indices", indices_json(damage_indices(table))}};
}

nlohmann::json steady_state_json(const SteadyState& state) {
  return {{"settled", state.settled},
          {"periods_used", state.periods_used},
          {"change", number_or_null(state.change)}};
}

}  // namespace crackle::spectral
