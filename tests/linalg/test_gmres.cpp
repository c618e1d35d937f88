// Restarted GMRES (linalg/gmres.hpp) against a dense LU solve.
#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <cmath>
#include <cstdio>
#include <random>

#include "linalg/gmres.hpp"

namespace crackle::linalg {
namespace {

double relative_difference(const VectorX& a, const VectorX& b) {
  return (a - b).cwiseAbs().maxCoeff() / b.cwiseAbs().maxCoeff();
}

TEST(Gmres, SolvesANonsymmetricSystemWithAndWithoutPreconditioner) {
  const Index n = 200;
  std::mt19937 random(1);
  std::normal_distribution<double> normal;
  MatrixX a = MatrixX::Identity(n, n) * 4.0;
  for (Index i = 0; i < n; ++i)
    for (Index j = 0; j < n; ++j) a(i, j) += normal(random) / std::sqrt(double(n));
  VectorX b = VectorX::NullaryExpr(n, [&](Index) { return normal(random); });
  const VectorX exact = a.partialPivLu().solve(b);
  const LinearAction apply = [&](const VectorX& x, VectorX& y) { y = a * x; };
  const LinearAction none = [](const VectorX& x, VectorX& y) { y = x; };
  VectorX x;
  const GmresReport plain = gmres(apply, none, b, x, 1e-12, 500, 30);  // restarted
  EXPECT_TRUE(plain.converged);
  EXPECT_LT(relative_difference(x, exact), 1e-10);
  const MatrixX inverse = a.inverse();
  const LinearAction exact_preconditioner = [&](const VectorX& in, VectorX& y) { y = inverse * in; };
  x.resize(0);
  const GmresReport preconditioned = gmres(apply, exact_preconditioner, b, x, 1e-12, 500, 30);
  EXPECT_LE(preconditioned.iterations, 2);
  EXPECT_LT(relative_difference(x, exact), 1e-10);
  std::printf("  GMRES(30): %d iterations plain, %d with the exact inverse\n", plain.iterations, preconditioned.iterations);
}

TEST(Gmres, AZeroRightHandSideAndAnIterationLimitAreReported) {
  const Index n = 50;
  MatrixX a = MatrixX::Identity(n, n);
  for (Index i = 0; i + 1 < n; ++i) a(i, i + 1) = 0.9;  // non-normal: GMRES needs many steps
  const LinearAction apply = [&](const VectorX& x, VectorX& y) { y = a * x; };
  const LinearAction none = [](const VectorX& x, VectorX& y) { y = x; };
  VectorX x = VectorX::Ones(n);
  const GmresReport zero = gmres(apply, none, VectorX::Zero(n), x, 1e-12, 100, 10);
  EXPECT_TRUE(zero.converged);
  EXPECT_EQ(zero.iterations, 0);
  EXPECT_EQ(x.norm(), 0.0);
  const VectorX b = VectorX::Ones(n);
  x.resize(0);
  const GmresReport limited = gmres(apply, none, b, x, 1e-14, 3, 10);
  EXPECT_FALSE(limited.converged);
  EXPECT_EQ(limited.iterations, 3);
  VectorX residual;
  apply(x, residual);
  EXPECT_NEAR(limited.relative_residual, (b - residual).norm() / b.norm(), 1e-12);  // the true residual
  EXPECT_GT(limited.relative_residual, 1e-14);
}

}  // namespace
}  // namespace crackle::linalg
