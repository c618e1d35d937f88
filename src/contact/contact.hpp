#pragma once
/// \file Penalty contact of the crack faces as node-pair springs (MODEL.md eq. 25d with GLL nodal
/// quadrature of the crack face), with optional Coulomb friction (eq. 15). It consumes the mesh's
/// crack pairs {minus, plus, n+, area} and knows nothing about time integration beyond the
/// velocity update it is told: the transient module plugs it in as a force term.
///
/// Two ways to integrate the pair springs in time:
/// - `implicit` (default): the penalty law is evaluated at the end of the step, U(i+1), solved in
///   closed form per pair (pairs share no node and the mass is diagonal); the bulk stays explicit.
///   Backward Euler in the stiff pair springs only: they do not limit the time step, and the two
///   small nodal masses of a pair do not bounce off each other on the stiff spring (a node-scale
///   chatter that central differences pump with energy, up to blow-up, when the spring period is
///   not resolved). The price is a small numerical dissipation: the relative normal velocity of
///   a pair coming into contact is lost (an inelastic node impact, O(h)), and closed springs
///   dissipate O(1/eps_N). Measured: 0.5% of the energy over 1.1e5 steps of a breathing crack.
/// - `explicit_forces`: the penalty law at U(i), as eq. (27) literally. Central differences at the
///   springs' own stability limit (the pair spring-mass frequency equal to omega_max) are stable
///   for a linear spring but not for one that switches on and off: an impact that lasts one or two
///   steps gains or loses an O(1) share of the pair's energy, and chatter at the crack mouth pumps
///   it until the energy check stops the run (docs/benchmarks.md section 4: every penalty >= 10 E/h
///   at the first closure). So the closed springs enter omega_max at kExplicitSpringResolution
///   times their own frequency: the step resolves the spring period with >= 14 steps (as
///   LS-DYNA's and Abaqus' contact steps are chosen from the pair's own spring-mass frequency), at
///   a cost of steps that grows as sqrt(eps_N).
#include <vector>

#include "core/choices.hpp"
#include "core/defaults.hpp"
#include "core/types.hpp"
#include "fem/assembly.hpp"
#include "mesh/mesh.hpp"

namespace crackle::contact {

/// Default c of the automatic normal penalty \f$\varepsilon_N = c\, C_{nnnn}/h\f$ with implicit pair
/// springs: stiff (the closed crack adds the compliance of a layer h/1000 thick, and the numerical
/// dissipation of the closed springs falls as 1/c) at no cost in time step.
inline constexpr double kDefaultPenaltyFactor = defaults::kImplicitPenaltyFactor;
/// Default c with explicit pair springs: their frequency stays at that of the elements, so that
/// they barely shrink the stable time step and central differences keep contact events stable.
inline constexpr double kDefaultExplicitPenaltyFactor = defaults::kExplicitPenaltyFactor;

/// Explicit pair springs enter the stable step's omega_max at this many times their own
/// spring-mass frequency (their stiffness times its square): dt <= 0.9 x 2 / (4 omega_pair) =
/// 0.45 / omega_pair, about 14 steps per spring period. Measured on plucked cantilevers (20+ closures,
/// penalties 0.01-100 x the explicit auto, docs/benchmarks.md section 4): with 2 the runs at 100 x
/// (and at 10 x on the deep beam) still diverge; with 4 every energy error stays below 6e-3.
inline constexpr double kExplicitSpringResolution = 4.0;

/// implicit (penalty law at U(i+1), the default) or explicit_forces (at U(i)): core/choices.hpp.
using crackle::ContactIntegration;

/// Options of the crack-face contact (the scene's `contact:` settings).
struct ContactOptions {
  double initial_gap = 0.0;     ///< g0 [m] of eq. (9), uniform over the crack (mesh::CrackSpec::gap)
  double normal_penalty = 0.0;  ///< \f$\varepsilon_N\f$ [Pa/m]; 0 = automatic (`penalty: auto`)
  /// c of the automatic penalty \f$\varepsilon_N = c\, C_{nnnn}/h\f$: C_nnnn the largest normal
  /// modulus (\f$c_{ijkl}n_in_jn_kn_l\f$, = E for nu = 0) and h the smallest size along n+ of the
  /// elements touching the crack. The closed crack then adds the compliance of a layer h/c thick.
  /// 0 = the default of the integration (kDefaultPenaltyFactor, kDefaultExplicitPenaltyFactor).
  double penalty_factor = 0.0;
  double friction_coefficient = 0.0;  ///< mu of eq. (15); 0 = frictionless
  double tangential_penalty = 0.0;    ///< \f$\varepsilon_T\f$ [Pa/m]; 0 = equal to \f$\varepsilon_N\f$
  ContactIntegration integration = ContactIntegration::implicit;
};

/// The penalties in use and how the automatic one was chosen (for logs and transient.json).
struct PenaltyChoice {
  double normal_penalty = 0.0;      ///< \f$\varepsilon_N\f$ [Pa/m]
  double tangential_penalty = 0.0;  ///< \f$\varepsilon_T\f$ [Pa/m] (used only with friction)
  bool automatic = false;
  double factor = 0.0;        ///< c (automatic only)
  double modulus = 0.0;       ///< C_nnnn [Pa] (automatic only)
  double element_size = 0.0;  ///< h [m] (automatic only)
};

/// Penalties from the options; InputError for negative values or a mesh without a crack.
PenaltyChoice choose_penalty(const mesh::Mesh& mesh, const fem::Materials& materials, const ContactOptions& options);

/// Normal modulus \f$C_{nnnn} = c_{ijkl} n_i n_j n_k n_l\f$ [Pa] of a Voigt stiffness along a unit n.
double normal_modulus(const fem::VoigtMatrix& stiffness, const Vec3& normal);

/// What the velocity update of the integrator does with a force F, for the implicit contact:
/// \f$(1 + \alpha h/2) V_{i+1/2} = (1 - \alpha h/2) V_{i-1/2} + h M^{-1} F\f$, \f$U_{i+1} = U_i + \Delta t\, V_{i+1/2}\f$.
struct VelocityUpdate {
  double dt = 0.0;     ///< Delta t(i+1) [s]
  double step = 0.0;   ///< h [s]
  double alpha = 0.0;  ///< mass-proportional damping [1/s]
  const VectorX* inverse_mass = nullptr;  ///< per DOF, 0 at held DOFs
};

/// Node-pair penalty springs over the split crack pairs. Front pairs (minus == plus) carry equal
/// and opposite forces on one node, i.e. none: they are skipped. Vectors are over all DOFs of
/// the DOF map (interleaved x, y, z per DOF node), normally the `open` variant.
class PenaltyContact {
 public:
  PenaltyContact(const mesh::Mesh& mesh, const mesh::DofMap& dofs, const fem::Materials& materials,
                 const ContactOptions& options);
  /// With penalties chosen elsewhere (on the whole mesh, for one rank's share of it, which may hold
  /// no pair at all).
  PenaltyContact(const mesh::Mesh& mesh, const mesh::DofMap& dofs, const ContactOptions& options,
                 const PenaltyChoice& penalty);

  const PenaltyChoice& penalty() const { return penalty_; }
  const ContactOptions& options() const { return options_; }
  bool has_friction() const { return options_.friction_coefficient > 0.0; }
  bool implicit() const { return options_.integration == ContactIntegration::implicit; }
  /// Split pairs (those that can carry force).
  Index n_pairs() const { return static_cast<Index>(pairs_.size()); }
  /// Sum of the areas of the split pairs [m^2].
  double total_area() const { return total_area_; }

  /// Sets the reference of the friction history to `displacement` and clears the tangential
  /// tractions and the dissipation. Call before the first step when U(0) is not zero.
  void reset(const VectorX& displacement);

  /// Explicit: adds the contact forces at U(i) to `force`, per pair \f$A(p\,n^+ + t_T)\f$ on minus
  /// and the opposite on plus, p from eq. (25d) at U(i), t_T from the return mapping (15) of the
  /// slip since the previous call. Call exactly once per time step, in order.
  void add_force(const VectorX& displacement, VectorX& force);

  /// Implicit: adds the contact forces evaluated at U(i+1) to `force`, which must already hold
  /// every other force of the step (call last): per pair, the end-of-step relative displacement is
  /// affine in the pair's own force through `update`, and the penalty law and the return mapping
  /// are solved for it in closed form (implicit_pair_response). Call exactly once per step.
  void add_implicit_force(const VectorX& displacement, const VectorX& velocity, const VelocityUpdate& update,
                          VectorX& force);

  /// For one rank of a distributed run (transient::Distribution): the pairs whose minus DOF is
  /// below `n_owned_dofs` are this rank's own; the others (ghost pairs, evaluated alike so that
  /// ghost DOFs get the same forces as their owners) are left out of every sum (force_dot, energies,
  /// counts, total_force). `total_area` is that of the whole crack (for the closed fraction).
  void count_owned_pairs_only(Index n_owned_dofs, double total_area);

  /// Dot product of the force vector of the last step with x.
  double force_dot(const VectorX& x) const;
  /// Energy stored in the penalty springs [J] (normal + tangential): at U(i) after add_force(), at
  /// U(i+1) after add_implicit_force().
  double stored_energy() const { return stored_energy_; }
  /// Energy dissipated by friction since reset() [J].
  double dissipated_energy() const { return dissipated_energy_; }
  /// Pairs in contact (g_N < 0), their area [m^2] and the pairs slipping, at the last step.
  Index n_closed() const { return n_closed_; }
  double closed_area() const { return closed_area_; }
  Index n_slipping() const { return n_slipping_; }
  /// Total contact force on the minus face at the last step [N].
  Vec3 total_force() const;
  /// The split pair whose plus node has DOF `plus_dof` (x component), or -1.
  Index find_pair(Index plus_dof) const;
  /// Contact state of pair k at the last step: 0 open (g_N >= 0), 1 closed and sticking, 2 closed
  /// and slipping (always 2 when closed without friction: the faces slide freely).
  int pair_state(Index k) const { return pairs_[k].state; }

  /// y += K_c x for every pair closed and sticking: normal springs \f$\varepsilon_N A\, n\otimes n\f$
  /// plus, with friction, tangential ones \f$\varepsilon_T A (I - n\otimes n)\f$. The stiffest
  /// contact state, for the stable time step of the explicit integration; times `scale`.
  void add_closed_stiffness(const VectorX& x, VectorX& y, double scale = 1.0) const;

 private:
  struct Pair {
    Index minus_dof = 0;  ///< first DOF (x) of the minus node; y, z follow
    Index plus_dof = 0;
    Vec3 normal = Vec3::Zero();
    double area = 0.0;
    Vec3 traction = Vec3::Zero();           ///< tangential traction on minus [Pa]
    Vec3 previous_relative = Vec3::Zero();  ///< u_minus - u_plus where the last step left it
    Vec3 force = Vec3::Zero();              ///< force on minus at the last step [N]
    bool counted = true;                    ///< in the sums (false: a ghost pair of another rank)
    int state = 0;                          ///< as pair_state()
  };
  void finish_step(double stored, double dissipated, Index closed, double closed_area, Index slipping);

  ContactOptions options_;
  PenaltyChoice penalty_;
  std::vector<Pair> pairs_;
  double total_area_ = 0.0;
  double stored_energy_ = 0.0;
  double dissipated_energy_ = 0.0;
  Index n_closed_ = 0;
  double closed_area_ = 0.0;
  Index n_slipping_ = 0;
};

}  // namespace crackle::contact
