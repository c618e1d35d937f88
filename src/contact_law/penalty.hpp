#pragma once
/// \file Pure pointwise kernels of the penalty contact law on the crack faces (libCEED QFunction
/// style: plain inputs, no mesh access, unit-tested alone). MODEL.md eqs. (9), (13)-(15), (25d).
///
/// Sign conventions. `n` is n+, the outward normal of the plus face, pointing from the plus face
/// towards the minus face. Tractions are those acting on the **minus** face; the plus face gets
/// the opposite. The contact pressure p = -t_N >= 0 (t_N <= 0 in eq. 14).
#include "core/types.hpp"

namespace crackle::contact {

/// Normal gap, eq. (9): \f$g_N = g_0 + (u^- - u^+)\cdot n^+\f$ [m]; negative means interpenetration.
inline double normal_gap(double initial_gap, const Vec3& u_minus, const Vec3& u_plus, const Vec3& normal) {
  return initial_gap + (u_minus - u_plus).dot(normal);
}

/// Penalty contact pressure, eq. (25d): \f$p = \varepsilon_N \max(0, -g_N)\f$ [Pa] (active only in
/// compression). The traction on the minus face is \f$+p\, n^+\f$.
inline double penalty_pressure(double gap, double normal_penalty) {
  return gap < 0.0 ? -normal_penalty * gap : 0.0;
}

/// Energy per unit area stored in the normal penalty spring: \f$\varepsilon_N \max(0,-g_N)^2/2\f$ [J/m^2].
inline double normal_penalty_energy(double gap, double normal_penalty) {
  return gap < 0.0 ? 0.5 * normal_penalty * gap * gap : 0.0;
}

/// Tangential part \f$(I - n\otimes n)\,v\f$ of a vector, eq. (13).
inline Vec3 tangential_part(const Vec3& v, const Vec3& normal) { return v - v.dot(normal) * normal; }

/// Result of one Coulomb return mapping.
struct CoulombUpdate {
  Vec3 traction = Vec3::Zero();  ///< tangential traction t_T on the minus face after the increment [Pa]
  bool slipping = false;         ///< the trial traction left the Coulomb cone and was scaled back
  /// Energy per unit area dissipated over the increment [J/m^2]: the work the interface absorbs by the
  /// midpoint rule, \f$-\tfrac12 (t_{old} + t_{new})\cdot\Delta s\f$, less the change of the stored
  /// tangential energy \f$|t|^2/(2\varepsilon_T)\f$. Exactly 0 in stick; \f$\approx \mu p\,|\Delta s_{slip}|\f$ in slip.
  double dissipation = 0.0;
};

/// Penalty-regularised Coulomb friction, eq. (15), as an elastic predictor and a radial return:
/// trial \f$t^{trial} = t_{old} - \varepsilon_T \Delta s_T\f$ from the tangential part of the
/// increment of the relative displacement \f$\Delta(u^- - u^+)\f$; if \f$|t^{trial}| \le \mu p\f$ it
/// sticks (\f$t = t^{trial}\f$), else it slips and \f$t = \mu p\, t^{trial}/|t^{trial}|\f$.
/// `pressure` is p >= 0 at the end of the increment (0 when the pair is open: the traction drops
/// to zero and its stored energy counts as dissipated).
CoulombUpdate coulomb_return_mapping(const Vec3& traction_old, const Vec3& relative_increment,
                                     const Vec3& normal, double tangential_penalty,
                                     double friction_coefficient, double pressure);

/// Energy per unit area stored in the tangential penalty spring: \f$|t_T|^2/(2\varepsilon_T)\f$ [J/m^2].
inline double tangential_penalty_energy(const Vec3& traction, double tangential_penalty) {
  return tangential_penalty > 0.0 ? 0.5 * traction.squaredNorm() / tangential_penalty : 0.0;
}

/// Result of the implicit (end-of-step) response of one pair.
struct PairResponse {
  double pressure = 0.0;         ///< p >= 0 at the end of the step [Pa]
  double gap = 0.0;              ///< g_N at the end of the step [m]
  Vec3 traction = Vec3::Zero();  ///< tangential traction on the minus face [Pa]
  bool slipping = false;
  double dissipation = 0.0;      ///< friction dissipation per unit area over the step [J/m^2] (as CoulombUpdate)
};

/// Penalty law (25d) and Coulomb return mapping (15) solved for the end of a time step, when the
/// end-of-step relative displacement \f$d = u^- - u^+\f$ is affine in the pair's own traction t_c:
/// \f$d_{end} = d_{free} + \lambda\, t_c\f$ (\f$\lambda\f$ = `compliance` [m/Pa] along n,
/// `tangential_compliance` in the tangent plane, from the step and the two nodal masses). Inputs: the free end gap \f$g_{free} = g_0 + d_{free}\cdot n\f$, the free
/// slip increment \f$d_{free} - d_{previous}\f$ (its tangential part is used), the traction of the
/// previous step. Closed form (backward Euler in the pair springs): \f$g = g_{free}/(1 + \varepsilon_N\lambda)\f$
/// and \f$p = -\varepsilon_N g\f$ if \f$g_{free} < 0\f$, else p = 0; stick
/// \f$t = (t_{old} - \varepsilon_T s_{free})/(1 + \varepsilon_T\lambda_T)\f$ (backward Euler), scaled back to
/// \f$|t| = \mu p\f$ outside the cone.
PairResponse implicit_pair_response(double free_gap, const Vec3& free_increment, const Vec3& normal,
                                    const Vec3& traction_old, double compliance, double tangential_compliance,
                                    double normal_penalty, double tangential_penalty, double friction_coefficient);

}  // namespace crackle::contact
