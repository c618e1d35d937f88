#include "transient/damping.hpp"

#include <cmath>

#include "core/errors.hpp"

namespace crackle::transient {
namespace {

void check_ratio(double ratio, double omega) {
  if (!(ratio >= 0.0) || !std::isfinite(ratio) || !(omega > 0.0) || !std::isfinite(omega)) {
    throw InputError("damping: expected a ratio >= 0 and an angular frequency > 0, got ratio " + format_number(ratio) +
                     " at omega " + format_number(omega) + " rad/s");
  }
}

}  // namespace

RayleighDamping mass_proportional_damping(double ratio, double omega) {
  check_ratio(ratio, omega);
  return {2.0 * ratio * omega, 0.0};
}

RayleighDamping stiffness_proportional_damping(double ratio, double omega) {
  check_ratio(ratio, omega);
  return {0.0, 2.0 * ratio / omega};
}

RayleighDamping stated_damping(std::optional<double> ratio, bool stiffness, double at_hz, double alpha, double beta) {
  if (!ratio) return {alpha, beta};
  const double omega = 2.0 * M_PI * at_hz;
  return stiffness ? stiffness_proportional_damping(*ratio, omega) : mass_proportional_damping(*ratio, omega);
}

double damping_ratio(const RayleighDamping& damping, double omega) {
  return damping.alpha / (2.0 * omega) + 0.5 * damping.beta * omega;
}

void check_damping(const RayleighDamping& damping) {
  if (!(damping.alpha >= 0.0) || !(damping.beta >= 0.0) || !std::isfinite(damping.alpha) || !std::isfinite(damping.beta)) {
    throw InputError("damping: expected alpha >= 0 and beta >= 0, got alpha = " + format_number(damping.alpha) +
                     " 1/s, beta = " + format_number(damping.beta) + " s");
  }
}

}  // namespace crackle::transient
