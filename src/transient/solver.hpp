#pragma once
/// \file A transient run: the semi-discrete system (MODEL.md eq. 26) with the matrix-free elastic
/// forces, Rayleigh damping, loads and crack-face contact as force terms, integrated by central
/// differences (eq. 28) with health checks, probes, energy balance and per-step callbacks.
///
/// Energy balance. Central differences conserve exactly, for a linear undamped system, the
/// modified energy \f$E_{i+1/2} = \tfrac12 V_{i+1/2}^T M V_{i+1/2} + \tfrac12 U_i^T K U_{i+1}\f$
/// (= kinetic + strain + \f$\tfrac{\Delta t}{2} V_{i+1/2}^T K U_i\f$), and its change over a step is
/// the work \f$F_i \cdot (U_{i+1} - U_{i-1})/2\f$ of the other forces. The run tracks
/// \f$E_{i+1/2} + \tilde\Phi_c - W_{ext} + D_{damping} + D_{friction}\f$, with \f$\tilde\Phi_c\f$ the
/// penalty energy (written the same way for explicit contact forces; at U(i+1) for implicit ones):
/// its drift from the first step is the energy error, caused only by the contact (its
/// nonlinearity, and the numerical dissipation of the implicit pair springs) and rounding. energy.csv shows the physical energies
/// (kinetic at t_i from the mean velocity, strain, penalty).
#include <filesystem>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "contact/contact.hpp"
#include "fem/assembly.hpp"
#include "fem/constraints.hpp"
#include "mesh/mesh.hpp"
#include "transient/damping.hpp"
#include "transient/elastic_operator.hpp"
#include "transient/excitation.hpp"
#include "transient/time_step.hpp"

namespace crackle::transient {

/// A probe records displacement, velocity and acceleration (3 components each) of one node.
struct Probe {
  std::string name;  ///< column prefix in the CSV
  Index node = 0;
};

/// Options of a run (the scene's `transient:` section).
struct TransientOptions {
  double end_time = 0.0;         ///< [s]; the run takes ceil(end_time / dt) steps
  double time_step = 0.0;        ///< [s]; 0 = time_step_options.safety_factor * dt_critical
  /// With an automatic time step: if > 0, dt is lowered to the largest step that divides this
  /// period [s] into whole steps, so that harmonics fall on exact DFT bins (spectral module).
  double whole_steps_per_period = 0.0;
  /// Run a time step above dt_critical anyway (the health checks will stop it if it diverges);
  /// without it such a step is refused with InputError before the run starts.
  bool force_time_step = false;
  TimeStepOptions time_step_options;
  RayleighDamping damping;
  /// DOF map of the run: `open` (crack faces split, with contact) or `uncracked` (faces tied).
  mesh::Variant variant = mesh::Variant::open;
  int energy_interval = 10;        ///< steps between energy samples (health checks, energy.csv rows)
  double energy_tolerance = 0.05;  ///< relative energy-balance error that stops the run
  /// The run stops as unstable when kinetic + strain + penalty energy exceeds this factor times the
  /// energy put in (initial energy + the absolute work of the loads).
  double growth_factor = 10.0;
  int probe_interval = 1;          ///< steps between probe rows
  bool progress = true;            ///< progress line with ETA on stderr
  double progress_interval = 1.0;  ///< [s] between progress lines
  /// If not empty, probes.csv, energy.csv and transient.json are written there when the run ends,
  /// also when it fails (then with "status": "unstable" and what was computed so far).
  std::filesystem::path output_directory;
  ElasticOperatorOptions elastic;
};

/// The physics of a run (the lead fills it from the scene's model).
struct TransientProblem {
  fem::Materials materials;                        ///< by region
  std::vector<fem::DirichletCondition> dirichlet;  ///< held DOFs (constant values)
  std::optional<contact::ContactOptions> contact;  ///< crack-face contact (open variant with a crack)
  std::vector<ExternalLoad> loads;
  InitialConditions initial;                       ///< over the DOFs of make_dof_map(mesh, variant)
  std::vector<Probe> probes;
};

/// Probe rows: times and, per probe, 9 columns u_x..u_z [m], v_x..v_z [m/s], a_x..a_z [m/s^2] at t_i.
struct ProbeHistory {
  std::vector<std::string> names;
  std::vector<double> time;
  std::vector<std::vector<double>> values;  ///< values[9 * probe + column][row]
};

/// Energy rows every energy_interval steps [J].
struct EnergyHistory {
  std::vector<double> time;
  std::vector<double> kinetic;        ///< 1/2 V_i^T M V_i, V_i the mean of the half-step velocities
  std::vector<double> strain;         ///< 1/2 U_i^T K U_i
  std::vector<double> contact;        ///< penalty springs (normal + tangential)
  std::vector<double> external_work;  ///< work of the loads since the first step
  std::vector<double> damping;        ///< dissipated by Rayleigh damping since the first step
  std::vector<double> friction;       ///< dissipated by friction since the first step
  std::vector<double> balance;        ///< drift of the modified energy balance
  std::vector<double> relative_error; ///< |balance| / energy scale
};

/// What a run did (transient.json).
struct TransientSummary {
  std::string status = "not run";  ///< "completed", "stopped" (by a callback), "unstable"
  std::string message;
  Index steps = 0;
  double time = 0.0;               ///< t at the end [s]
  double dt = 0.0;
  double dt_critical = 0.0;
  double omega_max = 0.0;          ///< [rad/s], with the margin
  bool time_step_forced = false;
  bool has_contact = false;
  contact::PenaltyChoice penalty;
  double friction_coefficient = 0.0;
  bool contact_implicit = true;
  RayleighDamping damping;
  double energy_error = 0.0;       ///< largest relative energy-balance error seen
  double contact_fraction = 0.0;   ///< time average of the closed fraction of the crack area
  double contact_time_fraction = 0.0;  ///< share of the step time spent in the contact forces
  double wall_s = 0.0;             ///< run time [s]
  double setup_s = 0.0;            ///< operator, mass, time-step estimate [s]
  double ns_per_dof_step = 0.0;
  Index n_dofs = 0;
  Index n_elements = 0;
  int n_threads = 1;
  std::string kernel;
  std::vector<std::string> warnings;
};

/// What a per-step callback sees after step i.
struct StepView {
  Index step = 0;             ///< i
  double time = 0.0;          ///< t_i of the probe sample [s]
  double dt = 0.0;
  /// Probe values at t_i, 9 per probe in Probe order (as ProbeHistory columns), every step.
  const std::vector<double>& probe_sample;
  const VectorX& displacement;  ///< U(i+1)
  const VectorX& velocity;      ///< V(i+1/2)
};

struct TransientCallbacks {
  /// Called after every step; return true to end the run early (e.g. steady state reached).
  std::function<bool(const StepView&)> on_step;
  /// Called once when the run ends, also when it fails (before the exception leaves run()).
  std::function<void(const TransientSummary&)> on_finish;
};

/// A transient run. The constructor builds everything and checks the time step (InputError for a
/// step above dt_critical unless forced); run() integrates.
class TransientSolver {
 public:
  /// `mesh` is borrowed and must outlive the solver.
  TransientSolver(const mesh::Mesh& mesh, TransientProblem problem, TransientOptions options);
  ~TransientSolver();

  const mesh::DofMap& dofs() const;
  const fem::Constraints& constraints() const;
  const TimeStepEstimate& time_step_estimate() const;
  double dt() const;
  Index n_steps() const;
  const contact::PenaltyContact* contact() const;  ///< null without contact
  const ElasticOperator& elastic_operator() const;
  const VectorX& lumped_mass() const;              ///< eq. (27), per DOF, all DOFs

  /// Integrates to end_time (or until a callback asks to stop). SolverError when the health
  /// checks fail (NaN/Inf, energy growth, energy balance), after flushing outputs and on_finish.
  const TransientSummary& run(const TransientCallbacks& callbacks = {});

  const TransientSummary& summary() const;
  const ProbeHistory& probes() const;
  const EnergyHistory& energy() const;
  const VectorX& displacement() const;  ///< U at the end (U(i+1) after the last step)
  const VectorX& velocity() const;      ///< V(i+1/2) after the last step

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

/// probes.csv: "time [s]", then per probe "<name> u_x [m]" ... "<name> a_z [m/s^2]".
void write_probe_csv(const std::filesystem::path& path, const ProbeHistory& probes);
/// energy.csv: time and the EnergyHistory columns with units.
void write_energy_csv(const std::filesystem::path& path, const EnergyHistory& energy);
/// transient.json: the summary (public names: steps, dt, dt_critical, penalty, energy_error,
/// contact_fraction, wall_s, and more).
void write_transient_json(const std::filesystem::path& path, const TransientSummary& summary);
/// The three files above into a directory (created if needed).
void write_transient_outputs(const std::filesystem::path& directory, const TransientSolver& solver);

}  // namespace crackle::transient
