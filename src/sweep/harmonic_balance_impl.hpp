#pragma once
/// \file The state of a HarmonicBalance (its pimpl), shared by the module's translation units: the
/// solver (harmonic_balance.cpp) and the stability of its solutions (stability.cpp: Hill's method and
/// the Floquet multipliers), which compile apart. Private to src/sweep.
#include <fftw3.h>

#include <Eigen/Dense>
#include <algorithm>
#include <atomic>
#include <cmath>
#include <complex>
#include <memory>
#include <string>
#include <vector>

#include "contact_law/penalty.hpp"
#include "core/errors.hpp"
#include "core/fftw_buffer.hpp"
#include "sweep/harmonic_balance.hpp"

namespace crackle::sweep {
namespace detail {

using Complex = std::complex<double>;
/// The automatic gap scale is at least this share of the linear gap response at the drive
/// (HarmonicBalanceOptions::scale_frequency): a floor for loads the crack barely sees statically,
/// small enough to leave the static scale in place wherever that one is not tiny.
inline constexpr double kDynamicScaleShare = 0.1;

/// Default N: a power of two >= 4H and >= 4096. A sample entering or leaving contact changes the
/// Jacobian by about eps_N A / N; near a lightly damped resonance that jump alone can fold the
/// sampled branch (measured: micro-folds at N = 64..1024 for Q = 50, H = 10; none from 4096 on).
inline int default_samples(int harmonics) {
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

}  // namespace detail

struct HarmonicBalance::Impl {
  using Complex = detail::Complex;
  using HarmonicReceptance = detail::HarmonicReceptance;
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
    FftwBuffer<fftw_complex> spectrum(N / 2 + 1);
    FftwBuffer<double> signal(N);
    for (Index i = 0; i < c; ++i) {
      for (int k = 0; k <= N / 2; ++k) spectrum[k][0] = spectrum[k][1] = 0.0;
      spectrum[0][0] = x[i];
      for (int k = 1; k <= H; ++k) {
        const Complex a = amplitude(x, k, i) * 0.5;
        spectrum[k][0] = a.real();
        spectrum[k][1] = a.imag();
      }
      fftw_execute_dft_c2r(backward, spectrum.data, signal.data);
      for (int j = 0; j < N; ++j) samples(i, j) = signal[j];
    }
    return samples;
  }

  /// Harmonics 0..H of time samples (c x N), real layout.
  VectorX to_harmonics(const MatrixX& samples) const {
    VectorX x = VectorX::Zero(n_unknowns());
    FftwBuffer<fftw_complex> spectrum(N / 2 + 1);
    FftwBuffer<double> signal(N);
    for (Index i = 0; i < c; ++i) {
      for (int j = 0; j < N; ++j) signal[j] = samples(i, j);
      fftw_execute_dft_r2c(forward, signal.data, spectrum.data);
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
    FftwBuffer<double> signal(N);
    FftwBuffer<fftw_complex> spectrum(N / 2 + 1);
    for (int local = 0; local < 3; ++local)
      for (int col = 0; col < nd; ++col) {
        if (tangent[local].col(col).cwiseAbs().maxCoeff() == 0.0) continue;
        for (int j = 0; j < N; ++j) signal[j] = tangent[local](j, col);
        fftw_execute_dft_r2c(forward, signal.data, spectrum.data);
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
    FftwBuffer<double> signal(N);
    FftwBuffer<fftw_complex> spectrum(N / 2 + 1);
    for (int j = 0; j < N; ++j) signal[j] = slope(i, j);
    fftw_execute_dft_r2c(forward, signal.data, spectrum.data);
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

}  // namespace crackle::sweep
