#pragma once
/// \file The largest eigenvalue of a symmetric positive semi-definite map by the Lanczos iteration
/// without reorthogonalisation (Golub and Van Loan, sec. 10.1): its largest Ritz value never exceeds
/// the largest eigenvalue and converges much faster than the power iteration. The stable time step
/// of the explicit model (transient/time_step.hpp) is made of it.
#include <functional>
#include <vector>

#include "core/types.hpp"
#include "linalg/linear_operator.hpp"

namespace crackle::linalg {

struct LanczosOptions {
  int max_iterations = 300;  ///< Lanczos steps at most
  double tolerance = 1e-6;   ///< relative change of the largest Ritz value over 10 steps that stops it
};

/// The vectors are one share of a distributed vector: dot products run over the first `owned`
/// entries and `sum` adds a list of partial sums over the shares (in place).
struct VectorShares {
  Index owned = 0;
  std::function<void(std::vector<double>&)> sum;
};

struct LanczosResult {
  double largest = 0.0;  ///< the largest Ritz value (0 for a zero start)
  int iterations = 0;
  bool zero_start = false;  ///< the start vector was zero: nothing was iterated
};

/// The largest eigenvalue of S A S with S = diag(scale) (A = K and scale = M^-1/2 give omega_max^2),
/// from `start` (normalised here). `a` must return completed products when the vectors are shares.
LanczosResult lanczos_largest(const LinearOperator& a, const VectorX& scale, VectorX start,
                              const LanczosOptions& options = {}, const VectorShares* shares = nullptr);

}  // namespace crackle::linalg
