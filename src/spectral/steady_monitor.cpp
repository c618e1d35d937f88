#include "spectral/steady_monitor.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>

namespace crackle::spectral {

SteadyStateMonitor::SteadyStateMonitor(const HarmonicOptions& options, double dt, std::size_t channels,
                                       int window_periods, double tolerance, int min_periods)
    : tolerance_(tolerance), min_periods_(min_periods) {
  window_periods_ = window_periods + (options.subharmonics && window_periods % 2);
  criterion_.window_periods = window_periods_;
  criterion_.tolerance = tolerance > 0.0 ? tolerance : 1e-300;
  for (std::size_t c = 0; c < channels; ++c) {
    accumulators_.push_back(std::make_unique<HarmonicAccumulator>(options, dt, 0.0));
  }
  values_.resize(channels);
}

bool SteadyStateMonitor::add(double time, const std::function<double(std::size_t)>& value) {
  int completed = 0;
  for (std::size_t c = 0; c < accumulators_.size(); ++c) {
    const double sample = value(c);
    values_[c].push_back(sample);
    completed = accumulators_[c]->add(time, sample);
  }
  if (completed == 0 || tolerance_ <= 0.0 || accumulators_.empty()) return false;
  const int periods = accumulators_.front()->n_periods();
  if (periods < std::max(min_periods_, 2 * window_periods_)) return false;
  SteadyState verdict;
  verdict.settled = true;
  verdict.periods_used = periods;
  verdict.change = 0.0;
  for (const auto& accumulator : accumulators_) {
    const SteadyState state = accumulator->steady_state(criterion_);
    verdict.settled = verdict.settled && state.settled;
    verdict.change = std::max(verdict.change, state.change);
  }
  if (steady_ && periods > change_period_) {
    previous_change_ = steady_->change;
    previous_period_ = change_period_;
  }
  change_period_ = periods;
  check_seconds_ = clock_.seconds();
  steady_ = verdict;
  return verdict.settled;
}

std::string SteadyStateMonitor::progress_note(double elapsed) const {
  if (tolerance_ <= 0.0 || accumulators_.empty()) return "";
  const int periods = accumulators_.front()->n_periods();
  const int earliest = std::max(min_periods_, 2 * window_periods_);
  const double per_period = periods > 0 ? elapsed / periods : 0.0;
  char text[200];
  if (!steady_ || periods < earliest) {
    std::snprintf(text, sizeof text, "steady state: first check at period %d (now %d), in %s", earliest, periods,
                  duration_text(per_period * (earliest - periods)).c_str());
    return text;
  }
  std::string eta = "not yet converging";
  if (previous_change_ > 0.0 && steady_->change > 0.0 && steady_->change < previous_change_ &&
      change_period_ > previous_period_) {
    const double rate = std::log(steady_->change / previous_change_) / (change_period_ - previous_period_);
    const double more = std::max(0.0, std::log(tolerance_ / steady_->change) / rate);
    eta = "ETA " + duration_text(std::max(0.0, per_period * more - (clock_.seconds() - check_seconds_))) +
          " at the current rate";
  }
  std::snprintf(text, sizeof text, "steady state: change %.2g (tolerance %.2g) at period %d, %s", steady_->change,
                tolerance_, periods, eta.c_str());
  return text;
}

}  // namespace crackle::spectral
