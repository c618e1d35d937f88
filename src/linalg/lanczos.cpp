#include "linalg/lanczos.hpp"

#include <Eigen/Eigenvalues>
#include <cmath>

namespace crackle::linalg {

LanczosResult lanczos_largest(const LinearOperator& stiffness, const VectorX& scale, VectorX q,
                              const LanczosOptions& options, const VectorShares* shares) {
  const Index n = static_cast<Index>(scale.size());
  const Index owned = shares ? shares->owned : n;
  const auto global_sums = [&](std::vector<double> values) {
    if (shares) shares->sum(values);
    return values;
  };
  LanczosResult result;
  const double start_norm = std::sqrt(global_sums({q.head(owned).squaredNorm()})[0]);
  if (!(start_norm > 0.0)) {
    result.zero_start = true;
    return result;
  }
  q /= start_norm;
  // Three fused passes per iteration (the iteration is memory-bound on large meshes).
  VectorX q_previous = VectorX::Zero(n), w(n), scaled = scale.cwiseProduct(q), product(n);
  std::vector<double> diagonal, off_diagonal;
  double largest = 0.0, largest_before = 0.0;
  int iteration = 0;
  for (; iteration < options.max_iterations; ++iteration) {
    stiffness.apply(scaled, product);
    const double b_previous = off_diagonal.empty() ? 0.0 : off_diagonal.back();
    double a = 0.0;
#pragma omp parallel for schedule(static) reduction(+ : a) if (n > 100000)
    for (Index k = 0; k < n; ++k) {
      w[k] = scale[k] * product[k] - b_previous * q_previous[k];
      if (k < owned) a += w[k] * q[k];
    }
    if (shares) a = global_sums({a})[0];
    double norm_squared = 0.0;
#pragma omp parallel for schedule(static) reduction(+ : norm_squared) if (n > 100000)
    for (Index k = 0; k < n; ++k) {
      w[k] -= a * q[k];
      if (k < owned) norm_squared += w[k] * w[k];
    }
    if (shares) norm_squared = global_sums({norm_squared})[0];
    const double b = std::sqrt(norm_squared);
    diagonal.push_back(a);
    const bool exhausted = !(b > 1e-14 * std::abs(a));
    if ((iteration + 1) % 10 == 0 || exhausted || iteration + 1 == options.max_iterations) {
      const Index size = static_cast<Index>(diagonal.size());
      Eigen::SelfAdjointEigenSolver<MatrixX> solver;
      VectorX d = Eigen::Map<const VectorX>(diagonal.data(), size);
      VectorX e = size > 1 ? VectorX(Eigen::Map<const VectorX>(off_diagonal.data(), size - 1)) : VectorX();
      solver.computeFromTridiagonal(d, e, Eigen::EigenvaluesOnly);
      largest = solver.eigenvalues().maxCoeff();
      if (exhausted || (largest_before > 0.0 && largest - largest_before <= options.tolerance * largest)) {
        ++iteration;
        break;
      }
      largest_before = largest;
    }
    off_diagonal.push_back(b);
    const double inverse_b = 1.0 / b;
#pragma omp parallel for schedule(static) if (n > 100000)
    for (Index k = 0; k < n; ++k) {
      q_previous[k] = q[k];
      q[k] = w[k] * inverse_b;
      scaled[k] = scale[k] * q[k];
    }
  }
  result.largest = largest;
  result.iterations = iteration;
  return result;
}

}  // namespace crackle::linalg
