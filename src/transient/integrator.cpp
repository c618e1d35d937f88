#include "transient/integrator.hpp"

#include <string>

#include "core/errors.hpp"

namespace crackle::transient {
namespace {

/// Below this many DOFs the update runs on one thread (starting threads costs more).
constexpr Index kParallelMinimum = 30000;

}  // namespace

CentralDifference::CentralDifference(Index n_dofs) : force_(VectorX::Zero(n_dofs)) {}

void CentralDifference::step(SecondOrderSystem& system, double time, double dt_previous, double dt,
                             VectorX& displacement, VectorX& velocity, StepSums* sums) {
  const Index n = system.n_dofs();
  if (displacement.size() != n || velocity.size() != n || force_.size() != n) {
    throw InputError("central differences: system of " + std::to_string(n) + " DOFs, vectors of " +
                     std::to_string(displacement.size()) + " and " + std::to_string(velocity.size()));
  }
  const double h = 0.5 * (dt_previous + dt);
  const double alpha = system.mass_damping();
  system.add_force(ForceInput{time, dt, h, displacement, velocity, alpha, system.inverse_mass()}, force_);
  const double damped = 1.0 - 0.5 * alpha * h;
  const double scale = 1.0 / (1.0 + 0.5 * alpha * h);
  const double* inverse_mass = system.inverse_mass().data();
  const double* mass = system.mass().data();
  double* u = displacement.data();
  double* v = velocity.data();
  double* f = force_.data();
  if (!sums) {
#pragma omp parallel for schedule(static) if (n > kParallelMinimum)
    for (Index k = 0; k < n; ++k) {
      const double v_new = scale * (damped * v[k] + h * inverse_mass[k] * f[k]);
      v[k] = v_new;
      u[k] += dt * v_new;
      f[k] = 0.0;
    }
    return;
  }
  const Index owned = system.n_owned();
  double kinetic_half = 0.0, kinetic_mid = 0.0, force_displacement = 0.0, force_velocity = 0.0;
#pragma omp parallel for schedule(static) reduction(+ : kinetic_half, kinetic_mid, force_displacement, force_velocity) if (owned > kParallelMinimum)
  for (Index k = 0; k < owned; ++k) {
    const double v_old = v[k];
    const double v_new = scale * (damped * v_old + h * inverse_mass[k] * f[k]);
    const double v_sum = v_old + v_new;
    kinetic_half += mass[k] * v_new * v_new;
    kinetic_mid += mass[k] * v_sum * v_sum;
    force_displacement += f[k] * u[k];
    force_velocity += f[k] * v_new;
    v[k] = v_new;
    u[k] += dt * v_new;
    f[k] = 0.0;
  }
  for (Index k = owned; k < n; ++k) {  // ghosts of a distributed run: updated, not counted
    const double v_new = scale * (damped * v[k] + h * inverse_mass[k] * f[k]);
    v[k] = v_new;
    u[k] += dt * v_new;
    f[k] = 0.0;
  }
  sums->kinetic_half = 0.5 * kinetic_half;
  sums->kinetic_mid = 0.125 * kinetic_mid;
  sums->force_displacement = force_displacement;
  sums->force_velocity = force_velocity;
  sums->mass_damping_dissipation = 0.25 * alpha * h * kinetic_mid;
}

}  // namespace crackle::transient
