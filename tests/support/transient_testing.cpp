#include "transient_testing.hpp"

#include <Eigen/Dense>
#include <algorithm>

namespace crackle::transient::testing {

std::shared_ptr<contact::ContactForce> plug_contact(const mesh::Mesh& mesh, TransientProblem& problem,
                                                    const contact::ContactOptions& options) {
  auto term = std::make_shared<contact::ContactForce>(mesh, mesh::make_dof_map(mesh, mesh::Variant::open),
                                                      problem.materials, options);
  problem.terms.push_back(term);
  return term;
}

DenseModes dense_modes(const SparseMatrix& stiffness, const VectorX& lumped_mass, const fem::Constraints& constraints,
                       int count) {
  const Index n_free = constraints.n_free();
  MatrixX a(n_free, n_free);
  const SparseMatrix free = fem::restrict_to_free(stiffness, constraints);
  a = MatrixX(free);
  VectorX scale(n_free);
  for (Index i = 0; i < n_free; ++i) scale[i] = 1.0 / std::sqrt(lumped_mass[constraints.free_dofs[i]]);
  a = scale.asDiagonal() * a * scale.asDiagonal();
  Eigen::SelfAdjointEigenSolver<MatrixX> solver(a);
  DenseModes modes;
  const int m = std::min<int>(count, n_free);
  modes.omega.resize(m);
  modes.shapes = MatrixX::Zero(stiffness.rows(), m);
  for (int k = 0; k < m; ++k) {
    modes.omega[k] = std::sqrt(std::max(0.0, solver.eigenvalues()[k]));
    for (Index i = 0; i < n_free; ++i) modes.shapes(constraints.free_dofs[i], k) = scale[i] * solver.eigenvectors()(i, k);
  }
  return modes;
}

double dense_omega_max(const SparseMatrix& stiffness, const VectorX& lumped_mass, const fem::Constraints& constraints) {
  const Index n_free = constraints.n_free();
  MatrixX a = MatrixX(fem::restrict_to_free(stiffness, constraints));
  VectorX scale(n_free);
  for (Index i = 0; i < n_free; ++i) scale[i] = 1.0 / std::sqrt(lumped_mass[constraints.free_dofs[i]]);
  a = scale.asDiagonal() * a * scale.asDiagonal();
  Eigen::SelfAdjointEigenSolver<MatrixX> solver(a, Eigen::EigenvaluesOnly);
  return std::sqrt(solver.eigenvalues().maxCoeff());
}

double windowed_dft(const std::vector<double>& signal, double dt, double frequency) {
  const std::size_t n = signal.size();
  double mean = 0.0;
  for (double s : signal) mean += s;
  mean /= static_cast<double>(n);
  std::complex<double> sum = 0.0;
  for (std::size_t k = 0; k < n; ++k) {
    const double window = 0.5 - 0.5 * std::cos(2.0 * M_PI * static_cast<double>(k) / static_cast<double>(n - 1));
    sum += window * (signal[k] - mean) * std::polar(1.0, -2.0 * M_PI * frequency * dt * static_cast<double>(k));
  }
  return std::abs(sum);
}

double dominant_frequency(const std::vector<double>& signal, double dt, double low, double high) {
  const double duration = dt * static_cast<double>(signal.size());
  const double resolution = 1.0 / duration;
  double best = low, best_value = -1.0;
  for (double f = low; f <= high; f += 0.25 * resolution) {
    const double value = windowed_dft(signal, dt, f);
    if (value > best_value) {
      best_value = value;
      best = f;
    }
  }
  double a = best - 0.25 * resolution, b = best + 0.25 * resolution;
  const double golden = 0.5 * (std::sqrt(5.0) - 1.0);
  for (int iteration = 0; iteration < 60; ++iteration) {
    const double c = b - golden * (b - a), d = a + golden * (b - a);
    if (windowed_dft(signal, dt, c) > windowed_dft(signal, dt, d)) {
      b = d;
    } else {
      a = c;
    }
  }
  return 0.5 * (a + b);
}

double zero_crossing_frequency(const std::vector<double>& signal, double dt) {
  double mean = 0.0;
  for (double s : signal) mean += s;
  mean /= static_cast<double>(signal.size());
  double first = -1.0, last = -1.0;
  int crossings = 0;
  for (std::size_t k = 1; k < signal.size(); ++k) {
    const double a = signal[k - 1] - mean, b = signal[k] - mean;
    if (a < 0.0 && b >= 0.0) {
      const double t = dt * (static_cast<double>(k - 1) + a / (a - b));
      if (first < 0.0) first = t;
      last = t;
      ++crossings;
    }
  }
  return crossings > 1 ? (crossings - 1) / (last - first) : 0.0;
}

}  // namespace crackle::transient::testing
