#include "sweep/harmonic_balance.hpp"
#include "sweep/harmonic_balance_impl.hpp"

#include <fftw3.h>

#include <Eigen/Dense>
#include <algorithm>
#include <atomic>
#include <cmath>
#include <complex>
#include <string>

#include "contact_law/penalty.hpp"
#include "core/errors.hpp"

namespace crackle::sweep {

using namespace detail;



// ---------------------------------------------------------------------------------------------

namespace {
/// Column of `outputs` holding `order` of Omega, or -1 when the solution has no such order
/// (order 1/2 of a nu = 1 solution, beyond H).
Index order_column(const Solution& sol, double order) {
  const double k = order * sol.subharmonic;
  const long column = std::lround(k);
  if (std::abs(k - column) > 1e-9 || column < 0 || column >= sol.outputs.cols()) return -1;
  return static_cast<Index>(column);
}
}  // namespace

double Solution::amplitude(Index row, double order) const {
  const Index column = order_column(*this, order);
  return column < 0 ? 0.0 : std::abs(outputs(row, column));
}

double Solution::phase(Index row, double order) const {
  const Index column = order_column(*this, order);
  return column < 0 ? 0.0 : std::arg(outputs(row, column));
}

OrderRatios Solution::ratios(Index row) const {
  OrderRatios r;
  const double a1 = amplitude(row, 1.0);
  if (a1 == 0.0) return r;
  r.second = amplitude(row, 2.0) / a1;
  r.third = amplitude(row, 3.0) / a1;
  r.half = amplitude(row, 0.5) / a1;
  return r;
}

HarmonicBalance::HarmonicBalance(const reduced::ReducedSystem& system, const HarmonicBalanceOptions& options)
    : impl_(std::make_unique<Impl>(system, options)) {
  Impl& d = *impl_;
  if (options.harmonics < 1) throw InputError("harmonic balance: harmonics must be >= 1, got " + std::to_string(options.harmonics));
  if (options.subharmonic != 1 && options.subharmonic != 2)
    throw InputError("harmonic balance: subharmonic must be 1 or 2, got " + std::to_string(options.subharmonic));
  d.c = system.n_rows();
  d.m = system.n_modes();
  d.H = options.harmonics;
  d.nu = options.subharmonic;
  d.N = options.time_samples > 0 ? options.time_samples : default_samples(d.H);
  if (d.N < 4 * d.H)
    throw InputError("harmonic balance: time_samples " + std::to_string(d.N) + " < 4 H = " + std::to_string(4 * d.H));
  if (system.pair_modes.rows() != d.c || system.pair_modes.cols() != d.m || system.residual.rows() != d.c ||
      system.residual.cols() != d.c || system.load_modal.size() != d.m || system.load_residual.size() != d.c ||
      system.initial_gap.size() != system.n_pairs())
    throw InputError("harmonic balance: the reduced system's sizes are inconsistent (m = " + std::to_string(d.m) +
                     ", c = " + std::to_string(d.c) + ")");
  d.rows_per_pair = static_cast<int>(system.rows_per_pair());
  d.matrix_free = selects_matrix_free(options, d.c);
  d.stiffness = VectorX::Zero(d.c);
  d.row_gap = VectorX::Zero(d.c);
  for (Index pair = 0; pair < system.n_pairs(); ++pair) {
    d.stiffness[d.rows_per_pair * pair] = system.normal_penalty * system.pair_area[pair];
    d.row_gap[d.rows_per_pair * pair] = system.initial_gap[pair];
  }
  if (d.rows_per_pair == 3) {
    d.basis.resize(d.N, 2 * d.H + 1);
    for (int j = 0; j < d.N; ++j) {
      d.basis(j, 0) = 1.0;
      for (int k = 1; k <= d.H; ++k) {
        d.basis(j, 2 * k - 1) = std::cos(2.0 * kPi * k * j / d.N);
        d.basis(j, 2 * k) = std::sin(2.0 * kPi * k * j / d.N);
      }
    }
  }

  // Planned on fftw_malloc arrays, as every transform of the plans runs (FftwBuffer): FFTW may then
  // use its SIMD codelets (plans for unaligned arrays ran buffered scalar ones and their copies: a
  // fifth of a sweep's time, docs/benchmarks.md 9.3).
  FftwBuffer<double> signal(d.N);
  FftwBuffer<fftw_complex> spectrum(d.N / 2 + 1);
  d.forward = fftw_plan_dft_r2c_1d(d.N, signal.data, spectrum.data, FFTW_ESTIMATE);
  d.backward = fftw_plan_dft_c2r_1d(d.N, spectrum.data, signal.data, FFTW_ESTIMATE);

  if (options.gap_scale > 0.0) {
    d.scale = options.gap_scale;
  } else {
    double s = d.c > 0 ? system.initial_gap.cwiseAbs().maxCoeff() : 0.0;
    ComplexVectorX dr, dd;
    d.modal_receptance(0.0, dr, dd);
    const VectorX static_gap = system.pair_modes * (dr.real().asDiagonal() * system.load_modal) + system.load_residual;
    if (d.c > 0) s = std::max(s, static_gap.cwiseAbs().maxCoeff());
    if (d.c > 0 && options.scale_frequency > 0.0) {
      d.modal_receptance(options.scale_frequency, dr, dd);
      const ComplexVectorX dynamic_gap = system.pair_modes.cast<Complex>() * dr.cwiseProduct(system.load_modal.cast<Complex>()) +
                                         system.load_residual.cast<Complex>();
      s = std::max(s, kDynamicScaleShare * dynamic_gap.cwiseAbs().maxCoeff());
    }
    d.scale = s > 0.0 ? s : 1e-6;
  }
}

HarmonicBalance::~HarmonicBalance() = default;

namespace {

/// J formed and LU-factorised; the bordered matrix's LU is kept for the next solve with the same border.
class DenseLinearization final : public Linearization {
 public:
  DenseLinearization(MatrixX jacobian, VectorX d_omega) : jacobian_(std::move(jacobian)) { d_omega_ = std::move(d_omega); }
  VectorX solve(const VectorX& b, double) override {
    if (!factored_) {
      lu_.compute(jacobian_);
      factored_ = true;
    }
    return lu_.solve(b);
  }
  VectorX solve_bordered(const VectorX& column, const VectorX& row, const VectorX& b, double) override {
    const Index n = jacobian_.rows();
    if (!(column.size() == column_.size() && row.size() == row_.size() && column == column_ && row == row_)) {
      MatrixX a(n + 1, n + 1);
      a.topLeftCorner(n, n) = jacobian_;
      a.topRightCorner(n, 1) = column;
      a.row(n) = row.transpose();
      bordered_.compute(a);
      column_ = column;
      row_ = row;
    }
    return bordered_.solve(b);
  }

 private:
  MatrixX jacobian_;
  Eigen::PartialPivLU<MatrixX> lu_;
  bool factored_ = false;
  Eigen::PartialPivLU<MatrixX> bordered_;
  VectorX column_, row_;
};

/// GMRES on the matrix-free Jacobian (krylov.hpp); its iterations go to the solver's statistics.
class KrylovLinearization final : public Linearization {
 public:
  KrylovLinearization(KrylovJacobian jacobian, VectorX d_omega, std::function<void(const GmresReport&)> record)
      : jacobian_(std::move(jacobian)), record_(std::move(record)) {
    d_omega_ = std::move(d_omega);
  }
  VectorX solve(const VectorX& b, double tolerance) override {
    GmresReport report;
    VectorX x = jacobian_.solve(b, tolerance, &report);
    record_(report);
    return x;
  }
  VectorX solve_bordered(const VectorX& column, const VectorX& row, const VectorX& b, double tolerance) override {
    GmresReport report;
    VectorX x = jacobian_.solve_bordered(column, row, b, tolerance, &report);
    record_(report);
    return x;
  }

 private:
  KrylovJacobian jacobian_;
  std::function<void(const GmresReport&)> record_;
};

}  // namespace

std::unique_ptr<Linearization> HarmonicBalance::Impl::linearize(const std::vector<HarmonicReceptance>& rec,
                                                                const VectorX& gaps, double factor) const {
  VectorX d_omega;
  if (!rec.empty() && rec[0].load_d.size() > 0) d_omega = -apply(rec, forces(gaps, factor), true) / scale;
  if (!matrix_free) return std::make_unique<DenseLinearization>(jacobian(rec, gaps, factor), std::move(d_omega));
  std::vector<ComplexVectorX> modal(H + 1);
  for (int k = 0; k <= H; ++k) modal[k] = rec[k].modal;
  ++krylov_factorisations;
  return std::make_unique<KrylovLinearization>(
      KrylovJacobian(system, H, std::move(modal), pair_derivatives(gaps, factor), options.krylov), std::move(d_omega),
      [this](const GmresReport& report) { record(report); });
}

bool HarmonicBalance::matrix_free() const { return impl_->matrix_free; }

std::unique_ptr<Linearization> HarmonicBalance::linearize(double omega, const VectorX& gaps, bool d_omega) const {
  return impl_->linearize(impl_->receptances(omega, d_omega, !impl_->matrix_free), gaps, 1.0);
}

KrylovStatistics HarmonicBalance::krylov_statistics() const {
  KrylovStatistics st;
  st.solves = impl_->krylov_solves;
  st.iterations = impl_->krylov_iterations;
  st.max_iterations = impl_->krylov_max;
  st.factorisations = impl_->krylov_factorisations;
  st.unconverged = impl_->krylov_unconverged;
  return st;
}

bool HarmonicBalance::selects_matrix_free(const HarmonicBalanceOptions& options, Index rows) {
  if (options.solver != LinearSolver::automatic) return options.solver == LinearSolver::krylov;
  return rows * (2 * options.harmonics + 1) > options.dense_limit;
}

double HarmonicBalance::memory_bytes(Index rows, Index modes, int harmonics, bool matrix_free, const KrylovOptions& krylov) {
  const double c = static_cast<double>(rows), m = static_cast<double>(modes), nc = 2.0 * harmonics + 1.0;
  const double n = c * nc;
  const double samples = c * std::max(4096.0, 4.0 * harmonics);  // AFT time samples (c x N)
  if (!matrix_free) {
    // J, its LU and the bordered (n + 1) LU; complex c x c receptances and their Omega derivatives per harmonic
    return 8.0 * (3.0 * n * n + 2.0 * samples) + 16.0 * 2.0 * (harmonics + 1.0) * c * c;
  }
  // dP/dG blocks, their deviations from the mean and the breathing pairs' LU (c (2H+1)^2 each), the
  // closing rows' LU and coupling and the breathing rows' flexibility (<= c x c each), the Krylov basis
  // and the vectors
  return 8.0 * (3.0 * c * nc * nc + 3.0 * c * c + (krylov.restart + 1.0 + 8.0) * n + 2.0 * samples + 4.0 * c * m);
}

Index HarmonicBalance::n_rows() const { return impl_->c; }
int HarmonicBalance::n_harmonics() const { return impl_->H; }
int HarmonicBalance::n_samples() const { return impl_->N; }
Index HarmonicBalance::n_unknowns() const { return impl_->n_unknowns(); }
double HarmonicBalance::gap_scale() const { return impl_->scale; }
const HarmonicBalanceOptions& HarmonicBalance::options() const { return impl_->options; }

VectorX HarmonicBalance::linear_gaps(double omega) const {
  return impl_->apply(impl_->receptances(omega, false, !impl_->matrix_free), VectorX::Zero(n_unknowns()), false);
}

VectorX HarmonicBalance::pair_forces(const VectorX& gaps) const { return impl_->forces(gaps); }

VectorX HarmonicBalance::residual(double omega, const VectorX& gaps) const {
  return impl_->residual(impl_->receptances(omega, false, !impl_->matrix_free), gaps);
}

MatrixX HarmonicBalance::jacobian(double omega, const VectorX& gaps, VectorX* d_omega) const {
  const auto rec = impl_->receptances(omega, d_omega != nullptr, true);
  if (d_omega) *d_omega = -impl_->apply(rec, impl_->forces(gaps), true) / impl_->scale;
  return impl_->jacobian(rec, gaps);
}

Solution HarmonicBalance::solve(double omega, const VectorX& guess) const {
  const Impl& d = *impl_;
  const auto rec = d.receptances(omega, false, !d.matrix_free);
  Solution sol;
  sol.omega = omega;
  sol.subharmonic = d.nu;
  const bool given = guess.size() == d.n_unknowns();
  sol.gaps = given ? guess : linear_gaps(omega);
  double norm = 0.0;
  int it = d.newton(rec, sol.gaps, 1.0, norm);
  if (norm > d.options.tolerance && !given) {
    // fallback from the linear guess: homotopy on the penalty, eps_N / 64 .. eps_N
    sol.gaps = linear_gaps(omega);
    for (double factor = 1.0 / 64.0; factor <= 1.0; factor *= 2.0) it += d.newton(rec, sol.gaps, factor, norm);
  }
  sol.iterations = it;
  sol.residual = norm;
  sol.converged = norm <= d.options.tolerance;
  if (!sol.converged)
    throw SolverError("harmonic balance: Newton did not converge at Omega = " + format_number(omega) +
                      " rad/s: residual " + format_number(norm) + " after " + std::to_string(it) + " iterations");
  complete(sol);
  return sol;
}

void HarmonicBalance::complete(Solution& sol) const {
  const Impl& d = *impl_;
  const reduced::ReducedSystem& s = d.system;
  sol.subharmonic = d.nu;
  sol.forces = d.forces(sol.gaps);
  const Index o = s.n_outputs();
  sol.modal.resize(d.m, d.H + 1);
  sol.outputs.resize(o, d.H + 1);
  ComplexVectorX pk(d.c);
  sol.rigid_imbalance = 0.0;
  for (int k = 0; k <= d.H; ++k) {
    ComplexVectorX dr, dd;
    d.modal_receptance(k * sol.omega / d.nu, dr, dd);
    for (Index i = 0; i < d.c; ++i) pk[i] = d.amplitude(sol.forces, k, i);
    const Complex load = k == d.nu ? 1.0 : 0.0;
    const ComplexVectorX modal_force = s.pair_modes.transpose().cast<Complex>() * pk + s.load_modal.cast<Complex>() * load;
    if (k == 0)
      for (Index r = 0; r < d.m; ++r)
        if (s.omega[r] == 0.0) sol.rigid_imbalance = std::max(sol.rigid_imbalance, std::abs(modal_force[r]));
    sol.modal.col(k) = dr.cwiseProduct(modal_force);
    if (o > 0)
      sol.outputs.col(k) = s.output_modes.cast<Complex>() * sol.modal.col(k) +
                           s.output_residual_pairs.cast<Complex>() * pk + s.output_residual_load.cast<Complex>() * load;
  }
  // H-convergence: share of the gap response in the top harmonics k >= first_top
  const int first_top = std::clamp(static_cast<int>(std::floor((1.0 - d.options.top_share) * d.H)) + 1, 1, d.H);
  double total = 0.0, top = 0.0;
  for (int k = 1; k <= d.H; ++k)
    for (Index i = 0; i < d.c; ++i) {
      const double a2 = std::norm(d.amplitude(sol.gaps, k, i));
      total += a2;
      if (k >= first_top) top += a2;
    }
  sol.top_harmonic_share = total > 0.0 ? std::sqrt(top / total) : 0.0;
  sol.harmonics_flagged = sol.top_harmonic_share > d.options.top_threshold;
}

VectorX resize_harmonics(const VectorX& gaps, Index rows, int harmonics) {
  VectorX out = VectorX::Zero(rows * (2 * harmonics + 1));
  const Index n = std::min(out.size(), gaps.size());
  out.head(n) = gaps.head(n);
  return out;
}

VectorX period_doubled_guess(const reduced::ReducedSystem& system, const Solution& period_one,
                             const Stability& stability, int harmonics, double amplitude) {
  if (period_one.subharmonic != 1)
    throw InputError("period_doubled_guess: needs a period-one solution (nu = 1), got nu = " +
                     std::to_string(period_one.subharmonic));
  const Index c = system.n_rows();
  const int h1 = static_cast<int>(period_one.gaps.size() / c - 1) / 2;
  VectorX guess = VectorX::Zero(c * (2 * harmonics + 1));
  auto put = [&](VectorX& x, int k, Index i, Complex value) {
    if (k == 0) {
      x[i] += value.real();
    } else {
      x[(2 * k - 1) * c + i] += value.real();
      x[(2 * k) * c + i] -= value.imag();
    }
  };
  // even harmonics: the period-one response
  for (int k = 0; k <= h1 && 2 * k <= harmonics; ++k)
    for (Index i = 0; i < c; ++i) {
      const Complex value = k == 0 ? Complex(period_one.gaps[i]) : Complex(period_one.gaps[(2 * k - 1) * c + i], -period_one.gaps[(2 * k) * c + i]);
      put(guess, 2 * k, i, value);
    }
  // odd harmonics: the critical eigenvector, harmonic k of Omega at Im(lambda) + k Omega = j Omega / 2
  if (stability.critical_mode.size() == 0) return guess;
  const int hill_h = static_cast<int>(stability.critical_mode.cols() - 1) / 2;
  const double shift = 2.0 * stability.critical_exponent.imag() / period_one.omega;
  VectorX odd = VectorX::Zero(guess.size());
  for (int k = -hill_h; k <= hill_h; ++k) {
    const long j = std::lround(2.0 * k + shift);
    if (j == 0 || std::abs(j) > harmonics) continue;
    const ComplexVectorX gaps = system.pair_modes.cast<Complex>() * stability.critical_mode.col(k + hill_h);
    for (Index i = 0; i < c; ++i) put(odd, static_cast<int>(std::abs(j)), i, j > 0 ? gaps[i] : std::conj(gaps[i]));
  }
  const double largest = odd.cwiseAbs().maxCoeff();
  if (largest > 0.0) guess += odd * (amplitude / largest);
  return guess;
}

}  // namespace crackle::sweep
