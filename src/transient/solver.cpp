#include "transient/solver.hpp"

#include <omp.h>

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "core/errors.hpp"
#include "core/resources.hpp"
#include "fem/loads.hpp"
#include "io/csv.hpp"
#include "io/files.hpp"
#include "transient/integrator.hpp"

namespace crackle::transient {
namespace {

/// A load as its nonzero nodal forces per unit amplitude, and its signal.
struct SparseLoad {
  std::string name;
  std::vector<Index> dofs;
  std::vector<double> values;  ///< nodal force per unit of the signal [N]
  Signal signal;
  double current = 0.0;        ///< signal value at the last add_force

  double dot(const VectorX& x) const {
    double sum = 0.0;
    for (std::size_t k = 0; k < dofs.size(); ++k) sum += values[k] * x[dofs[k]];
    return current * sum;
  }
};

std::string seconds_text(double seconds) {
  char buffer[32];
  if (seconds < 120.0) {
    std::snprintf(buffer, sizeof buffer, "%.1f s", seconds);
  } else if (seconds < 7200.0) {
    std::snprintf(buffer, sizeof buffer, "%.1f min", seconds / 60.0);
  } else {
    std::snprintf(buffer, sizeof buffer, "%.1f h", seconds / 3600.0);
  }
  return buffer;
}

}  // namespace

struct TransientSolver::Impl final : SecondOrderSystem {
  Impl(const mesh::Mesh& mesh_, TransientProblem problem_, TransientOptions options_)
      : mesh(mesh_), problem(std::move(problem_)), options(std::move(options_)) {}

  const mesh::Mesh& mesh;
  TransientProblem problem;
  TransientOptions options;
  mesh::DofMap dofs;
  fem::Constraints constraints;
  std::unique_ptr<ElasticOperator> elastic;
  VectorX lumped;        ///< all DOFs
  VectorX moving_mass;   ///< 0 at held DOFs
  VectorX inverse;       ///< 0 at held DOFs
  std::unique_ptr<contact::PenaltyContact> contact;
  std::vector<SparseLoad> loads;
  TimeStepEstimate estimate;
  double dt = 0.0;
  Index steps = 0;
  VectorX displacement, velocity;
  VectorX beta_force;    ///< -beta K V(i-1/2) of the last step (beta > 0)
  std::vector<Index> probe_dofs;

  // Dot products of the sparse force terms with U(i) and V(i-1/2), from add_force.
  double load_dot_displacement = 0.0, load_dot_velocity = 0.0;
  double contact_dot_displacement = 0.0, contact_dot_velocity = 0.0;
  double beta_dot_displacement = 0.0, beta_dot_velocity = 0.0;
  double contact_seconds = 0.0;

  TransientSummary summary;
  ProbeHistory probe_history;
  EnergyHistory energy_history;

  Index n_dofs() const override { return dofs.n_dofs(); }
  const VectorX& mass() const override { return moving_mass; }
  const VectorX& inverse_mass() const override { return inverse; }
  double mass_damping() const override { return options.damping.alpha; }

  void add_force(const ForceInput& input, VectorX& force) override {
    const VectorX& u = input.displacement;
    const VectorX& v = input.velocity;
    elastic->apply_add(-1.0, u, force);  // -K U, eq. (25a)
    if (options.damping.beta > 0.0) {
      beta_force.setZero();
      elastic->apply_add(-options.damping.beta, v, beta_force);  // -beta K V
      force += beta_force;
      beta_dot_displacement = beta_force.dot(u);
      beta_dot_velocity = beta_force.dot(v);
    }
    load_dot_displacement = load_dot_velocity = 0.0;
    for (SparseLoad& load : loads) {  // eq. (25b)
      load.current = load.signal.value(input.time);
      if (load.current == 0.0) continue;
      for (std::size_t k = 0; k < load.dofs.size(); ++k) force[load.dofs[k]] += load.current * load.values[k];
      load_dot_displacement += load.dot(u);
      load_dot_velocity += load.dot(v);
    }
    if (contact) {  // eq. (25d), (15); the implicit form needs the rest of F, so it comes last
      const Stopwatch watch;
      if (contact->implicit()) {
        contact->add_implicit_force(u, v, {input.dt, input.step, options.damping.alpha, &inverse}, force);
      } else {
        contact->add_force(u, force);
      }
      contact_dot_displacement = contact->force_dot(u);
      contact_dot_velocity = contact->force_dot(v);
      contact_seconds += watch.seconds();
    }
  }

  double load_dot(const VectorX& x) const {
    double sum = 0.0;
    for (const SparseLoad& load : loads) {
      if (load.current != 0.0) sum += load.dot(x);
    }
    return sum;
  }

  void warn(const std::string& text) {
    summary.warnings.push_back(text);
    if (options.progress) std::fprintf(stderr, "transient: warning: %s\n", text.c_str());
  }

  void setup();
  void integrate(const TransientCallbacks& callbacks);
};

void TransientSolver::Impl::setup() {
  const Stopwatch watch;
  const TransientOptions& o = options;
  if (!(o.end_time > 0.0) || !std::isfinite(o.end_time)) {
    throw InputError("transient.end_time: expected a time > 0 s, got " + format_number(o.end_time));
  }
  if (!(o.time_step >= 0.0) || !std::isfinite(o.time_step)) {
    throw InputError("transient.time_step: expected a time >= 0 s (0 = automatic), got " + format_number(o.time_step));
  }
  if (o.energy_interval < 1 || o.probe_interval < 1) {
    throw InputError("transient: expected energy_interval >= 1 and probe_interval >= 1, got " +
                     std::to_string(o.energy_interval) + " and " + std::to_string(o.probe_interval));
  }
  if (!(o.energy_tolerance > 0.0) || !(o.growth_factor > 1.0)) {
    throw InputError("transient: expected energy_tolerance > 0 and growth_factor > 1, got " +
                     format_number(o.energy_tolerance) + " and " + format_number(o.growth_factor));
  }
  check_damping(o.damping);

  dofs = mesh::make_dof_map(mesh, o.variant);
  constraints = fem::make_constraints(dofs, problem.dirichlet);
  elastic = std::make_unique<ElasticOperator>(mesh, dofs, problem.materials, o.elastic);
  lumped = fem::assemble_lumped_mass(mesh, dofs, problem.materials);  // eq. (27)
  moving_mass = lumped;
  inverse = lumped.cwiseInverse();
  for (Index k = 0; k < dofs.n_dofs(); ++k) {
    if (constraints.fixed[k]) moving_mass[k] = inverse[k] = 0.0;
  }

  if (problem.contact) {
    if (!mesh.has_crack()) throw InputError("transient.contact: the mesh has no crack");
    if (o.variant != mesh::Variant::open) {
      throw InputError("transient.contact: needs the open variant (crack faces split), got the " +
                       std::string(mesh::variant_name(o.variant)) + " one");
    }
    contact = std::make_unique<contact::PenaltyContact>(mesh, dofs, problem.materials, *problem.contact);
    summary.has_contact = true;
    summary.penalty = contact->penalty();
    summary.friction_coefficient = problem.contact->friction_coefficient;
    summary.contact_implicit = contact->implicit();
  }

  for (std::size_t k = 0; k < problem.loads.size(); ++k) {
    const ExternalLoad& load = problem.loads[k];
    const std::string where = "load '" + (load.name.empty() ? std::to_string(k) : load.name) + "'";
    check_signal(load.signal, where + ".signal");
    if (!std::isfinite(load.amplitude) || !(load.direction.norm() > 0.0)) {
      throw InputError(where + ": expected a finite amplitude and a nonzero direction, got amplitude " +
                       format_number(load.amplitude) + " N");
    }
    const Vec3 total = load.amplitude * load.direction.normalized();
    VectorX pattern = VectorX::Zero(dofs.n_dofs());
    if (!load.faces.empty()) {
      const double area = fem::face_area(mesh, load.faces);
      if (!(area > 0.0)) throw InputError(where + ": the face set has zero area");
      fem::add_face_traction(mesh, dofs, load.faces, total / area, pattern);
    } else {
      if (load.nodes.empty()) throw InputError(where + ": empty node set and no faces");
      fem::add_point_force(dofs, load.nodes, total, pattern);
    }
    SparseLoad sparse;
    sparse.name = load.name;
    sparse.signal = load.signal;
    for (Index d = 0; d < dofs.n_dofs(); ++d) {
      if (pattern[d] != 0.0 && !constraints.fixed[d]) {
        sparse.dofs.push_back(d);
        sparse.values.push_back(pattern[d]);
      }
    }
    loads.push_back(std::move(sparse));
  }

  for (const Probe& probe : problem.probes) {
    if (probe.node < 0 || probe.node >= mesh.n_nodes()) {
      throw InputError("probe '" + probe.name + "': node " + std::to_string(probe.node) + " outside a mesh of " +
                       std::to_string(mesh.n_nodes()) + " nodes");
    }
    for (int c = 0; c < 3; ++c) probe_dofs.push_back(dofs.dof(probe.node, c));
    probe_history.names.push_back(probe.name);
  }
  probe_history.values.assign(9 * problem.probes.size(), {});

  // Stable time step; explicit contact forces add their springs, every one closed (the stiffest
  // state). Implicit ones do not limit it.
  const double beta = o.damping.beta;
  const bool explicit_springs = contact && !contact->implicit();
  auto stiffness = [this, explicit_springs](const VectorX& x, VectorX& y) {
    elastic->apply(x, y);
    if (explicit_springs) contact->add_closed_stiffness(x, y);
  };
  estimate = estimate_time_step(stiffness, inverse, beta, o.time_step_options);
  if (o.time_step > 0.0 && o.time_step > estimate.dt_critical) {
    const std::string text = "time step " + format_number(o.time_step) + " s is above the stable limit dt_critical = " +
                             format_number(estimate.dt_critical) + " s (omega_max = " +
                             format_number(estimate.omega_max) + " rad/s" +
                             (explicit_springs ? " with the contact springs" : std::string()) +
                             (beta > 0.0 ? ", beta = " + format_number(beta) + " s" : std::string()) + ")";
    if (!o.force_time_step) throw InputError("transient.time_step: " + text + "; use a smaller one or force it");
    summary.time_step_forced = true;
    warn(text + ": forced");
  }
  dt = o.time_step > 0.0 ? o.time_step : estimate.dt_stable;
  if (o.time_step <= 0.0 && o.whole_steps_per_period > 0.0) {
    dt = o.whole_steps_per_period / std::ceil(o.whole_steps_per_period / dt);
  }
  if (beta > 0.0) {
    warn("stiffness-proportional damping (beta = " + format_number(beta) + " s, xi = " +
         format_number(estimate.damping_ratio) + " at omega_max) shrinks the stable time step to " +
         format_number(estimate.dt_critical) + " s and costs a second K product per step");
  }
  const double ratio = o.end_time / dt;
  if (ratio > 2e9) throw InputError("transient: end_time / dt = " + format_number(ratio) + " steps is too many");
  steps = std::max<Index>(1, static_cast<Index>(std::ceil(ratio - 1e-9)));

  // Initial state, eq. (6); held DOFs at their prescribed values and at rest.
  const Index n = dofs.n_dofs();
  const InitialConditions& initial = problem.initial;
  if ((initial.displacement.size() != 0 && initial.displacement.size() != n) ||
      (initial.velocity.size() != 0 && initial.velocity.size() != n)) {
    throw InputError("transient.initial: fields of " + std::to_string(initial.displacement.size()) + " and " +
                     std::to_string(initial.velocity.size()) + " values for " + std::to_string(n) + " DOFs");
  }
  displacement = initial.displacement.size() ? initial.displacement : VectorX::Zero(n);
  velocity = initial.velocity.size() ? initial.velocity : VectorX::Zero(n);
  if (!displacement.allFinite() || !velocity.allFinite()) throw InputError("transient.initial: non-finite values");
  for (Index k = 0; k < n; ++k) {
    if (constraints.fixed[k]) {
      displacement[k] = constraints.values[k];
      velocity[k] = 0.0;
    }
  }
  if (contact) contact->reset(displacement);
  if (beta > 0.0) beta_force = VectorX::Zero(n);

  summary.dt = dt;
  summary.dt_critical = estimate.dt_critical;
  summary.omega_max = estimate.omega_max;
  summary.damping = o.damping;
  summary.n_dofs = n;
  summary.n_elements = mesh.n_elements();
  summary.kernel = elastic->info().kernel;
  summary.setup_s = watch.seconds();
}

void TransientSolver::Impl::integrate(const TransientCallbacks& callbacks) {
  const Stopwatch wall;
  const TransientOptions& o = options;
  const Index n_probes = static_cast<Index>(problem.probes.size());
  const double alpha = o.damping.alpha;
  const double beta = o.damping.beta;
  CentralDifference integrator(dofs.n_dofs());
  StepSums sums;
  std::vector<double> sample(9 * n_probes), before(6 * n_probes);

  const double kinetic_initial = 0.5 * velocity.cwiseProduct(moving_mass).dot(velocity);
  double reference = 0.0, initial_physical = 0.0, friction_reference = 0.0;
  double external_work = 0.0, external_work_absolute = 0.0, damping_dissipated = 0.0, scale = 0.0;
  double closed_fraction_sum = 0.0;
  double last_progress = 0.0;
  contact_seconds = 0.0;
  summary.n_threads = omp_get_max_threads();
  summary.status = "running";

  for (Index i = 0; i < steps; ++i) {
    const double time = static_cast<double>(i) * dt;
    const bool sample_energy = i % o.energy_interval == 0 || i + 1 == steps;
    for (Index k = 0; k < 3 * n_probes; ++k) {
      before[k] = displacement[probe_dofs[k]];
      before[3 * n_probes + k] = velocity[probe_dofs[k]];
    }
    integrator.step(*this, time, i == 0 ? 0.0 : dt, dt, displacement, velocity,
                    sample_energy || alpha > 0.0 ? &sums : nullptr);
    const double h = i == 0 ? 0.5 * dt : dt;
    for (Index p = 0; p < n_probes; ++p) {
      for (int c = 0; c < 3; ++c) {
        const Index k = 3 * p + c;
        const double v_old = before[3 * n_probes + k], v_new = velocity[probe_dofs[k]];
        sample[9 * p + c] = before[k];
        sample[9 * p + 3 + c] = i == 0 ? v_old : 0.5 * (v_old + v_new);
        sample[9 * p + 6 + c] = (v_new - v_old) / h;
      }
    }
    if (i % o.probe_interval == 0) {
      probe_history.time.push_back(time);
      for (std::size_t c = 0; c < sample.size(); ++c) probe_history.values[c].push_back(sample[c]);
    }

    // Work of the loads and dissipation of damping over [t_{i-1/2}, t_{i+1/2}] (from the second step).
    const double load_dot_new = load_dot(velocity);
    const double contact_dot_new = contact ? contact->force_dot(velocity) : 0.0;
    const double beta_dot_new = beta > 0.0 ? beta_force.dot(velocity) : 0.0;
    if (i >= 1) {
      const double work = 0.5 * dt * (load_dot_velocity + load_dot_new);
      external_work += work;
      external_work_absolute += std::abs(work);
      if (alpha > 0.0) damping_dissipated += sums.mass_damping_dissipation;
      if (beta > 0.0) damping_dissipated -= 0.5 * dt * (beta_dot_velocity + beta_dot_new);
    }
    if (contact && contact->total_area() > 0.0) closed_fraction_sum += contact->closed_area() / contact->total_area();

    if (sample_energy) {
      // U_i . K U_i and V_{i+1/2} . K U_i from the fused sums, less the sparse terms' shares.
      const double ku_u = -(sums.force_displacement - load_dot_displacement - contact_dot_displacement - beta_dot_displacement);
      const double ku_v = -(sums.force_velocity - load_dot_new - contact_dot_new - beta_dot_new);
      const double strain = 0.5 * ku_u;
      // Penalty energy: explicit forces at U(i) get the same modified form as the strain energy;
      // implicit ones are those of U(i+1), stored at the end of the step.
      const double penalty = contact ? contact->stored_energy() : 0.0;
      const double penalty_modified = contact && !contact->implicit() ? penalty - 0.5 * dt * contact_dot_new : penalty;
      const double modified = sums.kinetic_half + strain + 0.5 * dt * ku_v + penalty_modified;
      const double kinetic = i == 0 ? kinetic_initial : sums.kinetic_mid;
      const double physical = kinetic + strain + penalty;
      if (i == 0) {
        reference = modified;
        initial_physical = physical;
        friction_reference = contact ? contact->dissipated_energy() : 0.0;
      }
      const double friction = contact ? contact->dissipated_energy() - friction_reference : 0.0;
      const double balance = modified - reference - external_work + damping_dissipated + friction;
      scale = std::max({scale, physical, std::abs(reference), initial_physical, external_work_absolute});
      const double relative = scale > 0.0 ? std::abs(balance) / scale : 0.0;
      energy_history.time.push_back(time);
      energy_history.kinetic.push_back(kinetic);
      energy_history.strain.push_back(strain);
      energy_history.contact.push_back(penalty);
      energy_history.external_work.push_back(external_work);
      energy_history.damping.push_back(damping_dissipated);
      energy_history.friction.push_back(friction);
      energy_history.balance.push_back(balance);
      energy_history.relative_error.push_back(relative);
      summary.steps = i + 1;
      summary.time = static_cast<double>(i + 1) * dt;
      const std::string where = " at step " + std::to_string(i) + " (t = " + format_number(time) + " s)";
      const std::string step_text = "; time step " + format_number(dt) + " s, dt_critical " +
                                    format_number(estimate.dt_critical) + " s";
      if (!std::isfinite(balance) || !std::isfinite(physical) || !std::isfinite(modified)) {
        throw SolverError("transient: non-finite displacement or velocity" + where + step_text);
      }
      const double budget = initial_physical + external_work_absolute;
      if (physical > o.growth_factor * budget) {
        throw SolverError("transient: unstable, energy " + format_number(physical) + " J grew beyond " +
                          format_number(o.growth_factor) + " times the energy put in (" + format_number(budget) +
                          " J)" + where + step_text);
      }
      summary.energy_error = std::max(summary.energy_error, relative);
      if (relative > o.energy_tolerance) {
        throw SolverError("transient: energy balance error " + format_number(relative) + " exceeds the tolerance " +
                          format_number(o.energy_tolerance) + where + step_text);
      }
    }
    summary.steps = i + 1;
    summary.time = static_cast<double>(i + 1) * dt;
    summary.contact_fraction = closed_fraction_sum / static_cast<double>(i + 1);

    if (callbacks.on_step) {
      const StepView view{i, time, dt, sample, displacement, velocity};
      if (callbacks.on_step(view)) {
        summary.status = "stopped";
        summary.message = "stopped by a callback at step " + std::to_string(i) + " (t = " + format_number(time) + " s)";
        break;
      }
    }
    if (o.progress && (i & 63) == 63) {
      const double elapsed = wall.seconds();
      if (elapsed - last_progress >= o.progress_interval) {
        last_progress = elapsed;
        const double done = static_cast<double>(i + 1) / static_cast<double>(steps);
        std::fprintf(stderr, "transient: step %lld/%lld (%.1f%%), t = %.4g s, elapsed %s, ETA %s\n",
                     static_cast<long long>(i + 1), static_cast<long long>(steps), 100.0 * done, summary.time,
                     seconds_text(elapsed).c_str(),
                     seconds_text(elapsed * (1.0 - done) / done).c_str());
      }
    }
  }
  if (summary.status == "running") summary.status = "completed";
  summary.wall_s = wall.seconds();
  summary.contact_time_fraction = summary.wall_s > 0.0 ? contact_seconds / summary.wall_s : 0.0;
  summary.ns_per_dof_step =
      summary.steps > 0 ? 1e9 * summary.wall_s / (static_cast<double>(summary.steps) * dofs.n_dofs()) : 0.0;
}

TransientSolver::TransientSolver(const mesh::Mesh& mesh, TransientProblem problem, TransientOptions options)
    : impl_(std::make_unique<Impl>(mesh, std::move(problem), std::move(options))) {
  impl_->setup();
}

TransientSolver::~TransientSolver() = default;

const mesh::DofMap& TransientSolver::dofs() const { return impl_->dofs; }
const fem::Constraints& TransientSolver::constraints() const { return impl_->constraints; }
const TimeStepEstimate& TransientSolver::time_step_estimate() const { return impl_->estimate; }
double TransientSolver::dt() const { return impl_->dt; }
Index TransientSolver::n_steps() const { return impl_->steps; }
const contact::PenaltyContact* TransientSolver::contact() const { return impl_->contact.get(); }
const ElasticOperator& TransientSolver::elastic_operator() const { return *impl_->elastic; }
const VectorX& TransientSolver::lumped_mass() const { return impl_->lumped; }
const TransientSummary& TransientSolver::summary() const { return impl_->summary; }
const ProbeHistory& TransientSolver::probes() const { return impl_->probe_history; }
const EnergyHistory& TransientSolver::energy() const { return impl_->energy_history; }
const VectorX& TransientSolver::displacement() const { return impl_->displacement; }
const VectorX& TransientSolver::velocity() const { return impl_->velocity; }

const TransientSummary& TransientSolver::run(const TransientCallbacks& callbacks) {
  Impl& impl = *impl_;
  const Stopwatch wall;
  auto finish = [&]() {
    if (!impl.options.output_directory.empty()) write_transient_outputs(impl.options.output_directory, *this);
    if (callbacks.on_finish) callbacks.on_finish(impl.summary);
  };
  try {
    impl.integrate(callbacks);
  } catch (const SolverError& error) {
    impl.summary.status = "unstable";
    impl.summary.message = error.what();
    impl.summary.wall_s = wall.seconds();
    try {
      finish();
    } catch (const std::exception& secondary) {
      throw SolverError(std::string(error.what()) + " (and writing the output failed: " + secondary.what() + ")");
    }
    throw;
  }
  finish();
  return impl.summary;
}

void write_probe_csv(const std::filesystem::path& path, const ProbeHistory& probes) {
  io::CsvTable table;
  table.add("time [s]", probes.time);
  static const char* quantities[3] = {"u", "v", "a"};
  static const char* units[3] = {"m", "m/s", "m/s^2"};
  for (std::size_t p = 0; p < probes.names.size(); ++p) {
    for (int q = 0; q < 3; ++q) {
      for (int c = 0; c < 3; ++c) {
        table.add(probes.names[p] + " " + quantities[q] + "_" + axis_name(c) + " [" + units[q] + "]",
                  probes.values[9 * p + 3 * q + c]);
      }
    }
  }
  io::write_csv(path, table);
}

void write_energy_csv(const std::filesystem::path& path, const EnergyHistory& energy) {
  io::CsvTable table;
  table.add("time [s]", energy.time);
  table.add("kinetic [J]", energy.kinetic);
  table.add("strain [J]", energy.strain);
  table.add("contact [J]", energy.contact);
  table.add("external_work [J]", energy.external_work);
  table.add("damping [J]", energy.damping);
  table.add("friction [J]", energy.friction);
  table.add("balance [J]", energy.balance);
  table.add("relative_error [-]", energy.relative_error);
  io::write_csv(path, table);
}

void write_transient_json(const std::filesystem::path& path, const TransientSummary& summary) {
  nlohmann::json json;
  json["status"] = summary.status;
  json["message"] = summary.message;
  json["steps"] = summary.steps;
  json["time"] = summary.time;
  json["dt"] = summary.dt;
  json["dt_critical"] = summary.dt_critical;
  json["omega_max"] = summary.omega_max;
  json["time_step_forced"] = summary.time_step_forced;
  if (summary.has_contact) {
    json["penalty"] = summary.penalty.normal_penalty;
    json["penalty_tangential"] = summary.penalty.tangential_penalty;
    json["penalty_auto"] = summary.penalty.automatic;
    if (summary.penalty.automatic) {
      json["penalty_factor"] = summary.penalty.factor;
      json["penalty_modulus"] = summary.penalty.modulus;
      json["penalty_element_size"] = summary.penalty.element_size;
    }
    json["friction"] = summary.friction_coefficient;
    json["contact_integration"] = summary.contact_implicit ? "implicit" : "explicit";
  } else {
    json["penalty"] = nullptr;
  }
  json["damping"] = {{"alpha", summary.damping.alpha}, {"beta", summary.damping.beta}};
  json["energy_error"] = summary.energy_error;
  json["contact_fraction"] = summary.contact_fraction;
  json["contact_time_fraction"] = summary.contact_time_fraction;
  json["wall_s"] = summary.wall_s;
  json["setup_s"] = summary.setup_s;
  json["ns_per_dof_step"] = summary.ns_per_dof_step;
  json["dofs"] = summary.n_dofs;
  json["elements"] = summary.n_elements;
  json["threads"] = summary.n_threads;
  json["kernel"] = summary.kernel;
  json["warnings"] = summary.warnings;
  io::write_json(path, json);
}

void write_transient_outputs(const std::filesystem::path& directory, const TransientSolver& solver) {
  io::ensure_directory(directory);
  write_probe_csv(directory / "probes.csv", solver.probes());
  write_energy_csv(directory / "energy.csv", solver.energy());
  write_transient_json(directory / "transient.json", solver.summary());
}

}  // namespace crackle::transient
