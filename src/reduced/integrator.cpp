#include "reduced/integrator.hpp"

#include <Eigen/Eigenvalues>
#include <Eigen/LU>
#include <algorithm>
#include <cmath>
#include <string>
#include <utility>

#include "contact/penalty.hpp"
#include "core/errors.hpp"

namespace crackle::reduced {
namespace {

/// The pair's local frame in row order (normal, tangent 1, tangent 2): the normal is the x axis.
const Vec3 kLocalNormal = Vec3::UnitX();
constexpr double kPi = 3.14159265358979323846;

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

/// Indices of the nonzero entries of p.
std::vector<Index> nonzero_rows(const VectorX& p) {
  std::vector<Index> rows;
  for (Index i = 0; i < p.size(); ++i)
    if (p[i] != 0.0) rows.push_back(i);
  return rows;
}

}  // namespace

ReducedIntegrator::ReducedIntegrator(const ReducedSystem& system, double time_step, LoadFunction load,
                                     ReducedIntegratorOptions options)
    : system_(system), time_step_(time_step), load_(std::move(load)), options_(options) {
  validate(system_);
  if (!(time_step_ > 0.0) || !std::isfinite(time_step_))
    throw InputError("reduced integrator: time step " + format_number(time_step_) + " s must be positive");
  if (!load_) load_ = [](double) { return 0.0; };
  const double h = time_step_;
  const VectorX omega2 = system_.omega.array().square();
  damping_ = system_.rayleigh_alpha + system_.rayleigh_beta * omega2.array();
  denominator_ = 1.0 + 0.5 * h * damping_.array() + 0.25 * h * h * omega2.array();
  // W = B Phi S (B Phi)^T + R, S_r = (h^2/4) / denominator_r.
  const VectorX s = (0.25 * h * h) / denominator_.array();
  w_ = system_.pair_modes * s.asDiagonal() * system_.pair_modes.transpose() + system_.residual;
  normal_stiffness_ = system_.normal_penalty * system_.pair_area;
  tangential_stiffness_ = system_.tangential_penalty * system_.pair_area;
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
  slip_direction_.assign(system_.n_pairs(), Vec3::Zero());
  // Static contact problem of the massless boundary at t0: g = g0 + B Phi q + R p + r_f a, W = R,
  // tangential forces 0 (their reference slip is the current one).
  VectorX free_gap = system_.pair_modes * q_ + system_.load_residual * load_value_;
  for (Index i = 0; i < system_.n_pairs(); ++i) free_gap[stride * i] += system_.initial_gap[i];
  p_ = VectorX::Zero(c);
  g_ = free_gap;
  last_iterations_ = 0;
  if (c > 0) solve_normal(system_.residual, free_gap, nullptr);
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
  total_factorizations_ = 0;
}

void ReducedIntegrator::solve_normal(const MatrixX& w, const VectorX& free_gap, CachedFactor* cache) {
  // Primal-dual active set on the normal rows, warm-started from the current forces.
  const Index n = system_.n_pairs(), stride = system_.rows_per_pair();
  std::vector<char> active(n);
  for (Index i = 0; i < n; ++i) active[i] = p_[stride * i] > 0.0 && normal_stiffness_[i] > 0.0;
  CachedFactor local;
  CachedFactor& factor = cache ? *cache : local;
  std::vector<Index> rows;
  for (int iteration = 1; iteration <= options_.max_contact_iterations; ++iteration) {
    rows.clear();
    for (Index i = 0; i < n; ++i)
      if (active[i]) rows.push_back(stride * i);
    p_.setZero();
    g_ = free_gap;
    if (!rows.empty()) {
      if (!factor.valid || factor.rows != rows) {
        MatrixX matrix = w(rows, rows);
        for (std::size_t k = 0; k < rows.size(); ++k) matrix(k, k) += 1.0 / normal_stiffness_[rows[k] / stride];
        factor.factor.compute(matrix);
        if (factor.factor.info() != Eigen::Success) fail("Cholesky factor of the active contact block failed");
        factor.rows = rows;
        factor.valid = true;
        ++total_factorizations_;
      }
      const VectorX x = factor.factor.solve(-free_gap(rows));
      p_(rows) = x;
      g_.noalias() += w(Eigen::all, rows) * x;
    }
    bool changed = false;
    for (Index i = 0; i < n; ++i) {
      if (!(normal_stiffness_[i] > 0.0)) continue;
      const Index r = stride * i;
      const bool now = active[i] ? p_[r] > 0.0 : g_[r] < 0.0;
      if (now != static_cast<bool>(active[i])) changed = true;
      active[i] = now;
    }
    if (!changed) {
      last_iterations_ = iteration;
      total_iterations_ += iteration;
      return;
    }
  }
  fail(("contact active set did not settle in " + std::to_string(options_.max_contact_iterations) + " iterations")
           .c_str());
}

void ReducedIntegrator::solve_with_friction(const VectorX& free_gap) {
  // Per closed pair: normal row (penalty), and two tangential rows, either stick (elastic predictor,
  // symmetric) or slip with the direction frozen (p_T = mu p_N e). Iterate states to a fixed point.
  const Index n = system_.n_pairs();
  const double mu = system_.friction_coefficient;
  std::vector<Index> rows;
  for (int iteration = 1; iteration <= options_.max_contact_iterations; ++iteration) {
    rows.clear();
    bool any_slip = false;
    for (Index i = 0; i < n; ++i) {
      if (state_[i] == PairState::kOpen) continue;
      for (Index j = 0; j < 3; ++j) rows.push_back(3 * i + j);
      any_slip = any_slip || state_[i] == PairState::kSlip;
    }
    p_.setZero();
    g_ = free_gap;
    if (!rows.empty()) {
      const Index size = static_cast<Index>(rows.size());
      VectorX rhs(size);
      for (Index k = 0; k < size; ++k) {
        const Index r = rows[k], pair = r / 3;
        const double stiffness = r % 3 == 0 ? normal_stiffness_[pair] : tangential_stiffness_[pair];
        rhs[k] = r % 3 == 0 ? -free_gap[r] : g_old_[r] + p_old_[r] / stiffness - free_gap[r];
      }
      auto assemble_symmetric = [&]() {
        MatrixX matrix = w_(rows, rows);
        for (Index k = 0; k < size; ++k) {
          const Index r = rows[k], pair = r / 3;
          matrix(k, k) += 1.0 / (r % 3 == 0 ? normal_stiffness_[pair] : tangential_stiffness_[pair]);
        }
        return matrix;
      };
      VectorX x;
      if (!any_slip) {
        if (!step_factor_.valid || step_factor_.rows != rows) {
          step_factor_.factor.compute(assemble_symmetric());
          if (step_factor_.factor.info() != Eigen::Success) fail("Cholesky factor of the stick contact block failed");
          step_factor_.rows = rows;
          step_factor_.valid = true;
          ++total_factorizations_;
        }
        x = step_factor_.factor.solve(rhs);
      } else {
        MatrixX matrix = assemble_symmetric();
        for (Index k = 0; k < size; k += 3) {
          const Index pair = rows[k] / 3;
          if (state_[pair] != PairState::kSlip) continue;
          for (Index j = 1; j < 3; ++j) {  // p_T_j - mu e_j p_N = 0
            matrix.row(k + j).setZero();
            matrix(k + j, k + j) = 1.0;
            matrix(k + j, k) = -mu * slip_direction_[pair][j];
            rhs[k + j] = 0.0;
          }
        }
        x = matrix.partialPivLu().solve(rhs);
        ++total_factorizations_;
      }
      p_(rows) = x;
      g_.noalias() += w_(Eigen::all, rows) * x;
    }
    bool changed = false;
    for (Index i = 0; i < n; ++i) {
      if (!(normal_stiffness_[i] > 0.0)) continue;
      const Index r = 3 * i;
      const bool closed_before = state_[i] != PairState::kOpen;
      const bool closed_now = closed_before ? p_[r] > 0.0 : g_[r] < 0.0;
      if (!closed_now) {
        if (closed_before) changed = true;
        state_[i] = PairState::kOpen;
        continue;
      }
      if (!closed_before) {
        state_[i] = PairState::kStick;
        changed = true;
        continue;
      }
      const double area = system_.pair_area[i];
      const contact::CoulombUpdate update = contact::coulomb_return_mapping(
          Vec3(0.0, p_old_[r + 1], p_old_[r + 2]) / area,
          Vec3(0.0, g_[r + 1] - g_old_[r + 1], g_[r + 2] - g_old_[r + 2]), kLocalNormal, system_.tangential_penalty,
          mu, p_[r] / area);
      if (update.slipping) {
        const Vec3 direction = update.traction.normalized();
        if (state_[i] != PairState::kSlip ||
            (direction - slip_direction_[i]).norm() > options_.slip_direction_tolerance)
          changed = true;
        state_[i] = PairState::kSlip;
        slip_direction_[i] = direction;
      } else if (state_[i] == PairState::kSlip) {
        state_[i] = PairState::kStick;
        changed = true;
      }
    }
    if (!changed) {
      last_iterations_ = iteration;
      total_iterations_ += iteration;
      return;
    }
  }
  fail(("stick/slip states did not settle in " + std::to_string(options_.max_contact_iterations) + " iterations")
           .c_str());
}

void ReducedIntegrator::solve_contact(const MatrixX& w, const VectorX& free_gap, bool tangential,
                                      CachedFactor* cache) {
  if (tangential)
    solve_with_friction(free_gap);
  else
    solve_normal(w, free_gap, cache);
}

void ReducedIntegrator::step() {
  const double h = time_step_;
  const Index c = system_.n_rows(), stride = system_.rows_per_pair();
  const double next_time = time_ + h;
  const double a1 = load_(next_time);
  const VectorX omega2 = system_.omega.array().square();
  // Predictors, then the end-of-step acceleration without the pair forces.
  const VectorX q_pred = q_ + h * v_ + (0.25 * h * h) * acc_;
  const VectorX v_pred = v_ + (0.5 * h) * acc_;
  VectorX acc_next = (system_.load_modal * a1 - damping_.cwiseProduct(v_pred) - omega2.cwiseProduct(q_pred))
                         .cwiseQuotient(denominator_);
  p_old_ = p_;
  g_old_ = g_;
  if (c > 0) {
    const VectorX q_free = q_pred + (0.25 * h * h) * acc_next;
    VectorX free_gap = system_.pair_modes * q_free + system_.load_residual * a1;
    for (Index i = 0; i < system_.n_pairs(); ++i) free_gap[stride * i] += system_.initial_gap[i];
    solve_contact(w_, free_gap, friction_active(), &step_factor_);
    const std::vector<Index> loaded = nonzero_rows(p_);
    if (!loaded.empty())
      acc_next += (system_.pair_modes(loaded, Eigen::all).transpose() * p_(loaded)).cwiseQuotient(denominator_);
  } else {
    last_iterations_ = 0;
  }
  const VectorX q_next = q_pred + (0.25 * h * h) * acc_next;
  const VectorX v_next = v_pred + (0.5 * h) * acc_next;
  if (!q_next.allFinite() || !v_next.allFinite() || !p_.allFinite()) fail("the state is not finite");

  // Energy account (see ReducedEnergy): trapezoidal external work, exact Newmark damping work.
  const double a_mean = 0.5 * (load_value_ + a1);
  const VectorX v_mean = 0.5 * (v_ + v_next);
  energy_.external_work += a_mean * system_.load_modal.dot(q_next - q_);
  if (c > 0) energy_.external_work += a_mean * system_.load_residual.dot(p_ - p_old_);
  energy_.damping_dissipation += h * (damping_.array() * v_mean.array().square()).sum();
  if (friction_active()) {
    for (Index i = 0; i < system_.n_pairs(); ++i) {
      const Index r = 3 * i;
      const double area = system_.pair_area[i];
      energy_.friction_dissipation +=
          area * contact::coulomb_return_mapping(Vec3(0.0, p_old_[r + 1], p_old_[r + 2]) / area,
                                                 Vec3(0.0, g_[r + 1] - g_old_[r + 1], g_[r + 2] - g_old_[r + 2]),
                                                 kLocalNormal, system_.tangential_penalty,
                                                 system_.friction_coefficient, p_[r] / area)
                     .dissipation;
    }
  }
  q_ = q_next;
  v_ = v_next;
  acc_ = acc_next;
  load_value_ = a1;
  ++step_count_;
  time_ = next_time;
  energy_.kinetic = 0.5 * v_.squaredNorm();
  energy_.modal_strain = 0.5 * (system_.omega.array() * q_.array()).square().sum();
  energy_.residual_strain = residual_strain(p_, load_value_);
  energy_.penalty = penalty_energy();
  update_energy_scale();
}

void ReducedIntegrator::advance(Index n_steps) {
  for (Index k = 0; k < n_steps; ++k) step();
}

double ReducedIntegrator::residual_strain(const VectorX& p, double a) const {
  const std::vector<Index> loaded = nonzero_rows(p);
  if (loaded.empty()) return 0.0;
  const VectorX p_loaded = p(loaded);
  return 0.5 * p_loaded.dot(system_.residual(loaded, loaded) * p_loaded) +
         a * p_loaded.dot(system_.load_residual(loaded));
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
