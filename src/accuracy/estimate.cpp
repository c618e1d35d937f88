#include "accuracy/estimate.hpp"

#include <cmath>
#include <cstdio>
#include <limits>
#include <sstream>
#include <stdexcept>

namespace crackle::accuracy {
namespace {

double relative(double change, double value) {
  const double scale = std::abs(value);
  return scale > 0.0 ? change / scale : (change == 0.0 ? 0.0 : std::copysign(HUGE_VAL, change));
}

std::string number(double value, int digits) {
  char text[64];
  std::snprintf(text, sizeof text, "%.*g", digits, value);
  return text;
}

/// An observed order outside its sane range: Fs = 3 and not asymptotic; far outside (below half the
/// least or above twice the most): not verified.
void check_order(Component& component, double order, double order_min, double order_max) {
  if (order >= order_min && order <= order_max) return;
  component.safety_factor = kCautiousSafetyFactor;
  component.asymptotic = false;
  component.reason = "observed order " + number(order, 3) + " outside [" + number(order_min, 3) + ", " +
                     number(order_max, 3) + "]";
  if (order < 0.5 * order_min || order > 2.0 * order_max) component.verified = false;
}

}  // namespace

Component three_level(const std::string& name, double q1, double q2, double q3, double ratio, double order_min,
                      double order_max) {
  Component component;
  component.name = name;
  component.value = q3;
  component.refined = q3;
  if (!std::isfinite(q1) || !std::isfinite(q2) || !std::isfinite(q3)) {
    component.delta = std::numeric_limits<double>::quiet_NaN();
    component.verified = component.asymptotic = false;
    component.reason = "a level has no finite value";
    return component;
  }
  const double e21 = q2 - q1, e32 = q3 - q2;
  if (e21 == 0.0 && e32 == 0.0) {
    component.delta = 0.0;
    return component;
  }
  const double levels_ratio = e21 / e32;  // (Q1 - Q2) / (Q2 - Q3)
  component.ratio = std::isfinite(levels_ratio) ? levels_ratio : 0.0;
  auto cautious = [&](const std::string& reason) {
    component.safety_factor = kCautiousSafetyFactor;
    component.delta = kCautiousSafetyFactor * relative(e32, q3);
    component.asymptotic = false;
    component.verified = false;
    component.reason = reason;
    return component;
  };
  if (!std::isfinite(levels_ratio) || levels_ratio <= 0.0) {
    return cautious("non-monotone refinement ((Q1 - Q2)/(Q2 - Q3) = " + number(levels_ratio, 3) + ")");
  }
  if (levels_ratio <= 1.0) {
    return cautious("not converging (the change grows from level to level: ratio " + number(levels_ratio, 3) + ")");
  }
  const double order = std::log(levels_ratio) / std::log(ratio);
  component.observed_order = order;
  const double correction = e32 / (levels_ratio - 1.0);  // Q_ext - Q3 (eq. 2)
  check_order(component, order, order_min, order_max);
  component.delta = component.safety_factor * relative(correction, q3);
  return component;
}

Component three_level_at(const std::string& name, double q1, double q2, double q3, int run, double ratio,
                         double order_min, double order_max) {
  Component component = three_level(name, q1, q2, q3, ratio, order_min, order_max);
  if (run >= 3 || !std::isfinite(component.delta)) return component;
  const double value = run == 1 ? q1 : q2;
  component.value = value;
  if (component.safety_factor == kCautiousSafetyFactor && component.observed_order == 0.0) {
    // Non-monotone or not converging: three times the change to the next level.
    component.delta = kCautiousSafetyFactor * relative((run == 1 ? q2 : q3) - value, value);
    return component;
  }
  if (q1 == q2 && q2 == q3) return component;
  const double extrapolated = q3 + (q3 - q2) / (component.ratio - 1.0);  // eq. 2
  component.delta = component.safety_factor * relative(extrapolated - value, value);
  return component;
}

Component three_level_sizes(const std::string& name, double q1, double q2, double q3, double h1, double h2,
                            double h3, int run, double order_min, double order_max, double safety_factor) {
  const double r21 = h1 / h2, r32 = h2 / h3;
  if (!(r21 > 1.0) || !(r32 > 1.0)) {
    throw std::invalid_argument("three_level_sizes: the cell sizes must decrease from level to level");
  }
  // The levels' ratio as a function of the order; it grows with p from (ln r21 / ln r32 at p -> 0)
  // and is solved by bisection on a bracket wide enough for any sane order.
  const auto levels_ratio = [&](double p) {
    return std::pow(r32, p) * (std::pow(r21, p) - 1.0) / (std::pow(r32, p) - 1.0);
  };
  Component component = three_level(name, q1, q2, q3, 2.0, order_min, order_max);  // the checks
  if (!std::isfinite(component.delta) || component.observed_order == 0.0) {
    // A level without a value, equal levels, or a non-monotone or not converging refinement:
    // three_level_at's cautious answer.
    return three_level_at(name, q1, q2, q3, run, 2.0, order_min, order_max);
  }
  const double target = component.ratio;
  double low = 1e-6, high = 64.0;
  if (levels_ratio(low) > target || levels_ratio(high) < target) {
    component = three_level_at(name, q1, q2, q3, run, 2.0, order_min, order_max);
    component.safety_factor = kCautiousSafetyFactor;
    component.asymptotic = component.verified = false;
    component.reason = "no order reproduces the levels' ratio " + number(target, 3);
    return component;
  }
  for (int i = 0; i < 200; ++i) {
    const double middle = 0.5 * (low + high);
    (levels_ratio(middle) < target ? low : high) = middle;
  }
  const double order = 0.5 * (low + high);
  component.observed_order = order;
  component.safety_factor = safety_factor;
  component.asymptotic = component.verified = true;
  component.reason.clear();
  check_order(component, order, order_min, order_max);
  const double value = run == 1 ? q1 : run == 2 ? q2 : q3;
  const double extrapolated = q3 + (q3 - q2) / (std::pow(r32, order) - 1.0);  // eq. 2
  component.value = value;
  component.refined = q3;
  component.delta = component.safety_factor * relative(extrapolated - value, value);
  return component;
}

Component one_refinement(const std::string& name, double value, double refined, double refinement, double order) {
  Component component;
  component.name = name;
  component.value = value;
  component.refined = refined;
  const double change = refined - value;
  if (!std::isfinite(value) || !std::isfinite(refined)) {
    component.delta = std::numeric_limits<double>::quiet_NaN();
    component.verified = component.asymptotic = false;
    component.reason = "the refinement has no finite value";
    return component;
  }
  if (order > 0.0 && refinement > 1.0) {
    const double rp = std::pow(refinement, order);
    component.observed_order = 0.0;
    component.delta = kSafetyFactor * relative(change * rp / (rp - 1.0), value);
  } else {
    component.safety_factor = kCautiousSafetyFactor;
    component.delta = kCautiousSafetyFactor * relative(change, value);
  }
  return component;
}

Component checked_against(Component component, const std::string& check, double check_value) {
  const double difference = relative(check_value - component.value, component.value);
  if (!std::isfinite(difference) || !std::isfinite(component.delta)) return component;
  component.check = check;
  component.check_delta = difference;
  component.levels_delta = component.delta;
  const double levels = std::abs(component.delta);
  if (std::abs(difference) > levels) {
    component.delta = std::copysign(difference, component.delta != 0.0 ? component.delta : difference);
  }
  if (component.verified && std::abs(difference) > kCheckRefutes * levels) {
    component.verified = component.asymptotic = false;
    component.reason = check + " differs by " + number(100.0 * std::abs(difference), 3) + " %, more than " +
                       number(kCheckRefutes, 2) + " times the levels' estimate (" + number(100.0 * levels, 3) +
                       " %): the levels are not in the asymptotic range";
  }
  return component;
}

Component residue(const std::string& name, double value, double relative_residue) {
  Component component;
  component.name = name;
  component.value = value;
  component.refined = value;
  component.safety_factor = 1.0;
  component.delta = relative_residue;
  return component;
}

Component window_tail(const std::string& name, double before, double previous, double value, double slowest_ratio) {
  const bool undamped = !(slowest_ratio > 1.0) && !std::isnan(slowest_ratio);
  const double change = std::isfinite(previous) ? value - previous : 0.0;
  // Three times the last change, or what the slowest decay leaves of it where that is more.
  const double cautious_factor = slowest_ratio > 1.0
                                     ? std::max(kCautiousSafetyFactor, kSafetyFactor / (slowest_ratio - 1.0))
                                     : kCautiousSafetyFactor;
  Component component;
  if (!std::isfinite(before)) {
    component = one_refinement(name, value, value + change, 1.0, 0.0);
    component.delta = cautious_factor * relative(change, value);
    component.asymptotic = false;
    component.reason = "fewer than three analysis windows (the change from the window before, " +
                       number(cautious_factor, 3) + " times)";
  } else {
    component = three_level(name, before, previous, value, kOrderLevelRatio, kOrderRateMin, kOrderRateMax);
    if (!std::isfinite(component.delta)) return component;
    if (component.observed_order == 0.0 && component.ratio != 0.0) {
      // Not geometric over the last windows (beats): bounded, not a failed refinement: counted as
      // verified, marked not asymptotic.
      component.delta = cautious_factor * relative(change, value);
      component.verified = true;
      component.reason = "the start transient's decay is not geometric over the last three windows (" +
                         component.reason + "): " + number(cautious_factor, 3) + " times the last change";
    } else if (component.ratio > 1.0 && slowest_ratio > 1.0 && component.ratio > slowest_ratio) {
      component.delta = component.safety_factor * relative(change / (slowest_ratio - 1.0), value);
      component.asymptotic = false;
      component.reason = "the windows' decay ratio " + number(component.ratio, 3) + " is faster than the damping's " +
                         "slowest decay allows (" + number(slowest_ratio, 3) + " per window): that ratio used";
    } else if (!component.verified) {
      component.verified = true;  // an observed rate out of range: Fs = 3, not asymptotic
      component.reason = "the start transient's decay is not geometric over the last three windows (" +
                         component.reason + ")";
    }
  }
  component.bound_ratio = std::isfinite(slowest_ratio) ? slowest_ratio : 0.0;
  if (undamped) {
    component.delta = kCautiousSafetyFactor * relative(change, value);
    component.safety_factor = kCautiousSafetyFactor;
    component.verified = component.asymptotic = false;
    component.reason = "the run has no damping: its start transient does not decay";
  }
  return component;
}

Estimate combine(const std::string& quantity, double value, std::vector<Component> components) {
  Estimate estimate;
  estimate.quantity = quantity;
  estimate.value = value;
  double squares = 0.0, corrections = 0.0, margins = 0.0, cautious = 0.0;
  for (const Component& component : components) {
    if (std::isfinite(component.delta)) {
      estimate.sum += std::abs(component.delta);
      estimate.signed_sum += component.delta;
      squares += component.delta * component.delta;
      if (component.safety_factor < kCautiousSafetyFactor && component.safety_factor >= 1.0) {
        const double correction = component.delta / component.safety_factor;
        corrections += correction;
        margins += (component.safety_factor - 1.0) * std::abs(correction);
      } else {
        cautious += std::abs(component.delta);
      }
    }
    estimate.asymptotic = estimate.asymptotic && component.asymptotic;
    estimate.verified = estimate.verified && component.verified;
    if (!component.reason.empty() && !component.verified) estimate.reasons.push_back(component.name + ": " + component.reason);
  }
  estimate.rss = std::sqrt(squares);
  estimate.error = std::abs(corrections) + margins + cautious;
  estimate.components = std::move(components);
  return estimate;
}

std::string estimate_line(const Estimate& estimate) {
  std::ostringstream line;
  line << estimate.quantity << " = " << number(estimate.value, 5) << " ± " << number(100.0 * estimate.error, 2) << " %";
  if (!estimate.components.empty()) {
    line << " (";
    for (std::size_t i = 0; i < estimate.components.size(); ++i) {
      const Component& component = estimate.components[i];
      // Signed (the error of the value: + where the refined value is larger), so that a reader sees
      // where the components cancel and why the estimate is below the sum of their moduli.
      const double percent = 100.0 * component.delta;
      line << (i ? ", " : "") << component.name << " " << (percent > 0.0 ? "+" : "") << number(percent, 2);
    }
    line << ")";
  }
  if (!estimate.verified) {
    line << ", not verified:";
    for (const std::string& reason : estimate.reasons) line << " " << reason << ";";
    std::string text = line.str();
    text.pop_back();
    return text;
  }
  if (!estimate.asymptotic) line << ", not asymptotic";
  return line.str();
}

}  // namespace crackle::accuracy
