#include "contact_law/penalty.hpp"

#include <cmath>

namespace crackle::contact {
namespace {

/// Radial return onto the cone |t| <= limit (eq. 15): the traction, and true if it slips.
bool radial_return(const Vec3& trial, double limit, Vec3& traction) {
  const double trial_norm = trial.norm();
  if (trial_norm <= limit) {
    traction = trial;
    return false;
  }
  traction = trial_norm > 0.0 ? Vec3(trial * (limit / trial_norm)) : Vec3::Zero();
  return true;
}

/// Work absorbed over a slipping step by the midpoint rule, less the change of the stored energy
/// |t|^2 / (2 eps_T). (In stick t_new = t_old - eps_T ds, and the two cancel exactly.)
double slip_dissipation(const Vec3& old, const Vec3& traction, const Vec3& slip, double tangential_penalty) {
  const double absorbed = -0.5 * (old + traction).dot(slip);
  const double stored_change =
      tangential_penalty > 0.0 ? 0.5 * (traction.squaredNorm() - old.squaredNorm()) / tangential_penalty : 0.0;
  return absorbed - stored_change;
}

}  // namespace

CoulombUpdate coulomb_return_mapping(const Vec3& traction_old, const Vec3& relative_increment,
                                     const Vec3& normal, double tangential_penalty,
                                     double friction_coefficient, double pressure) {
  // Elastic predictor on the tangent plane, then radial return onto the cone |t| = mu p (eq. 15).
  const Vec3 old = tangential_part(traction_old, normal);
  const Vec3 slip_increment = tangential_part(relative_increment, normal);
  const Vec3 trial = old - tangential_penalty * slip_increment;
  const double limit = friction_coefficient * std::max(pressure, 0.0);
  CoulombUpdate update;
  update.slipping = radial_return(trial, limit, update.traction);
  if (update.slipping) update.dissipation = slip_dissipation(old, update.traction, slip_increment, tangential_penalty);
  return update;
}

PairResponse implicit_pair_response(double free_gap, const Vec3& free_increment, const Vec3& normal,
                                    const Vec3& traction_old, double compliance, double tangential_compliance,
                                    double normal_penalty, double tangential_penalty, double friction_coefficient) {
  PairResponse response;
  response.gap = free_gap;
  if (free_gap < 0.0) {
    response.gap = free_gap / (1.0 + normal_penalty * compliance);
    response.pressure = -normal_penalty * response.gap;
  }
  if (!(friction_coefficient > 0.0)) return response;
  const Vec3 old = tangential_part(traction_old, normal);
  const Vec3 free_slip = tangential_part(free_increment, normal);
  const Vec3 trial = (old - tangential_penalty * free_slip) / (1.0 + tangential_penalty * tangential_compliance);
  const double limit = friction_coefficient * response.pressure;
  response.slipping = radial_return(trial, limit, response.traction);
  if (response.slipping) {
    // With the slip the traction actually produces.
    const Vec3 slip = free_slip + tangential_compliance * response.traction;
    response.dissipation = slip_dissipation(old, response.traction, slip, tangential_penalty);
  }
  return response;
}

}  // namespace crackle::contact
