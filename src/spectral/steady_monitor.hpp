#pragma once
/// \file The steady-state controller of a harmonically driven run: the signals of several probes,
/// each with its harmonic accumulator (harmonics.hpp), the verdict over all of them (every table
/// settled, DETECTION.md sec. 1's window residue), and the progress line's note with an ETA.
#include <cstddef>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "core/resources.hpp"
#include "spectral/harmonics.hpp"

namespace crackle::spectral {

class SteadyStateMonitor {
 public:
  /// `channels` signals sampled every `dt` from t = 0; the window is `window_periods` (made even
  /// with sub-harmonics: the period-two content needs whole pairs); `tolerance` <= 0: never settles
  /// (the run goes to its last period); no verdict before max(min_periods, 2 windows).
  SteadyStateMonitor(const HarmonicOptions& options, double dt, std::size_t channels, int window_periods,
                     double tolerance, int min_periods);

  /// Feeds one sample of every channel (value(c) at `time`); true when every channel's table has
  /// settled, so the run may stop. Keeps every sample (the spectra and history plots take them).
  bool add(double time, const std::function<double(std::size_t)>& value);

  /// How far the detector is, and when it may stop the run (the largest change extrapolated
  /// geometrically from its last two checks); "" without a tolerance. `elapsed`: seconds of the run.
  std::string progress_note(double elapsed) const;

  std::size_t channels() const { return accumulators_.size(); }
  HarmonicAccumulator& accumulator(std::size_t c) { return *accumulators_[c]; }
  const HarmonicAccumulator& accumulator(std::size_t c) const { return *accumulators_[c]; }
  const std::vector<double>& values(std::size_t c) const { return values_[c]; }
  /// The latest verdict over all channels (none before the first check).
  const std::optional<SteadyState>& verdict() const { return steady_; }
  int window_periods() const { return window_periods_; }

 private:
  std::vector<std::unique_ptr<HarmonicAccumulator>> accumulators_;
  std::vector<std::vector<double>> values_;
  SteadyStateCriterion criterion_;
  double tolerance_ = 0.0;
  int min_periods_ = 0, window_periods_ = 0;
  std::optional<SteadyState> steady_;
  Stopwatch clock_;             ///< since the monitor was made (the run's start)
  double check_seconds_ = 0.0;  ///< clock_ at the last steady-state check
  double previous_change_ = 0.0;
  int previous_period_ = 0, change_period_ = 0;
};

}  // namespace crackle::spectral
