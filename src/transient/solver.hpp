#pragma once
/// \file A transient run: the semi-discrete system (MODEL.md eq. 26) of one fem::System (lumped
/// mass, K as an operator) with force terms plugged in (fem::ForceTerm: stiffness-proportional
/// damping, loads, and from outside the crack contact), integrated by central differences (eq. 28)
/// with health checks, probes, energy balance and per-step callbacks. The solver computes; it
/// writes no file (the run pipeline does, once).
///
/// Energy balance. Central differences conserve exactly, for a linear undamped system, the
/// modified energy \f$E_{i+1/2} = \tfrac12 V_{i+1/2}^T M V_{i+1/2} + \tfrac12 U_i^T K U_{i+1}\f$
/// (= kinetic + strain + \f$\tfrac{\Delta t}{2} V_{i+1/2}^T K U_i\f$), and its change over a step is
/// the work \f$F_i \cdot (U_{i+1} - U_{i-1})/2\f$ of the other forces. The run tracks
/// \f$E_{i+1/2} + \tilde\Phi - W_{ext} + D_{damping} + D_{internal}\f$, a loop over the force terms
/// by their fem::EnergyRole: the stored energy \f$\tilde\Phi\f$ of the potential terms (written the
/// modified way for forces of U(i), as is for forces of U(i+1)), the work of the external ones, the
/// work of the dissipative ones and the terms' internal dissipation (friction). Its drift from the
/// first step is the energy error, caused only by the nonlinear terms and rounding. The elastic
/// term's dot products come from the integrator's fused sums less those of the other terms (one
/// pass less over memory). energy.csv shows the physical energies (kinetic at t_i from the mean
/// velocity, strain, penalty).
#include <filesystem>
#include <functional>
#include <map>
#include <memory>
#include <string>
#include <vector>


#include "fem/force_term.hpp"
#include "fem/system.hpp"
#include "transient/damping.hpp"
#include "transient/distribution.hpp"
#include "transient/excitation.hpp"
#include "transient/time_step.hpp"

namespace crackle::transient {

/// A probe records displacement, velocity and acceleration (3 components each) of one node, or, as a
/// crack-opening probe, of one crack pair's relative motion in the pair's frame: the normal gap
/// \f$g_N = g_0 + (u^- - u^+)\cdot n^+\f$ (MODEL.md eq. 9) and the slip along two tangents (eq. 10).
struct Probe {
  std::string name;  ///< column prefix in the CSV
  Index node = 0;    ///< the node; for an opening probe the pair's plus node
  /// Crack-opening probe: the pair's minus node (-1: a node probe), its frame (rows n+, t1, t2) and g0.
  Index minus_node = -1;
  Eigen::Matrix3d frame = Eigen::Matrix3d::Identity();
  double initial_gap = 0.0;
  /// Opening probe: the contact state of its pair as the last contact evaluation left it (0 open,
  /// 1 stick, 2 slip); empty: the state follows from the gap (0 if g_N >= 0, else 2).
  std::function<int()> state;
  /// True when that evaluation is at the end of the step (implicit contact: U(i+1)), so the row of
  /// t_i reads the state before step i; false when it is at U(i) (explicit), read after the step.
  bool state_at_step_end = false;
  bool opening() const { return minus_node >= 0; }
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
  /// DOF map of the run when the solver builds its own system: `open` (crack faces split) or
  /// `uncracked` (faces tied).
  mesh::Variant variant = mesh::Variant::open;
  int energy_interval = 10;        ///< steps between energy samples (health checks, energy.csv rows)
  double energy_tolerance = 0.05;  ///< relative energy-balance error that stops the run
  /// The run stops as unstable when kinetic + strain + penalty energy exceeds this factor times the
  /// energy put in (initial energy + the absolute work of the loads).
  double growth_factor = 10.0;
  int probe_interval = 1;          ///< steps between probe rows
  bool progress = true;            ///< progress line with ETA on stderr
  /// How messages name the run length and the time step (`file:line: transient.periods`); the
  /// bare key names when empty.
  std::string run_length_key;
  std::string time_step_key;
  double progress_interval = 1.0;  ///< [s] between progress lines
  /// A distributed run on hexahedra: apply the boundary elements, start the halo, apply the
  /// interior elements while it travels (false: all elements, then the halo; the same sums, one
  /// thread: bitwise). Off by default: with shared-memory MPI on one machine it measured no gain
  /// (p = 2) or a loss (p = 1, ~10 %), docs/benchmarks.md section 10.
  bool overlap_halo = false;
  fem::ElasticOperatorOptions elastic;
};

/// The physics of a run besides the linear system.
struct TransientProblem {
  fem::Materials materials;                        ///< by region (when the solver builds its system)
  std::vector<fem::DirichletCondition> dirichlet;  ///< held DOFs (when the solver builds its system)
  std::vector<ExternalLoad> loads;
  InitialConditions initial;                       ///< over the DOFs of the system's DOF map
  std::vector<Probe> probes;
  /// Force terms plugged in from outside (the crack contact), over the system's DOFs; evaluated
  /// after the damping and the loads, a term that needs the other forces last.
  std::vector<std::shared_ptr<fem::ForceTerm>> terms;
  /// Null: one process. Otherwise the run is this rank's share of a distributed run: the system is
  /// the rank's local mesh (its elements; owned nodes first, then ghosts), the initial fields are
  /// over its local DOFs, a probe whose node another rank owns has node -1, loads are placed on the
  /// rank's own faces (their shares are summed by the halo), and the plugged-in terms are pointwise
  /// over pairs of local nodes (evaluated after the halo completed the other forces, on owned and
  /// ghost pairs alike; their sums count owned pairs only). All ranks call run() together.
  std::shared_ptr<const Distribution> distribution;
};

/// Probe rows: times and, per probe, 9 columns u_x..u_z [m], v_x..v_z [m/s], a_x..a_z [m/s^2] at t_i
/// (an opening probe: gap, slip_1, slip_2 [m], their rates and accelerations, and its state).
struct ProbeHistory {
  std::vector<std::string> names;
  std::vector<char> opening;                ///< per probe: a crack-opening probe
  std::vector<double> time;
  std::vector<std::vector<double>> values;  ///< values[9 * probe + column][row]
  std::vector<std::vector<double>> states;  ///< per probe: contact state per row (opening probes only)
};

/// Energy rows every energy_interval steps [J].
struct EnergyHistory {
  std::vector<double> time;
  std::vector<double> kinetic;        ///< 1/2 V_i^T M V_i, V_i the mean of the half-step velocities
  std::vector<double> strain;         ///< 1/2 U_i^T K U_i
  std::vector<double> contact;        ///< stored in the potential terms besides K (penalty springs)
  std::vector<double> external_work;  ///< work of the loads since the first step
  std::vector<double> damping;        ///< dissipated by Rayleigh damping since the first step
  std::vector<double> friction;       ///< dissipated inside the terms (friction) since the first step
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
  RayleighDamping damping;
  double energy_error = 0.0;       ///< largest relative energy-balance error seen
  double contact_fraction = 0.0;   ///< time average of the terms' active fraction (closed crack area)
  std::map<std::string, double> term_seconds;  ///< time spent in each plugged-in force term [s]
  double wall_s = 0.0;             ///< run time [s]
  double setup_s = 0.0;            ///< operator, mass, time-step estimate [s]
  double ns_per_dof_step = 0.0;
  Index n_dofs = 0;
  Index n_elements = 0;
  int n_threads = 1;
  int ranks = 1;                   ///< MPI ranks of a distributed run
  Index elements_min = 0;          ///< fewest elements of a rank (the partition's balance)
  Index elements_max = 0;          ///< most elements of a rank
  bool halo_overlapped = false;    ///< interior elements applied while the halo travelled
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
  /// Text appended to each progress line (e.g. how far the steady-state detector is, with its
  /// own ETA): the line's ETA counts to the end time, a run that stops early ends sooner.
  std::function<std::string(double elapsed_s)> progress_note;
};

/// A transient run. The constructor builds everything and checks the time step (InputError for a
/// step above dt_critical unless forced); run() integrates.
class TransientSolver {
 public:
  /// Over a shared system (its lumped mass and K); problem.materials and dirichlet are unused.
  TransientSolver(std::shared_ptr<const fem::System> system, TransientProblem problem, TransientOptions options);
  /// Builds its own system from `mesh` (borrowed, must outlive the solver), problem.materials,
  /// problem.dirichlet and options.variant.
  TransientSolver(const mesh::Mesh& mesh, TransientProblem problem, TransientOptions options);
  ~TransientSolver();

  const fem::System& system() const;
  const mesh::DofMap& dofs() const;
  const fem::Constraints& constraints() const;
  const TimeStepEstimate& time_step_estimate() const;
  double dt() const;
  Index n_steps() const;
  const fem::ElasticOperator& elastic_operator() const;
  const VectorX& lumped_mass() const;              ///< eq. (27), per DOF, all DOFs

  /// Steps between probe rows (TransientOptions::probe_interval), set before run().
  void set_probe_interval(Index steps);

  /// Integrates to end_time (or until a callback asks to stop). SolverError when the health
  /// checks fail (NaN/Inf, energy growth, energy balance), after on_finish.
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

}  // namespace crackle::transient
