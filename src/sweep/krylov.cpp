#include "sweep/krylov.hpp"

#include <algorithm>
#include <cmath>

namespace crackle::sweep {

namespace {
using Complex = std::complex<double>;

/// Complex harmonic k (k >= 1) of column pair (2k-1, 2k) of a c x (2H+1) real layout: a - i b.
Eigen::VectorXcd harmonic(const MatrixX& x, int k) {
  if (k == 0) return x.col(0).cast<Complex>();
  return x.col(2 * k - 1).cast<Complex>() - Complex(0.0, 1.0) * x.col(2 * k).cast<Complex>();
}
void set_harmonic(MatrixX& x, int k, const Eigen::VectorXcd& value) {
  if (k == 0) {
    x.col(0) = value.real();
    return;
  }
  x.col(2 * k - 1) = value.real();
  x.col(2 * k) = -value.imag();
}
/// The entries of rows d.first .. d.first + d.rows - 1 of a real layout (c rows), indexed as d.block.
void gather(const VectorX& x, const PairDerivative& d, Index c, VectorX& local) {
  const Index nc = x.size() / c;
  local.resize(d.rows * nc);
  for (Index hc = 0; hc < nc; ++hc)
    for (int l = 0; l < d.rows; ++l) local[hc * d.rows + l] = x[hc * c + d.first + l];
}
void scatter(const VectorX& local, const PairDerivative& d, Index c, VectorX& x) {
  const Index nc = x.size() / c;
  for (Index hc = 0; hc < nc; ++hc)
    for (int l = 0; l < d.rows; ++l) x[hc * c + d.first + l] = local[hc * d.rows + l];
}
}  // namespace

double inexact_forcing(double norm, double tolerance) {
  if (!(norm > 0.0)) return 0.5;
  return std::clamp(std::max(std::min(1e-2, norm), 0.5 * tolerance / norm), 1e-14, 0.5);
}

void apply_receptance(const reduced::ReducedSystem& system, const std::vector<Eigen::VectorXcd>& modal,
                      const VectorX& p, VectorX& g, bool residual) {
  const Index c = system.n_rows();
  const int H = static_cast<int>(modal.size()) - 1;
  const Eigen::Map<const MatrixX> forces(p.data(), c, 2 * H + 1);
  // R is real: it acts on the cos and sin columns alike (one product for all harmonics)
  MatrixX gaps = residual ? MatrixX(system.residual * forces) : MatrixX::Zero(c, 2 * H + 1);
  const MatrixX projected = system.pair_modes.transpose() * forces;  // U^T P, m x (2H+1)
  MatrixX scaled(projected.rows(), projected.cols());
  for (int k = 0; k <= H; ++k) {
    Eigen::VectorXcd q = modal[k].cwiseProduct(harmonic(projected, k));
    if (k == 0) q = q.real().cast<Complex>();  // the mean: the static (real) receptance
    set_harmonic(scaled, k, q);
  }
  gaps.noalias() += system.pair_modes * scaled;
  g = Eigen::Map<const VectorX>(gaps.data(), gaps.size());
}

KrylovJacobian::KrylovJacobian(const reduced::ReducedSystem& system, int harmonics, std::vector<Eigen::VectorXcd> modal,
                               std::vector<PairDerivative> derivatives, const KrylovOptions& options)
    : system_(system), c_(system.n_rows()), m_(system.n_modes()), H_(harmonics), options_(options),
      modal_(std::move(modal)), derivatives_(std::move(derivatives)) {
  mean_stiffness_ = VectorX::Zero(c_);
  for (const PairDerivative& d : derivatives_)
    for (int local = 0; local < d.rows; ++local) mean_stiffness_[d.first + local] = d.block(local, local);
  for (Index i = 0; i < c_; ++i)
    if (mean_stiffness_[i] != 0.0) active_.push_back(i);
  const Index na = closing_rows();
  coupling_.resize(c_, na);
  for (Index a = 0; a < na; ++a) coupling_.col(a) = system.residual.col(active_[a]) * mean_stiffness_[active_[a]];
  MatrixX closed = MatrixX::Identity(na, na);
  for (Index a = 0; a < na; ++a)
    for (Index b = 0; b < na; ++b) closed(a, b) -= coupling_(active_[a], b);
  if (na > 0) closed_.compute(closed);
  ku_ = mean_stiffness_.asDiagonal() * system.pair_modes;
  y_ = solve_mean(system.pair_modes);
  const MatrixX s = ku_.transpose() * y_;
  woodbury_.resize(H_ + 1);
  for (int k = 0; k <= H_; ++k) {
    Eigen::MatrixXcd a = Eigen::MatrixXcd::Identity(m_, m_) - s.cast<Complex>() * modal_[k].asDiagonal();
    woodbury_[k].compute(a);
  }
  if (options_.preconditioner == KrylovPreconditioner::pair_blocks) setup_pair_blocks();
}

void KrylovJacobian::setup_pair_blocks() {
  const int nc = 2 * H_ + 1;
  // the breathing pairs: dP/dG other than its harmonic-diagonal mean K (closed for part of the period)
  for (std::size_t p = 0; p < derivatives_.size(); ++p) {
    const PairDerivative& d = derivatives_[p];
    MatrixX deviation = d.block;
    for (int hc = 0; hc < nc; ++hc)
      for (int l = 0; l < d.rows; ++l) deviation(hc * d.rows + l, hc * d.rows + l) -= mean_stiffness_[d.first + l];
    if (deviation.cwiseAbs().maxCoeff() <= 1e-12 * d.block.cwiseAbs().maxCoeff()) continue;
    breathing_.push_back(p);
    breathing_offset_.push_back(static_cast<Index>(breathing_rows_.size()));
    for (int l = 0; l < d.rows; ++l) breathing_rows_.push_back(d.first + l);
    deviation_.push_back(std::move(deviation));
  }
  const Index nb = static_cast<Index>(breathing_rows_.size());
  if (nb == 0) return;
  // Z_k = M_k^{-1} H_k = (I - R K)^{-1} R + Y W_k Y^T, W_k = D_k (I - S D_k)^{-1}: its columns of the breathing rows
  MatrixX columns(c_, nb);
  for (Index j = 0; j < nb; ++j) columns.col(j) = system_.residual.col(breathing_rows_[j]);
  flexibility_ = solve_mean(columns);
  y_breathing_.resize(nb, m_);
  for (Index j = 0; j < nb; ++j) y_breathing_.row(j) = y_.row(breathing_rows_[j]);
  modal_flexibility_.resize(H_ + 1);
  for (int k = 0; k <= H_; ++k) {
    modal_flexibility_[k] = modal_[k].asDiagonal() * woodbury_[k].inverse();
    if (k == 0) modal_flexibility_[k] = modal_flexibility_[k].real().cast<Complex>();  // the static receptance
  }
  // per breathing pair: I - E_p F_p, F_p = Z_k's diagonal block of the pair (real layout per harmonic)
  for (std::size_t b = 0; b < breathing_.size(); ++b) {
    const int r = derivatives_[breathing_[b]].rows;
    const Index offset = breathing_offset_[b];
    const MatrixX residual = flexibility_.block(derivatives_[breathing_[b]].first, offset, r, r);
    const MatrixX modes = y_breathing_.middleRows(offset, r);
    MatrixX flexibility = MatrixX::Zero(r * nc, r * nc);
    for (int k = 0; k <= H_; ++k) {
      const Eigen::MatrixXcd f = residual.cast<Complex>() + modes.cast<Complex>() * modal_flexibility_[k] * modes.transpose();
      if (k == 0) {
        flexibility.topLeftCorner(r, r) = f.real();
        continue;
      }
      // (a, b) -> (Re f a + Im f b, -Im f a + Re f b): the real layout of f (a - i b)
      const Index a = (2 * k - 1) * r, s = 2 * k * r;
      flexibility.block(a, a, r, r) = f.real();
      flexibility.block(a, s, r, r) = f.imag();
      flexibility.block(s, a, r, r) = -f.imag();
      flexibility.block(s, s, r, r) = f.real();
    }
    local_.emplace_back(MatrixX(MatrixX::Identity(r * nc, r * nc) - deviation_[b] * flexibility));
  }
}

MatrixX KrylovJacobian::solve_mean(const MatrixX& b) const {
  const Index na = closing_rows();
  if (na == 0) return b;
  MatrixX rhs(na, b.cols());
  for (Index a = 0; a < na; ++a) rhs.row(a) = b.row(active_[a]);
  const MatrixX za = closed_.solve(rhs);
  MatrixX z = b;
  z.noalias() += coupling_ * za;  // open rows: z_i = b_i + R_ia K_a z_a
  for (Index a = 0; a < na; ++a) z.row(active_[a]) = za.row(a);
  return z;
}

void KrylovJacobian::apply(const VectorX& x, VectorX& y) const {
  VectorX p = VectorX::Zero(size());
  VectorX local, out;
  for (const PairDerivative& d : derivatives_) {
    gather(x, d, c_, local);
    out.noalias() = d.block * local;
    scatter(out, d, c_, p);
  }
  VectorX g;
  apply_receptance(system_, modal_, p, g);
  y = x - g;
}

void KrylovJacobian::precondition(const VectorX& x, VectorX& y) const {
  precondition_mean(x, y);
  if (breathing_.empty()) return;
  // J^{-1} = (I - Z E)^{-1} M^{-1} = M^{-1} + Z P (I - E_b P^T Z P)^{-1} E_b P^T M^{-1} (E = dP/dG - K on the
  // breathing rows P), with P^T Z P replaced by its diagonal blocks F_p
  const int nc = 2 * H_ + 1;
  const Index nb = static_cast<Index>(breathing_rows_.size());
  MatrixX w(nb, nc);
  VectorX local;
  for (std::size_t b = 0; b < breathing_.size(); ++b) {
    const PairDerivative& d = derivatives_[breathing_[b]];
    gather(y, d, c_, local);
    local = local_[b].solve(deviation_[b] * local);
    for (int hc = 0; hc < nc; ++hc)
      for (int l = 0; l < d.rows; ++l) w(breathing_offset_[b] + l, hc) = local[hc * d.rows + l];
  }
  // y += Z_k w per harmonic: the residual part (real, all harmonics at once) and the modal part
  Eigen::Map<MatrixX> out(y.data(), c_, nc);
  out.noalias() += flexibility_ * w;
  const MatrixX t = y_breathing_.transpose() * w;  // Y_b^T w, m x (2H+1)
  MatrixX v(m_, nc);
  for (int k = 0; k <= H_; ++k) {
    Eigen::VectorXcd q = modal_flexibility_[k] * harmonic(t, k);
    if (k == 0) q = q.real().cast<Complex>();
    set_harmonic(v, k, q);
  }
  out.noalias() += y_ * v;
}

void KrylovJacobian::precondition_mean(const VectorX& x, VectorX& y) const {
  const int nc = 2 * H_ + 1;
  const MatrixX z = solve_mean(Eigen::Map<const MatrixX>(x.data(), c_, nc));
  const MatrixX t = ku_.transpose() * z;  // (K U)^T z, m x (2H+1)
  MatrixX v(m_, nc);
  for (int k = 0; k <= H_; ++k) {
    Eigen::VectorXcd q = modal_[k].cwiseProduct(woodbury_[k].solve(harmonic(t, k)));
    if (k == 0) q = q.real().cast<Complex>();
    set_harmonic(v, k, q);
  }
  MatrixX out = z;
  out.noalias() += y_ * v;
  y = Eigen::Map<const VectorX>(out.data(), out.size());
}

VectorX KrylovJacobian::solve(const VectorX& b, double tolerance, GmresReport* report) const {
  VectorX x;
  const GmresReport r = gmres([this](const VectorX& in, VectorX& out) { apply(in, out); },
                              [this](const VectorX& in, VectorX& out) { precondition(in, out); }, b, x, tolerance,
                              options_.max_iterations, options_.restart);
  if (report) *report = r;
  return x;
}

VectorX KrylovJacobian::solve_bordered(const VectorX& column, const VectorX& row, const VectorX& b, double tolerance,
                                       GmresReport* report) const {
  const Index n = size();
  VectorX z2;
  precondition(column, z2);
  const double corner = row[n] - row.head(n).dot(z2);
  auto action = [&](const VectorX& in, VectorX& out) {
    VectorX top;
    apply(in.head(n), top);
    out.resize(n + 1);
    out.head(n) = top + column * in[n];
    out[n] = row.dot(in);
  };
  // the bordered preconditioner [M column; row^T] by the bordering lemma
  auto bordered = [&](const VectorX& in, VectorX& out) {
    VectorX z1;
    precondition(in.head(n), z1);
    const double last = (in[n] - row.head(n).dot(z1)) / corner;
    out.resize(n + 1);
    out.head(n) = z1 - last * z2;
    out[n] = last;
  };
  VectorX x;
  const GmresReport r = gmres(action, bordered, b, x, tolerance, options_.max_iterations, options_.restart);
  if (report) *report = r;
  return x;
}

}  // namespace crackle::sweep
