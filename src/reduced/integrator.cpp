#include "reduced/integrator.hpp"
#include "reduced/integrator_detail.hpp"

#include <Eigen/Eigenvalues>
#include <Eigen/LU>
#include <algorithm>
#include <cmath>
#include <string>
#include <utility>

#include "contact_law/penalty.hpp"
#include "core/errors.hpp"

namespace crackle::reduced {
using detail::kLocalNormal;

namespace {

void require_size(const char* what, Index actual, Index expected) {
  if (actual != expected)
    throw InputError(std::string("reduced system: ") + what + " has " + std::to_string(actual) + " entries, expected " +
                     std::to_string(expected));
}

void validate(const ReducedSystem& system) {
  const Index m = system.n_modes(), c = system.n_rows(), n = system.n_pairs(), o = system.n_outputs();
  require_size("initial_gap", static_cast<Index>(system.initial_gap.size()), n);
  require_size("pair_modes rows", static_cast<Index>(system.pair_modes.rows()), c);
  if (c > 0) require_size("pair_modes columns", static_cast<Index>(system.pair_modes.cols()), m);
  require_size("residual rows", static_cast<Index>(system.residual.rows()), c);
  require_size("residual columns", static_cast<Index>(system.residual.cols()), c);
  require_size("load_modal", static_cast<Index>(system.load_modal.size()), m);
  require_size("load_residual", static_cast<Index>(system.load_residual.size()), c);
  if (o > 0) {
    require_size("output_modes columns", static_cast<Index>(system.output_modes.cols()), m);
    require_size("output_residual_pairs rows", static_cast<Index>(system.output_residual_pairs.rows()), o);
    require_size("output_residual_pairs columns", static_cast<Index>(system.output_residual_pairs.cols()), c);
    require_size("output_residual_load", static_cast<Index>(system.output_residual_load.size()), o);
  }
  for (Index r = 0; r < m; ++r)
    if (!(system.omega[r] >= 0.0))
      throw InputError("reduced system: omega[" + std::to_string(r) + "] = " + format_number(system.omega[r]) +
                       " is negative or not a number");
  if (system.normal_penalty < 0.0 || system.tangential_penalty < 0.0 || system.friction_coefficient < 0.0)
    throw InputError("reduced system: negative penalty or friction coefficient");
}

/// Frictionless active set: the share of the deepest penetration an open row needs to enter, and the
/// iterations per step staged so (measured at 1081 pairs and 10 modes, bench_reduced: 0.5 halves the
/// factorisation work against entering every penetrated row at once; docs/benchmarks.md 8.3).
constexpr double kStagedDepth = 0.5;
constexpr int kStagedIterations = 10;


}  // namespace

ReducedIntegrator::ReducedIntegrator(const ReducedSystem& system, double time_step, LoadFunction load,
                                     ReducedIntegratorOptions options)
    : system_(system), time_step_(time_step), load_(std::move(load)), options_(options) {
  validate(system_);
  if (!(time_step_ > 0.0) || !std::isfinite(time_step_))
    throw InputError("reduced integrator: time step " + format_number(time_step_) + " s must be positive");
  if (!load_) load_ = [](double) { return 0.0; };
  const double h = time_step_;
  omega2_ = system_.omega.array().square();
  damping_ = system_.rayleigh_alpha + system_.rayleigh_beta * omega2_.array();
  denominator_ = 1.0 + 0.5 * h * damping_.array() + 0.25 * h * h * omega2_.array();
  pair_modes_transposed_ = system_.pair_modes.transpose();
  // W = B Phi S (B Phi)^T + R, S_r = (h^2/4) / denominator_r.
  const VectorX s = (0.25 * h * h) / denominator_.array();
  w_ = system_.pair_modes * s.asDiagonal() * system_.pair_modes.transpose() + system_.residual;
  normal_stiffness_ = system_.normal_penalty * system_.pair_area;
  tangential_stiffness_ = system_.tangential_penalty * system_.pair_area;
  if (friction_active()) {
    row_compliance_.resize(system_.n_rows());
    for (Index i = 0; i < system_.n_pairs(); ++i)
      row_compliance_.segment(3 * i, 3) << 1.0 / normal_stiffness_[i], 1.0 / tangential_stiffness_[i],
          1.0 / tangential_stiffness_[i];
  }
  const Index m = system_.n_modes();
  set_initial_state(VectorX::Zero(m), VectorX::Zero(m), 0.0);
}

bool ReducedIntegrator::friction_active() const {
  return system_.friction && system_.friction_coefficient > 0.0 && system_.tangential_penalty > 0.0;
}

void ReducedIntegrator::fail(const char* what) const {
  throw SolverError(std::string("reduced integrator: ") + what + " at step " + std::to_string(step_count_ + 1) +
                    " (t = " + format_number(time_ + time_step_) + " s, h = " + format_number(time_step_) + " s)");
}

void ReducedIntegrator::set_initial_state(const VectorX& modal_displacement, const VectorX& modal_velocity,
                                          double time) {
  const Index m = system_.n_modes(), c = system_.n_rows(), stride = system_.rows_per_pair();
  require_size("initial modal displacement", static_cast<Index>(modal_displacement.size()), m);
  require_size("initial modal velocity", static_cast<Index>(modal_velocity.size()), m);
  q_ = modal_displacement;
  v_ = modal_velocity;
  time_ = time;
  step_count_ = 0;
  load_value_ = load_(time_);
  state_.assign(system_.n_pairs(), PairState::kOpen);
  // Static contact problem of the massless boundary at t0: g = g0 + B Phi q + R p + r_f a, W = R,
  // tangential forces 0 (their reference slip is the current one).
  VectorX free_gap = system_.pair_modes * q_ + system_.load_residual * load_value_;
  for (Index i = 0; i < system_.n_pairs(); ++i) free_gap[stride * i] += system_.initial_gap[i];
  p_ = VectorX::Zero(c);
  g_ = free_gap;
  last_iterations_ = 0;
  if (c > 0) {
    ActiveSetFactor factor;  // of R, not of the step's W
    solve_normal(system_.residual, free_gap, factor);
  }
  normal_factor_.clear();
  for (Index i = 0; i < system_.n_pairs(); ++i)
    if (p_[stride * i] > 0.0) state_[i] = PairState::kStick;
  p_old_ = p_;
  g_old_ = g_;
  acc_ = system_.load_modal * load_value_ - damping_.cwiseProduct(v_) -
         system_.omega.array().square().matrix().cwiseProduct(q_);
  if (c > 0) acc_ += system_.pair_modes.transpose() * p_;

  energy_ = ReducedEnergy{};
  energy_.kinetic = 0.5 * v_.squaredNorm();
  energy_.modal_strain = 0.5 * (system_.omega.array() * q_.array()).square().sum();
  energy_.residual_strain = residual_strain(p_, load_value_);
  energy_.penalty = penalty_energy();
  initial_total_ = energy_.total();
  energy_scale_ = 0.0;
  update_energy_scale();
  total_iterations_ = 0;
  switching_steps_ = 0;
  unconserved_switching_steps_ = 0;
  implicit_switching_steps_ = 0;
  switching_correction_ = 0.0;
  total_factorizations_ = 0;
  total_factor_updates_ = 0;
  total_factor_work_ = 0.0;
  total_gauss_seidel_rounds_ = 0;
  total_factorized_rows_ = 0;
  largest_factorized_rows_ = 0;
}

bool ReducedIntegrator::ActiveSetFactor::append(const std::vector<Index>& rows, const MatrixX& coupling,
                                                const MatrixX& block) {
  // [L 0; C^T S] with L C = coupling and S S^T = block - C^T C.
  const Index n = size(), b = static_cast<Index>(rows.size());
  if (b == 0) return true;
  if (lower_.rows() < n + b) {
    const Index capacity = std::max<Index>(n + b, 2 * n);
    MatrixX grown = MatrixX::Zero(capacity, capacity);
    grown.topLeftCorner(n, n) = lower_.topLeftCorner(n, n);
    lower_.swap(grown);
  }
  MatrixX c = coupling;
  if (n > 0) lower_.topLeftCorner(n, n).triangularView<Eigen::Lower>().solveInPlace(c);
  MatrixX schur = block;
  if (n > 0) schur.selfadjointView<Eigen::Lower>().rankUpdate(c.transpose(), -1.0);
  const Eigen::LLT<MatrixX> factor(schur);
  if (factor.info() != Eigen::Success) return false;
  lower_.block(n, 0, b, n) = c.transpose();
  lower_.block(n, n, b, b) = factor.matrixL();
  rows_.insert(rows_.end(), rows.begin(), rows.end());
  return true;
}

VectorX ReducedIntegrator::ActiveSetFactor::solve(const VectorX& rhs) const {
  const Index n = size();
  VectorX x = rhs;
  const auto lower = lower_.topLeftCorner(n, n).triangularView<Eigen::Lower>();
  lower.solveInPlace(x);
  lower.transpose().solveInPlace(x);
  return x;
}

void ReducedIntegrator::solve_normal(const MatrixX& w, const VectorX& free_gap, ActiveSetFactor& factor) {
  // Primal-dual active set on the normal rows, warm-started from the current forces (see the class
  // doc); the factor of H_AA follows the set by row removals and block appends.
  const Index n = system_.n_pairs(), stride = system_.rows_per_pair();
  // Appends rows to the factor: a factorisation when it is empty, else an update.
  const auto append = [&](const std::vector<Index>& rows) {
    if (rows.empty()) return;
    const double a = static_cast<double>(factor.size()), b = static_cast<double>(rows.size());
    total_factor_work_ += a * a * b + a * b * b + b * b * b / 3.0;
    if (factor.size() == 0) {
      ++total_factorizations_;
      total_factorized_rows_ += static_cast<long>(rows.size());
    } else {
      total_factor_updates_ += static_cast<long>(rows.size());
    }
    MatrixX block = w(rows, rows);
    for (std::size_t k = 0; k < rows.size(); ++k) block(k, k) += 1.0 / normal_stiffness_[rows[k] / stride];
    if (!factor.append(rows, w(factor.rows(), rows), block))
      fail("Cholesky factor of the active contact block failed");
    largest_factorized_rows_ = std::max(largest_factorized_rows_, static_cast<long>(factor.size()));
  };
  std::vector<char> active(n, 0);
  std::vector<Index> warm;
  for (Index i = 0; i < n; ++i)
    if (p_[stride * i] > 0.0 && normal_stiffness_[i] > 0.0) active[i] = 1, warm.push_back(stride * i);
  // The cached factor is kept if it holds exactly the warm set (in any order).
  bool cached = factor.size() == static_cast<Index>(warm.size());
  for (Index row : factor.rows()) cached = cached && active[row / stride];
  if (!cached) {
    factor.clear();
    append(warm);
  }
  const int limit = options_.max_contact_iterations;
  std::vector<Index> released, entering;
  for (int iteration = 1; iteration <= limit; ++iteration) {
    const VectorX x = factor.solve(-free_gap(factor.rows()));
    p_.setZero();
    p_(factor.rows()) = x;
    g_ = free_gap;
    if (factor.size() > 0) g_.noalias() += w(Eigen::all, factor.rows()) * x;
    released.clear();
    entering.clear();
    for (Index k = 0; k < factor.size(); ++k)
      if (!(x[k] > 0.0)) released.push_back(k);
    // Staged activation: the open rows penetrated at least kStagedDepth times as deep as the deepest
    // enter; the response of their forces lifts the shallower ones or leaves them for the next
    // iteration (all penetrated rows enter after kStagedIterations, as a plain primal-dual set).
    double deepest = 0.0;
    for (Index i = 0; i < n; ++i)
      if (!active[i] && normal_stiffness_[i] > 0.0) deepest = std::min(deepest, g_[stride * i]);
    const double threshold = iteration <= kStagedIterations ? kStagedDepth * deepest : 0.0;
    for (Index i = 0; i < n; ++i)
      if (!active[i] && normal_stiffness_[i] > 0.0 && g_[stride * i] < 0.0 && g_[stride * i] <= threshold)
        entering.push_back(stride * i);
    if (released.empty() && entering.empty()) {
      last_iterations_ = iteration;
      total_iterations_ += iteration;
      return;
    }
    // Released rows: the factor is cut before the first of them (the rows before it keep their
    // factor) and the kept rows after it are appended again, with the entering ones.
    std::vector<Index> appended;
    if (!released.empty()) {
      for (Index k : released) active[factor.rows()[k] / stride] = 0;
      for (Index k = released.front() + 1; k < factor.size(); ++k)
        if (active[factor.rows()[k] / stride]) appended.push_back(factor.rows()[k]);
      total_factor_updates_ += static_cast<long>(factor.size() - released.front());
      factor.truncate(released.front());
    }
    for (Index row : entering) active[row / stride] = 1;
    appended.insert(appended.end(), entering.begin(), entering.end());
    append(appended);
  }
  fail(("contact active set did not settle in " + std::to_string(limit) + " iterations").c_str());
}

void ReducedIntegrator::solve_contact(const VectorX& free_gap) {
  if (friction_active())
    solve_with_friction(free_gap);
  else
    solve_normal(w_, free_gap, normal_factor_);
}

void ReducedIntegrator::trial_step(double a1, bool end_of_step_force, StepTrial& trial) {
  const double h = time_step_;
  const Index c = system_.n_rows(), stride = system_.rows_per_pair();
  const VectorX& omega2 = omega2_;
  // Predictors, then the end-of-step acceleration without the pair forces. With the end-of-step
  // force the step's contact force is p_{n+1} in both Newmark terms: p_n leaves the predictors.
  VectorX start_acc = acc_;
  if (end_of_step_force) start_acc -= modal_pair_force(p_old_);
  VectorX q_pred = q_ + h * v_ + (0.25 * h * h) * start_acc;
  VectorX v_pred = v_ + (0.5 * h) * start_acc;
  VectorX acc_next = (system_.load_modal * a1 - damping_.cwiseProduct(v_pred) - omega2.cwiseProduct(q_pred))
                         .cwiseQuotient(denominator_);
  if (c > 0) {
    p_ = p_old_;  // warm start
    g_ = g_old_;
    VectorX free_gap = system_.pair_modes * (q_pred + (0.25 * h * h) * acc_next) + system_.load_residual * a1;
    for (Index i = 0; i < system_.n_pairs(); ++i) free_gap[stride * i] += system_.initial_gap[i];
    if (end_of_step_force) {
      // q_{n+1} = q_free + 2 S (B Phi)^T p_{n+1}: the step compliance W + B Phi S (B Phi)^T, formed at
      // the first such step; the contact solve runs on it with its own cached factors.
      if (switching_w_.rows() != c) {
        const VectorX s = (0.25 * h * h) / denominator_.array();
        switching_w_ = w_ + system_.pair_modes * s.asDiagonal() * system_.pair_modes.transpose();
      }
      swap_switching_compliance();
      solve_contact(free_gap);
      swap_switching_compliance();
      const VectorX force = modal_pair_force(p_);
      q_pred += (0.25 * h * h) * force;
      v_pred += (0.5 * h) * force;
      acc_next = (system_.load_modal * a1 - damping_.cwiseProduct(v_pred) - omega2.cwiseProduct(q_pred) + force)
                     .cwiseQuotient(denominator_);
    } else {
      solve_contact(free_gap);
      acc_next += modal_pair_force(p_).cwiseQuotient(denominator_);
    }
  } else {
    last_iterations_ = 0;
  }
  trial.q = q_pred + (0.25 * h * h) * acc_next;
  trial.v = v_pred + (0.5 * h) * acc_next;
  trial.acc = acc_next;
  if (!trial.q.allFinite() || !trial.v.allFinite() || !p_.allFinite()) fail("the state is not finite");

  // Energy account (see ReducedEnergy): trapezoidal external work, exact Newmark damping work.
  const double a_mean = 0.5 * (load_value_ + a1);
  trial.external = a_mean * system_.load_modal.dot(trial.q - q_);
  if (c > 0) trial.external += a_mean * system_.load_residual.dot(p_ - p_old_);
  trial.friction = 0.0;
  if (friction_active()) {
    for (Index i = 0; i < system_.n_pairs(); ++i) {
      const Index r = 3 * i;
      const double area = system_.pair_area[i];
      trial.friction += area * contact::coulomb_return_mapping(
                                   Vec3(0.0, p_old_[r + 1], p_old_[r + 2]) / area,
                                   Vec3(0.0, g_[r + 1] - g_old_[r + 1], g_[r + 2] - g_old_[r + 2]), kLocalNormal,
                                   system_.tangential_penalty, system_.friction_coefficient, p_[r] / area)
                                   .dissipation;
    }
  }
  trial.modal_strain = 0.5 * (system_.omega.array() * trial.q.array()).square().sum();
  trial.residual_strain = residual_strain(p_, a1);
  trial.penalty = penalty_energy();
}

void ReducedIntegrator::step() {
  const double h = time_step_;
  const double next_time = time_ + h;
  const double a1 = load_(next_time);
  p_old_ = p_;
  g_old_ = g_;
  StepTrial trial;
  trial_step(a1, false, trial);
  if (system_.n_rows() > 0 && closed_set_changed()) {
    // A switching step (HYBRID.md §3 as implemented, see the file doc): the trapezoidal contact
    // force is exact only while the closed set holds; here the step's energy error is removed by a
    // velocity jump along the contact-force change, and where that cannot remove it, the step is
    // redone with the end-of-step contact force (which cannot gain energy) and then corrected.
    ++switching_steps_;
    if (options_.conserve_switching_energy && !conserve_switching_energy(trial, false)) {
      ++implicit_switching_steps_;
      trial_step(a1, true, trial);
      if (!conserve_switching_energy(trial, true)) ++unconserved_switching_steps_;
    }
  }
  const VectorX v_mean = 0.5 * (v_ + trial.v);
  energy_.external_work += trial.external;
  energy_.damping_dissipation += h * (damping_.array() * v_mean.array().square()).sum();
  energy_.friction_dissipation += trial.friction;
  q_ = trial.q;
  v_ = trial.v;
  acc_ = trial.acc;
  load_value_ = a1;
  ++step_count_;
  time_ = next_time;
  energy_.kinetic = 0.5 * v_.squaredNorm();
  energy_.modal_strain = trial.modal_strain;
  energy_.residual_strain = trial.residual_strain;
  energy_.penalty = trial.penalty;
  update_energy_scale();
  if (options_.energy_tolerance > 0.0 && energy_error() > options_.energy_tolerance)
    throw SolverError("reduced integrator: energy balance error " + format_number(energy_error()) +
                      " exceeds " + format_number(options_.energy_tolerance) + " at step " +
                      std::to_string(step_count_) + " (t = " + format_number(time_) + " s, h = " +
                      format_number(time_step_) + " s): take more steps per period");
}

bool ReducedIntegrator::closed_set_changed() const {
  const Index stride = system_.rows_per_pair();
  for (Index i = 0; i < system_.n_pairs(); ++i)
    if ((p_[stride * i] > 0.0) != (p_old_[stride * i] > 0.0)) return true;
  return false;
}

bool ReducedIntegrator::conserve_switching_energy(StepTrial& trial, bool best_effort) {
  // The step's energy error as a function of a velocity jump lambda d along the modal image of the
  // contact-force change, d = (B Phi)^T (p_{n+1} - p_n):
  //   e(lambda) = 1/2 |v + lambda d|^2 + h sum_r d_r (vbar_r + lambda d_r / 2)^2 + (the rest of the balance),
  // vbar = (v_n + v) / 2 (the step's exact damping work): a quadratic in lambda whose root nearest 0
  // makes the step conserve energy exactly. An energy loss (e(0) < 0) always has a root; a gain may
  // not (false; with best_effort the minimiser of e is applied).
  const double h = time_step_;
  const VectorX d = modal_pair_force(p_ - p_old_);
  if (d.squaredNorm() == 0.0) return true;
  const VectorX v_mean = 0.5 * (v_ + trial.v);
  const double error = 0.5 * trial.v.squaredNorm() + h * (damping_.array() * v_mean.array().square()).sum() +
                       trial.modal_strain + trial.residual_strain + trial.penalty + trial.friction -
                       trial.external - energy_.stored();
  const double quadratic = 0.5 * d.squaredNorm() + 0.25 * h * (damping_.array() * d.array().square()).sum();
  const double linear = trial.v.dot(d) + h * (damping_.array() * v_mean.array() * d.array()).sum();
  if (!(quadratic > 0.0)) return error <= 0.0;
  const double discriminant = linear * linear - 4.0 * quadratic * error;
  double lambda;
  if (discriminant >= 0.0) {
    const double root = std::sqrt(discriminant);
    const double denominator = linear >= 0.0 ? -linear - root : -linear + root;
    lambda = denominator != 0.0 ? 2.0 * error / denominator : 0.0;
  } else if (best_effort) {
    lambda = -linear / (2.0 * quadratic);
  } else {
    return false;
  }
  switching_correction_ += std::abs(error);
  trial.v += lambda * d;
  trial.acc -= lambda * damping_.cwiseProduct(d);
  return discriminant >= 0.0;
}

void ReducedIntegrator::swap_switching_compliance() {
  std::swap(w_, switching_w_);
  std::swap(normal_factor_, switching_normal_factor_);
  std::swap(step_factor_, switching_factor_);
}

VectorX ReducedIntegrator::modal_pair_force(const VectorX& p) const {
  VectorX force = VectorX::Zero(system_.n_modes());
  for (Index r = 0; r < p.size(); ++r)
    if (p[r] != 0.0) force.noalias() += p[r] * pair_modes_transposed_.col(r);
  return force;
}

void ReducedIntegrator::advance(Index n_steps) {
  for (Index k = 0; k < n_steps; ++k) step();
}

double ReducedIntegrator::residual_strain(const VectorX& p, double a) const {
  // 1/2 p^T R p + a p^T r_f over the loaded rows, R read by its columns (contiguous; p is zero off
  // the loaded rows): R's indexed view read by rows cost as much as the rest of the step.
  double quadratic = 0.0, load = 0.0;
  for (Index j = 0; j < p.size(); ++j) {  // no list of the loaded rows: this runs twice a step
    if (p[j] == 0.0) continue;
    quadratic += p[j] * system_.residual.col(j).dot(p);
    load += p[j] * system_.load_residual[j];
  }
  return 0.5 * quadratic + a * load;
}

double ReducedIntegrator::penalty_energy() const {
  // Normal: eps_N A g^2 / 2 = p^2 / (2 eps_N A) (from p, robust for stiff penalties); tangential |t|^2 A / (2 eps_T).
  const Index stride = system_.rows_per_pair();
  double energy = 0.0;
  for (Index i = 0; i < system_.n_pairs(); ++i) {
    const double p = p_[stride * i];
    if (p > 0.0) energy += 0.5 * p * p / normal_stiffness_[i];
    if (stride == 3 && system_.tangential_penalty > 0.0) {
      const double area = system_.pair_area[i];
      energy += area * contact::tangential_penalty_energy(Vec3(0.0, p_[stride * i + 1], p_[stride * i + 2]) / area,
                                                          system_.tangential_penalty);
    }
  }
  return energy;
}

void ReducedIntegrator::update_energy_scale() {
  energy_scale_ = std::max({energy_scale_, std::abs(energy_.stored()), std::abs(energy_.external_work),
                            energy_.damping_dissipation + energy_.friction_dissipation});
}

double ReducedIntegrator::energy_error() const {
  return energy_scale_ > 0.0 ? std::abs(energy_.total() - initial_total_) / energy_scale_ : 0.0;
}

VectorX ReducedIntegrator::outputs() const {
  if (system_.n_outputs() == 0) return VectorX();
  VectorX y = system_.output_modes * q_ + system_.output_residual_load * load_value_;
  if (system_.n_rows() > 0) y += system_.output_residual_pairs * p_;
  return y;
}

double ReducedIntegrator::output(Index row) const {
  double y = system_.output_modes.row(row).dot(q_) + system_.output_residual_load[row] * load_value_;
  if (system_.n_rows() > 0) y += system_.output_residual_pairs.row(row).dot(p_);
  return y;
}

Index ReducedIntegrator::n_closed() const {
  Index count = 0;
  for (Index i = 0; i < system_.n_pairs(); ++i)
    if (p_[system_.rows_per_pair() * i] > 0.0) ++count;
  return count;
}

Index ReducedIntegrator::n_slipping() const {
  if (!friction_active()) return 0;
  return static_cast<Index>(std::count(state_.begin(), state_.end(), PairState::kSlip));
}

int ReducedIntegrator::pair_state(Index pair) const {
  if (!(p_[system_.rows_per_pair() * pair] > 0.0)) return 0;
  return friction_active() && state_[pair] != PairState::kSlip ? 1 : 2;
}

double ReducedIntegrator::closed_fraction() const {
  return system_.n_pairs() > 0 ? static_cast<double>(n_closed()) / system_.n_pairs() : 0.0;
}

double reduced_time_step(const ReducedSystem& system, double max_frequency_hz, int steps_per_period) {
  if (steps_per_period < 1)
    throw InputError("reduced time step: steps per period " + std::to_string(steps_per_period) + " must be >= 1");
  double frequency = std::isfinite(max_frequency_hz) ? max_frequency_hz : 0.0;
  if (system.n_modes() > 0) frequency = std::max(frequency, system.omega.maxCoeff() / (2.0 * kPi));
  if (!(frequency > 0.0))
    throw InputError("reduced time step: no positive frequency to resolve (max_frequency_hz = " +
                     format_number(max_frequency_hz) + ", no elastic mode)");
  return 1.0 / (steps_per_period * frequency);
}

}  // namespace crackle::reduced

namespace crackle::reduced {

double reduced_closed_max_frequency(const ReducedSystem& system) {
  validate(system);
  const Index stride = system.rows_per_pair(), m = system.n_modes();
  std::vector<Index> rows;
  std::vector<double> stiffness;
  for (Index i = 0; i < system.n_pairs(); ++i)
    for (Index j = 0; j < stride; ++j) {
      const double eps = j == 0 ? system.normal_penalty : system.tangential_penalty;
      if (eps * system.pair_area[i] > 0.0) {
        rows.push_back(stride * i + j);
        stiffness.push_back(eps * system.pair_area[i]);
      }
    }
  MatrixX closed = system.omega.array().square().matrix().asDiagonal();
  if (!rows.empty()) {
    MatrixX compliance = system.residual(rows, rows);
    for (std::size_t k = 0; k < rows.size(); ++k) compliance(k, k) += 1.0 / stiffness[k];
    const Eigen::LLT<MatrixX> factor(compliance);
    if (factor.info() != Eigen::Success) throw SolverError("reduced closed frequency: R + 1/(eps A) is not positive definite");
    const MatrixX pair_modes = system.pair_modes(rows, Eigen::all);
    closed += pair_modes.transpose() * factor.solve(pair_modes);
  }
  if (m == 0) return 0.0;
  const Eigen::SelfAdjointEigenSolver<MatrixX> eigen(closed, Eigen::EigenvaluesOnly);
  return std::sqrt(std::max(eigen.eigenvalues().maxCoeff(), 0.0)) / (2.0 * kPi);
}

}  // namespace crackle::reduced
