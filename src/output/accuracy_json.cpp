/// \file The accuracy blocks (output/accuracy_json.hpp).
#include "output/accuracy_json.hpp"

namespace crackle::output {

nlohmann::json component_json(const accuracy::Component& component) {
  nlohmann::json json = {{"delta", component.delta},
                         {"refined", component.refined},
                         {"safety_factor", component.safety_factor},
                         {"verified", component.verified},
                         {"asymptotic", component.asymptotic}};
  if (component.ratio != 0.0) {
    json["levels_ratio"] = component.ratio;
    json["observed_rate"] = component.observed_order;
  }
  if (component.bound_ratio != 0.0) json["decay_ratio_bound"] = component.bound_ratio;
  if (!component.reason.empty()) json["reason"] = component.reason;
  if (!component.check.empty()) json["check"] = {{"level", component.check},
                     {"delta", component.check_delta},
                     {"levels_delta", component.levels_delta}};
  return json;
}

nlohmann::json estimate_json(const accuracy::Estimate& estimate) {
  nlohmann::json components = nlohmann::json::object();
  for (const accuracy::Component& component : estimate.components) components[component.name] = component_json(component);
  return {{"value", estimate.value},   {"error", estimate.error},  {"sum", estimate.sum},
          {"signed", estimate.signed_sum}, {"rss", estimate.rss},
          {"verified", estimate.verified}, {"asymptotic", estimate.asymptotic}, {"reasons", estimate.reasons},
          {"components", components}};
}

nlohmann::json accuracy_json(const AccuracySummary& summary) {
  nlohmann::json json = {{"estimated", true},
                         {"setting", summary.setting},
                         {"tolerance", summary.tolerance ? nlohmann::json(*summary.tolerance) : nlohmann::json(nullptr)},
                         {"quantities", summary.quantities},
                         {"budget_s", summary.budget_s},
                         {"error", summary.error},
                         {"verified", summary.verified},
                         {"runs", summary.runs},
                         {"run_s", summary.run_s},
                         {"estimate_s", summary.estimate_s},
                         {"share", summary.wall_s > 0.0 ? summary.estimate_s / summary.wall_s : 0.0}};
  if (summary.met) json["met"] = *summary.met;
  if (!summary.blocking.empty()) json["blocking"] = summary.blocking;
  return json;
}

}  // namespace crackle::output
