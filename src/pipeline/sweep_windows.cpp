#include "pipeline/sweep_windows.hpp"

#include <algorithm>

#include "core/errors.hpp"

namespace crackle::pipeline {

std::string json_pointer_token(const std::string& text) {
  std::string escaped;
  for (char c : text) escaped += c == '~' ? "~0" : c == '/' ? "~1" : std::string(1, c);
  return escaped;
}

SweepWindows sweep_windows(const nlohmann::json& main, const std::vector<std::string>& peak_keys) {
  SweepWindows result;
  const nlohmann::json& settings = main.at("settings");
  if (settings.at("method") != "harmonic_balance") {
    result.reason = "a stepped sine: the whole range is stepped again";
    return result;
  }
  if (settings.at("subharmonic").get<int>() == 2 && settings.at("stability").get<bool>()) {
    result.reason = "a period-two branch, switched to from the period-one branch";
    return result;
  }
  if (!main.at("completed").get<bool>()) {
    result.reason = "the sweep did not reach the end of its range";
    return result;
  }
  for (const nlohmann::json& event : main.at("events")) {
    const std::string kind = event.at("kind");
    if (kind == "fold" || kind == "period_doubling") {
      result.reason = "a " + kind + " at " + format_number(event.at("frequency_hz").get<double>()) +
                      " Hz: a window started inside the range could land on another branch";
      return result;
    }
  }
  const double from = settings.at("from_hz"), to = settings.at("to_hz");
  struct Window {
    double begin, end;
    std::vector<std::string> peaks;
  };
  const double half = std::max(kWindowHalfWidth, kWindowSteps / settings.at("points").get<double>());
  std::vector<Window> raw;
  for (const auto& [name, probe] : main.at("probes").items()) {
    for (const std::string& key : peak_keys) {
      if (!probe.contains(key) || probe[key].is_null()) continue;
      const double at = (probe[key].at("frequency_hz").get<double>() - from) / (to - from);
      Window window{std::clamp(at - half, 0.0, 1.0), std::clamp(at + half, 0.0, 1.0), {}};
      if (window.begin == 0.0) window.end = std::max(window.end, 2.0 * half);  // as wide at the range's ends
      if (window.end == 1.0) window.begin = std::min(window.begin, 1.0 - 2.0 * half);
      window.peaks.push_back("/probes/" + json_pointer_token(name) + "/" + key);
      raw.push_back(window);
    }
  }
  if (raw.empty()) {
    result.reason = "no peak to estimate";
    return result;
  }
  std::sort(raw.begin(), raw.end(), [](const Window& a, const Window& b) { return a.begin < b.begin; });
  std::vector<Window> merged;
  for (Window& window : raw) {
    if (!merged.empty() && window.begin <= merged.back().end) {
      merged.back().end = std::max(merged.back().end, window.end);
      merged.back().peaks.insert(merged.back().peaks.end(), window.peaks.begin(), window.peaks.end());
    } else {
      merged.push_back(std::move(window));
    }
  }
  for (const Window& window : merged) result.covered += window.end - window.begin;
  if (result.covered > kWindowsMostOfRange) {
    result.reason = "the peaks' windows would cover " + format_number(100.0 * result.covered) + " % of the range";
    result.covered = 0.0;
    return result;
  }
  for (std::size_t w = 0; w < merged.size(); ++w) {
    result.windows.emplace_back(merged[w].begin, merged[w].end);
    for (const std::string& peak : merged[w].peaks) result.peaks.emplace_back(peak, w);
  }
  return result;
}

bool windows_hold(const SweepWindows& windows, const nlohmann::json& refined, std::string& why) {
  const double from = refined.at("settings").at("from_hz"), to = refined.at("settings").at("to_hz");
  for (const auto& [pointer, index] : windows.peaks) {
    const nlohmann::json::json_pointer at(pointer);
    if (!refined.contains(at) || refined[at].is_null()) {
      why = pointer + ": no such peak in the refinement sweep";
      return false;
    }
    const nlohmann::json& peak = refined[at];
    const double f = peak.at("frequency_hz").get<double>(), fraction = (f - from) / (to - from);
    const auto& [begin, end] = windows.windows.at(index);
    if (peak.value("window_edge", false) || fraction < begin || fraction > end) {
      why = pointer + " at " + format_number(f) + " Hz: at the end of its window or outside it";
      return false;
    }
  }
  return true;
}

}  // namespace crackle::pipeline
