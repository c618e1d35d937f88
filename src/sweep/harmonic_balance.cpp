#include "sweep/harmonic_balance.hpp"

#include <fftw3.h>

#include <Eigen/Dense>
#include <Eigen/Eigenvalues>
#include <unsupported/Eigen/MatrixFunctions>
#include <algorithm>
#include <atomic>
#include <cmath>
#include <complex>
#include <string>

#include "contact_law/penalty.hpp"
#include "core/errors.hpp"

namespace crackle::sweep {

LinearSolver linear_solver_named(const std::string& name) {
  return name == "dense" ? LinearSolver::dense : name == "krylov" ? LinearSolver::krylov : LinearSolver::automatic;
}

namespace {

using Complex = std::complex<double>;
/// The automatic gap scale is at least this share of the linear gap response at the drive
/// (HarmonicBalanceOptions::scale_frequency): a floor for loads the crack barely sees statically,
/// small enough to leave the static scale in place wherever that one is not tiny.
constexpr double kDynamicScaleShare = 0.1;

/// Default N: a power of two >= 4H and >= 4096. A sample entering or leaving contact changes the
/// Jacobian by about eps_N A / N; near a lightly damped resonance that jump alone can fold the
/// sampled branch (measured: micro-folds at N = 64..1024 for Q = 50, H = 10; none from 4096 on).
int default_samples(int harmonics) {
  int n = 4096;
  while (n < 4 * harmonics) n *= 2;
  return n;
}

/// Receptances of one harmonic: H(omega_k) (c x c) and E(omega_k) (c), with their Omega derivatives.
struct HarmonicReceptance {
  ComplexVectorX modal;    ///< D_r(omega_k), m
  ComplexVectorX modal_d;  ///< dD_r/dOmega (with d omega_k / d Omega), m
  ComplexMatrixX pairs;    ///< empty when matrix-free
  ComplexVectorX load;
  ComplexMatrixX pairs_d;  ///< dH/dOmega
  ComplexVectorX load_d;   ///< dE/dOmega
};

}  // namespace

struct HarmonicBalance::Impl {
  const reduced::ReducedSystem& system;
  HarmonicBalanceOptions options;
  Index c = 0;
  Index m = 0;
  int H = 0;
  int N = 0;
  int nu = 1;
  double scale = 1.0;
  VectorX stiffness;  ///< eps_N A per row (0 on tangential rows)
  VectorX row_gap;    ///< g0 per row (0 on tangential rows)
  int rows_per_pair = 1;
  MatrixX basis;      ///< N x (2H+1): 1, cos k tau_j, sin k tau_j (friction tangents)
  fftw_plan forward = nullptr;   ///< r2c, N -> N/2+1
  fftw_plan backward = nullptr;  ///< c2r
  bool matrix_free = false;
  mutable std::atomic<long> krylov_solves{0}, krylov_iterations{0}, krylov_factorisations{0}, krylov_unconverged{0};
  mutable std::atomic<int> krylov_max{0};

  Impl(const reduced::ReducedSystem& s, const HarmonicBalanceOptions& o) : system(s), options(o) {}
  ~Impl() {
    if (forward) fftw_destroy_plan(forward);
    if (backward) fftw_destroy_plan(backward);
  }

  Index n_unknowns() const { return c * (2 * H + 1); }

  /// D_r(omega) and dD_r/domega; rigid modes are left out of the static (omega = 0) receptance.
  void modal_receptance(double omega, ComplexVectorX& d, ComplexVectorX& d_omega) const {
    d.resize(m);
    d_omega.resize(m);
    for (Index r = 0; r < m; ++r) {
      const double w = system.omega[r];
      const double zeta = system.damping_ratio(r);
      const Complex den(w * w - omega * omega, 2.0 * zeta * w * omega);
      if (std::abs(den) == 0.0) {
        d[r] = 0.0;
        d_omega[r] = 0.0;
        continue;
      }
      d[r] = 1.0 / den;
      d_omega[r] = Complex(2.0 * omega, -2.0 * zeta * w) / (den * den);
    }
  }

  /// The receptances of harmonics 0..H; the c x c matrices only when `dense` (the dense solver's).
  std::vector<HarmonicReceptance> receptances(double omega, bool derivatives, bool dense) const {
    std::vector<HarmonicReceptance> out(H + 1);
    const MatrixX& bphi = system.pair_modes;
    for (int k = 0; k <= H; ++k) {
      const double wk = k * omega / nu;
      ComplexVectorX d, dd;
      modal_receptance(wk, d, dd);
      HarmonicReceptance& h = out[k];
      h.modal = d;
      h.modal_d = dd * (static_cast<double>(k) / nu);
      if (!dense) {
        h.load = bphi.cast<Complex>() * d.cwiseProduct(system.load_modal.cast<Complex>()) +
                 system.load_residual.cast<Complex>();
        if (derivatives) h.load_d = bphi.cast<Complex>() * h.modal_d.cwiseProduct(system.load_modal.cast<Complex>());
        continue;
      }
      const ComplexMatrixX scaled = bphi.cast<Complex>() * d.asDiagonal();
      h.pairs = scaled * bphi.transpose().cast<Complex>();
      h.pairs += system.residual.cast<Complex>();
      h.load = scaled * system.load_modal.cast<Complex>() + system.load_residual.cast<Complex>();
      if (derivatives) {
        const double dk = static_cast<double>(k) / nu;  // d omega_k / d Omega
        const ComplexMatrixX scaled_d = bphi.cast<Complex>() * (dd * dk).asDiagonal();
        h.pairs_d = scaled_d * bphi.transpose().cast<Complex>();
        h.load_d = scaled_d * system.load_modal.cast<Complex>();
      }
    }
    return out;
  }

  /// Complex amplitude of harmonic k of row i from the real layout (k = 0: the mean).
  Complex amplitude(const VectorX& x, int k, Index i) const {
    if (k == 0) return x[i];
    return Complex(x[(2 * k - 1) * c + i], -x[(2 * k) * c + i]);
  }
  void set_amplitude(VectorX& x, int k, Index i, Complex value) const {
    if (k == 0) {
      x[i] = value.real();
      return;
    }
    x[(2 * k - 1) * c + i] = value.real();
    x[(2 * k) * c + i] = -value.imag();
  }

  /// Time samples (c x N, row-major by row) of a harmonic vector.
  MatrixX to_time(const VectorX& x) const {
    MatrixX samples(c, N);
    std::vector<fftw_complex> spectrum(N / 2 + 1);
    std::vector<double> signal(N);
    for (Index i = 0; i < c; ++i) {
      for (auto& s : spectrum) s[0] = s[1] = 0.0;
      spectrum[0][0] = x[i];
      for (int k = 1; k <= H; ++k) {
        const Complex a = amplitude(x, k, i) * 0.5;
        spectrum[k][0] = a.real();
        spectrum[k][1] = a.imag();
      }
      fftw_execute_dft_c2r(backward, spectrum.data(), signal.data());
      for (int j = 0; j < N; ++j) samples(i, j) = signal[j];
    }
    return samples;
  }

  /// Harmonics 0..H of time samples (c x N), real layout.
  VectorX to_harmonics(const MatrixX& samples) const {
    VectorX x = VectorX::Zero(n_unknowns());
    std::vector<fftw_complex> spectrum(N / 2 + 1);
    std::vector<double> signal(N);
    for (Index i = 0; i < c; ++i) {
      for (int j = 0; j < N; ++j) signal[j] = samples(i, j);
      fftw_execute_dft_r2c(forward, signal.data(), spectrum.data());
      x[i] = spectrum[0][0] / N;
      for (int k = 1; k <= H; ++k)
        set_amplitude(x, k, i, Complex(spectrum[k][0], spectrum[k][1]) * (2.0 / N));
    }
    return x;
  }

  /// Contact law at the samples: forces (c x N) and, optionally, dlaw/dg.
  MatrixX law(const MatrixX& gaps, MatrixX* slope, double factor = 1.0) const {
    if (rows_per_pair == 3) {
      MatrixX p(c, N);
      for (Index pair = 0; pair < c / 3; ++pair) p.middleRows(3 * pair, 3) = friction_law(gaps, pair, nullptr, factor);
      return p;
    }
    MatrixX p(c, N);
    if (slope) slope->setZero(c, N);
    for (Index i = 0; i < c; ++i)
      for (int j = 0; j < N; ++j) {
        p(i, j) = contact::penalty_pressure(gaps(i, j), factor * stiffness[i]);
        if (slope && gaps(i, j) < 0.0) (*slope)(i, j) = -factor * stiffness[i];
      }
    return p;
  }


  /// Normal penalty and Coulomb return mapping of one pair (rows 3 pair .. 3 pair + 2) marched over
  /// two periods from a zero traction; the second period is kept (3 x N). With `tangent`, also the
  /// derivatives of the kept forces with respect to the pair's gap harmonics, propagated through the
  /// march: (*tangent)[row] is N x 3(2H+1), direction index = component * 3 + local row.
  MatrixX friction_law(const MatrixX& gaps, Index pair, std::vector<MatrixX>* tangent, double factor) const {
    const Index row = 3 * pair;
    const double area = system.pair_area[pair];
    const double eps_n = factor * system.normal_penalty;
    const double eps_t = factor * system.tangential_penalty;
    const double mu = system.friction_coefficient;
    const int nc = 2 * H + 1;
    const int nd = 3 * nc;
    MatrixX p(3, N);
    if (tangent) tangent->assign(3, MatrixX::Zero(N, nd));
    Vec3 traction = Vec3::Zero();
    MatrixX d_traction = MatrixX::Zero(2, tangent ? nd : 0);
    const Vec3 normal(0.0, 0.0, 1.0);
    for (int step = 0; step < 2 * N; ++step) {
      const int j = step % N;
      const int previous = (j + N - 1) % N;
      const double gap_n = gaps(row, j);
      const double pressure = contact::penalty_pressure(gap_n, eps_n);
      Vec3 increment = Vec3::Zero();
      if (step > 0) increment << gaps(row + 1, j) - gaps(row + 1, previous), gaps(row + 2, j) - gaps(row + 2, previous), 0.0;
      const contact::CoulombUpdate update =
          contact::coulomb_return_mapping(traction, increment, normal, eps_t, mu, pressure);
      if (tangent) {
        // d trial = d t_old - eps_T d(increment); directions of the tangential rows' components
        MatrixX d_trial = d_traction;
        if (step > 0)
          for (int hc = 0; hc < nc; ++hc) {
            const double db = basis(j, hc) - basis(previous, hc);
            d_trial(0, hc * 3 + 1) -= eps_t * db;
            d_trial(1, hc * 3 + 2) -= eps_t * db;
          }
        if (!update.slipping) {
          d_traction = d_trial;
        } else {
          const Eigen::Vector2d trial(traction[0] - eps_t * increment[0], traction[1] - eps_t * increment[1]);
          const double norm = trial.norm();
          if (norm > 0.0) {
            const Eigen::Vector2d dir = trial / norm;
            const double limit = mu * pressure;
            const Eigen::Matrix2d projector = (Eigen::Matrix2d::Identity() - dir * dir.transpose()) * (limit / norm);
            d_traction = projector * d_trial;
            if (gap_n < 0.0)
              for (int hc = 0; hc < nc; ++hc) d_traction.col(hc * 3) += dir * (mu * -eps_n * basis(j, hc));
          } else {
            d_traction.setZero();
          }
        }
      }
      traction = update.traction;
      if (step >= N) {
        p(0, j) = area * pressure;
        p(1, j) = area * traction[0];
        p(2, j) = area * traction[1];
        if (tangent) {
          if (gap_n < 0.0)
            for (int hc = 0; hc < nc; ++hc) (*tangent)[0](j, hc * 3) = -area * eps_n * basis(j, hc);
          (*tangent)[1].row(j) = area * d_traction.row(0);
          (*tangent)[2].row(j) = area * d_traction.row(1);
        }
      }
    }
    return p;
  }

  /// dP/dG block of one friction pair: (3(2H+1))^2, index component * 3 + local row on both sides.
  MatrixX friction_derivative(const MatrixX& gaps, Index pair, double factor) const {
    std::vector<MatrixX> tangent;
    friction_law(gaps, pair, &tangent, factor);
    const int nc = 2 * H + 1;
    const int nd = 3 * nc;
    MatrixX block = MatrixX::Zero(nd, nd);
    std::vector<double> signal(N);
    std::vector<fftw_complex> spectrum(N / 2 + 1);
    for (int local = 0; local < 3; ++local)
      for (int col = 0; col < nd; ++col) {
        if (tangent[local].col(col).cwiseAbs().maxCoeff() == 0.0) continue;
        for (int j = 0; j < N; ++j) signal[j] = tangent[local](j, col);
        fftw_execute_dft_r2c(forward, signal.data(), spectrum.data());
        block(local, col) = spectrum[0][0] / N;
        for (int k = 1; k <= H; ++k) {
          block((2 * k - 1) * 3 + local, col) = 2.0 * spectrum[k][0] / N;
          block((2 * k) * 3 + local, col) = -2.0 * spectrum[k][1] / N;
        }
      }
    return block;
  }

  /// Subtracts H * dP from the columns of the rows `first .. first + r - 1` (one pair), given the
  /// pair's dP block indexed component * r + local row.
  void subtract_pair(MatrixX& jac, const std::vector<HarmonicReceptance>& rec, Index first, int r, const MatrixX& block) const {
    const int nc = 2 * H + 1;
    for (int col_hc = 0; col_hc < nc; ++col_hc)
      for (int col_local = 0; col_local < r; ++col_local) {
        const int bcol = col_hc * r + col_local;
        if (block.col(bcol).cwiseAbs().maxCoeff() == 0.0) continue;
        auto column = jac.col(col_hc * c + first + col_local);
        for (int local = 0; local < r; ++local) {
          const Index i = first + local;
          column.segment(0, c) -= rec[0].pairs.col(i).real() * block(local, bcol);
          for (int k = 1; k <= H; ++k) {
            const double ja = block((2 * k - 1) * r + local, bcol);
            const double jb = block((2 * k) * r + local, bcol);
            if (ja == 0.0 && jb == 0.0) continue;
            const auto re = rec[k].pairs.col(i).real();
            const auto im = rec[k].pairs.col(i).imag();
            column.segment((2 * k - 1) * c, c) -= re * ja + im * jb;
            column.segment((2 * k) * c, c) -= -im * ja + re * jb;
          }
        }
      }
  }

  VectorX forces(const VectorX& gaps, double factor = 1.0) const {
    return to_harmonics(law(to_time(gaps), nullptr, factor));
  }

  /// Linear part: g0 delta_k0 + H P + E F, in [m].
  VectorX apply(const std::vector<HarmonicReceptance>& rec, const VectorX& p, bool derivative) const {
    VectorX g = VectorX::Zero(n_unknowns());
    ComplexVectorX pk(c);
    if (rec[0].pairs.size() == 0 && c > 0) {  // matrix-free: H applied per harmonic from R and U D_k U^T
      std::vector<ComplexVectorX> modal(H + 1);
      for (int k = 0; k <= H; ++k) modal[k] = derivative ? rec[k].modal_d : rec[k].modal;
      apply_receptance(system, modal, p, g, !derivative);
      const ComplexVectorX& load = derivative ? rec[nu].load_d : rec[nu].load;
      for (Index i = 0; i < c; ++i) set_amplitude(g, nu, i, amplitude(g, nu, i) + load[i]);
      if (!derivative) g.head(c) += row_gap;
      return g;
    }
    for (int k = 0; k <= H; ++k) {
      for (Index i = 0; i < c; ++i) pk[i] = amplitude(p, k, i);
      const ComplexMatrixX& hk = derivative ? rec[k].pairs_d : rec[k].pairs;
      ComplexVectorX gk = (k == 0 ? ComplexMatrixX(hk.real().cast<Complex>()) : hk) * pk;
      if (k == nu) gk += derivative ? rec[k].load_d : rec[k].load;
      for (Index i = 0; i < c; ++i) set_amplitude(g, k, i, gk[i]);
    }
    if (!derivative)
      g.head(c) += row_gap;
    return g;
  }

  /// Block of dP/dG of one row (2H+1 square, component order 0, a_1, b_1, ...), from the DFT of the slope.
  MatrixX force_derivative(const MatrixX& slope, Index i) const {
    std::vector<double> signal(N);
    std::vector<fftw_complex> spectrum(N / 2 + 1);
    for (int j = 0; j < N; ++j) signal[j] = slope(i, j);
    fftw_execute_dft_r2c(forward, signal.data(), spectrum.data());
    VectorX dc(2 * H + 1), ds(2 * H + 1);
    for (int k = 0; k <= 2 * H; ++k) {
      dc[k] = spectrum[k][0] / N;
      ds[k] = -spectrum[k][1] / N;
    }
    auto cosc = [&](int k) { return dc[std::abs(k)]; };
    auto sinc = [&](int k) { return k >= 0 ? ds[k] : -ds[-k]; };
    const int n = 2 * H + 1;
    MatrixX block(n, n);
    block(0, 0) = dc[0];
    for (int mm = 1; mm <= H; ++mm) {
      block(0, 2 * mm - 1) = dc[mm];
      block(0, 2 * mm) = ds[mm];
    }
    for (int l = 1; l <= H; ++l) {
      block(2 * l - 1, 0) = 2.0 * dc[l];
      block(2 * l, 0) = 2.0 * ds[l];
      for (int mm = 1; mm <= H; ++mm) {
        block(2 * l - 1, 2 * mm - 1) = cosc(l - mm) + cosc(l + mm);
        block(2 * l - 1, 2 * mm) = sinc(mm + l) + sinc(mm - l);
        block(2 * l, 2 * mm - 1) = sinc(l + mm) + sinc(l - mm);
        block(2 * l, 2 * mm) = cosc(l - mm) - cosc(l + mm);
      }
    }
    return block;
  }

  /// dP/dG per pair with a closed sample (krylov.hpp's blocks), at the samples of `gaps`.
  std::vector<PairDerivative> pair_derivatives(const VectorX& gaps, double factor) const {
    const MatrixX samples = to_time(gaps);
    std::vector<PairDerivative> out;
    if (rows_per_pair == 3) {
      for (Index pair = 0; pair < c / 3; ++pair) {
        MatrixX block = friction_derivative(samples, pair, factor);
        if (block.cwiseAbs().maxCoeff() > 0.0) out.push_back({3 * pair, 3, std::move(block)});
      }
      return out;
    }
    MatrixX slope;
    law(samples, &slope, factor);
    for (Index j = 0; j < c; ++j)
      if (slope.row(j).cwiseAbs().maxCoeff() > 0.0) out.push_back({j, 1, force_derivative(slope, j)});
    return out;
  }

  /// The linearisation of the (penalty-scaled) residual at `gaps`, dense or matrix-free.
  std::unique_ptr<Linearization> linearize(const std::vector<HarmonicReceptance>& rec, const VectorX& gaps,
                                           double factor) const;

  void record(const GmresReport& report) const {
    ++krylov_solves;
    krylov_iterations += report.iterations;
    if (!report.converged) ++krylov_unconverged;
    int seen = krylov_max.load();
    while (report.iterations > seen && !krylov_max.compare_exchange_weak(seen, report.iterations)) {
    }
  }

  /// Scaled Jacobian I - H dP/dG.
  MatrixX jacobian(const std::vector<HarmonicReceptance>& rec, const VectorX& gaps, double factor = 1.0) const {
    const Index n = n_unknowns();
    MatrixX jac = MatrixX::Identity(n, n);
    const MatrixX samples = to_time(gaps);
    if (rows_per_pair == 3) {
      for (Index pair = 0; pair < c / 3; ++pair)
        subtract_pair(jac, rec, 3 * pair, 3, friction_derivative(samples, pair, factor));
      return jac;
    }
    MatrixX slope;
    law(samples, &slope, factor);
    for (Index j = 0; j < c; ++j) {
      if (slope.row(j).cwiseAbs().maxCoeff() == 0.0) continue;
      subtract_pair(jac, rec, j, 1, force_derivative(slope, j));
    }
    return jac;
  }

  VectorX residual(const std::vector<HarmonicReceptance>& rec, const VectorX& gaps, double factor = 1.0) const {
    return (gaps - apply(rec, forces(gaps, factor), false)) / scale;
  }

  /// Damped Newton at fixed Omega with the penalty scaled by `factor`; returns the iterations taken.
  int newton(const std::vector<HarmonicReceptance>& rec, VectorX& gaps, double factor, double& norm) const {
    VectorX r = residual(rec, gaps, factor);
    norm = r.lpNorm<Eigen::Infinity>();
    int it = 0;
    while (norm > options.tolerance && it < options.max_iterations) {
      ++it;
      const VectorX step = linearize(rec, gaps, factor)->solve(-r, inexact_forcing(r.norm(), options.tolerance)) * scale;
      // full steps first (the piecewise-linear contact mostly converges in a few), then backtracking
      // on the 2-norm of the residual against the cycles plain Newton can fall into
      double alpha = 1.0;
      VectorX trial = gaps + step;
      VectorX r_trial = residual(rec, trial, factor);
      while (it > options.max_iterations / 4 && r_trial.norm() > r.norm() && alpha > 1.0 / 64.0) {
        alpha *= 0.5;
        trial = gaps + alpha * step;
        r_trial = residual(rec, trial, factor);
      }
      gaps = trial;
      r = r_trial;
      norm = r.lpNorm<Eigen::Infinity>();
    }
    return it;
  }

  /// A run of consecutive samples j = first .. first + count - 1 with one contact active set, and its
  /// contact stiffness condensed through the massless boundary in modal coordinates (m x m):
  /// K_c = (B Phi)_a^T (K_a^{-1} + R_aa)^{-1} (B Phi)_a, a the closed rows (zero when none is closed).
  struct StiffnessRun {
    int first = 0;
    int count = 0;
    MatrixX stiffness;
  };

  /// The runs of the frictionless linearised contact along a solution's samples (they cover 0..N-1).
  std::vector<StiffnessRun> condensed_stiffness(const Solution& sol) const {
    const MatrixX gaps = to_time(sol.gaps);
    std::vector<StiffnessRun> runs;
    std::vector<Index> previous_active;
    for (int j = 0; j < N; ++j) {
      std::vector<Index> active;
      for (Index i = 0; i < c; ++i)
        if (gaps(i, j) < 0.0 && stiffness[i] > 0.0) active.push_back(i);
      if (!runs.empty() && active == previous_active) {  // consecutive samples mostly share the active set
        ++runs.back().count;
        continue;
      }
      const Index na = static_cast<Index>(active.size());
      MatrixX flex(na, na);
      MatrixX bphi(na, m);
      for (Index a = 0; a < na; ++a) {
        for (Index b = 0; b < na; ++b) flex(a, b) = system.residual(active[a], active[b]);
        flex(a, a) += 1.0 / stiffness[active[a]];
        bphi.row(a) = system.pair_modes.row(active[a]);
      }
      runs.push_back({j, 1, na > 0 ? MatrixX(bphi.transpose() * flex.ldlt().solve(bphi)) : MatrixX::Zero(m, m)});
      previous_active = std::move(active);
    }
    return runs;
  }

  /// Default tolerance on Re lambda: 1e-6 times the lowest nonzero modal frequency (w0 without one).
  double stability_tolerance(double w0) const {
    double wmin = 0.0;
    for (Index r = 0; r < m; ++r)
      if (system.omega[r] > 0.0 && (wmin == 0.0 || system.omega[r] < wmin)) wmin = system.omega[r];
    return 1e-6 * (wmin > 0.0 ? wmin : w0);
  }

  void require_frictionless(const char* method) const {
    if (rows_per_pair == 3)
      throw InputError(std::string(method) + " with friction is not implemented: the return mapping's history is not a "
                       "periodic stiffness (run the continuation with stability off)");
  }
};

namespace {

/// Fills the multipliers, the counts of unstable ones by kind and the critical exponent of `st`
/// from its exponents (period T = 2 pi / w0 of the base frequency).
void classify(Stability& st, double period, double tolerance) {
  const Index count = st.exponents.size();
  st.multipliers.resize(count);
  st.max_real_part = -1e300;
  Index best = 0;
  for (Index e = 0; e < count; ++e) {
    const std::complex<double> lambda = st.exponents[e];
    st.multipliers[e] = std::exp(lambda * period);
    st.max_real_part = std::max(st.max_real_part, lambda.real());
    if (lambda.real() > st.exponents[best].real()) best = e;
    if (lambda.real() > tolerance) {
      const double angle = std::arg(st.multipliers[e]);
      if (std::abs(angle) < 1e-4)
        ++st.unstable_positive;
      else
        (kPi - std::abs(angle) < 1e-4 ? st.unstable_negative : st.unstable_complex) += 1;
    }
  }
  st.stable = st.max_real_part <= tolerance;
  if (count > 0) st.critical_exponent = st.exponents[best];
}

}  // namespace

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

  std::vector<double> signal(d.N);
  std::vector<fftw_complex> spectrum(d.N / 2 + 1);
  d.forward = fftw_plan_dft_r2c_1d(d.N, signal.data(), spectrum.data(), FFTW_ESTIMATE | FFTW_UNALIGNED);
  d.backward = fftw_plan_dft_c2r_1d(d.N, spectrum.data(), signal.data(), FFTW_ESTIMATE | FFTW_UNALIGNED);

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

Stability HarmonicBalance::hill_stability(const Solution& sol, double tolerance) const {
  const Impl& d = *impl_;
  const reduced::ReducedSystem& s = d.system;
  const Index m = d.m;
  const int H = d.H;
  const int N = d.N;
  const double w0 = sol.omega / d.nu;
  d.require_frictionless("Hill's method");
  if (tolerance <= 0.0) tolerance = d.stability_tolerance(w0);
  // contact stiffness condensed through the massless boundary, in modal coordinates, per sample
  std::vector<MatrixX> stiff(N);
  for (const auto& run : d.condensed_stiffness(sol))
    for (int j = run.first; j < run.first + run.count; ++j) stiff[j] = run.stiffness;
  // Fourier coefficients K_j = (1/N) sum_n K(tau_n) e^{-i j tau_n}, j = 0..2H, one r2c per entry
  std::vector<ComplexMatrixX> khat(2 * H + 1, ComplexMatrixX::Zero(m, m));
  {
    std::vector<double> signal(N);
    std::vector<fftw_complex> spectrum(N / 2 + 1);
    for (Index r = 0; r < m; ++r)
      for (Index q = 0; q < m; ++q) {
        for (int n = 0; n < N; ++n) signal[n] = stiff[n](r, q);
        fftw_execute_dft_r2c(d.forward, signal.data(), spectrum.data());
        for (int jj = 0; jj <= 2 * H; ++jj) khat[jj](r, q) = Complex(spectrum[jj][0], spectrum[jj][1]) / double(N);
      }
  }
  auto coefficient = [&](int jj) -> ComplexMatrixX { return jj >= 0 ? khat[jj] : ComplexMatrixX(khat[-jj].conjugate()); };
  const Index size = m * (2 * H + 1);
  ComplexMatrixX m0 = ComplexMatrixX::Zero(size, size);
  ComplexMatrixX m1 = ComplexMatrixX::Zero(size, size);
  for (int k = -H; k <= H; ++k) {
    const Index bk = (k + H) * m;
    for (int l = -H; l <= H; ++l) m0.block(bk, (l + H) * m, m, m) = coefficient(k - l);
    for (Index r = 0; r < m; ++r) {
      const double damping = 2.0 * s.damping_ratio(r) * s.omega[r];
      const Complex ik(0.0, k * w0);
      m0(bk + r, bk + r) += s.omega[r] * s.omega[r] + ik * ik + ik * damping;
      m1(bk + r, bk + r) = 2.0 * ik + damping;
    }
  }
  ComplexMatrixX companion = ComplexMatrixX::Zero(2 * size, 2 * size);
  companion.topRightCorner(size, size).setIdentity();
  companion.bottomLeftCorner(size, size) = -m0;
  companion.bottomRightCorner(size, size) = -m1;
  Eigen::ComplexEigenSolver<ComplexMatrixX> eig(companion, true);
  if (eig.info() != Eigen::Success) throw SolverError("Hill's method: the eigen-solve failed at Omega = " + format_number(sol.omega));
  // select the exponents whose eigenvectors concentrate in the central harmonics, one per family
  struct Candidate {
    Complex lambda;
    double centroid;
    Index index;
  };
  std::vector<Candidate> candidates;
  for (Index e = 0; e < 2 * size; ++e) {
    const auto v = eig.eigenvectors().col(e).head(size);
    double wsum = 0.0, ksum = 0.0;
    for (int k = -H; k <= H; ++k) {
      const double w = v.segment((k + H) * m, m).squaredNorm();
      wsum += w;
      ksum += k * w;
    }
    candidates.push_back({eig.eigenvalues()[e], wsum > 0.0 ? std::abs(ksum / wsum) : 1e300, e});
  }
  std::sort(candidates.begin(), candidates.end(), [](const Candidate& a, const Candidate& b) { return a.centroid < b.centroid; });
  Stability st;
  std::vector<Complex> chosen;
  std::vector<Index> chosen_index;
  // family members differ by i k w0; truncation makes their real parts differ slightly
  const double family_tol = 1e-3 * w0;
  for (const Candidate& cand : candidates) {
    if (static_cast<Index>(chosen.size()) == 2 * m) break;
    bool same_family = false;
    for (const Complex& other : chosen) {
      const double shift = (cand.lambda.imag() - other.imag()) / w0;
      if (std::abs(cand.lambda.real() - other.real()) < family_tol && std::abs(shift - std::round(shift)) < 1e-3 &&
          std::lround(shift) != 0)
        same_family = true;
    }
    if (!same_family) {
      chosen.push_back(cand.lambda);
      chosen_index.push_back(cand.index);
    }
  }
  const Index count = static_cast<Index>(chosen.size());
  st.exponents.resize(count);
  for (Index e = 0; e < count; ++e) st.exponents[e] = chosen[e];
  classify(st, 2.0 * kPi / w0, tolerance);
  if (count > 0) {
    Index best = 0;
    for (Index e = 1; e < count; ++e)
      if (chosen[e].real() > chosen[best].real()) best = e;
    const auto v = eig.eigenvectors().col(chosen_index[best]).head(size);
    st.critical_mode.resize(m, 2 * H + 1);
    for (int k = -H; k <= H; ++k) st.critical_mode.col(k + H) = v.segment((k + H) * m, m);
  }
  return st;
}

Stability HarmonicBalance::floquet_stability(const Solution& sol, double tolerance) const {
  const Impl& d = *impl_;
  const reduced::ReducedSystem& s = d.system;
  const Index m = d.m;
  const int H = d.H;
  const int N = d.N;
  const double w0 = sol.omega / d.nu;
  const double period = 2.0 * kPi / w0;
  const double h = period / N;
  d.require_frictionless("Floquet stability");
  if (tolerance <= 0.0) tolerance = d.stability_tolerance(w0);
  // x = (q, q'), x' = A(t) x with A = [0 I; -(Omega_r^2 + K_c(t)) -2 zeta_r omega_r], K_c held over
  // [t_j - h/2, t_j + h/2) around each sample: the propagator of a run of equal samples is one exponential
  MatrixX base = MatrixX::Zero(2 * m, 2 * m);
  base.topRightCorner(m, m).setIdentity();
  for (Index r = 0; r < m; ++r) {
    base(m + r, r) = -s.omega[r] * s.omega[r];
    base(m + r, m + r) = -2.0 * s.damping_ratio(r) * s.omega[r];
  }
  const auto runs = d.condensed_stiffness(sol);
  std::vector<MatrixX> half_step(runs.size());  // exp(A h / 2) per run, for the critical mode
  MatrixX monodromy = MatrixX::Identity(2 * m, 2 * m);
  for (std::size_t i = 0; i < runs.size(); ++i) {
    MatrixX a = base;
    a.bottomLeftCorner(m, m) -= runs[i].stiffness;
    monodromy = MatrixX((a * (runs[i].count * h)).exp()) * monodromy;
    half_step[i] = (a * (0.5 * h)).exp();
  }
  // The eigen-solve on (q, q'/omega_r): velocities are omega_r times the displacements, and Eigen's real
  // Schur form does not balance (unscaled, it failed to converge on a 10 x 10 monodromy of the cantilever).
  VectorX scaling = VectorX::Ones(2 * m);
  for (Index r = 0; r < m; ++r)
    if (s.omega[r] > 0.0) scaling[m + r] = 1.0 / s.omega[r];
  const MatrixX balanced = scaling.asDiagonal() * monodromy * scaling.cwiseInverse().asDiagonal();
  ComplexVectorX multipliers;
  ComplexMatrixX vectors;
  Eigen::EigenSolver<MatrixX> real_eig(balanced, true);
  if (real_eig.info() == Eigen::Success) {
    multipliers = real_eig.eigenvalues();
    vectors = real_eig.eigenvectors();
  } else {  // the complex QR as a fallback
    Eigen::ComplexEigenSolver<ComplexMatrixX> complex_eig(balanced.cast<Complex>(), true);
    if (complex_eig.info() != Eigen::Success)
      throw SolverError("Floquet stability: the eigen-solve of the monodromy matrix failed at Omega = " +
                        format_number(sol.omega));
    multipliers = complex_eig.eigenvalues();
    vectors = complex_eig.eigenvectors();
  }
  Stability st;
  st.exponents.resize(2 * m);
  for (Index e = 0; e < 2 * m; ++e) st.exponents[e] = std::log(multipliers[e]) / period;
  classify(st, period, tolerance);
  if (2 * m == 0) return st;
  // critical mode in Hill's layout: s(t) = e^{-lambda t} q(t) sampled at t_j and its harmonics k = -H..H
  Index best = 0;
  for (Index e = 1; e < 2 * m; ++e)
    if (st.exponents[e].real() > st.exponents[best].real()) best = e;
  const Complex lambda = st.exponents[best];
  ComplexVectorX x = scaling.cwiseInverse().cast<Complex>().asDiagonal() * vectors.col(best);  // at t = -h/2
  ComplexMatrixX mode = ComplexMatrixX::Zero(m, 2 * H + 1);
  std::size_t run = 0;
  for (int j = 0; j < N; ++j) {
    while (j >= runs[run].first + runs[run].count) ++run;
    x = half_step[run].cast<Complex>() * x;  // to t_j
    const double t = j * h;
    const ComplexVectorX periodic = x.head(m) * std::exp(-lambda * t);
    for (int k = -H; k <= H; ++k) mode.col(k + H) += periodic * std::polar(1.0 / N, -k * w0 * t);
    x = half_step[run].cast<Complex>() * x;  // to t_j + h/2
  }
  st.critical_mode = mode;
  return st;
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
