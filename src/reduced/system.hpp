#pragma once
/// \file The reduced model of a cracked body, condensed on its crack pairs (HYBRID.md §2): the open
/// body's lowest modes plus the residual (static) flexibility seen by the crack pairs, the load and
/// the probes. Plain dense data, no mesh: the reduced transient and the harmonic balance both
/// consume it, and small systems (oscillators) can be written by hand in tests.
///
/// **Pair rows.** Each crack pair contributes `rows_per_pair()` rows to B (HYBRID.md §1): row
/// `rows_per_pair() * i` is the normal direction n+ of pair i; with friction the two tangents a_1,
/// a_2 (an orthonormal basis of the plane normal to n+) follow. A row's gap is the relative
/// displacement (u_minus - u_plus) along its direction (MODEL.md eqs. 9-10), so the normal gap is
/// g_N = g0 + (B u)_normal. A row's force p is the contact force on the **minus** node along that
/// direction [N] (the plus node gets -p): normal p = eps_N A max(0, -g_N) >= 0 (eq. 25d with the
/// pair's area A), tangential p = A t_T from the Coulomb return mapping (eq. 15). Contact power is
/// p . dg/dt.
#include <vector>

#include "core/types.hpp"

namespace crackle::reduced {

/// The condensed reduced model. Sizes: m modes, c = rows_per_pair() * n_pairs() pair rows,
/// o output rows (probe displacement components).
struct ReducedSystem {
  // ---- modal part: K phi_r = omega_r^2 M phi_r, phi_r^T M phi_s = delta_rs (open variant)
  VectorX omega;            ///< omega_r [rad/s], m entries, ascending; 0 for rigid-body modes
  double rayleigh_alpha = 0.0;  ///< C = alpha M + beta K (MODEL.md eq. 26): zeta_r = alpha/(2 omega_r) + beta omega_r/2
  double rayleigh_beta = 0.0;

  // ---- crack pairs
  bool friction = false;    ///< rows per pair: 3 (normal, tangent 1, tangent 2) with friction, else 1
  VectorX pair_area;        ///< A_i [m^2], one per pair
  VectorX initial_gap;      ///< g0_i [m], one per pair (normal rows only)
  double normal_penalty = 0.0;       ///< eps_N [Pa/m] (MODEL.md eq. 25d)
  double tangential_penalty = 0.0;   ///< eps_T [Pa/m] (friction only)
  double friction_coefficient = 0.0; ///< mu (eq. 15)
  MatrixX pair_modes;       ///< B Phi, c x m
  MatrixX residual;         ///< R = B G_res B^T, c x c, symmetric positive (semi)definite [m/N]

  // ---- external load f(t) = load_shape * a(t)
  VectorX load_modal;       ///< Phi^T f_hat, m entries [N per unit of a]
  VectorX load_residual;    ///< r_f = B G_res f_hat, c entries [m per unit of a]

  // ---- outputs (probe displacement components): y = C u
  MatrixX output_modes;          ///< C Phi, o x m
  MatrixX output_residual_pairs; ///< C G_res B^T, o x c [m/N]
  VectorX output_residual_load;  ///< C G_res f_hat, o entries [m per unit of a]

  Index n_modes() const { return static_cast<Index>(omega.size()); }
  Index n_pairs() const { return static_cast<Index>(pair_area.size()); }
  Index rows_per_pair() const { return friction ? 3 : 1; }
  Index n_rows() const { return rows_per_pair() * n_pairs(); }
  Index n_outputs() const { return static_cast<Index>(output_modes.rows()); }
  /// The least modal decay rate of the damping, alpha/2 + beta omega_0^2/2 [1/s] at the lowest mode
  /// (omega ascending; a rigid mode decays at alpha/2): the system's start transient decays no
  /// faster. 0 without modes.
  double slowest_decay_rate() const {
    if (n_modes() == 0) return 0.0;
    return 0.5 * (rayleigh_alpha + rayleigh_beta * omega[0] * omega[0]);
  }
  /// Modal damping ratio zeta_r of the Rayleigh damping (exact per mode); rigid modes (omega 0)
  /// get alpha-only damping handled by the integrators (zeta undefined): returns 0 there.
  double damping_ratio(Index mode) const {
    const double w = omega[mode];
    return w > 0.0 ? rayleigh_alpha / (2.0 * w) + rayleigh_beta * w / 2.0 : 0.0;
  }
};

}  // namespace crackle::reduced
