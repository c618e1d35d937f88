#pragma once
/// \file The accuracy blocks of spectrum.json, sweep.json, run.json and modal.json (DETECTION.md
/// sec. 1): one quantity's estimate with its components, and the block's summary fields.
#include <optional>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "accuracy/estimate.hpp"

namespace crackle::output {

/// What an estimate's fields mean (spectrum.json's and sweep.json's `accuracy.method` end with it).
inline constexpr const char* kEstimateFields =
    "error: the estimate, |sum of delta/Fs| over the components whose sign is trusted (Fs < 3) plus their "
    "margins (Fs - 1) |delta/Fs| plus |delta| of the others (equal to sum where the components share a sign), "
    "sum: sum of |delta| (the conservative bound), signed: sum of delta, rss: root-sum-square";

/// One component: delta, refined, safety factor, verified, asymptotic, levels ratio and rate, the
/// decay bound of a window, reason, the check level.
nlohmann::json component_json(const accuracy::Component& component);

/// One quantity's estimate: value, error, sum, signed, rss, verified, asymptotic, reasons and the
/// components by name.
nlohmann::json estimate_json(const accuracy::Estimate& estimate);

/// The block's summary fields.
struct AccuracySummary {
  std::string setting;                  ///< the setting the estimate is of, in words
  std::optional<double> tolerance;      ///< relative; empty: none asked for
  std::vector<std::string> quantities;  ///< what the tolerance applies to
  double budget_s = 0.0;
  double error = 0.0;                   ///< the largest estimate of `quantities`
  bool verified = true;
  std::optional<bool> met;              ///< empty: no tolerance
  std::string blocking;                 ///< the component that kept the tolerance from being met
  nlohmann::json runs;                  ///< the refinement runs, as their runner lists them
  double run_s = 0.0, estimate_s = 0.0, wall_s = 0.0;
};

/// estimated, setting, tolerance, quantities, budget_s, error, verified, runs, run_s, estimate_s,
/// share (of the wall time), met and blocking where there are.
nlohmann::json accuracy_json(const AccuracySummary& summary);

}  // namespace crackle::output
