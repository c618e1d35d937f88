// The Lanczos estimate of the largest eigenvalue (linalg/lanczos.hpp) against exact spectra.
#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "linalg/lanczos.hpp"

namespace crackle::linalg {
namespace {

/// The 1D Laplacian tridiag(-1, 2, -1) of size n: eigenvalues 2 - 2 cos(k pi / (n + 1)).
SparseMatrix laplacian(Index n) {
  std::vector<Eigen::Triplet<double, Index>> entries;
  for (Index i = 0; i < n; ++i) {
    entries.emplace_back(i, i, 2.0);
    if (i + 1 < n) {
      entries.emplace_back(i, i + 1, -1.0);
      entries.emplace_back(i + 1, i, -1.0);
    }
  }
  SparseMatrix matrix(n, n);
  matrix.setFromTriplets(entries.begin(), entries.end());
  return matrix;
}

TEST(Lanczos, TheLargestRitzValueApproachesTheLargestEigenvalueFromBelow) {
  const Index n = 400;
  const CsrOperator a(laplacian(n));
  const double exact = 2.0 - 2.0 * std::cos(n * M_PI / (n + 1.0));
  const VectorX start = VectorX::LinSpaced(n, -1.0, 2.0);
  const LanczosResult result = lanczos_largest(a, VectorX::Ones(n), start);
  EXPECT_FALSE(result.zero_start);
  EXPECT_LE(result.largest, exact * (1.0 + 1e-12));  // never above it
  EXPECT_GT(result.largest, exact * (1.0 - 1e-3));
  EXPECT_LT(result.iterations, 300);
  // S A S with S = diag(s): a uniform scale s multiplies the eigenvalues by s^2.
  const LanczosResult scaled = lanczos_largest(a, VectorX::Constant(n, 3.0), start);
  EXPECT_NEAR(scaled.largest / result.largest, 9.0, 1e-9 * 9.0);
  // An iteration limit stops it, still below.
  const LanczosResult limited = lanczos_largest(a, VectorX::Ones(n), start, {10, 1e-6});
  EXPECT_EQ(limited.iterations, 10);
  EXPECT_LE(limited.largest, exact);
}

TEST(Lanczos, ASmallSpectrumIsExhaustedAndAZeroStartIsReported) {
  // diag(1, 4, 9) restricted by the scale to the first two entries: the largest eigenvalue is 4, and
  // the Krylov space is exhausted after two steps.
  SparseMatrix d(3, 3);
  d.insert(0, 0) = 1.0;
  d.insert(1, 1) = 4.0;
  d.insert(2, 2) = 9.0;
  const CsrOperator a(d);
  const VectorX scale = (VectorX(3) << 1.0, 1.0, 0.0).finished();
  const LanczosResult result = lanczos_largest(a, scale, (VectorX(3) << 1.0, 1.0, 0.0).finished());
  EXPECT_NEAR(result.largest, 4.0, 1e-12);
  EXPECT_LE(result.iterations, 3);
  const LanczosResult none = lanczos_largest(a, scale, VectorX::Zero(3));
  EXPECT_TRUE(none.zero_start);
  EXPECT_EQ(none.iterations, 0);
}

}  // namespace
}  // namespace crackle::linalg
