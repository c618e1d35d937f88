#include "pipeline/modal_accuracy.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <utility>
#include <functional>
#include <limits>

#include "accuracy/estimate.hpp"
#include "pipeline/refinement.hpp"

namespace crackle::pipeline {
namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

/// Sane observed orders in the representative cell size DOFs^-1/3 of the levels. Raising p on a body
/// with a crack front or a clamped edge converges algebraically in the DOFs, not geometrically in p
/// (Babuska and Szabo): on data/beam.yaml the change per order falls by 6.6 then 3.6, and a
/// geometric extrapolation in p puts f_open 1 above a finer mesh's value (docs/benchmarks.md 11.9).
/// Measured there: orders 1.9-4.9 in DOFs^-1/3. The levels are not similar grids and their order
/// cannot show the asymptotic range, so Fs = 3 (with 1.25 the estimate fell below the error of a
/// grid twice as fine for 7 of 18 frequencies: effectivity 0.81-1.43; with 3: 1.9-3.4).
constexpr double kSizeOrderMin = 0.5, kSizeOrderMax = 15.0;

/// `f_uncracked = 209.42 ± 0.0014 %, f_open = ... (mesh)`, with the distinct reasons of those not
/// verified: the only component is the mesh.
std::string short_line(const std::vector<std::pair<std::string, const accuracy::Estimate*>>& estimates) {
  std::string line;
  std::vector<std::string> reasons;
  bool asymptotic = true;
  for (const auto& [name, estimate] : estimates) {
    char value[48];
    std::snprintf(value, sizeof value, "%.6g", estimate->value);
    line += (line.empty() ? "" : ", ") + name + " = " + value + " ± " + percent(estimate->sum);
    for (const std::string& reason : estimate->reasons) {
      if (std::find(reasons.begin(), reasons.end(), reason) == reasons.end()) reasons.push_back(reason);
    }
    asymptotic = asymptotic && estimate->asymptotic;
  }
  line += " (mesh)";
  for (std::size_t i = 0; i < reasons.size(); ++i) line += (i ? "; " : ", not verified: ") + reasons[i];
  if (reasons.empty() && !asymptotic) line += ", not asymptotic";
  return line;
}

}  // namespace

accuracy::Component frequency_mesh_component(std::vector<int> orders, std::vector<double> values,
                                             std::vector<double> dofs, int run_order) {
  if (orders.size() == 3 && orders.front() == 1 && run_order != 1) {
    orders.erase(orders.begin());
    values.erase(values.begin());
    dofs.erase(dofs.begin());
  }
  const auto run = std::find(orders.begin(), orders.end(), run_order) - orders.begin();
  const double value = values[run];
  for (std::size_t k = 0; k < values.size(); ++k) {
    if (!std::isfinite(values[k]) || !(dofs[k] > 0.0)) {
      accuracy::Component component = missing_component("mesh", value);
      component.reason = "a level lacks this frequency (its solve failed, or the mode pairs differently there)";
      return component;
    }
  }
  if (values.size() == 3) {
    const auto size = [&](int k) { return std::cbrt(1.0 / dofs[k]); };
    return accuracy::three_level_sizes("mesh", values[0], values[1], values[2], size(0), size(1), size(2),
                                       static_cast<int>(run) + 1, kSizeOrderMin, kSizeOrderMax,
                                       accuracy::kCautiousSafetyFactor);
  }
  // Two orders: the change between them, three times, and no rate to check it by.
  accuracy::Component component;
  component.name = "mesh";
  component.value = value;
  component.refined = values.back();
  component.safety_factor = accuracy::kCautiousSafetyFactor;
  component.delta = accuracy::kCautiousSafetyFactor * (values.back() - values.front()) / std::abs(value);
  component.asymptotic = component.verified = false;
  component.reason = "two levels (orders " + std::to_string(orders.front()) + " and " +
                     std::to_string(orders.back()) + "): no observed rate";
  return component;
}

ModalLevelPlan modal_level_plan(const scene::Scene& scene, int ranks) {
  ModalLevelPlan plan;
  const scene::AccuracySection& accuracy = scene.accuracy;
  plan.tolerance = accuracy.tolerance;
  if (accuracy.estimate == scene::EstimateChoice::off) {
    plan.reason = "accuracy.estimate: off";
    return plan;
  }
  if (!scene.gmsh_file.empty()) {
    plan.reason = "a Gmsh mesh: no family of refinements (the element order is the file's)";
    return plan;
  }
  if (ranks > 1) {
    plan.reason = "not under mpirun (the levels are run on one process: crackle modal without mpirun)";
    return plan;
  }
  const int order = scene.box.order;
  plan.run_order = order;
  if (order >= 3) {
    for (int level = std::max(2, order - 2); level <= order; ++level) plan.orders.push_back(level);
  } else if (accuracy.estimate == scene::EstimateChoice::on || accuracy.tolerance) {
    for (int level = order; level <= std::min(kHighestOrder, order + 2); ++level) plan.orders.push_back(level);
  } else {
    plan.reason = "element order " + std::to_string(order) +
                  ": the levels of an estimate are the lower orders from 2 (order 1 locks in bending), so it needs "
                  "mesh.box.order 3 or more, or accuracy.estimate: on (the orders above, up to 4: several times "
                  "this solve)";
    return plan;
  }
  if (plan.orders.size() == 3 && plan.orders.back() == order && plan.orders.front() == kCheckOrder) {
    plan.check_cells = {2 * scene.box.cells[0], 2 * scene.box.cells[1], 2 * scene.box.cells[2]};
  }
  plan.estimate = true;
  return plan;
}

ModalLevel modal_level(const modal::ModalResult& result, int order, double wall_s) {
  ModalLevel level;
  level.order = order;
  level.wall_s = wall_s;
  for (const modal::VariantResult& variant : result.variants) {
    const VectorX& frequencies = variant.modes.frequencies_hz;
    level.variants[mesh::variant_name(variant.variant)] = {frequencies.data(), frequencies.data() + frequencies.size()};
  }
  level.dofs = static_cast<long>(result.free_dofs());
  level.pairs = result.pairs;
  return level;
}

nlohmann::json modal_accuracy_not_estimated(const std::string& reason) {
  return {{"estimated", false}, {"reason", reason}};
}

namespace {

/// The estimates of one plan's levels: the mesh component of a quantity from its values at the
/// plan's orders (a missing level: NaN), checked against the check level where there is one; every
/// estimate joins `summary`.
class LevelEstimates {
 public:
  LevelEstimates(const ModalLevelPlan& plan, const std::vector<const ModalLevel*>& at, const ModalLevel& run,
                 const ModalLevel* check)
      : plan_(plan), at_(at), run_(run), check_(check) {
    if (plan.check_cells)
      check_name_ = "order " + std::to_string(kCheckOrder) + " on cells " + nlohmann::json(*plan.check_cells).dump();
  }

  accuracy::Estimate operator()(const std::string& quantity, const std::function<double(const ModalLevel&)>& value_at) {
    std::vector<double> values, dofs;
    for (const ModalLevel* level : at_) {
      values.push_back(level ? value_at(*level) : kNaN);
      dofs.push_back(level ? static_cast<double>(level->dofs) : kNaN);
    }
    accuracy::Component mesh = frequency_mesh_component(plan_.orders, values, dofs, plan_.run_order);
    if (check_) mesh = accuracy::checked_against(mesh, check_name_, value_at(*check_));
    accuracy::Estimate estimate = accuracy::combine(quantity, value_at(run_), {mesh});
    add_to_summary(estimate, summary);
    return estimate;
  }

  SettingSummary summary;

 private:
  const ModalLevelPlan& plan_;
  const std::vector<const ModalLevel*>& at_;
  const ModalLevel& run_;
  const ModalLevel* check_;
  std::string check_name_;
};

/// modal.json accuracy `variants`: each variant's frequencies with their estimates.
nlohmann::json variants_json(const ModalLevel& run, LevelEstimates& estimate_of) {
  nlohmann::json variants = nlohmann::json::object();
  for (const auto& [name, frequencies] : run.variants) {
    nlohmann::json list = nlohmann::json::array();
    for (std::size_t i = 0; i < frequencies.size(); ++i) {
      list.push_back(output::estimate_json(estimate_of("f_" + name + " " + std::to_string(i + 1), [&](const ModalLevel& l) {
        const auto found = l.variants.find(name);
        return found != l.variants.end() && i < found->second.size() ? found->second[i] : kNaN;
      })));
    }
    variants[name] = {{"frequencies_hz", list}};
  }
  return variants;
}

/// modal.json accuracy `pairs`: each mode pair's three frequencies and ratio with their estimates;
/// the terminal lines in `lines`.
nlohmann::json pairs_json(const ModalLevel& run, LevelEstimates& estimate_of, std::vector<std::string>& lines) {
  nlohmann::json pairs = nlohmann::json::array();
  for (std::size_t i = 0; i < run.pairs.size(); ++i) {
    const modal::ModePair& pair = run.pairs[i];
    // A level whose mode i pairs with another open mode (or none) lacks the open frequency's partner.
    auto same_pair = [&](const ModalLevel& l) {
      return i < l.pairs.size() && l.pairs[i].paired == pair.paired && l.pairs[i].open_mode == pair.open_mode;
    };
    auto field = [&](double modal::ModePair::*member, bool needs_pairing) {
      return [&, member, needs_pairing](const ModalLevel& l) {
        if (i >= l.pairs.size() || (needs_pairing && !same_pair(l))) return kNaN;
        return l.pairs[i].*member;
      };
    };
    const std::string mode = " " + std::to_string(i + 1);
    const accuracy::Estimate f_u = estimate_of("f_uncracked" + mode, field(&modal::ModePair::f_uncracked_hz, false));
    const accuracy::Estimate f_o = estimate_of("f_open" + mode, field(&modal::ModePair::f_open_hz, true));
    const accuracy::Estimate f_b = estimate_of("f_bilinear" + mode, field(&modal::ModePair::f_bilinear_hz, true));
    const accuracy::Estimate ratio = estimate_of("ratio" + mode, field(&modal::ModePair::ratio, true));
    pairs.push_back({{"f_uncracked_hz", output::estimate_json(f_u)},
                     {"f_open_hz", output::estimate_json(f_o)},
                     {"f_bilinear_hz", output::estimate_json(f_b)},
                     {"ratio", output::estimate_json(ratio)}});
    lines.push_back("accuracy mode" + mode + ": " + short_line({{"f_uncracked", &f_u}, {"f_open", &f_o},
                                                                {"f_bilinear", &f_b}}));
  }
  return pairs;
}

}  // namespace

ModalAccuracy modal_accuracy(const ModalLevelPlan& plan, const std::vector<ModalLevel>& levels, double estimate_s,
                             double wall_s) {
  // The levels by order, in the plan's order (a missing one: every value NaN).
  std::vector<const ModalLevel*> at;
  const ModalLevel* run = nullptr;
  const auto check_found = std::find_if(levels.begin(), levels.end(), [](const ModalLevel& l) { return l.check; });
  const ModalLevel* check = check_found == levels.end() ? nullptr : &*check_found;
  for (int order : plan.orders) {
    const auto found = std::find_if(levels.begin(), levels.end(),
                                    [&](const ModalLevel& l) { return l.order == order && !l.check; });
    at.push_back(found == levels.end() ? nullptr : &*found);
    if (order == plan.run_order) run = at.back();
  }
  if (!run) return {modal_accuracy_not_estimated("the solve at the scene's order is missing"), {}};

  ModalAccuracy out;
  LevelEstimates estimate_of(plan, at, *run, check);
  const nlohmann::json variants = variants_json(*run, estimate_of);
  const nlohmann::json pairs = pairs_json(*run, estimate_of, out.lines);
  if (run->pairs.empty()) {
    for (const auto& [name, list] : variants.items()) {
      for (std::size_t i = 0; i < list["frequencies_hz"].size(); ++i) {
        const nlohmann::json& estimate = list["frequencies_hz"][i];
        out.lines.push_back("accuracy " + name + " mode " + std::to_string(i + 1) + ": " +
                            percent(estimate.value("error", 0.0)) +
                            (estimate.value("verified", false) ? "" : ", not verified"));
      }
    }
  }
  const SettingSummary& summary = estimate_of.summary;
  ToleranceOutcome outcome;
  if (plan.tolerance) {
    outcome.met = summary.verified && summary.worst <= *plan.tolerance;
    if (!*outcome.met) {
      outcome.blocking = summary.verified ? "crackle modal does not refine by itself (mesh.box.order raises the order)"
                                          : "an estimate that is not verified";
    }
  }
  nlohmann::json runs = nlohmann::json::array();
  for (const ModalLevel* level : at) {
    if (level) runs.push_back({{"order", level->order}, {"dofs", level->dofs}, {"wall_s", level->wall_s}});
  }
  if (check) {
    runs.push_back({{"order", check->order}, {"cells", *plan.check_cells}, {"check", true}, {"dofs", check->dofs},
                    {"wall_s", check->wall_s}});
  }
  out.block = accuracy_summary("p" + std::to_string(plan.run_order), plan.tolerance,
                               {"f_uncracked", "f_open", "f_bilinear"}, 0.0, summary, outcome, runs, run->wall_s,
                               estimate_s, wall_s);
  out.block.erase("budget_s");
  out.block["orders"] = plan.orders;
  out.block["run_order"] = plan.run_order;
  out.block["variants"] = variants;
  out.block["pairs"] = pairs;
  return out;
}

}  // namespace crackle::pipeline
