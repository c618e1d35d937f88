/// \file The stability of harmonic-balance solutions (frictionless): Hill's method and the Floquet
/// multipliers from the monodromy matrix of the sampled orbit (compiled apart from the solver: the
/// eigen-solvers and matrix exponentials are its heaviest part).
#include <fftw3.h>

#include <Eigen/Dense>
#include <Eigen/Eigenvalues>
#include <unsupported/Eigen/MatrixFunctions>
#include <cmath>
#include <complex>
#include <vector>

#include "sweep/harmonic_balance.hpp"
#include "sweep/harmonic_balance_impl.hpp"

namespace crackle::sweep {

using namespace detail;

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
    FftwBuffer<double> signal(N);
    FftwBuffer<fftw_complex> spectrum(N / 2 + 1);
    for (Index r = 0; r < m; ++r)
      for (Index q = 0; q < m; ++q) {
        for (int n = 0; n < N; ++n) signal[n] = stiff[n](r, q);
        fftw_execute_dft_r2c(d.forward, signal.data, spectrum.data);
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

}  // namespace crackle::sweep
