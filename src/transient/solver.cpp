#include "transient/solver.hpp"

#include <omp.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <exception>

#include "core/errors.hpp"
#include "core/interrupt.hpp"
#include "core/resources.hpp"
#include "transient/force_terms.hpp"
#include "transient/integrator.hpp"

namespace crackle::transient {
namespace {

/// K plus the springs of the terms that bound the stable step (every contact spring closed).
class StableStepOperator final : public linalg::LinearOperator {
 public:
  StableStepOperator(const linalg::LinearOperator& stiffness, const std::vector<std::shared_ptr<fem::ForceTerm>>& terms,
                     const Distribution* distribution)
      : stiffness_(stiffness), terms_(terms), distribution_(distribution) {}
  Index n_rows() const override { return stiffness_.n_rows(); }
  void apply(const VectorX& x, VectorX& y) const override {
    stiffness_.apply(x, y);
    if (distribution_) distribution_->complete(y);  // element shares summed; the pair springs are pointwise
    for (const auto& term : terms_) term->add_stiffness_bound(x, y);
  }
  void apply_add(double scale, const VectorX& x, VectorX& y) const override {
    VectorX product;
    apply(x, product);
    y += scale * product;
  }

 private:
  const linalg::LinearOperator& stiffness_;
  const std::vector<std::shared_ptr<fem::ForceTerm>>& terms_;
  const Distribution* distribution_;
};

/// Where a distributed run's element kernels are cut: after the boundary elements, and in the
/// middle of the interior (TransientSolver::Impl::add_force_overlapped). Set with or without
/// overlap_halo, so that both apply the same chunks.
std::vector<Index> elastic_cuts(const mesh::Mesh& mesh, const Distribution& distribution) {
  const Index boundary = distribution.n_boundary_elements();
  return {boundary, boundary + (mesh.n_elements() - boundary) / 2};
}

/// A term's dot products with U(i) and V(i-1/2) from its add_force, and its time.
struct TermRecord {
  double dot_displacement = 0.0;
  double dot_velocity = 0.0;
  double dot_velocity_new = 0.0;  ///< with V(i+1/2), after the step
  double stored = 0.0;            ///< stored_energy() after the step
  double dissipated = 0.0;        ///< dissipated_energy() after the step
  double active = 0.0;            ///< active_fraction() after the step
  double seconds = 0.0;
};

}  // namespace

struct TransientSolver::Impl final : SecondOrderSystem {
  Impl(TransientProblem problem_, TransientOptions options_)
      : problem(std::move(problem_)), options(std::move(options_)) {}

  TransientProblem problem;
  TransientOptions options;
  std::shared_ptr<const fem::System> system;
  const fem::ElasticOperator* elastic = nullptr;
  VectorX moving_mass;   ///< 0 at held DOFs
  VectorX inverse;       ///< 0 at held DOFs
  /// Damping, loads, then the plugged-in terms (one needing the other forces last).
  std::vector<std::shared_ptr<fem::ForceTerm>> terms;
  std::vector<TermRecord> records;
  TimeStepEstimate estimate;
  double dt = 0.0;
  Index steps = 0;
  VectorX displacement, velocity;
  std::vector<Index> probe_dofs;        ///< 3 per probe: the node's (an opening probe's plus node); -1 on another rank's
  std::vector<Index> probe_minus_dofs;  ///< 3 per probe: an opening probe's minus node, else -1
  std::vector<double> rank_sums;        ///< sum_over_ranks' buffer, reused every step

  /// A probe's three readings of a field: the node's components, or the pair's relative motion in
  /// its frame (plus g0 on the normal for the displacement); zeros on a rank that does not own it
  /// (the sum over ranks is the owner's reading).
  Vec3 probe_reading(Index p, const VectorX& field, bool is_displacement) const {
    Vec3 value = Vec3::Zero();
    if (probe_dofs[3 * p] < 0) return value;
    for (int c = 0; c < 3; ++c) value[c] = field[probe_dofs[3 * p + c]];
    const Probe& probe = problem.probes[p];
    if (!probe.opening()) return value;
    Vec3 minus;
    for (int c = 0; c < 3; ++c) minus[c] = field[probe_minus_dofs[3 * p + c]];
    Vec3 relative = probe.frame * (minus - value);
    if (is_displacement) relative[0] += probe.initial_gap;
    return relative;
  }

  TransientSummary summary;
  ProbeHistory probe_history;
  EnergyHistory energy_history;

  Index n_dofs() const override { return system->n_dofs(); }
  Index n_owned() const override { return distribution ? distribution->n_owned_dofs() : n_dofs(); }
  const Distribution* distribution = nullptr;
  /// Terms before this index add element shares (damping, loads); the halo completes the force
  /// after them, before the plugged-in pointwise terms (distributed runs only).
  std::size_t halo_before = 0;
  const VectorX& mass() const override { return moving_mass; }
  const VectorX& inverse_mass() const override { return inverse; }
  double mass_damping() const override { return options.damping.alpha; }

  /// Distributed runs whose elements can be applied in ranges: the boundary elements
  /// [0, boundary_end), then the interior [boundary_end, n) in two halves cut at interior_middle.
  bool overlap = false;
  Index boundary_end = 0, interior_middle = 0;
  StiffnessDamping* damping_term = nullptr;  ///< terms[0] when beta > 0

  void add_force(const fem::StepInput& input, VectorX& force) override {
    if (overlap) {
      add_force_overlapped(input, force);
      return;
    }
    elastic->apply_add(-1.0, input.displacement, force);  // -K U, eq. (25a)
    for (std::size_t k = 0; k < terms.size(); ++k) {
      if (distribution && k == halo_before) distribution->complete(force);
      const Stopwatch watch;
      terms[k]->add_force(input, force);
      records[k].dot_displacement = terms[k]->force_dot(input.displacement);
      records[k].dot_velocity = terms[k]->force_dot(input.velocity);
      records[k].seconds += watch.seconds();
    }
    if (distribution && halo_before == terms.size()) distribution->complete(force);
  }

  /// add_force with the halo overlapped: the element terms (-K U, -beta K V) over the boundary
  /// elements and the loads, then the scatter-add of the ghost shares starts; the first half of
  /// the interior while it travels, then the sums go back to the ghosts while the second half
  /// runs (the interior touches no DOF another rank holds); then the pointwise terms.
  void add_force_overlapped(const fem::StepInput& input, VectorX& force) {
    const Index n_elements = elastic->info().n_elements;
    const Index ranges[3][2] = {{0, boundary_end}, {boundary_end, interior_middle}, {interior_middle, n_elements}};
    const auto apply_range = [&](int r) {
      elastic->apply_add_elements(-1.0, input.displacement, force, ranges[r][0], ranges[r][1]);
      if (damping_term) {
        const Stopwatch watch;
        damping_term->add_part(*elastic, input, force, ranges[r][0], ranges[r][1]);
        records[0].seconds += watch.seconds();
      }
    };
    if (damping_term) damping_term->clear_parts();
    apply_range(0);
    for (std::size_t k = damping_term ? 1 : 0; k < halo_before; ++k) add_term_force(k, input, force);
    distribution->send_shares(force);
    apply_range(1);
    distribution->receive_sums(force);
    apply_range(2);
    distribution->receive_ghosts(force);
    if (damping_term) {
      records[0].dot_displacement = damping_term->force_dot(input.displacement);
      records[0].dot_velocity = damping_term->force_dot(input.velocity);
    }
    for (std::size_t k = halo_before; k < terms.size(); ++k) add_term_force(k, input, force);
  }

  void add_term_force(std::size_t k, const fem::StepInput& input, VectorX& force) {
    const Stopwatch watch;
    terms[k]->add_force(input, force);
    records[k].dot_displacement = terms[k]->force_dot(input.displacement);
    records[k].dot_velocity = terms[k]->force_dot(input.velocity);
    records[k].seconds += watch.seconds();
  }

  void warn(const std::string& text) {
    summary.warnings.push_back(text);
    if (options.progress && (!distribution || distribution->rank() == 0)) std::fprintf(stderr, "transient: warning: %s\n", text.c_str());
  }

  void check_options() const;
  void setup();
  void add_terms();
  void choose_time_step();
  void set_initial_state();
  void probe_sample(Index i, const std::vector<double>& before, std::vector<double>& sample) const;
  void opening_states(const std::vector<int>& states_before, std::vector<double>& states) const;
  void record_probes(Index i, const std::vector<double>& sample, const std::vector<double>& states, double time);
  void record_terms();
  void sum_over_ranks(std::vector<double>& sample, std::vector<double>& states, StepSums& sums, bool with_sums,
                      std::exception_ptr failure);
  /// The step callback; over ranks, its verdict (stop, failure) is agreed by all.
  bool step_callback(const TransientCallbacks& callbacks, const StepView& view) const;
  void progress_line(Index i, double elapsed, const std::string& note) const;
  void integrate(const TransientCallbacks& callbacks);
};

void TransientSolver::Impl::check_options() const {
  const TransientOptions& o = options;
  const std::string length_key = o.run_length_key.empty() ? "transient.periods / transient.duration" : o.run_length_key;
  const std::string step_key = o.time_step_key.empty() ? "transient.time_step" : o.time_step_key;
  if (!(o.end_time > 0.0) || !std::isfinite(o.end_time)) {
    throw InputError(length_key + ": expected a run time > 0 s, got " + format_number(o.end_time));
  }
  if (!(o.time_step >= 0.0) || !std::isfinite(o.time_step)) {
    throw InputError(step_key + ": expected a time >= 0 s (0 = automatic), got " + format_number(o.time_step));
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
}

void TransientSolver::Impl::add_terms() {
  if (options.damping.beta > 0.0) {
    auto damping = std::make_shared<StiffnessDamping>(*elastic, options.damping.beta);
    damping_term = damping.get();
    terms.push_back(std::move(damping));
  }
  for (std::size_t k = 0; k < problem.loads.size(); ++k) {
    const ExternalLoad& load = problem.loads[k];
    const std::string where = "load '" + (load.name.empty() ? std::to_string(k) : load.name) + "'";
    check_signal(load.signal, where + ".signal");
    if (!std::isfinite(load.amplitude) || !(load.direction.norm() > 0.0)) {
      throw InputError(where + ": expected a finite amplitude and a nonzero direction, got amplitude " +
                       format_number(load.amplitude) + " N");
    }
    if (load.nodal_forces) {
      fem::LoadShape shape;
      shape.name = where;
      shape.dofs = load.nodal_forces->dofs;
      shape.values = load.nodal_forces->values;
      for (Index dof : shape.dofs) {
        if (dof < 0 || dof >= n_dofs()) throw InputError(where + ": a nodal force outside the run's DOFs");
      }
      terms.push_back(std::make_shared<ExternalForce>(std::move(shape), load.signal));
      continue;
    }
    const fem::LoadPlacement placement{where, load.nodes, load.faces, load.amplitude * load.direction.normalized()};
    terms.push_back(std::make_shared<ExternalForce>(system->load_shape(placement), load.signal));
  }
  std::stable_partition(problem.terms.begin(), problem.terms.end(),
                        [](const auto& term) { return !term->needs_other_forces(); });
  if (problem.terms.size() > 1 && problem.terms[problem.terms.size() - 2]->needs_other_forces()) {
    throw InputError("transient: at most one force term may need the other forces of the step");
  }
  halo_before = terms.size();
  terms.insert(terms.end(), problem.terms.begin(), problem.terms.end());
  records.assign(terms.size(), TermRecord{});
}

void TransientSolver::Impl::choose_time_step() {
  const TransientOptions& o = options;
  // Stable time step; terms with springs that bound it (explicit contact) add them, all closed.
  const double beta = o.damping.beta;
  bool bounded_by_terms = false;
  VectorX probe = VectorX::Ones(n_dofs()), bound = VectorX::Zero(n_dofs());
  for (const auto& term : terms) term->add_stiffness_bound(probe, bound);
  bounded_by_terms = bound.squaredNorm() > 0.0;
  if (distribution) {
    std::vector<double> any{bounded_by_terms ? 1.0 : 0.0};
    distribution->sum(any);
    bounded_by_terms = any[0] > 0.0;
  }
  estimate = estimate_time_step(StableStepOperator(*elastic, terms, distribution), inverse, beta,
                                o.time_step_options, distribution);
  if (o.time_step > 0.0 && o.time_step > estimate.dt_critical) {
    const std::string text = "time step " + format_number(o.time_step) + " s is above the stable limit dt_critical = " +
                             format_number(estimate.dt_critical) + " s (omega_max = " +
                             format_number(estimate.omega_max) + " rad/s" +
                             (bounded_by_terms ? " with the contact springs" : std::string()) +
                             (beta > 0.0 ? ", beta = " + format_number(beta) + " s" : std::string()) + ")";
    if (!o.force_time_step) {
      throw InputError((o.time_step_key.empty() ? "transient.time_step" : o.time_step_key) + ": " + text +
                       "; use a smaller one or force it");
    }
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
  if (ratio > 2e9) {
    throw InputError((o.run_length_key.empty() ? "transient.periods / transient.duration" : o.run_length_key) +
                     ": expected a run of at most 2e9 steps, got " + format_number(o.end_time) + " s over dt = " +
                     format_number(dt) + " s, " + format_number(ratio) + " steps");
  }
  steps = std::max<Index>(1, static_cast<Index>(std::ceil(ratio - 1e-9)));
}

void TransientSolver::Impl::set_initial_state() {
  // Initial state, eq. (6); held DOFs at their prescribed values and at rest.
  const Index n = n_dofs();
  const fem::Constraints& constraints = system->constraints();
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
  for (const auto& term : terms) term->start(displacement);
}

void TransientSolver::Impl::setup() {
  const Stopwatch watch;
  check_options();
  elastic = &system->stiffness();
  const fem::Constraints& constraints = system->constraints();
  moving_mass = system->lumped_mass();  // eq. (27)
  distribution = problem.distribution.get();
  if (distribution) {
    distribution->complete(moving_mass);  // shares of the elements of every rank
    std::exception_ptr failure;
    for (Index k = 0; k < n_dofs() && !failure; ++k) {
      if (!(moving_mass[k] > 0.0)) {
        failure = std::make_exception_ptr(InputError(
            "lumped mass " + format_number(moving_mass[k]) + " of global DOF " +
            std::to_string(distribution->global_dofs()[k]) +
            " is not positive (material density <= 0, or a node outside every element)"));
      }
    }
    distribution->agree(failure);
  }
  inverse = moving_mass.cwiseInverse();
  for (Index k = 0; k < n_dofs(); ++k) {
    if (constraints.fixed[k]) moving_mass[k] = inverse[k] = 0.0;
  }
  add_terms();
  const mesh::Mesh& mesh = system->mesh();
  if (distribution) {
    // The overlapped halo needs the elements in ranges: a matrix-free kernel (tetrahedra's
    // assembled K is applied row by row, not by element, so they complete after all elements)
    // whose chunks begin at the cuts (elastic_cuts(), made by the constructor that builds the
    // system; a shared system's operator may lack them).
    const std::vector<Index> cuts = elastic_cuts(mesh, *distribution);
    boundary_end = cuts[0];
    interior_middle = cuts[1];
    overlap = options.overlap_halo && elastic->can_apply_elements(0, boundary_end) &&
              elastic->can_apply_elements(boundary_end, interior_middle) &&
              elastic->can_apply_elements(interior_middle, mesh.n_elements());
    summary.halo_overlapped = overlap;
  }
  for (const Probe& probe : problem.probes) {
    if (distribution && probe.node == -1) {  // owned by another rank: this rank adds zeros
      for (int c = 0; c < 3; ++c) {
        probe_dofs.push_back(-1);
        probe_minus_dofs.push_back(-1);
      }
      probe_history.names.push_back(probe.name);
      probe_history.opening.push_back(probe.opening() ? 1 : 0);
      continue;
    }
    if (probe.node < 0 || probe.node >= mesh.n_nodes()) {
      throw InputError("probe '" + probe.name + "': node " + std::to_string(probe.node) + " outside a mesh of " +
                       std::to_string(mesh.n_nodes()) + " nodes");
    }
    if (probe.opening() && (probe.minus_node >= mesh.n_nodes() || system->dofs().dof(probe.minus_node, 0) ==
                                                                        system->dofs().dof(probe.node, 0))) {
      throw InputError("probe '" + probe.name + "': nodes " + std::to_string(probe.minus_node) + " and " +
                       std::to_string(probe.node) + " are not a split crack pair of this run's DOF map");
    }
    for (int c = 0; c < 3; ++c) {
      probe_dofs.push_back(system->dofs().dof(probe.node, c));
      probe_minus_dofs.push_back(probe.opening() ? system->dofs().dof(probe.minus_node, c) : -1);
    }
    probe_history.names.push_back(probe.name);
    probe_history.opening.push_back(probe.opening() ? 1 : 0);
  }
  probe_history.values.assign(9 * problem.probes.size(), {});
  probe_history.states.assign(problem.probes.size(), {});
  choose_time_step();
  set_initial_state();

  summary.dt = dt;
  summary.dt_critical = estimate.dt_critical;
  summary.omega_max = estimate.omega_max;
  summary.damping = options.damping;
  summary.n_dofs = distribution ? distribution->n_global_dofs() : n_dofs();
  std::vector<double> elements{static_cast<double>(mesh.n_elements())};
  if (distribution) {
    summary.ranks = distribution->ranks();
    elements.resize(distribution->ranks(), 0.0);
    std::swap(elements[0], elements[distribution->rank()]);
    distribution->sum(elements);  // elements per rank
  }
  summary.elements_min = static_cast<Index>(*std::min_element(elements.begin(), elements.end()));
  summary.elements_max = static_cast<Index>(*std::max_element(elements.begin(), elements.end()));
  double total_elements = 0.0;
  for (double count : elements) total_elements += count;
  summary.n_elements = static_cast<Index>(total_elements);
  summary.kernel = elastic->info().kernel;
  summary.setup_s = watch.seconds();
}

void TransientSolver::Impl::probe_sample(Index i, const std::vector<double>& before, std::vector<double>& sample) const {
  const Index n_probes = static_cast<Index>(problem.probes.size());
  const double h = i == 0 ? 0.5 * dt : dt;
  for (Index p = 0; p < n_probes; ++p) {
    const Vec3 velocity_new = probe_reading(p, velocity, false);
    for (int c = 0; c < 3; ++c) {
      const Index k = 3 * p + c;
      const double v_old = before[3 * n_probes + k], v_new = velocity_new[c];
      sample[9 * p + c] = before[k];
      sample[9 * p + 3 + c] = i == 0 ? v_old : 0.5 * (v_old + v_new);
      sample[9 * p + 6 + c] = (v_new - v_old) / h;
    }
  }
}

void TransientSolver::Impl::record_terms() {
  for (std::size_t k = 0; k < terms.size(); ++k) {
    TermRecord& record = records[k];
    record.dot_velocity_new = terms[k]->force_dot(velocity);
    record.stored = terms[k]->stored_energy();
    record.dissipated = terms[k]->dissipated_energy();
    record.active = terms[k]->active_fraction();
  }
}

void TransientSolver::Impl::sum_over_ranks(std::vector<double>& sample, std::vector<double>& states, StepSums& sums,
                                          bool with_sums, std::exception_ptr failure) {
  // One reduction per step: the probe rows and the opening probes' states (zeros from the ranks
  // that do not own a probe), the terms' dot products and energies, the step sums when the step
  // computed them, and the number of ranks whose step failed (then all stop with one error).
  std::vector<double>& values = rank_sums;  // kept between steps: no allocation in the step loop
  values.assign(sample.begin(), sample.end());
  values.insert(values.end(), states.begin(), states.end());
  values.push_back(failure ? 1.0 : 0.0);
  for (const TermRecord& r : records) {
    values.insert(values.end(), {r.dot_displacement, r.dot_velocity, r.dot_velocity_new, r.stored, r.dissipated, r.active});
  }
  if (with_sums) {
    values.insert(values.end(), {sums.kinetic_half, sums.kinetic_mid, sums.force_displacement, sums.force_velocity,
                                 sums.mass_damping_dissipation});
  }
  distribution->sum(values);
  std::size_t next = sample.size();
  std::copy(values.begin(), values.begin() + static_cast<std::ptrdiff_t>(next), sample.begin());
  for (double& state : states) state = values[next++];
  if (values[next++] > 0.0) distribution->agree(failure);
  for (TermRecord& r : records) {
    for (double* field : {&r.dot_displacement, &r.dot_velocity, &r.dot_velocity_new, &r.stored, &r.dissipated, &r.active}) {
      *field = values[next++];
    }
  }
  if (with_sums) {
    for (double* field : {&sums.kinetic_half, &sums.kinetic_mid, &sums.force_displacement, &sums.force_velocity,
                          &sums.mass_damping_dissipation}) {
      *field = values[next++];
    }
  }
}

void TransientSolver::Impl::opening_states(const std::vector<int>& states_before, std::vector<double>& states) const {
  // A rank that does not own an opening probe's pair adds 0 (its callers give it a state of 0).
  for (std::size_t p = 0; p < problem.probes.size(); ++p) {
    const Probe& probe = problem.probes[p];
    states[p] = !probe.opening() || !probe.state ? 0.0 : probe.state_at_step_end ? states_before[p] : probe.state();
  }
}

void TransientSolver::Impl::record_probes(Index i, const std::vector<double>& sample, const std::vector<double>& states,
                                          double time) {
  if (i % options.probe_interval != 0) return;
  probe_history.time.push_back(time);
  for (std::size_t c = 0; c < sample.size(); ++c) probe_history.values[c].push_back(sample[c]);
  // The opening probes' contact states (without a contact term: from the sign of the gap).
  for (std::size_t p = 0; p < problem.probes.size(); ++p) {
    const Probe& probe = problem.probes[p];
    if (!probe.opening()) continue;
    probe_history.states[p].push_back(probe.state ? static_cast<int>(states[p]) : (sample[9 * p] < 0.0 ? 2 : 0));
  }
}

bool TransientSolver::Impl::step_callback(const TransientCallbacks& callbacks, const StepView& view) const {
  if (!distribution) return callbacks.on_step(view);
  // Every rank stops when one asks to, and all fail together when one's callback fails.
  bool stop = false;
  std::exception_ptr failure;
  try {
    stop = callbacks.on_step(view);
  } catch (...) {
    failure = std::current_exception();
  }
  std::vector<double> verdict{stop ? 1.0 : 0.0, failure ? 1.0 : 0.0};
  distribution->sum(verdict);
  if (verdict[1] > 0.0) distribution->agree(failure);
  return verdict[0] > 0.0;
}

void TransientSolver::Impl::progress_line(Index i, double elapsed, const std::string& note) const {
  const double done = static_cast<double>(i + 1) / static_cast<double>(steps);
  std::fprintf(stderr, "transient: step %lld/%lld (%.1f%%), t = %.4g s, elapsed %s, ETA %s to the end time%s%s\n",
               static_cast<long long>(i + 1), static_cast<long long>(steps), 100.0 * done, summary.time,
               duration_text(elapsed).c_str(), duration_text(elapsed * (1.0 - done) / done).c_str(),
               note.empty() ? "" : "; ", note.c_str());
}

namespace {

/// The running energy balance of a transient run (see solver.hpp), summed over the force terms.
class EnergyBalance {
 public:
  EnergyBalance(const std::vector<std::shared_ptr<fem::ForceTerm>>& terms, std::vector<TermRecord>& records,
                double kinetic_initial)
      : terms_(terms), records_(records), kinetic_initial_(kinetic_initial) {}

  /// After step i: the terms' work over [t_{i-1/2}, t_{i+1/2}] (from the second step) and the
  /// mass-proportional damping of the integrator.
  void add_step_work(Index i, double dt, const StepSums& sums, double alpha) {
    double external_new = 0.0, external_old = 0.0;
    for (std::size_t k = 0; k < terms_.size(); ++k) {
      if (terms_[k]->role() == fem::EnergyRole::external) {
        external_old += records_[k].dot_velocity;
        external_new += records_[k].dot_velocity_new;
      }
    }
    if (i < 1) return;
    const double work = 0.5 * dt * (external_old + external_new);
    external_work_ += work;
    external_work_absolute_ += std::abs(work);
    if (alpha > 0.0) damping_ += sums.mass_damping_dissipation;
    for (std::size_t k = 0; k < terms_.size(); ++k) {
      if (terms_[k]->role() == fem::EnergyRole::dissipative) {
        damping_ -= 0.5 * dt * (records_[k].dot_velocity + records_[k].dot_velocity_new);
      }
    }
  }

  /// One energy row at step i; returns |balance| / scale.
  double sample(Index i, double time, double dt, const StepSums& sums, EnergyHistory& history) {
    // U_i . K U_i and V_{i+1/2} . K U_i from the fused sums, less the other terms' shares.
    double rest_displacement = sums.force_displacement, rest_velocity = sums.force_velocity;
    for (fem::EnergyRole role : {fem::EnergyRole::external, fem::EnergyRole::potential, fem::EnergyRole::dissipative}) {
      for (std::size_t k = 0; k < terms_.size(); ++k) {
        if (terms_[k]->role() != role) continue;
        rest_displacement -= records_[k].dot_displacement;
        rest_velocity -= records_[k].dot_velocity_new;
      }
    }
    const double strain = -0.5 * rest_displacement;
    // Stored energy of the other potential terms: those of U(i) in the same modified form as the
    // strain energy, those of U(i+1) as they are.
    double stored = 0.0, stored_modified = 0.0, internal = 0.0;
    for (std::size_t k = 0; k < terms_.size(); ++k) {
      internal += records_[k].dissipated;
      if (terms_[k]->role() != fem::EnergyRole::potential) continue;
      stored += records_[k].stored;
      stored_modified += terms_[k]->explicit_in_time() ? records_[k].stored - 0.5 * dt * records_[k].dot_velocity_new
                                                       : records_[k].stored;
    }
    const double modified = sums.kinetic_half + strain - 0.5 * dt * rest_velocity + stored_modified;
    const double kinetic = i == 0 ? kinetic_initial_ : sums.kinetic_mid;
    physical_ = kinetic + strain + stored;
    if (i == 0) {
      reference_ = modified;
      initial_physical_ = physical_;
      internal_reference_ = internal;
    }
    const double friction = internal - internal_reference_;
    balance_ = modified - reference_ - external_work_ + damping_ + friction;
    modified_ = modified;
    scale_ = std::max({scale_, physical_, std::abs(reference_), initial_physical_, external_work_absolute_});
    const double relative = scale_ > 0.0 ? std::abs(balance_) / scale_ : 0.0;
    history.time.push_back(time);
    history.kinetic.push_back(kinetic);
    history.strain.push_back(strain);
    history.contact.push_back(stored);
    history.external_work.push_back(external_work_);
    history.damping.push_back(damping_);
    history.friction.push_back(friction);
    history.balance.push_back(balance_);
    history.relative_error.push_back(relative);
    return relative;
  }

  bool finite() const { return std::isfinite(balance_) && std::isfinite(physical_) && std::isfinite(modified_); }
  double physical() const { return physical_; }
  /// The energy put in: the initial energy and the absolute work of the loads.
  double budget() const { return initial_physical_ + external_work_absolute_; }

 private:
  const std::vector<std::shared_ptr<fem::ForceTerm>>& terms_;
  std::vector<TermRecord>& records_;
  double kinetic_initial_;
  double reference_ = 0.0, initial_physical_ = 0.0, internal_reference_ = 0.0;
  double external_work_ = 0.0, external_work_absolute_ = 0.0, damping_ = 0.0, scale_ = 0.0;
  double physical_ = 0.0, modified_ = 0.0, balance_ = 0.0;
};

}  // namespace

void TransientSolver::Impl::integrate(const TransientCallbacks& callbacks) {
  const Stopwatch wall;
  const TransientOptions& o = options;
  const Index n_probes = static_cast<Index>(problem.probes.size());
  CentralDifference integrator(n_dofs());
  StepSums sums;
  std::vector<double> sample(9 * n_probes), before(6 * n_probes);
  std::vector<int> states_before(n_probes, 0);  // the opening probes' states at U(i) (implicit contact)
  std::vector<double> states(n_probes, 0.0);      // the states recorded for step i
  const Index owned = n_owned();
  std::vector<double> kinetic_initial{
      0.5 * velocity.head(owned).cwiseProduct(moving_mass.head(owned)).dot(velocity.head(owned))};
  if (distribution) distribution->sum(kinetic_initial);
  EnergyBalance balance(terms, records, kinetic_initial[0]);
  double active_sum = 0.0, last_progress = 0.0;
  for (TermRecord& record : records) record.seconds = 0.0;
  summary.n_threads = omp_get_max_threads();
  summary.status = "running";

  for (Index i = 0; i < steps; ++i) {
    const double time = static_cast<double>(i) * dt;
    const bool sample_energy = i % o.energy_interval == 0 || i + 1 == steps;
    for (Index p = 0; p < n_probes; ++p) {
      const Vec3 u = probe_reading(p, displacement, true), v = probe_reading(p, velocity, false);
      for (int c = 0; c < 3; ++c) {
        before[3 * p + c] = u[c];
        before[3 * (n_probes + p) + c] = v[c];
      }
      const Probe& probe = problem.probes[p];
      if (probe.state && probe.state_at_step_end) states_before[p] = i == 0 ? (u[0] < 0.0 ? 2 : 0) : probe.state();
    }
    const bool with_sums = sample_energy || o.damping.alpha > 0.0;
    std::exception_ptr failure;  // a distributed run: this rank's step failed, the others are told
    try {
      integrator.step(*this, time, i == 0 ? 0.0 : dt, dt, displacement, velocity, with_sums ? &sums : nullptr);
      record_terms();
      opening_states(states_before, states);
    } catch (...) {
      if (!distribution) throw;
      failure = std::current_exception();
    }
    probe_sample(i, before, sample);
    if (distribution) sum_over_ranks(sample, states, sums, with_sums, failure);
    record_probes(i, sample, states, time);
    balance.add_step_work(i, dt, sums, o.damping.alpha);
    for (const TermRecord& record : records) active_sum += record.active;

    if (sample_energy) {
      const double relative = balance.sample(i, time, dt, sums, energy_history);
      summary.steps = i + 1;
      summary.time = static_cast<double>(i + 1) * dt;
      const std::string where = " at step " + std::to_string(i) + " (t = " + format_number(time) + " s)";
      const std::string step_text = "; time step " + format_number(dt) + " s, dt_critical " +
                                    format_number(estimate.dt_critical) + " s";
      if (!balance.finite()) throw SolverError("transient: non-finite displacement or velocity" + where + step_text);
      if (balance.physical() > o.growth_factor * balance.budget()) {
        throw SolverError("transient: unstable, energy " + format_number(balance.physical()) + " J grew beyond " +
                          format_number(o.growth_factor) + " times the energy put in (" +
                          format_number(balance.budget()) + " J)" + where + step_text);
      }
      summary.energy_error = std::max(summary.energy_error, relative);
      if (relative > o.energy_tolerance) {
        throw SolverError("transient: energy balance error " + format_number(relative) + " exceeds the tolerance " +
                          format_number(o.energy_tolerance) + where + step_text);
      }
    }
    summary.steps = i + 1;
    summary.time = static_cast<double>(i + 1) * dt;
    summary.contact_fraction = active_sum / static_cast<double>(i + 1);

    if (callbacks.on_step) {
      const StepView view{i, time, dt, sample, displacement, velocity};
      if (step_callback(callbacks, view)) {
        summary.status = "stopped";
        summary.message = "stopped by a callback at step " + std::to_string(i) + " (t = " + format_number(time) + " s)";
        break;
      }
    }
    if (!distribution && (i & 63) == 63) poll_interrupt();
    if (o.progress && (!distribution || distribution->rank() == 0) && (i & 63) == 63 && wall.seconds() - last_progress >= o.progress_interval) {
      last_progress = wall.seconds();
      progress_line(i, last_progress, callbacks.progress_note ? callbacks.progress_note(last_progress) : "");
    }
  }
  if (summary.status == "running") summary.status = "completed";
  summary.wall_s = wall.seconds();
  for (std::size_t k = 0; k < terms.size(); ++k) summary.term_seconds[terms[k]->name()] += records[k].seconds;
  summary.ns_per_dof_step =
      summary.steps > 0 ? 1e9 * summary.wall_s / (static_cast<double>(summary.steps) * summary.n_dofs) : 0.0;
}

TransientSolver::TransientSolver(std::shared_ptr<const fem::System> system, TransientProblem problem,
                                 TransientOptions options)
    : impl_(std::make_unique<Impl>(std::move(problem), std::move(options))) {
  impl_->system = std::move(system);
  impl_->setup();
}

TransientSolver::TransientSolver(const mesh::Mesh& mesh, TransientProblem problem, TransientOptions options)
    : impl_(std::make_unique<Impl>(std::move(problem), std::move(options))) {
  Impl& impl = *impl_;
  if (impl.problem.distribution) impl.options.elastic.element_cuts = elastic_cuts(mesh, *impl.problem.distribution);
  impl_->system = std::make_shared<fem::System>(mesh, impl.problem.materials, impl.problem.dirichlet,
                                                impl.options.variant, impl.options.elastic,
                                                impl.problem.distribution != nullptr);
  impl_->setup();
}

TransientSolver::~TransientSolver() = default;

const fem::System& TransientSolver::system() const { return *impl_->system; }
const mesh::DofMap& TransientSolver::dofs() const { return impl_->system->dofs(); }
const fem::Constraints& TransientSolver::constraints() const { return impl_->system->constraints(); }
const TimeStepEstimate& TransientSolver::time_step_estimate() const { return impl_->estimate; }
double TransientSolver::dt() const { return impl_->dt; }
Index TransientSolver::n_steps() const { return impl_->steps; }
const fem::ElasticOperator& TransientSolver::elastic_operator() const { return *impl_->elastic; }
const VectorX& TransientSolver::lumped_mass() const { return impl_->system->lumped_mass(); }
void TransientSolver::set_probe_interval(Index steps) {
  if (steps < 1) throw InputError("transient: expected probe_interval >= 1, got " + std::to_string(steps));
  impl_->options.probe_interval = static_cast<int>(steps);
}
const TransientSummary& TransientSolver::summary() const { return impl_->summary; }
const ProbeHistory& TransientSolver::probes() const { return impl_->probe_history; }
const EnergyHistory& TransientSolver::energy() const { return impl_->energy_history; }
const VectorX& TransientSolver::displacement() const { return impl_->displacement; }
const VectorX& TransientSolver::velocity() const { return impl_->velocity; }

const TransientSummary& TransientSolver::run(const TransientCallbacks& callbacks) {
  Impl& impl = *impl_;
  const Stopwatch wall;
  try {
    impl.integrate(callbacks);
  } catch (const SolverError& error) {
    impl.summary.status = "unstable";
    impl.summary.message = error.what();
    impl.summary.wall_s = wall.seconds();
    if (callbacks.on_finish) {
      try {
        callbacks.on_finish(impl.summary);
      } catch (const std::exception& secondary) {
        throw SolverError(std::string(error.what()) + " (and writing the output failed: " + secondary.what() + ")");
      }
    }
    throw;
  }
  if (callbacks.on_finish) callbacks.on_finish(impl.summary);
  return impl.summary;
}

}  // namespace crackle::transient
